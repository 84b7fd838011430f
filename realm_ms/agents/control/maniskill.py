"""The ManiSkill binding of ``DroidArmDriver`` (physx_cpu and physx_cuda), and the PhysX side of
the driver's contract on SAPIEN joints (shared with the sysid replay simulator)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import torch
from gymnasium import spaces
from mani_skill.agents.controllers.base_controller import BaseController, ControllerConfig

from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.control.config import DroidControlConfig
from realm_ms.agents.control.driver import DroidArmDriver
from realm_ms.agents.urdf import ARM_JOINTS


def configure_arm_joints(joints_per_arm_joint, driver: DroidArmDriver) -> None:
    """Set the PhysX side of the driver's contract on SAPIEN joints: a zero-stiffness drive (carrying
    the driver's ``drive_damping``: zero unless ``integrator="implicit_damping"``), the armature, no
    PhysX friction (the driver applies friction in N.m) and no link damping on the joint's child link.
    ``joints_per_arm_joint[i]`` is a list of ``PhysxArticulationJoint`` for arm joint i (one per env).
    """
    damping = driver.drive_damping.cpu().numpy()
    armature = driver.armature.cpu().numpy()
    for i, objs in enumerate(joints_per_arm_joint):
        for j in objs:
            j.set_drive_properties(0.0, float(damping[i]), force_limit=1e6, mode="force")
            j.set_friction(0.0)
            j.set_armature([float(armature[i])])
            zero_link_damping(j.get_child_link())


def zero_link_damping(link) -> None:
    """PhysX's default link damping (0.05 1/s, linear and angular) is not part of a rigid-body arm: it
    drags the wrist through the whole arm's motion (0.1-0.3 mrad RMS against the MuJoCo reference)."""
    link.set_linear_damping(0.0)
    link.set_angular_damping(0.0)


@dataclass
class DroidJointImpedanceControllerConfig(ControllerConfig):
    joint_names: Sequence[str] = ARM_JOINTS
    model_factory: object = None  # () -> ArmModel; set by the agent
    control: DroidControlConfig = field(default_factory=DroidControlConfig)
    clip_to_joint_limits: bool = True
    normalize_action: bool = False
    controller_cls = None  # set below


class DroidJointImpedanceController(BaseController):
    """8 physics substeps per 15 Hz action; absolute joint targets (rad) as the action."""

    config: DroidJointImpedanceControllerConfig
    sets_target_qpos = False
    sets_target_qvel = False

    def __init__(self, config, articulation, control_freq, sim_freq=None, scene=None):
        super().__init__(config, articulation, control_freq, sim_freq, scene)
        self._dt = 1.0 / (self._sim_steps * control_freq)
        self.actuation = ActuationModel()
        control = dataclasses.replace(config.control, path_steps=self._sim_steps)  # one plan per action
        self.driver = DroidArmDriver(config.model_factory(), control, scene.num_envs, self.device, self.actuation)
        self.driver.allow_numpy = True
        self._idx = self.active_joint_indices
        self._qf_cpu = None  # reusable qf buffer (CPU backend)

    def _initialize_action_space(self):
        limits = self.articulation.get_qlimits()[0, self.active_joint_indices].cpu().numpy()
        self.single_action_space = spaces.Box(limits[:, 0], limits[:, 1], dtype=np.float32)

    def set_robot_model(self, actuation: ActuationModel) -> None:
        """Install an identified robot model's actuation stages (see ``realm_ms.sysid``)."""
        self.actuation.stages = list(actuation.stages)
        self.driver.actuation = self.actuation

    def set_drive_property(self):
        configure_arm_joints([joint._objs for joint in self.joints], self.driver)
        if not self.scene._gpu_sim_initialized:
            for link in self.articulation.links:
                link.disable_gravity = False  # the controller compensates gravity like libfranka
                for obj in link._objs:  # the gripper rides on the arm: no link damping anywhere
                    zero_link_damping(obj)

    def reset(self):
        mask = self.scene._reset_mask
        env_idx = None if bool(mask.all()) else torch.nonzero(mask)[:, 0]
        self.driver.reset(self.qpos, env_idx)

    def set_action(self, action):
        action = self._preprocess_action(action)
        if self.config.clip_to_joint_limits:
            if getattr(self, "_limits", None) is None or self._limits[0].device != action.device:
                self._limits = tuple(torch.as_tensor(v, device=action.device) for v in (self.single_action_space.low, self.single_action_space.high))
            action = torch.maximum(torch.minimum(action, self._limits[1]), self._limits[0])
        self.driver.set_target(action)

    def before_simulation_step(self):
        if self.scene.gpu_sim_enabled:
            px = self.scene.px
            px.gpu_fetch_articulation_qpos()
            px.gpu_fetch_articulation_qvel()
            tau = self.driver.torque(self.qpos, self.qvel, self._dt)
            px.cuda_articulation_qf.torch()[self.articulation._data_index[:, None], self._idx[None]] = tau
            px.gpu_apply_articulation_qf()
        else:  # physx_cpu: one articulation; numpy in/out
            obj = self.articulation._objs[0]
            if self._qf_cpu is None:
                idx = self._idx.cpu().numpy()
                contiguous = np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx)))
                self._idx_np = slice(int(idx[0]), int(idx[0]) + len(idx)) if contiguous else idx  # a view, no gather
                self._qf_cpu = np.zeros(obj.dof, dtype=np.float32)
            idx = self._idx_np
            self._qf_cpu[idx] = self.driver.torque(obj.qpos[idx][None], obj.qvel[idx][None], self._dt)[0]
            obj.qf = self._qf_cpu

    def get_state(self) -> dict:
        return {"target_qpos": self.driver.q_target}

    def set_state(self, state: dict):
        self.driver.set_target(state["target_qpos"])


DroidJointImpedanceControllerConfig.controller_cls = DroidJointImpedanceController
