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


def catch_up(ctx: Ctx, tol: float = 0.05, max_steps: int = 30):
    """Where the env converts the expert's joint targets into a DROID velocity or Cartesian action,
    each step moves at most DROID's per-step limit from the *measured* pose (0.2 rad per joint,
    0.075 m and 0.15 rad for the TCP), so a fast turn falls behind its target: hold the target until
    every joint is within ``tol`` of it (at most ``max_steps``). Under joint-position actions the
    controller tracks the target itself, and this waits for nothing."""
    if getattr(ctx.env, "droid_actions", None) is None:
        return
    for _ in range(max_steps):
        lag = (ctx.env.agent.arm_qpos[ctx.i].detach().cpu().double() - ctx.ex.q_cmd[ctx.i]).abs().max()
        if float(lag) < tol:
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


GENTLE_STEP = 0.03  # gripper position per control step when closing gently (~1/4 of full speed)
GENTLE_SQUEEZE = 0.02  # gripper position past first grasp that a gentle pinch holds (~20 N per pad)


def close(ctx: Ctx, entity=None, max_steps: int = 14, gentle: bool = False):
    """Close until the two-pad grasp holds ``entity`` (plus 3 steps to build force) or timeout.

    ``gentle`` (every object grasp): close a little per step and, once both pads hold, keep the grip
    just past that width (~20 N per pad, enough for 2 kg at the pads' friction). Closed at full
    command the pads squeeze with the drive's saturated force (40-90 N each) and PhysX lets them
    overlap a light object, then pushes them apart along its shortest way out: a 6 mm tea bag's
    rounded edge ends up under a pad (the pad rides onto its top), a chess pawn is squeezed up out
    of the pinch. Drawer handles (no object to hold) are closed at full command."""
    if not gentle:
        ctx.cmd = Target(ctx.cmd.p.copy(), ctx.cmd.yaw, CLOSED)
    held = 0
    for _ in range(max_steps + (int(CLOSED / GENTLE_STEP) if gentle else 0)):
        if gentle and not held:
            ctx.cmd = Target(ctx.cmd.p.copy(), ctx.cmd.yaw, min(CLOSED, ctx.gripper_pos() + GENTLE_STEP))
        yield ctx.cmd
        if entity is not None and ctx.grasped(entity):
            if gentle and not held:
                ctx.cmd = Target(ctx.cmd.p.copy(), ctx.cmd.yaw, min(CLOSED, ctx.gripper_pos() + GENTLE_SQUEEZE))
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
FLAT = 0.02  # m: objects lower than this are pinched with the pads skimming the table
PAD_FLOOR = 0.0  # m: pad bottoms on the table when pinching a flat object (closing lifts the hand ~1 mm)
PAD_CLEARANCE = 0.003  # m between the pad bottoms and the table when the pads touch a taller object
PAD_BELOW_TCP_OPEN = 0.0044  # m, pad bottoms under the TCP with the gripper open (measured on the sim)
PAD_LENGTH = 0.0375  # m, the 2F-85 pads' vertical extent


def pad_below_tcp(width: float) -> float:
    """How far the pad bottoms hang below the TCP when the pad faces are ``width`` apart.

    The 2F-85's pads ride a parallelogram: closing swings them inwards AND down (14 mm over the
    stroke), so a TCP height chosen with the gripper open puts the pads into the table once they
    reach a narrow object. Exact for the linkage of ``realm_ms.agents.robotiq_2f85``."""
    from realm_ms.agents import robotiq_2f85 as g

    s = (width / 2 - g._DRIVER_PIVOT_Y - g._PAD_FACE_Y_IN_FOLLOWER) / g._CRANK  # sin(phi0 - theta)
    c = math.sqrt(max(1.0 - min(max(s, -1.0), 1.0) ** 2, 0.0))
    return PAD_BELOW_TCP_OPEN + g._CRANK * (c - math.cos(g._PHI0))


def grasp_height(base: float, top: float, width: float) -> float:
    """TCP height for a top-down grasp of an object standing on ``base`` with its top at ``top``,
    ``width`` across the pads. Chosen for where the pads' bottoms are once they touch the object
    (``pad_below_tcp``): 1 cm below its mid-height, so the vertical pads meet a rounded object at its
    widest (closing above the equator squeezes it down and out), and low enough that the 37.5 mm
    pads cover a short object's top, but never into the table. Flat objects (a spoon, a coin) are
    pinched with the pads on the table."""
    h = top - base
    pad_bottom = PAD_FLOOR if h < FLAT else max(PAD_CLEARANCE, min(h / 2 - 0.01, h - PAD_LENGTH + 0.0025))
    return base + pad_bottom + pad_below_tcp(width)


def grasp_yaw_for(extents, r: np.ndarray, ref: float = DEFAULT_YAW) -> float:
    """Closing direction across the object's narrow horizontal side (mod pi), near ``ref``."""
    th = obj_yaw(r)
    ex, ey = float(extents[0]), float(extents[1])
    if abs(ex - ey) < 0.15 * max(ex, ey):  # square-ish: either face pair
        return nearest_yaw([th, th + math.pi / 2], ref)
    return nearest_yaw([th + math.pi / 2] if ex > ey else [th], ref)


def width_across(extents, r: np.ndarray, yaw: float) -> float:
    """The object's bounding-box extent along the closing direction ``yaw`` (pads' travel)."""
    d = abs(wrap(yaw - obj_yaw(r)))
    along_x = min(d, math.pi - d) < math.pi / 4
    return float(extents[0] if along_x else extents[1])


UPRIGHT_COS = 0.9  # object z axis within ~25 deg of vertical: standing as placed


def tipped_grasp(pos: np.ndarray, r: np.ndarray, ext, ref: float = DEFAULT_YAW) -> tuple[np.ndarray, float, float, float]:
    """Grasp of a toppled object from its rotated bounding box: (x, y, bottom z) of the box centre's
    column, closing yaw across the box's narrower horizontal side, the width there, top z."""
    ext = np.asarray(ext, float)
    c = pos + r @ np.array([0.0, 0.0, ext[2] / 2])
    half_z = float(np.abs(r[2]) @ ext) / 2

    def along(d) -> float:  # the box's extent along the direction d
        return float(np.abs(np.asarray(d) @ r) @ ext)

    k = int(np.argmax(np.linalg.norm(r[:2], axis=0) * ext))  # the local axis lying most along the table
    u = np.array([r[0, k], r[1, k], 0.0])
    u /= max(np.linalg.norm(u), 1e-9)
    v = np.array([-u[1], u[0], 0.0])
    wu, wv = along(u), along(v)
    yaws = [math.atan2(u[1], u[0]), math.atan2(v[1], v[0])]
    if abs(wu - wv) < 0.15 * max(wu, wv):
        y = nearest_yaw(yaws, ref)
    else:
        y = nearest_yaw([yaws[0] if wu < wv else yaws[1]], ref)
    width = along([math.cos(y), math.sin(y), 0.0])
    return np.array([c[0], c[1], c[2] - half_z]), y, width, c[2] + half_z


def object_geometry(ctx: "Ctx", obj) -> tuple:
    """(catalog spec, per-axis scale, extents) of ``obj`` in this env: perturbations give each
    sub-env its own model and size (SB-NOUN, VB-MOBJ)."""
    assets = getattr(obj, "assets", None) or [obj.asset]
    k = ctx.i if len(assets) > 1 else 0
    asset = assets[k]
    ext_all = getattr(obj, "_extents", None)
    ext = np.asarray(obj.extents if ext_all is None else ext_all[k if ext_all.shape[0] > 1 else 0].cpu().numpy(), float)
    scale = ext / np.maximum(np.asarray(asset.extents, float), 1e-9)
    return asset, scale, ext


def scaled_vertices(asset, scale, samples: int = 3000) -> np.ndarray | None:
    """Points of the collision mesh's surface in the object frame, at the object's scale: its
    vertices plus ``samples`` points spread over its faces (a low-poly cylinder has vertices only at
    its ends), drawn with a fixed seed. None when the object has no mesh."""
    try:
        import trimesh

        m = trimesh.load(str(asset.collision_path), force="mesh")
        pts, _ = trimesh.sample.sample_surface(m, samples, seed=0)
        v = np.concatenate([np.asarray(m.vertices, float), np.asarray(pts, float)])
    except Exception:
        return None
    return v * np.asarray(scale, float)


@dataclass(frozen=True)
class GraspSlice:
    point: np.ndarray  # (x, y, z_top) in the object frame
    top: float  # slice top above the object's origin (m)
    width: float | None  # extent across the pads at the slice (None: the bounding box's)


_PROFILE_CACHE: dict = {}
PAD_HALF_WIDTH = 0.011  # m, half the 2F-85 pad's extent across the closing direction (20.7 mm, measured on the sim)


def _under_whole_pad(v: np.ndarray, ax: int, c: float) -> bool:
    """Whether the object is under the whole pad centred at ``c`` along axis ``ax`` (its middle
    and both edges). A slice that only reaches into a part (a tea bag's bag ends 4 mm past its
    bounding-box centre, then a gap to its tag) puts the pads on a rounded corner, which a pinch
    rides up onto."""
    return all(bool((np.abs(v[:, ax] - (c + o)) < 0.002).any()) for o in (-PAD_HALF_WIDTH + 0.002, 0.0, PAD_HALF_WIDTH - 0.002))


def grasp_slice(asset, scale, ext) -> GraspSlice:
    """Where to grasp a rigid object, in its (scaled) frame.

    Elongated objects are sliced along their long local axis; the expert grasps the middle of the
    tallest run of slices that fit in the gripper, mid-length when the centre is in that run (a
    marker, a banana); a flat object at the narrowest of its tallest slices (a spoon by its neck,
    not by its 3 mm handle nor across its bowl, where lifting rolls it out of the pinch). Compact
    objects: the bounding-box centre."""
    ext = np.asarray(ext, float)
    key = (asset.id, tuple(np.round(ext, 5)))
    if key in _PROFILE_CACHE:
        return _PROFILE_CACHE[key]
    out = GraspSlice(np.array([0.0, 0.0, ext[2]]), float(ext[2]), None)
    v = scaled_vertices(asset, scale) if max(ext[0], ext[1]) > 1.8 * min(ext[0], ext[1]) else None
    if v is not None:
        ax = 0 if ext[0] >= ext[1] else 1
        lo, hi = v[:, ax].min(), v[:, ax].max()
        slices = []
        for c in [0.0, *np.linspace(lo + 0.02, hi - 0.02, 15)]:
            sel = np.abs(v[:, ax] - c) < 0.012
            if sel.sum() >= 10 and np.ptp(v[sel, 1 - ax]) < 0.075 and _under_whole_pad(v, ax, c):
                slices.append((c, v[sel, 2].max(), (v[sel, 1 - ax].max() + v[sel, 1 - ax].min()) / 2, np.ptp(v[sel, 1 - ax])))
        if slices:
            h_max = max(s[1] for s in slices)
            tall = [s for s in slices if s[1] > h_max - min(0.003, 0.2 * h_max)]
            # mid-length when the bounding-box centre is (nearly) as tall, else the middle of the tall run
            mid = 0.0 if tall[0][0] == 0.0 else float(np.mean([s[0] for s in tall]))
            if h_max < FLAT:  # a few-mm pinch holds on a narrow section (a spoon's neck), not across its bowl
                w_min = min(s[3] for s in tall)
                tall = [s for s in tall if s[3] < w_min + 0.003]
            c, h, m, w = min(tall, key=lambda s: abs(s[0] - mid))
            pt = np.zeros(3)
            pt[ax], pt[1 - ax], pt[2] = c, m, h
            out = GraspSlice(pt, float(h), float(w))
    _PROFILE_CACHE[key] = out
    return out


def grasp(ctx: Ctx, obj, tries: int = 3, clearance: float = 0.10, point=None, yaw=None):
    """Approach, descend, close on a rigid task object; re-tries from above when the grasp fails.
    Returns True on a real two-pad grasp."""
    asset, scale, ext = object_geometry(ctx, obj)

    def target() -> tuple[np.ndarray, float, bool]:
        pos, r = ctx.obj_pose(obj)
        if point is not None:
            return np.asarray(point(ctx), float), (yaw(ctx) if yaw is not None else grasp_yaw_for(ext, r)), False
        if r[2, 2] < UPRIGHT_COS:  # toppled (a tall, round-bottomed object rolls over): its rotated box
            g, y_box, width, top = tipped_grasp(pos, r, ext)
            y = yaw(ctx) if yaw is not None else y_box
            return np.array([g[0], g[1], grasp_height(g[2], top, width)]), y, top - g[2] < FLAT
        y = yaw(ctx) if yaw is not None else grasp_yaw_for(ext, r)
        sl = grasp_slice(asset, scale, ext)
        w = pos + r @ np.array([sl.point[0], sl.point[1], 0.0])
        width = sl.width if sl.width is not None else width_across(ext, r, y)
        return np.array([w[0], w[1], grasp_height(pos[2], pos[2] + sl.top, width)]), y, sl.top < FLAT

    for attempt in range(tries):
        g, y, _ = target()
        yield from approach(ctx, g, y, clearance=clearance)
        # re-read: the object has settled (spawned 2 mm up) or been nudged since the approach began
        g, _, flat = target()
        # a flat object leaves no margin: the TCP must really be at the pinch height before closing
        yield from descend(ctx, g, tol=0.003 if flat else 0.008)
        yield from close(ctx, obj.entity, gentle=True)
        if ctx.grasped(obj.entity):
            return True
        ctx.log.append(f"grasp attempt {attempt} failed")
        yield from release(ctx)
        yield from lift(ctx, clearance)
    return False
