"""Shared motion primitives of the scripted expert, written as per-env generators.

A skill is a generator ``skill(ctx)`` that yields one :class:`Target` per control step for one env;
primitives (``move``, ``grip``, ``approach``, ``descend``, ``close``, ``lift``, ``carry``,
``release``, ``grasp``) are generators the skills ``yield from``. The :class:`~realm_ms.expert.core.Expert`
turns the targets of all envs into ``droid_joint_pos`` actions with one batched IK solve per step.

All positions are in the robot base frame (x forward, z up, origin at the robot base, which sits at
table height). The gripper always points down; ``yaw`` is the direction of the closing axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

CONTROL_HZ = 15.0
OPEN, CLOSED = 0.0, 1.0
MIN_GRASP_Z = 0.012  # m, lowest TCP height above the table (pads end 4 mm below the TCP)
DEFAULT_YAW = -math.pi / 4  # closing direction with joint 7 at 0


@dataclass
class Target:
    p: np.ndarray  # (3,) TCP position, base frame
    yaw: float  # closing direction (rad)
    grip: float  # 0 open .. 1 closed


class Ctx:
    """One env's view for a skill: state readers + the commanded TCP target so far."""

    def __init__(self, expert, i: int):
        self.ex, self.i = expert, i
        self.env = expert.env
        self.cmd: Target | None = None  # last commanded target
        self.log: list[str] = []

    # ---------------------------------------------------------------- state (base frame, numpy)
    def to_base(self, p_world: torch.Tensor) -> np.ndarray:
        return (p_world[self.i] - self.ex.base_p[self.i]).detach().cpu().numpy().astype(float)

    def tcp(self) -> np.ndarray:
        return self.to_base(self.env.agent.tcp_pose.p)

    def grasped(self, entity) -> bool:
        return bool(self.env.agent.is_grasping(entity)[self.i])

    def gripper_pos(self) -> float:
        return float(self.env.agent.gripper_position[self.i])

    def table_z(self) -> float:
        return 0.0  # robot base at table height

    def obj_pose(self, obj) -> tuple[np.ndarray, np.ndarray]:
        """Object origin (base frame) and its 3x3 rotation."""
        from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix

        pose = obj.pose
        return self.to_base(pose.p), quaternion_to_matrix(pose.q[self.i : self.i + 1])[0].cpu().numpy().astype(float)


def obj_yaw(r: np.ndarray) -> float:
    return math.atan2(r[1, 0], r[0, 0])


def wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def nearest_yaw(candidates, ref: float = DEFAULT_YAW) -> float:
    """Gripper yaw (mod pi, symmetric fingers) among ``candidates`` closest to ``ref``."""
    best, best_d = None, 1e9
    for c in candidates:
        for k in (-2, -1, 0, 1, 2):
            y = c + k * math.pi
            d = abs(y - ref)
            if d < best_d:
                best, best_d = y, d
    return best


# -------------------------------------------------------------------- primitives (generators)
def move(ctx: Ctx, p, yaw: float | None = None, grip: float | None = None, speed: float = 0.15,
         yaw_speed: float = 1.2, tol: float = 0.01, settle: int = 25, min_steps: int = 0):
    """Move the commanded TCP in a straight line to ``p`` at ``speed`` m/s, then wait until the real
    TCP is within ``tol`` (at most ``settle`` steps)."""
    c = ctx.cmd
    p = np.asarray(p, float)
    yaw = c.yaw if yaw is None else yaw
    grip = c.grip if grip is None else grip
    start, y0 = c.p.copy(), c.yaw
    dist = float(np.linalg.norm(p - start))
    n = max(int(math.ceil(dist / (speed / CONTROL_HZ))), int(math.ceil(abs(yaw - y0) / (yaw_speed / CONTROL_HZ))), 1, min_steps)
    for k in range(1, n + 1):
        a = k / n
        ctx.cmd = Target(start + a * (p - start), y0 + a * (yaw - y0), grip)
        yield ctx.cmd
    for _ in range(settle):
        if np.linalg.norm(ctx.tcp() - p) < tol:
            break
        yield ctx.cmd


def hold(ctx: Ctx, steps: int, grip: float | None = None):
    if grip is not None:
        ctx.cmd = Target(ctx.cmd.p.copy(), ctx.cmd.yaw, grip)
    for _ in range(steps):
        yield ctx.cmd


def grip(ctx: Ctx, value: float, steps: int = 10):
    """Open/close the gripper in place (full stroke takes ~0.6 s = 9 steps)."""
    yield from hold(ctx, steps, grip=value)


def close(ctx: Ctx, entity=None, max_steps: int = 14):
    """Close until the two-pad grasp holds ``entity`` (plus 3 steps to build force) or timeout."""
    ctx.cmd = Target(ctx.cmd.p.copy(), ctx.cmd.yaw, CLOSED)
    held = 0
    for _ in range(max_steps):
        yield ctx.cmd
        if entity is not None and ctx.grasped(entity):
            held += 1
            if held >= 3:
                return


def release(ctx: Ctx, steps: int = 8):
    yield from grip(ctx, OPEN, steps)


def approach(ctx: Ctx, p, yaw: float, clearance: float = 0.10, grip_value: float = OPEN, speed: float = 0.2):
    """Go to ``clearance`` above ``p`` with the gripper set to ``grip_value``; first rises to a safe
    height if the TCP is low (so the transit does not sweep the table)."""
    above = np.asarray(p, float) + np.array([0, 0, clearance])
    cur = ctx.cmd.p
    safe_z = max(above[2], cur[2])
    if cur[2] < safe_z - 0.02:
        yield from move(ctx, [cur[0], cur[1], safe_z], grip=grip_value, settle=0)
    yield from move(ctx, [above[0], above[1], safe_z], yaw=yaw, grip=grip_value, speed=speed, settle=0)
    yield from move(ctx, above, speed=speed, tol=0.012, settle=20)


def descend(ctx: Ctx, p, speed: float = 0.08, tol: float = 0.008):
    yield from move(ctx, p, speed=speed, tol=tol, settle=20)


def lift(ctx: Ctx, dz: float, speed: float = 0.12):
    p = ctx.cmd.p + np.array([0, 0, dz])
    yield from move(ctx, p, speed=speed, tol=0.015, settle=10)


def carry(ctx: Ctx, p, yaw: float | None = None, speed: float = 0.15):
    yield from move(ctx, p, yaw=yaw, speed=speed, tol=0.012, settle=20)


# -------------------------------------------------------------------- object geometry helpers
def grasp_height(top: float, centre: float) -> float:
    """TCP height for a top-down grasp: at the object's centre, but not so low that the gripper
    base hits the top (fingers reach ~5 cm) nor that the pads dig into the table."""
    return max(min(centre, top - 0.035), MIN_GRASP_Z)


def grasp_yaw_for(extents, r: np.ndarray, ref: float = DEFAULT_YAW) -> float:
    """Closing direction across the object's narrow horizontal side (mod pi), near ``ref``."""
    th = obj_yaw(r)
    ex, ey = float(extents[0]), float(extents[1])
    if abs(ex - ey) < 0.15 * max(ex, ey):  # square-ish: either face pair
        return nearest_yaw([th, th + math.pi / 2], ref)
    return nearest_yaw([th + math.pi / 2] if ex > ey else [th], ref)


_PROFILE_CACHE: dict = {}


def grasp_point_local(obj) -> tuple[np.ndarray, float]:
    """Where to grasp a rigid object, in its frame: (x, y, z_top) of the best slice and the slice height.

    Elongated objects are sliced along their long local axis; the expert grasps the tallest slice
    that fits in the gripper (a spoon by its bowl, not by its 3 mm handle). Compact objects: the
    bounding-box centre."""
    key = obj.asset.id
    if key in _PROFILE_CACHE:
        return _PROFILE_CACHE[key]
    ext = np.asarray(obj.extents, float)
    out = (np.array([0.0, 0.0, ext[2]]), float(ext[2]))
    if max(ext[0], ext[1]) > 1.8 * min(ext[0], ext[1]):
        try:
            import trimesh

            m = trimesh.load(str(obj.asset.collision_path), force="mesh")
            v = np.asarray(m.vertices)
            ax = 0 if ext[0] >= ext[1] else 1
            lo, hi = v[:, ax].min(), v[:, ax].max()
            best = None
            for c in np.linspace(lo + 0.02, hi - 0.02, 15):
                sel = np.abs(v[:, ax] - c) < 0.012
                if sel.sum() < 3:
                    continue
                width = np.ptp(v[sel, 1 - ax])
                h = v[sel, 2].max()
                if width < 0.075 and (best is None or h > best[0] + 1e-3):
                    mid = (v[sel, 1 - ax].max() + v[sel, 1 - ax].min()) / 2
                    pt = np.zeros(3)
                    pt[ax], pt[1 - ax], pt[2] = c, mid, h
                    best = (h, pt)
            if best is not None:
                # prefer the centre when it is (nearly) as tall: a marker or banana is grasped mid-length
                sel = np.abs(v[:, ax]) < 0.012
                if sel.sum() >= 3 and v[sel, 2].max() > best[0] - 0.003:
                    best = (v[sel, 2].max(), np.array([0.0, 0.0, v[sel, 2].max()]))
                out = (best[1], float(best[0]))
        except Exception:  # no mesh: bounding box centre
            pass
    _PROFILE_CACHE[key] = out
    return out


def grasp(ctx: Ctx, obj, tries: int = 3, clearance: float = 0.10, point=None, yaw=None):
    """Approach, descend, close on a rigid task object; re-tries from above when the grasp fails.
    Returns True on a real two-pad grasp."""
    for attempt in range(tries):
        pos, r = ctx.obj_pose(obj)
        ext = obj.extents
        if point is not None:
            g = np.asarray(point(ctx), float)
        else:
            local, h = grasp_point_local(obj)
            w = pos + r @ np.array([local[0], local[1], 0.0])
            if h < 0.02:  # flat (spoon, ticket): pads skim the table
                z = pos[2] + max(h / 2, 0.004)
            else:
                z = grasp_height(pos[2] + h, pos[2] + min(h, float(ext[2])) / 2)
            g = np.array([w[0], w[1], z])
        y = yaw(ctx) if yaw is not None else grasp_yaw_for(ext, r)
        yield from approach(ctx, g, y, clearance=clearance)
        yield from descend(ctx, g)
        yield from close(ctx, obj.entity)
        if ctx.grasped(obj.entity):
            return True
        ctx.log.append(f"grasp attempt {attempt} failed")
        yield from release(ctx)
        yield from lift(ctx, clearance)
    return False
