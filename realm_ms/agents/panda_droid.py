"""The DROID robot: Franka Panda + Robotiq 2F-85 on a fixed base, robot uid ``panda_droid``.

Control modes (first = default):
- ``droid_joint_pos``: 8-D action = 7 absolute joint targets (rad) + gripper in [0, 1] (1 = closed),
  at 15 Hz; the arm is torque-controlled by the Polymetis hybrid joint impedance law every physics
  step (``realm_ms.agents.control``), gravity compensated by the robot's own model as on the real arm.
- ``pd_joint_pos``, ``pd_joint_delta_pos``, ``pd_ee_delta_pose``: ManiSkill's usual ideal PD modes for
  RL users (PhysX drives, gravity disabled on the links as ManiSkill does for its Panda).

Cameras: ``wrist`` (on the gripper, ~88 deg HFOV); the two external cameras belong to the task.
"""

from __future__ import annotations

import copy

import numpy as np
import torch
from mani_skill.agents.base_agent import BaseAgent, Keyframe
from mani_skill.agents.controllers import PDEEPoseControllerConfig, PDJointPosControllerConfig
from mani_skill.agents.registration import register_agent
from mani_skill.sensors.camera import CameraConfig

import sapien

from realm_ms.agents import robotiq_2f85 as gripper
from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.arm_model import ArmModel
from realm_ms.agents.control.config import DroidControlConfig
from realm_ms.agents.control.maniskill import DroidJointImpedanceControllerConfig
from realm_ms.contacts import any_contact
from realm_ms.errors import InputError
from realm_ms.rendering import CameraSettings, vertical_fov
from realm_ms.agents.urdf import ARM_JOINTS, CAMERA_LINK, DROID_RESET_QPOS, FLANGE_LINK, TCP_LINK, panda_droid_urdf_path

WRIST_HFOV_DEG = 87.7  # ZED mini, DROID wrist camera


_MODEL_CACHE: dict[str, ArmModel] = {}


def droid_arm_model() -> ArmModel:
    """The robot's own model of its arm + mounted gripper (what libfranka/Polymetis know)."""
    path = str(panda_droid_urdf_path())
    if path not in _MODEL_CACHE:
        _MODEL_CACHE[path] = ArmModel.from_urdf(path, "panda_link0", FLANGE_LINK)
    return copy.copy(_MODEL_CACHE[path])


@register_agent()
class PandaDroid(BaseAgent):
    uid = "panda_droid"
    fix_root_link = True
    disable_self_collisions = False
    load_multiple_collisions = True
    urdf_config = gripper.URDF_CONFIG
    keyframes = dict(
        droid_reset=Keyframe(qpos=np.array(DROID_RESET_QPOS + (0.0,) * len(gripper.GRIPPER_JOINTS)), pose=sapien.Pose()),
    )

    def __init__(self, *args, droid_control: DroidControlConfig | None = None, camera: CameraSettings | None = None, **kwargs):
        """``droid_control``: the Polymetis law's settings; ``camera``: the wrist camera's size and
        shader (the env passes the settings its exterior cameras use)."""
        self.droid_control = droid_control if droid_control is not None else DroidControlConfig()
        self.camera = camera if camera is not None else CameraSettings()
        super().__init__(*args, **kwargs)

    @property
    def urdf_path(self) -> str:
        return str(panda_droid_urdf_path())

    # ------------------------------------------------------------------ controllers
    @property
    def _controller_configs(self):
        arm_droid = DroidJointImpedanceControllerConfig(
            joint_names=ARM_JOINTS, model_factory=droid_arm_model, control=self.droid_control
        )
        grip = gripper.gripper_controller_configs()  # gripper (1-D, [0, 1], 1 = closed) + passive joints
        ideal = dict(stiffness=1e3, damping=1e2, force_limit=100)
        arm_pos = PDJointPosControllerConfig(list(ARM_JOINTS), None, None, normalize_action=False, **ideal)
        arm_delta = PDJointPosControllerConfig(list(ARM_JOINTS), -0.1, 0.1, use_delta=True, **ideal)
        arm_ee = PDEEPoseControllerConfig(
            joint_names=list(ARM_JOINTS), pos_lower=-0.1, pos_upper=0.1, rot_lower=-0.1, rot_upper=0.1,
            ee_link=TCP_LINK, urdf_path=self.urdf_path, **ideal,
        )
        return dict(
            droid_joint_pos=dict(arm=arm_droid, **grip, balance_passive_force=False),
            pd_joint_pos=dict(arm=arm_pos, **grip),
            pd_joint_delta_pos=dict(arm=arm_delta, **grip),
            pd_ee_delta_pose=dict(arm=arm_ee, **grip),
        )

    @property
    def arm_controller(self):
        ctrl = self.controller
        return ctrl.controllers["arm"] if hasattr(ctrl, "controllers") else ctrl

    def set_robot_model(self, model) -> None:
        """Use identified dynamics: a ``RobotModel``, a ``MODEL.yaml`` path or name, a dict (the arm's
        stages and the gripper's response), or an ``ActuationModel`` (the arm's stages alone)."""
        if isinstance(model, ActuationModel):
            actuation, law = model, None
        else:
            from realm_ms.agents.robot_model import RobotModel

            model = RobotModel.load(model)
            actuation, law = model.actuation(), model.gripper_law()
        arm = self.controllers["droid_joint_pos"].controllers["arm"] if "droid_joint_pos" in self.controllers else None
        if arm is None:
            raise InputError("robot_model needs the droid_joint_pos control mode")
        arm.set_robot_model(actuation)
        actuation.build(self.robot, arm.active_joint_indices.tolist())
        for mode in self.controllers.values():  # the gripper's response, in every control mode
            grip = mode.controllers.get("gripper") if hasattr(mode, "controllers") else None
            if grip is not None:
                grip.set_response(law)

    # ------------------------------------------------------------------ sensors
    @property
    def _sensor_configs(self):
        c = self.camera
        return [
            CameraConfig(
                "wrist", pose=sapien.Pose(), width=c.width, height=c.height, fov=vertical_fov(WRIST_HFOV_DEG, c.width, c.height),
                near=0.01, far=10.0, mount=self.robot.links_map[CAMERA_LINK], shader_config=c.shader_config(),
            )
        ]

    # ------------------------------------------------------------------ loading hooks
    def _after_loading_articulation(self):
        gripper.add_loop_closures(self.scene, self.robot)

    def _after_init(self):
        self.tcp = self.robot.links_map[TCP_LINK]
        self.pads = gripper.pad_links(self.robot)
        self.gripper_links = [l for l in self.robot.links if l.name in gripper.GRIPPER_LINKS]
        self._arm_idx = torch.as_tensor([self.robot.active_joints_map[j].active_index[0] for j in ARM_JOINTS])
        self._grip_idx = torch.as_tensor([self.robot.active_joints_map[j].active_index[0] for j in gripper.GRIPPER_JOINTS])

    # ------------------------------------------------------------------ state
    def reset_qpos(self, arm_qpos: torch.Tensor) -> torch.Tensor:
        """Full qpos (B, dof) for arm joint positions with the gripper open."""
        q = torch.zeros(arm_qpos.shape[0], self.robot.max_dof, device=arm_qpos.device)
        q[:, self._arm_idx.to(q.device)] = arm_qpos
        return q

    @property
    def tcp_pose(self):
        return self.tcp.pose

    @property
    def arm_qpos(self) -> torch.Tensor:
        return self.robot.get_qpos()[:, self._arm_idx.to(self.device)]

    @property
    def gripper_position(self) -> torch.Tensor:
        """(B,) in [0, 1], 0 = open, 1 = closed (DROID convention)."""
        return gripper.gripper_position(self.robot.get_qpos()[:, self._grip_idx.to(self.device)])

    def droid_state(self) -> torch.Tensor:
        """DROID ``observation.state``: 7 joint positions + gripper position, (B, 8)."""
        return torch.cat([self.arm_qpos, self.gripper_position[:, None]], dim=1)

    def get_proprioception(self):
        obs = super().get_proprioception()
        obs["droid_state"] = self.droid_state()
        return obs

    def finger_positions(self) -> torch.Tensor:
        """Inner finger pad positions (B, 2, 3)."""
        return torch.stack([p.pose.p for p in self.pads], dim=1)

    def is_touching(self, entities) -> torch.Tensor:
        """Any gripper link in contact with any of ``entities`` (actors or links)."""
        return any_contact(self.scene, self.gripper_links, list(entities))

    def is_grasping(self, object=None, min_force: float = 1.0) -> torch.Tensor:
        """Real two-pad grasp: both pads press on the object with >= ``min_force`` N, opposing."""
        return gripper.two_pad_grasp(self.scene, self.robot, object, min_force=min_force)

    def is_static(self, threshold: float = 0.2) -> torch.Tensor:
        qvel = self.robot.get_qvel()[:, self._arm_idx.to(self.device)]
        return torch.max(torch.abs(qvel), 1)[0] <= threshold
