"""``RealmEnv``: the one ManiSkill env class behind every REALM task; a task is a ``TaskSpec``.

Episode protocol (REALM, with its pitfalls fixed):
- 15 Hz absolute joint-position control of the DROID Panda (``droid_joint_pos``), 120 Hz physics;
- cameras ``exterior_1``, ``exterior_2``, ``wrist``: DROID's 1280x720 optics, observed at
  ``camera_width`` x ``camera_height`` (default 320x180; pass 1280x720 for native frames);
- objects are placed collision-free at their resting height from a seeded per-env RNG;
- the object reference pose is captured ``settle_steps`` control steps after reset (the analogue
  of REALM's warm-up), so stages cannot latch on placement transients; no stage is met before;
- progression = consecutive latched stages / N; ``success`` once all are met; the episode
  terminates ``success_tail`` (15) steps after success or is truncated at the horizon.
"""

from __future__ import annotations

from typing import Any

import sapien
import torch
from mani_skill.envs.sapien_env import BaseEnv
from mani_skill.sensors.camera import CameraConfig
from mani_skill.utils import sapien_utils
from mani_skill.utils.structs.pose import Pose
from mani_skill.utils.structs.types import GPUMemoryConfig, SceneConfig, SimConfig

from realm_ms.agents.droid_controller import DroidControlConfig
from realm_ms.agents.panda_droid import PandaDroid
from realm_ms.rendering import shader_config, vertical_fov
from realm_ms.tasks.placement import sample_placements
from realm_ms.tasks.progression import ProgressionTracker, StageInputs, Thresholds
from realm_ms.tasks.scenes import get_scene
from realm_ms.tasks.spec import CameraSpec, TaskSpec

class RealmEnv(BaseEnv):
    """Base of all REALM-* envs. Subclasses only set ``task_spec`` (see ``spec.register_task``)."""

    task_spec: TaskSpec
    SUPPORTED_ROBOTS = ["panda_droid"]
    SUPPORTED_REWARD_MODES = ["sparse", "none"]
    SUPPORTED_OBS_MODES = ["state", "state_dict", "none", "sensor_data", "rgb", "rgb+depth", "rgb+segmentation", "rgbd", "depth", "segmentation"]

    def __init__(
        self,
        *args,
        robot_uids: str = "panda_droid",
        scene_name: str | None = None,
        camera_width: int = 320,
        camera_height: int = 180,
        shader: str = "default",
        settle_steps: int = 5,
        success_tail: int = 15,
        robot_model: Any = None,  # MODEL.yaml path, dict or RobotModel from `realm sysid fit`
        droid_control: dict | DroidControlConfig | None = None,
        thresholds: Thresholds = Thresholds(),
        **kwargs,
    ):
        self.scene_def = get_scene(scene_name or self.task_spec.scene)
        self.camera_size = (int(camera_width), int(camera_height))
        self.shader = shader
        self.settle_steps = int(settle_steps)
        self.success_tail = int(success_tail)
        self.thresholds = thresholds
        self.instruction = self.task_spec.instruction
        self.robot_model = None
        if robot_model is not None:  # an identified model: its effects and the presets it was fitted on
            from realm_ms.sysid.robot_model import load_robot_model

            self.robot_model = load_robot_model(robot_model)
            if not isinstance(droid_control, DroidControlConfig):
                droid_control = dict(gains=self.robot_model.gains, joint_physics=self.robot_model.joint_physics) | (droid_control or {})
            if "sim_config" not in kwargs and int(self.robot_model.physics_hz) != 120:
                kwargs["sim_config"] = dict(sim_freq=int(self.robot_model.physics_hz))
        if droid_control is not None:  # e.g. dict(gains="realm", model_rate="control")
            if robot_uids != PandaDroid.uid:
                raise ValueError("droid_control configures the panda_droid agent only")
            cfg = droid_control if isinstance(droid_control, DroidControlConfig) else DroidControlConfig(**droid_control)
            robot_uids = type("PandaDroidConfigured", (PandaDroid,), {"droid_control": cfg})
        super().__init__(*args, robot_uids=robot_uids, **kwargs)

    # ------------------------------------------------------------------ configuration
    @property
    def _default_sim_config(self):
        return SimConfig(
            sim_freq=120,
            control_freq=15,
            spacing=10,
            scene_config=SceneConfig(solver_position_iterations=15, solver_velocity_iterations=1),
            gpu_memory_config=GPUMemoryConfig(max_rigid_contact_count=2**20, max_rigid_patch_count=2**18, found_lost_pairs_capacity=2**25),
        )

    def _camera_config(self, cam: CameraSpec, size: tuple[int, int], shader: str) -> CameraConfig:
        w, h = size
        pose = sapien_utils.look_at(eye=list(cam.eye), target=list(cam.target))
        return CameraConfig(
            cam.uid, pose=pose, width=w, height=h, fov=vertical_fov(cam.hfov_deg, w, h), near=0.01, far=10.0,
            shader_config=shader_config(shader),
        )

    @property
    def _default_sensor_configs(self):
        return [self._camera_config(c, self.camera_size, self.shader) for c in self.task_spec.cameras]

    @property
    def _default_human_render_camera_configs(self):
        cam = CameraSpec("render_camera", eye=(-0.25, 0.75, 0.75), target=(0.55, 0.0, 0.05), hfov_deg=80)
        return self._camera_config(cam, (640, 360), "default")

    def get_language_instruction(self) -> list[str]:
        return [self.instruction] * self.num_envs

    # ------------------------------------------------------------------ loading
    def _load_agent(self, options: dict):
        super()._load_agent(options, sapien.Pose(p=[0, 0, self.scene_def.table_top_z]))
        self.agent.wrist_camera = (*self.camera_size, self.shader)
        if self.robot_model is not None:
            self.agent.set_robot_model(self.robot_model.actuation())

    def _load_scene(self, options: dict):
        from realm_ms.tasks.objects import build_task_object

        self.scene_def.build(self)
        self.objects = {}
        for o in self.task_spec.objects:
            self.objects[o.name] = build_task_object(self, o)
        spec = self.task_spec
        self.main = self.objects[spec.main.name]
        targets = spec.by_role("target")
        self.target = self.objects[targets[0].name] if targets else None
        self.tracker = ProgressionTracker(spec.skill, self.num_envs, self.device, self.thresholds)

    def _load_lighting(self, options: dict):
        self.scene_def.load_lighting(self)

    # ------------------------------------------------------------------ episodes
    def _initialize_episode(self, env_idx: torch.Tensor, options: dict):
        with torch.device(self.device):
            b = len(env_idx)
            spec = self.task_spec
            qpos = self.agent.reset_qpos(torch.as_tensor(spec.init_qpos, dtype=torch.float32).expand(b, -1))
            self.agent.reset(qpos)
            self.agent.robot.set_pose(Pose.create_from_pq(torch.tensor([0.0, 0.0, self.scene_def.table_top_z]).expand(b, 3)))
            movable = [o for o in spec.objects if o.role != "fixture"]
            rngs = [self._batched_episode_rng[int(i)] for i in env_idx.cpu()]
            xy, yaw = sample_placements(
                rngs,
                radii=[self.objects[o.name].footprint_radius for o in movable],
                regions=[o.region or spec.spawn_region for o in movable],
                yaw_ranges=[o.yaw for o in movable],
                min_separation=spec.min_separation,
                obstacles=[(o.pose[0], o.pose[1], self.objects[o.name].footprint_radius) for o in spec.by_role("fixture")],
            )
            for k, o in enumerate(movable):
                obj = self.objects[o.name]
                p = torch.zeros(b, 3)
                p[:, :2] = torch.as_tensor(xy[:, k], dtype=torch.float32)
                p[:, 2] = self.scene_def.table_top_z + obj.rest_height
                obj.set_pose(p, torch.as_tensor(yaw[:, k], dtype=torch.float32))
            for o in spec.by_role("fixture"):
                self.objects[o.name].reset_fixture(env_idx, o, self.scene_def)
            self.tracker.reset(env_idx)
            if not hasattr(self, "_settle_left"):
                self._settle_left = torch.zeros(self.num_envs, dtype=torch.long)
                self._success_steps = torch.zeros(self.num_envs, dtype=torch.long)
                self._obj_pos0 = torch.zeros(self.num_envs, 3)
                self._obj_quat0 = torch.zeros(self.num_envs, 4)
                self._openness0 = torch.zeros(self.num_envs)
            self._settle_left[env_idx] = self.settle_steps
            self._success_steps[env_idx] = 0

    def _capture_reference(self, mask: torch.Tensor) -> None:
        """Reference pose of the main object, after settling (and after any object swap)."""
        self._obj_pos0[mask] = self.main.anchor_pos()[mask]
        self._obj_quat0[mask] = self.main.pose.q[mask]
        if self.main.is_articulated:
            self._openness0[mask] = self.main.openness()[mask]

    def _after_control_step(self):
        if not hasattr(self, "_settle_left"):
            return
        due = self._settle_left == 1
        if due.any():
            self._capture_reference(due)
        self._settle_left = (self._settle_left - 1).clamp(min=0)

    # ------------------------------------------------------------------ evaluation
    def stage_inputs(self) -> StageInputs:
        """Lazy inputs of the rubric's predicates (see ``StageInputs``)."""
        main = self.main
        x = StageInputs(
            obj_pos=main.anchor_pos,
            obj_pos0=self._obj_pos0,
            finger_pos=self.agent.finger_positions,
            touching=lambda: self.agent.is_touching(main.touch_entities()),
            grasped=(lambda: self.agent.is_grasping(main.entity)) if not main.is_articulated else (lambda: torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)),
            obj_quat=lambda: main.pose.q,
            obj_quat0=self._obj_quat0,
        )
        if self.target is not None:
            target = self.target
            x.target_pos = target.anchor_pos
            x.placed_into = lambda: target.contains(main)
            x.placed_onto = lambda: target.supports(main, self.scene)
        if main.is_articulated:
            x.openness, x.openness0 = main.openness, self._openness0
            x.toggled = main.toggled
            x.extra["opening"] = self.task_spec.skill != "close_drawer"
        return x

    def evaluate(self) -> dict:
        if not hasattr(self, "_settle_left"):
            z = torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)
            return {"success": z, "progression": z.float()}
        settled = self._settle_left == 0
        self.tracker.met[~settled] = False  # nothing counts before the reference exists
        self.tracker.update(self.stage_inputs(), active=settled)
        return {
            "success": self.tracker.success,
            "progression": self.tracker.progression,
            "settled": settled,
            **self.tracker.info(),
        }

    def step(self, action):
        obs, reward, _, truncated, info = super().step(action)
        self._success_steps = torch.where(info["success"], self._success_steps + 1, 0)
        terminated = self._success_steps > self.success_tail
        return obs, reward, terminated, truncated, info

    def stalled_stage(self) -> list[str]:
        return self.tracker.stalled_stage()

    # ------------------------------------------------------------------ observations / rewards
    def _get_obs_extra(self, info: dict):
        out = dict(tcp_pose=self.agent.tcp_pose.raw_pose)
        if "state" in self.obs_mode:
            out.update(obj_pose=self.main.pose.raw_pose, obj_pos0=self._obj_pos0)
            if self.target is not None:
                out["target_pose"] = self.target.pose.raw_pose
            if self.main.is_articulated:  # drawer openness fraction / switch state
                out["openness"] = self.main.openness()[:, None]
                out["toggled"] = self.main.toggled()[:, None].float()
        return out

    def compute_sparse_reward(self, obs, action, info):
        return info["progression"]
