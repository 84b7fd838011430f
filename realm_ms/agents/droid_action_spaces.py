"""DROID's four action spaces, converted to the joint-position target the DROID controller tracks.

DROID's ``RobotEnv(action_space=..., gripper_action_space=...)`` turns every action into a joint
target for the same Polymetis impedance controller at 15 Hz (``FrankaRobot.create_action_dict`` in
droid-dataset/droid ``droid/franka/robot.py``); this module reproduces that conversion with the
constants of ``RobotIKSolver`` (``droid/robot_ik/robot_ik_solver.py``):

- ``joint_position`` (8): absolute joints + gripper; the env's own ``droid_joint_pos`` (no conversion).
- ``joint_velocity`` (8): v in [-1, 1]^7; if max|v| > 1 the whole vector is divided by it
  (``joint_velocity_to_delta``); target = q + 0.2 v (``max_joint_delta``).
- ``cartesian_velocity`` (7): linear and angular parts each rescaled to norm <= 1, times 0.075 m and
  0.15 rad (``cartesian_velocity_to_delta``); the delta is mapped to joint velocities by the
  dm_robotics ``Cartesian6dVelocityEffector`` DROID configures (see ``DroidIK``), then
  ``joint_velocity_to_delta`` again; target = q + delta.
- ``cartesian_position`` (7): absolute flange pose [x, y, z, roll, pitch, yaw] (euler "xyz", base
  frame, Polymetis ``ee_link_name: panda_link8``); ``pose_diff(target, current)`` /
  ``cartesian_delta_to_velocity`` (no clipping there), then as ``cartesian_velocity``: one step
  moves at most 0.075 m / 0.15 rad toward the target.
- gripper (last entry): ``position`` = absolute in [0, 1] (0 open, 1 closed), clipped; ``velocity``
  = g + 0.25 v, |v| > 1 scaled to 1 (``gripper_velocity_to_delta``, ``max_gripper_delta``), then
  clipped to [0, 1]. DROID's default (``gripper_action_space=None``): velocity for the velocity
  spaces, position otherwise. openpi's DROID client uses ``joint_velocity`` + ``position``.

Poses use DROID's ``droid/misc/transformations.py``: euler "xyz" (scipy, extrinsic),
``add_poses(delta, source)`` = position sum and ``R(delta) * R(source)`` (world-frame rotation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from realm_ms.errors import InputError

# RobotIKSolver.__init__ (droid/robot_ik/robot_ik_solver.py)
MAX_JOINT_DELTA = 0.2  # rad per step (relative_max_joint_delta = 0.2 for every joint)
MAX_GRIPPER_DELTA = 0.25
MAX_LIN_DELTA = 0.075  # m per step
MAX_ROT_DELTA = 0.15  # rad per step
CONTROL_HZ = 15
# its cartesian_6d_velocity_effector.ControlParams
NULLSPACE_REFERENCE = np.zeros(7)
NULLSPACE_GAIN = 0.025  # scaled by 1 / control_timestep_seconds inside the effector
REGULARIZATION_WEIGHT = 1e-2
MIN_DISTANCE_FROM_LIMIT = 0.3  # rad
LIMIT_VELOCITY_SCALE = 0.95
# Panda joint limits of DROID's MJCF (droid/robot_ik/franka/panda.xml)
Q_LIMITS = np.array([[-2.8973, 2.8973], [-1.7628, 1.7628], [-2.8973, 2.8973], [-3.0718, -0.0698],
                     [-2.8973, 2.8973], [-0.0175, 3.7525], [-2.8973, 2.8973]])

ACTION_SPACES = ("joint_position", "joint_velocity", "cartesian_velocity", "cartesian_position")
GRIPPER_SPACES = ("position", "velocity")


def check_action_space(action_space: str, gripper_action_space: str | None) -> None:
    """ValueError naming the known spaces when either name is unknown."""
    if action_space not in ACTION_SPACES:
        raise InputError(f"unknown action_space {action_space!r}; known: {', '.join(ACTION_SPACES)}")
    if gripper_action_space is not None and gripper_action_space not in GRIPPER_SPACES:
        raise InputError(f"unknown gripper_action_space {gripper_action_space!r}; known: {', '.join(GRIPPER_SPACES)} "
                         f"(or None: DROID's default, velocity for the velocity spaces)")


#: the controller DROID's spaces are converted for (ManiSkill's pd_* modes read actions their own way)
DROID_CONTROL_MODE = "droid_joint_pos"


def check_control_mode(action_space: str, gripper_action_space: str | None, control_mode: str | None) -> None:
    """ValueError when a DROID action space other than joint_position (+ position gripper) meets a
    control mode other than ``droid_joint_pos`` (None = the env's default, droid_joint_pos): its
    conversion produces droid_joint_pos targets, which e.g. pd_joint_delta_pos would read as deltas."""
    if control_mode in (None, DROID_CONTROL_MODE):
        return
    if action_space == "joint_position" and gripper_action_space in (None, "position"):
        return
    space = action_space + (f":{gripper_action_space}" if gripper_action_space else "")
    raise InputError(f"action_space {space!r} is DROID's and needs control_mode={DROID_CONTROL_MODE!r} (got "
                     f"{control_mode!r}); leave control_mode out, or use action_space='joint_position' with "
                     f"ManiSkill's modes")


def resolve_gripper_space(action_space: str, gripper_action_space: str | None) -> str:
    """DROID's default: ``velocity`` if the arm space is a velocity space, else ``position``."""
    if gripper_action_space is not None:
        return gripper_action_space
    return "velocity" if "velocity" in action_space else "position"


# ---------------------------------------------------------------------------- DROID's formulas (batched)
def joint_velocity_to_delta(v: np.ndarray) -> np.ndarray:
    """(B, 7): rows with max|v| > 1 divided by it (direction kept), times ``MAX_JOINT_DELTA``."""
    v = np.asarray(v, dtype=np.float64)
    m = np.abs(v).max(axis=-1, keepdims=True)
    return np.where(m > 1, v / np.maximum(m, 1e-12), v) * MAX_JOINT_DELTA


def joint_delta_to_velocity(d: np.ndarray) -> np.ndarray:
    return np.asarray(d, dtype=np.float64) / MAX_JOINT_DELTA


def _unit_ball(x: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(x, axis=-1, keepdims=True)
    return np.where(n > 1, x / np.maximum(n, 1e-12), x)


def cartesian_velocity_to_delta(v: np.ndarray) -> np.ndarray:
    """(B, 6): linear and angular parts each rescaled to norm <= 1, times 0.075 m / 0.15 rad."""
    v = np.asarray(v, dtype=np.float64)
    return np.concatenate([_unit_ball(v[..., :3]) * MAX_LIN_DELTA, _unit_ball(v[..., 3:6]) * MAX_ROT_DELTA], -1)


def cartesian_delta_to_velocity(d: np.ndarray) -> np.ndarray:
    d = np.asarray(d, dtype=np.float64)
    return np.concatenate([d[..., :3] / MAX_LIN_DELTA, d[..., 3:6] / MAX_ROT_DELTA], -1)


def gripper_velocity_to_delta(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return np.where(np.abs(v) > 1, np.sign(v), v) * MAX_GRIPPER_DELTA


def gripper_delta_to_velocity(d: np.ndarray) -> np.ndarray:
    return np.asarray(d, dtype=np.float64) / MAX_GRIPPER_DELTA


def add_poses(delta: np.ndarray, source: np.ndarray) -> np.ndarray:
    """DROID ``add_poses``: positions add, rotations compose as R(delta) * R(source) (euler xyz)."""
    rot = Rotation.from_euler("xyz", delta[..., 3:6]) * Rotation.from_euler("xyz", source[..., 3:6])
    return np.concatenate([delta[..., :3] + source[..., :3], rot.as_euler("xyz")], -1)


def pose_diff(target: np.ndarray, source: np.ndarray) -> np.ndarray:
    """DROID ``pose_diff``: position difference and euler xyz of R(target) * R(source)^-1."""
    rot = Rotation.from_euler("xyz", target[..., 3:6]) * Rotation.from_euler("xyz", source[..., 3:6]).inv()
    return np.concatenate([target[..., :3] - source[..., :3], rot.as_euler("xyz")], -1)


# ---------------------------------------------------------------------------- IK
class DroidIK:
    """DROID's Cartesian-velocity -> joint-velocity map, on the robot's own arm model.

    DROID runs dm_robotics' ``Cartesian6dVelocityEffector`` (an LSQP stack of tasks) on the
    ``wrist_site`` of its MJCF (the flange origin, ``panda_link8``); the command is the Cartesian
    *delta* treated as a velocity about that origin in base orientation, with
    ``control_timestep_seconds = 1/15``. Reproduced here per env row:

    1. damped least squares  min ||J x - v||^2 + 1e-2 ||x||^2  (``regularization_weight``),
       subject to |x_i| <= 0.2 (``joint_velocity_limits``) and the joint-position-limit constraint
       -0.95 (q - q_lo - 0.3) / dt <= x <= 0.95 (q_hi - 0.3 - q) / dt (dt = 1/15, as DROID configures
       it, although the result is then applied as a whole-step delta), where a joint already inside
       the 0.3 rad margin gets 0 as its bound toward the limit, never a push away from it
       (dm_robotics ``JointPositionLimitConstraint::UpdateBounds``): the bounds always admit 0, so
       the arm can always move away from a limit; an active-set solve;
    2. nullspace: toward x_ns = 0.025 (q_ref - q) / dt with q_ref = 0 (``nullspace_gain``,
       ``nullspace_joint_position_reference=[0]*7``) inside J's nullspace, shortened to stay in the
       bounds (the effector's second hierarchy keeps the first task's result, within its slack);
    3. where the solve fails the effector returns zeros (it catches the solver's exception): same
       here for a non-finite solution.

    The result is a joint delta in rad; ``RobotIKSolver.cartesian_velocity_to_joint_velocity``
    returns it divided by 0.2 (``joint_delta_to_velocity``) and ``create_action_dict`` applies
    ``joint_velocity_to_delta`` to it.
    """

    def __init__(self, nullspace: bool = True):
        from realm_ms.agents.panda_droid import droid_arm_model

        self.model = droid_arm_model().to("cpu", torch.float64)
        self.nullspace = nullspace

    def flange(self, q: np.ndarray) -> np.ndarray:
        """(B, 4, 4) flange (panda_link8) poses in the base frame."""
        return self.model.fk(torch.as_tensor(np.asarray(q, dtype=np.float64).reshape(-1, 7))).numpy()

    def pose(self, q: np.ndarray) -> np.ndarray:
        """(B, 6) DROID ``cartesian_position``: flange xyz + euler xyz."""
        t = self.flange(q)
        return np.concatenate([t[:, :3, 3], Rotation.from_matrix(t[:, :3, :3]).as_euler("xyz")], -1)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """(B, 6, 7) flange Jacobian, linear rows at the flange origin, base orientation."""
        return self.model.jacobian(torch.as_tensor(np.asarray(q, dtype=np.float64).reshape(-1, 7))).numpy()

    def bounds(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dt = 1.0 / CONTROL_HZ
        lo_lim, hi_lim = Q_LIMITS[:, 0] + MIN_DISTANCE_FROM_LIMIT, Q_LIMITS[:, 1] - MIN_DISTANCE_FROM_LIMIT
        room = hi_lim > lo_lim
        # inside the margin (distance <= 0): 0 toward the limit, as dm_robotics sets it
        lo = np.where(room, -LIMIT_VELOCITY_SCALE * np.maximum(q - lo_lim, 0.0) / dt, 0.0)
        hi = np.where(room, LIMIT_VELOCITY_SCALE * np.maximum(hi_lim - q, 0.0) / dt, 0.0)
        return np.maximum(-MAX_JOINT_DELTA, lo), np.minimum(MAX_JOINT_DELTA, hi)

    def cartesian_delta_to_joint_delta(self, delta: np.ndarray, q: np.ndarray) -> np.ndarray:
        """(B, 6) Cartesian deltas (already scaled: <= 0.075 m / 0.15 rad) -> (B, 7) joint deltas."""
        q = np.asarray(q, dtype=np.float64).reshape(-1, 7)
        delta = np.asarray(delta, dtype=np.float64).reshape(-1, 6)
        jac = self.jacobian(q)
        out = np.zeros_like(q)
        for i in range(len(q)):
            lo, hi = self.bounds(q[i])
            x = _bounded_dls(jac[i], delta[i], lo, hi, REGULARIZATION_WEIGHT)
            if self.nullspace:
                x_ns = NULLSPACE_GAIN * (NULLSPACE_REFERENCE - q[i]) * CONTROL_HZ
                x = _nullspace_step(jac[i], x, x_ns, lo, hi)
            if np.all(np.isfinite(x)):  # a failed solve: the effector returns zeros
                out[i] = x
        return out


def _bounded_dls(j: np.ndarray, v: np.ndarray, lo: np.ndarray, hi: np.ndarray, reg: float) -> np.ndarray:
    """min ||J x - v||^2 + reg ||x||^2 with lo <= x <= hi (active set: clamp, re-solve the free joints)."""
    n = j.shape[1]
    at = np.zeros(n, dtype=int)  # 0 free, -1 at lo, +1 at hi
    x = np.zeros(n)
    for _ in range(3 * n):
        free = at == 0
        fixed = np.where(at < 0, lo, np.where(at > 0, hi, 0.0))
        x = fixed.copy()
        if free.any():
            jf = j[:, free]
            r = v - j[:, ~free] @ fixed[~free]
            x[free] = np.linalg.solve(jf.T @ jf + reg * np.eye(int(free.sum())), jf.T @ r)
        viol = free & ((x < lo - 1e-12) | (x > hi + 1e-12))
        if viol.any():  # clamp the worst violation, re-solve
            k = np.argmax(np.where(viol, np.maximum(lo - x, x - hi), -np.inf))
            at[k] = -1 if x[k] < lo[k] else 1
            continue
        g = j.T @ (j @ x - v) + reg * x  # KKT: release a clamped joint that wants to move inward
        release = ((at < 0) & (g < -1e-12)) | ((at > 0) & (g > 1e-12))
        if not release.any():
            break
        at[np.argmax(np.abs(np.where(release, g, 0.0)))] = 0
    return np.clip(x, lo, hi)


def _nullspace_step(j: np.ndarray, x: np.ndarray, x_ns: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """x + a N (x_ns - x), N = J's nullspace projector, the largest a in [0, 1] inside the bounds."""
    n = np.eye(j.shape[1]) - np.linalg.pinv(j) @ j
    d = n @ (x_ns - x)
    a = 1.0
    for k in range(len(x)):
        if d[k] > 1e-12:
            a = min(a, max(0.0, (hi[k] - x[k]) / d[k]))
        elif d[k] < -1e-12:
            a = min(a, max(0.0, (lo[k] - x[k]) / d[k]))
    return x + a * d


# ---------------------------------------------------------------------------- the env-facing converter
@dataclass(frozen=True)
class DroidActionSpace:
    """One (action_space, gripper_action_space) pair: its bounds and both directions of its conversion."""

    action_space: str
    gripper: str  # resolved: "position" | "velocity"

    @property
    def dim(self) -> int:
        return 7 if self.action_space.startswith("cartesian") else 8  # DROID RobotEnv.DoF

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-dim (low, high). Velocity dims: [-1, 1] (DROID asserts it; larger vectors are rescaled,
        not clipped). Poses: a 1.5 m box around the base, euler in [-pi, pi]."""
        g = (0.0, 1.0) if self.gripper == "position" else (-1.0, 1.0)
        if self.action_space == "joint_position":
            lo, hi = list(Q_LIMITS[:, 0]), list(Q_LIMITS[:, 1])
        elif self.action_space == "cartesian_position":
            lo, hi = [-1.5, -1.5, -1.5] + [-np.pi] * 3, [1.5, 1.5, 1.5] + [np.pi] * 3
        else:
            n = self.dim - 1
            lo, hi = [-1.0] * n, [1.0] * n
        return np.array(lo + [g[0]], dtype=np.float32), np.array(hi + [g[1]], dtype=np.float32)

    def gym_space(self):
        import gymnasium as gym

        lo, hi = self.bounds()
        return gym.spaces.Box(lo, hi, dtype=np.float32)

    # --------------------------------------------------------------------- action -> joint target
    def to_joint_target(self, action: np.ndarray, q: np.ndarray, g: np.ndarray, ik: DroidIK | None = None) -> np.ndarray:
        """(B, dim) actions at joints ``q`` (B, 7) and gripper ``g`` (B,) -> (B, 8) ``droid_joint_pos``."""
        a = np.asarray(action, dtype=np.float64).reshape(-1, self.dim)
        q = np.asarray(q, dtype=np.float64).reshape(-1, 7)
        g = np.asarray(g, dtype=np.float64).reshape(-1)
        arm, grip = a[:, :-1], a[:, -1]
        if self.gripper == "velocity":
            g_t = np.clip(g + gripper_velocity_to_delta(grip), 0.0, 1.0)
        else:
            g_t = np.clip(grip, 0.0, 1.0)
        if self.action_space == "joint_position":
            q_t = arm
        elif self.action_space == "joint_velocity":
            q_t = q + joint_velocity_to_delta(arm)
        else:
            ik = ik or DroidIK()
            if self.action_space == "cartesian_position":
                arm = cartesian_delta_to_velocity(pose_diff(arm, ik.pose(q)))
            dq = ik.cartesian_delta_to_joint_delta(cartesian_velocity_to_delta(arm), q)
            q_t = q + joint_velocity_to_delta(joint_delta_to_velocity(dq))
        return np.concatenate([q_t, g_t[:, None]], 1)

    # --------------------------------------------------------------------- joint target -> action
    def from_joint_target(self, target: np.ndarray, q: np.ndarray, g: np.ndarray, ik: DroidIK | None = None) -> np.ndarray:
        """The action in this space that asks for the (B, 8) joint target from state (q, g): DROID's
        ``create_action_dict`` inverse directions (``joint_delta_to_velocity``, ``pose_diff``,
        ``cartesian_delta_to_velocity``, ``gripper_delta_to_velocity``), unclipped."""
        t = np.asarray(target, dtype=np.float64).reshape(-1, 8)
        q = np.asarray(q, dtype=np.float64).reshape(-1, 7)
        g = np.asarray(g, dtype=np.float64).reshape(-1)
        grip = t[:, 7] if self.gripper == "position" else gripper_delta_to_velocity(t[:, 7] - g)
        if self.action_space == "joint_position":
            arm = t[:, :7]
        elif self.action_space == "joint_velocity":
            arm = joint_delta_to_velocity(t[:, :7] - q)
        else:
            ik = ik or DroidIK()
            pose = ik.pose(t[:, :7])
            arm = pose if self.action_space == "cartesian_position" else cartesian_delta_to_velocity(pose_diff(pose, ik.pose(q)))
        return np.concatenate([arm, grip[:, None]], 1)

    def hold(self, q: np.ndarray, g: np.ndarray, ik: DroidIK | None = None) -> np.ndarray:
        """(B, dim) actions that keep the robot where it is (velocity zero, position = current)."""
        t = np.concatenate([np.asarray(q, np.float64).reshape(-1, 7), np.asarray(g, np.float64).reshape(-1, 1)], 1)
        return self.from_joint_target(t, q, g, ik)


def make_action_space(action_space: str = "joint_position", gripper_action_space: str | None = None) -> DroidActionSpace:
    check_action_space(action_space, gripper_action_space)
    return DroidActionSpace(action_space, resolve_gripper_space(action_space, gripper_action_space))


class EnvActionConverter:
    """What ``RealmEnv`` holds for a non-default action space: reads the robot's state, converts."""

    def __init__(self, space: DroidActionSpace):
        self.space = space
        self.ik = DroidIK() if space.action_space.startswith("cartesian") else None

    def __call__(self, agent, action: torch.Tensor) -> torch.Tensor:
        q = agent.arm_qpos.detach().cpu().double().numpy()
        g = agent.gripper_position.detach().cpu().double().numpy()
        a = action.detach().cpu().double().numpy().reshape(-1, self.space.dim)
        if len(a) == 1 and len(q) > 1:
            a = np.repeat(a, len(q), 0)
        t = self.space.to_joint_target(a, q, g, self.ik)
        t[:, :7] = np.clip(t[:, :7], Q_LIMITS[:, 0], Q_LIMITS[:, 1])
        return torch.as_tensor(t, dtype=torch.float32, device=action.device)


def parse_action_space_flag(text: str | None) -> dict:
    """``SPACE`` or ``SPACE:GRIPPER`` (e.g. ``joint_velocity:position``) -> env keywords; ``{}`` for
    None / the default. ValueError (listing the known names) for anything else."""
    if not text:
        return {}
    space, _, grip = text.partition(":")
    grip = grip or None
    check_action_space(space, grip)
    if space == "joint_position" and grip in (None, "position"):
        return {}
    return {"action_space": space} | ({"gripper_action_space": grip} if grip else {})


def space_of_keywords(env_kwargs: dict | None) -> DroidActionSpace:
    """The action space env keywords (``action_space``, ``gripper_action_space``) describe."""
    kw = env_kwargs or {}
    return make_action_space(kw.get("action_space", "joint_position"), kw.get("gripper_action_space"))


def action_space_name(env_kwargs: dict | None) -> str:
    """``SPACE:GRIPPER`` (resolved, e.g. ``joint_velocity:velocity``) of env keywords: records name it."""
    space = space_of_keywords(env_kwargs)
    return f"{space.action_space}:{space.gripper}"


def hold_action(env) -> torch.Tensor:
    """(num_envs, dim) actions of ``env``'s action space that keep its robots still (batched runner)."""
    u = env.unwrapped if hasattr(env, "unwrapped") else env
    state = u.agent.droid_state()
    conv = getattr(u, "droid_actions", None)
    if conv is None:
        return state.clone()
    s = state.detach().cpu().double().numpy()
    return torch.as_tensor(conv.space.hold(s[:, :7], s[:, 7], conv.ik), dtype=state.dtype, device=state.device)
