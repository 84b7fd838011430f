"""Robotiq 2F-85 for the ``panda_droid`` agent: linkage closure, controller, observation, grasp test.

Kinematics (see ``assets/robotiq_2f85_template.urdf`` and ``docs/robot.md``): per side a 4-bar
parallelogram. The outer knuckle (driver) is actuated; the outer finger (coupler) is rigid on it;
the inner finger (follower, carrying the pad) and the inner knuckle (spring link) are passive.
The URDF is a tree; :func:`add_loop_closures` closes each loop at runtime with a PhysX drive whose
x/y/z limits are (0, 0) (a ball joint; the linkage is planar, so it acts as the missing revolute),
exactly like ManiSkill's ``xarm6_robotiq`` recipe. On the closed linkage ``q_inner_knuckle = q_driver``
and ``q_inner_finger = -q_driver``: the pads stay parallel to the palm.

Command / observation convention (DROID): 0 = open, 1 = closed. Driver angle 0 rad = open
(85.4 mm between the silicone pads), :data:`DRIVER_CLOSED` = 0.8 rad = closed (pads meet).

Actuation model: the drivers are PD position drives (target = command * 0.8 rad) whose torque
saturates at ``force_limit`` (an effort limit per driver). Free motion is damping-limited
(speed ~ force_limit / damping), and on contact the error is large, so each pad presses with the
saturated torque: F_pad ~ force_limit / (L cos(phi)) with L = 57.5 mm the parallelogram crank,
i.e. ~16-18 N per N.m. Defaults: :data:`GRIPPER_FORCE_LIMIT` = 4 N.m -> 62-73 N per pad measured
on 3-5 cm cubes (real 2F-85: 20-235 N); the driver target is rate-limited to
:data:`GRIPPER_MAX_SPEED` -> full stroke in 0.58 s (real 2F-85: 0.57 s at 150 mm/s). See
``docs/robot.md`` and ``tests/agents/test_gripper.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Union

import numpy as np
import sapien
import torch
from gymnasium import spaces
from mani_skill.agents.controllers.passive_controller import PassiveControllerConfig
from mani_skill.agents.controllers.pd_joint_pos import (
    PDJointPosMimicController,
    PDJointPosMimicControllerConfig,
)

__all__ = [
    "ACTIVE_JOINTS",
    "PASSIVE_JOINTS",
    "GRIPPER_JOINTS",
    "CONTROL_JOINT",
    "PAD_LINKS",
    "GRIPPER_LINKS",
    "DRIVER_OPEN",
    "DRIVER_CLOSED",
    "PAD_INWARD_NORMAL_LOCAL",
    "PAD_MATERIAL",
    "PAD_PATCH_RADIUS",
    "PAD_MIN_PATCH_RADIUS",
    "URDF_CONFIG",
    "GRIPPER_STIFFNESS",
    "GRIPPER_DAMPING",
    "GRIPPER_FORCE_LIMIT",
    "GRIPPER_MAX_SPEED",
    "GRIPPER_FRICTION",
    "GRIPPER_ARMATURE",
    "GRIPPER_COLLISION_BIT",
    "RobotiqGripperController",
    "RobotiqGripperControllerConfig",
    "add_loop_closures",
    "disable_gripper_self_collisions",
    "set_gripper_armature",
    "gripper_controller_configs",
    "gripper_position",
    "gripper_width",
    "gripper_qpos_from_position",
    "pad_links",
    "two_pad_grasp",
]

# --------------------------------------------------------------------------------------------- #
# Names and geometry
# --------------------------------------------------------------------------------------------- #
#: actuated drivers; the controller drives both (the left one mimics the right one)
ACTIVE_JOINTS = ("left_outer_knuckle_joint", "right_outer_knuckle_joint")
#: the joint that carries the 1-D command in the mimic controller
CONTROL_JOINT = "right_outer_knuckle_joint"
#: passive joints of the linkage (free, no drive), closed by :func:`add_loop_closures`
PASSIVE_JOINTS = (
    "left_inner_knuckle_joint",
    "right_inner_knuckle_joint",
    "left_inner_finger_joint",
    "right_inner_finger_joint",
)
GRIPPER_JOINTS = ACTIVE_JOINTS + PASSIVE_JOINTS
#: links touching objects; inward contact normal is -y in each pad's frame
PAD_LINKS = ("left_inner_finger_pad", "right_inner_finger_pad")
GRIPPER_LINKS = (
    "robotiq_arg2f_base_link",
    "left_outer_knuckle",
    "right_outer_knuckle",
    "left_outer_finger",
    "right_outer_finger",
    "left_inner_finger",
    "right_inner_finger",
    "left_inner_finger_pad",
    "right_inner_finger_pad",
    "left_inner_knuckle",
    "right_inner_knuckle",
)
DRIVER_OPEN = 0.0
DRIVER_CLOSED = 0.8
PAD_INWARD_NORMAL_LOCAL = (0.0, -1.0, 0.0)

# loop-closure anchors (per side, identical in the mirrored side frames): the follower pivot on the
# inner knuckle (spring link) and the same point in the inner finger (follower) frame
_ANCHOR_ON_INNER_KNUCKLE = (0.0, 0.0375989, 0.043496)
_ANCHOR_ON_INNER_FINGER = (0.0, -0.018, 0.0065)

# width model (exact for the parallelogram; y/z in the gripper base frame)
_DRIVER_PIVOT_Y = 0.0306011
_CRANK = float(np.hypot(0.0375989, 0.043496))  # 0.057495 m
_PHI0 = float(np.arctan2(0.0375989, 0.043496))  # 0.7127 rad
_PAD_FACE_Y_IN_FOLLOWER = -0.0189 - 0.0066  # silicone face, follower frame

# --------------------------------------------------------------------------------------------- #
# Materials and drive parameters
# --------------------------------------------------------------------------------------------- #
#: silicone pads. PhysX averages the two friction coefficients of a contact (default combine mode),
#: so against ManiSkill's default object material (0.3) the effective coefficient is ~1.15.
PAD_MATERIAL = dict(static_friction=2.0, dynamic_friction=2.0, restitution=0.0)
#: torsional-friction patch radius of the pad contacts (pads are 22 x 37.5 mm)
PAD_PATCH_RADIUS = 0.02
PAD_MIN_PATCH_RADIUS = 0.01
#: pass as (or merge into) the agent's ``urdf_config``
URDF_CONFIG = dict(
    _materials=dict(robotiq_pad=dict(PAD_MATERIAL)),
    link={
        name: dict(
            material="robotiq_pad",
            patch_radius=PAD_PATCH_RADIUS,
            min_patch_radius=PAD_MIN_PATCH_RADIUS,
        )
        for name in PAD_LINKS
    },
)

GRIPPER_FORCE_LIMIT = 4.0  # N.m per driver -> ~70-75 N per pad
GRIPPER_MAX_SPEED = 0.8 / 0.6  # rad/s of the driver target: full stroke in 0.6 s (~140 mm/s)
GRIPPER_STIFFNESS = 400.0  # N.m/rad -> torque saturates for errors > 0.01 rad
GRIPPER_DAMPING = 5.0  # N.m.s/rad
GRIPPER_FRICTION = 0.0
#: joint-space armature (kg.m^2) on all 6 gripper joints. The linkage links weigh 3.5-22 g while the
#: loop closure carries ~100 N at full grip force; without armature PhysX's iterative solver lets
#: the closure slip by 5-10 deg at 15 position iterations (pads tilt, inner fingers hit their
#: limits). 0.01 keeps the pads parallel within ~1 deg at the default 15 iterations; it is also a
#: plausible reflected inertia of the 2F-85 worm-gear drive.
GRIPPER_ARMATURE = 0.01
GRIPPER_COLLISION_BIT = 31


# --------------------------------------------------------------------------------------------- #
# Loop closures and collision filtering
# --------------------------------------------------------------------------------------------- #
def _scene_and_robot(agent_or_scene, robot):
    if robot is None:  # a ManiSkill BaseAgent
        return agent_or_scene.scene, agent_or_scene.robot
    return agent_or_scene, robot


def _links_map(robot) -> dict:
    if hasattr(robot, "links_map"):  # ManiSkill Articulation
        return robot.links_map
    return {l.name: l for l in robot.get_links()}  # sapien.physx.PhysxArticulation


def add_loop_closures(
    agent_or_scene,
    robot=None,
    disable_self_collisions: bool = True,
    armature: Optional[float] = GRIPPER_ARMATURE,
) -> list:
    """Close both 4-bar loops of the 2F-85; by default also disable intra-gripper collisions
    (:func:`disable_gripper_self_collisions`) and set the gripper joint armature
    (:data:`GRIPPER_ARMATURE`, needed for a stiff closure; ``None`` leaves it alone).

    ``add_loop_closures(agent)`` with a ManiSkill ``BaseAgent`` (call it in
    ``_after_loading_articulation``), or ``add_loop_closures(scene, robot)`` with a ManiSkill
    ``ManiSkillScene`` + ``Articulation`` (drives are created in every sub-scene the robot lives in,
    via ``scene.create_drive``, so ``num_envs >= 1`` works) or a plain ``sapien.Scene`` + physx
    articulation. Returns the ``[left, right]`` drives.
    """
    scene, robot = _scene_and_robot(agent_or_scene, robot)
    links = _links_map(robot)
    drives = []
    for side in ("left", "right"):
        knuckle = links[f"{side}_inner_knuckle"]
        finger = links[f"{side}_inner_finger"]
        # ManiSkillScene.create_drive builds one drive per sub-scene (Drive struct); a plain
        # sapien.Scene.create_drive takes the physx link components directly. Same call either way.
        d = scene.create_drive(
            knuckle, sapien.Pose(_ANCHOR_ON_INNER_KNUCKLE), finger, sapien.Pose(_ANCHOR_ON_INNER_FINGER)
        )
        d.set_limit_x(0, 0)
        d.set_limit_y(0, 0)
        d.set_limit_z(0, 0)
        drives.append(d)
    if disable_self_collisions:
        disable_gripper_self_collisions(robot)
    if armature is not None:
        set_gripper_armature(robot, armature)
    return drives


def set_gripper_armature(robot, armature: float = GRIPPER_ARMATURE) -> None:
    """Set the joint armature of the 6 gripper joints (before GPU init, e.g. in
    ``_after_loading_articulation``)."""
    if hasattr(robot, "active_joints_map"):  # ManiSkill Articulation: one physx joint per sub-scene
        joints = [j for n in GRIPPER_JOINTS for j in robot.active_joints_map[n]._objs]
    else:
        joints = [j for j in robot.get_active_joints() if j.name in GRIPPER_JOINTS]
    for j in joints:
        j.set_armature(np.full(1, armature, dtype=np.float32))


def disable_gripper_self_collisions(
    robot, bit_idx: int = GRIPPER_COLLISION_BIT, extra_links: Sequence[str] = ("panda_link7",)
) -> None:
    """Put all gripper links (+ ``extra_links`` that exist, by default the wrist ``panda_link7``)
    in one collision-filter group (group 2, bit ``bit_idx``): they never collide with each other.
    They still collide with everything else (objects, table, other arm links)."""
    links = _links_map(robot)
    for name in tuple(GRIPPER_LINKS) + tuple(extra_links):
        link = links.get(name)
        if link is None:
            continue
        if hasattr(link, "set_collision_group_bit"):  # ManiSkill Link (all sub-scenes)
            link.set_collision_group_bit(group=2, bit_idx=bit_idx, bit=1)
        else:  # sapien physx link
            for cs in link.get_collision_shapes():
                g = cs.get_collision_groups()
                g[2] |= 1 << bit_idx
                cs.set_collision_groups(g)


# --------------------------------------------------------------------------------------------- #
# Controller: 1-D command in [0, 1] (1 = closed)
# --------------------------------------------------------------------------------------------- #
class RobotiqGripperController(PDJointPosMimicController):
    """Mimic PD controller on the two drivers with a 1-D action in [0, 1] (0 open, 1 closed).

    ``goal = clip(a, 0, 1) * closed_qpos`` (with ``binarize_threshold`` set: ``a > thr`` -> 1 else
    0, the REALM/DROID binary gripper). Like the real 2F-85 (position request + speed + force), the
    drive target moves towards the goal at ``max_speed`` rad/s (updated every physics step), and the
    PD drive's torque is capped by ``force_limit`` (grip force on contact). ``max_speed=None`` sets
    the goal at once (then the closing speed is only limited by the drive). A robot model's
    ``gripper_response`` effect (``set_response``) replaces the plain rate limit by its law: the
    request delayed, a slower or faster stroke, a lag."""

    config: "RobotiqGripperControllerConfig"
    response = None  # a ``GripperLaw`` (agents/effects/gripper_response.py), or None: the plain rate limit

    def set_response(self, law) -> None:
        """Run the drive target through ``law`` (a ``GripperLaw``; None: back to the plain rate limit)."""
        self.response = law
        if law is not None and getattr(self, "_target_qpos", None) is not None:  # else at the next reset
            law.reset(self._target_qpos)

    def _initialize_action_space(self):
        self.single_action_space = spaces.Box(
            np.zeros(1, dtype=np.float32), np.ones(1, dtype=np.float32), dtype=np.float32
        )

    def _preprocess_action(self, action):
        action = super()._preprocess_action(action)  # shape check only (normalize_action=False)
        action = torch.as_tensor(action, device=self.device, dtype=torch.float32)
        if self.config.binarize_threshold is not None:
            action = (action > self.config.binarize_threshold).to(torch.float32)
        action = torch.clamp(action, 0.0, 1.0)
        return self.config.open_qpos + action * (self.config.closed_qpos - self.config.open_qpos)

    def reset(self):
        super().reset()
        self._goal_qpos = self._target_qpos.clone()
        if self.response is not None:
            self.response.reset(self._target_qpos, self.scene._reset_mask)
        # the drive may still hold the previous episode's target; idle steps skip writing it
        self.set_drive_targets(self._target_qpos)

    def set_action(self, action):
        if self.config.max_speed is None:
            return super().set_action(action)
        goal = self._preprocess_action(action)
        self._step = 0
        if getattr(self, "_goal_qpos", None) is None:
            self._goal_qpos = self.qpos.clone()
        g = self._goal_qpos.clone()
        g[:, self.control_joint_indices] = goal
        g[:, self.mimic_joint_indices] = (
            g[:, self.mimic_control_joint_indices] * self._multiplier[None, :] + self._offset[None, :]
        )
        self._goal_qpos = g

    def before_simulation_step(self):
        if self.config.max_speed is None:
            return super().before_simulation_step()
        self._step += 1
        dt = float(self.articulation.px.timestep)
        if self.response is not None:  # its delay line and lag move even when the request holds still
            target = self.response.step(self._goal_qpos, dt, self.config.max_speed)
            if torch.equal(target, self._target_qpos):
                return
            self._target_qpos = target.clone()  # ManiSkill writes reset rows into it in place
        elif torch.equal(self._target_qpos, self._goal_qpos):
            return  # idle gripper: the drive already holds this target
        else:
            max_dq = self.config.max_speed * dt
            self._target_qpos = self._target_qpos + torch.clamp(self._goal_qpos - self._target_qpos, -max_dq, max_dq)
        self.set_drive_targets(self._target_qpos)
        if self.scene.gpu_sim_enabled:  # ManiSkill applies GPU targets once per action; we move them every substep
            self.scene.px.gpu_apply_articulation_target_position()

    def get_state(self) -> dict:
        return {"target_qpos": self._target_qpos, "goal_qpos": self._goal_qpos}

    def set_state(self, state: dict):
        self._target_qpos = state["target_qpos"]
        self._goal_qpos = state.get("goal_qpos", self._target_qpos)

    def __repr__(self):
        return (
            f"RobotiqGripperController(cmd in [0,1] -> driver goal in "
            f"[{self.config.open_qpos}, {self.config.closed_qpos}] rad, max_speed={self.config.max_speed} rad/s)"
        )


@dataclass
class RobotiqGripperControllerConfig(PDJointPosMimicControllerConfig):
    open_qpos: float = DRIVER_OPEN
    closed_qpos: float = DRIVER_CLOSED
    max_speed: Optional[float] = None
    binarize_threshold: Optional[float] = None
    normalize_action: bool = False
    controller_cls = RobotiqGripperController

    def __post_init__(self):
        self.normalize_action = False


def gripper_controller_configs(
    stiffness: float = GRIPPER_STIFFNESS,
    damping: float = GRIPPER_DAMPING,
    force_limit: float = GRIPPER_FORCE_LIMIT,
    friction: float = GRIPPER_FRICTION,
    max_speed: Optional[float] = GRIPPER_MAX_SPEED,
    binarize_threshold: Optional[float] = None,
    passive_damping: float = 0.0,
) -> dict:
    """ManiSkill controller configs for the gripper, to merge into a control-mode dict:
    ``dict(arm=..., **gripper_controller_configs())``.

    Returns ``{"gripper": RobotiqGripperControllerConfig (1-D action in [0, 1], 1 = closed),
    "gripper_passive": PassiveControllerConfig (0-D)}``. The action of the combined controller is
    ``[arm..., gripper]``."""
    active = RobotiqGripperControllerConfig(
        joint_names=list(ACTIVE_JOINTS),
        lower=None,
        upper=None,
        stiffness=stiffness,
        damping=damping,
        force_limit=force_limit,
        friction=friction,
        normalize_action=False,
        mimic={"left_outer_knuckle_joint": dict(joint=CONTROL_JOINT, multiplier=1.0, offset=0.0)},
        max_speed=max_speed,
        binarize_threshold=binarize_threshold,
    )
    passive = PassiveControllerConfig(
        joint_names=list(PASSIVE_JOINTS), damping=passive_damping, friction=0.0
    )
    return dict(gripper=active, gripper_passive=passive)


# --------------------------------------------------------------------------------------------- #
# Observation helpers
# --------------------------------------------------------------------------------------------- #
def _driver_angles(qpos_gripper, robot=None):
    """Driver angles (..., 2) from a tensor whose last dim is 2 (ACTIVE_JOINTS order), 6
    (GRIPPER_JOINTS order) or, with ``robot`` given, the full robot qpos."""
    q = torch.as_tensor(qpos_gripper)
    if robot is not None:
        idx = [robot.active_joints_map[n].active_index[0].item() for n in ACTIVE_JOINTS]
        return q[..., idx]
    if q.shape[-1] in (2, 6):
        return q[..., :2]
    raise ValueError(
        f"expected last dim 2 (ACTIVE_JOINTS) or 6 (GRIPPER_JOINTS), got {tuple(q.shape)}; pass robot= for full qpos"
    )


def gripper_position(qpos_gripper, robot=None) -> torch.Tensor:
    """DROID gripper observation in [0, 1] (0 open, 1 closed): mean driver angle / 0.8 rad.

    Shape ``(...,)`` -> use ``[..., None]`` for a 1-D feature. See :func:`_driver_angles` for inputs."""
    q = _driver_angles(qpos_gripper, robot).to(torch.float32)
    return torch.clamp(q.mean(-1) / DRIVER_CLOSED, 0.0, 1.0)


def gripper_width(qpos_gripper, robot=None) -> torch.Tensor:
    """Distance between the two silicone pad faces (m) on the closed linkage (0.0854 open, ~0 closed)."""
    th = _driver_angles(qpos_gripper, robot).to(torch.float32).mean(-1)
    half = _DRIVER_PIVOT_Y + _CRANK * torch.sin(_PHI0 - th) + _PAD_FACE_Y_IN_FOLLOWER
    return torch.clamp(2 * half, min=0.0)


def gripper_qpos_from_position(position: Union[float, np.ndarray]) -> np.ndarray:
    """Consistent 6-vector in GRIPPER_JOINTS order for a position in [0, 1] (for keyframes/resets).

    Order: (left_outer, right_outer, left_inner_knuckle, right_inner_knuckle, left_inner_finger,
    right_inner_finger) = (t, t, t, t, -t, -t) with t = position * 0.8."""
    t = np.clip(np.asarray(position, dtype=np.float64), 0, 1) * DRIVER_CLOSED
    return np.stack([t, t, t, t, -t, -t], axis=-1)


def pad_links(robot) -> tuple:
    """``(left_pad, right_pad)`` links of a ManiSkill Articulation (or a physx articulation)."""
    links = _links_map(robot)
    return links[PAD_LINKS[0]], links[PAD_LINKS[1]]


# --------------------------------------------------------------------------------------------- #
# Grasp predicate
# --------------------------------------------------------------------------------------------- #
def _angle(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    na = torch.linalg.norm(a, dim=-1).clamp_min(1e-9)
    nb = torch.linalg.norm(b, dim=-1).clamp_min(1e-9)
    return torch.arccos(torch.clamp((a * b).sum(-1) / (na * nb), -1.0, 1.0))


def two_pad_grasp(
    scene,
    robot,
    actor,
    min_force: float = 1.0,
    max_angle: float = 75.0,
) -> torch.Tensor:
    """Real two-finger grasp test, batched over envs: ``(num_envs,)`` bool tensor.

    True iff BOTH pads touch ``actor`` (ManiSkill scene ``get_pairwise_contact_forces``) with a
    net force >= ``min_force`` N each, each force within ``max_angle`` degrees of that pad's
    outward normal (the object pushes the pad open, i.e. +y of the pad frame; friction that carries
    the object's weight tilts it), and the two forces opposing each other (angle > 90 deg)."""
    from realm_ms.contacts import pairwise_forces

    left, right = pad_links(robot)
    f_l, f_r = pairwise_forces(scene, [(left, actor), (right, actor)])
    # outward normal of each pad = +y of its frame (the object pushes the pad open)
    out_l = left.pose.to_transformation_matrix()[..., :3, 1]
    out_r = right.pose.to_transformation_matrix()[..., :3, 1]
    max_a = np.deg2rad(max_angle)
    ok_l = (torch.linalg.norm(f_l, dim=-1) >= min_force) & (_angle(f_l, out_l) <= max_a)
    ok_r = (torch.linalg.norm(f_r, dim=-1) >= min_force) & (_angle(f_r, out_r) <= max_a)
    opposing = _angle(f_l, f_r) > np.pi / 2
    return ok_l & ok_r & opposing
