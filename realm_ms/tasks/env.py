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

import dataclasses
import sys
import warnings

import numpy as np
import sapien
import torch
from mani_skill.envs.sapien_env import BaseEnv
from mani_skill.sensors.camera import Camera, CameraConfig
from mani_skill.utils import sapien_utils
from mani_skill.utils.structs.pose import Pose
from mani_skill.utils.structs.types import GPUMemoryConfig, SceneConfig, SimConfig

from realm_ms.agents.control import DroidControlConfig
from realm_ms.agents.panda_droid import PandaDroid
from realm_ms.known_warnings import install as _silence_known_warnings
from realm_ms.rendering import camera_shader_config, is_ray_traced, keep_renderer, vertical_fov
from realm_ms.tasks.perturbation_set import PerturbationSet
from realm_ms.tasks.placement import sample_placements
from realm_ms.tasks.progression import ProgressionTracker, StageInputs
from realm_ms.tasks.scenes import get_scene
from realm_ms.tasks.config import RealmEnvConfig, _control_fields
from realm_ms.tasks.task_spec import TASKS, CameraSpec, TaskSpec

_silence_known_warnings()


class RealmEnv(BaseEnv):
    """Base of all REALM-* envs. Subclasses only set ``task_spec`` (see ``register_task`` below)."""

    task_spec: TaskSpec
    SUPPORTED_ROBOTS = ["panda_droid"]
    SUPPORTED_REWARD_MODES = ["sparse", "none"]
    SUPPORTED_OBS_MODES = ["state", "state_dict", "none", "sensor_data", "rgb", "rgb+depth", "rgb+segmentation", "rgbd", "depth", "segmentation"]

    def __init__(self, *args, config: RealmEnvConfig | None = None, robot_uids: str = "panda_droid", **kwargs):
        """``config`` or its fields as keywords (``camera_width=``, ``shader=``, ``droid_control=``,
        ``robot_model=``, ``perturbation=``, ... see ``RealmEnvConfig``); other keywords go to ManiSkill."""
        config, kwargs = RealmEnvConfig.from_kwargs(config, kwargs)
        from realm_ms.agents.droid_action_spaces import check_control_mode

        # before the scene is built: DROID's spaces convert to droid_joint_pos targets only
        check_control_mode(config.action_space, config.gripper_action_space, kwargs.get("control_mode"))
        self.robot_model = None
        if config.robot_model is not None:  # an identified model: its effects and the presets it was fitted on
            from realm_ms.agents.robot_model import load_robot_model

            self.robot_model = load_robot_model(config.robot_model)
            if "sim_config" not in kwargs and int(self.robot_model.physics_hz) != 120:
                kwargs["sim_config"] = dict(sim_freq=int(self.robot_model.physics_hz))
        control = config.control
        if control is None or isinstance(control, dict):  # a model's presets, under the keywords given
            base = dict(gains=self.robot_model.gains, joint_physics=self.robot_model.joint_physics) if self.robot_model else {}
            control = DroidControlConfig(**_control_fields(base | (control or {})))
        if config.control is not None and robot_uids != PandaDroid.uid:
            raise ValueError("droid_control configures the panda_droid agent only")
        self.config = config = dataclasses.replace(config, control=control)
        self.scene_def = get_scene(config.scene or self.task_spec.scene)
        self.cameras = config.cameras
        self.settle_steps = config.settle_steps
        self.success_tail = config.success_tail
        self.thresholds = config.thresholds
        self.instruction = self.task_spec.instruction
        # --- perturbations: resolved here, drawn every reset (hooks below; logic in realm_ms.perturbations)
        self.perturbation_spec = config.perturbation
        self.perturbations = PerturbationSet.resolve(config.perturbation)
        self.active_spec = self.task_spec  # the task as perturbed in sub-env 0 (instruction, skill, objects)
        self._pert_fresh = False
        # ---
        self._action_warned: set[str] = set()
        self.droid_actions = None  # converter of a non-default DROID action space (_install_action_space)
        self._contacts_dirty = False  # simulated since the last (re)build: see _forget_contacts
        # Cameras capture on every step unless a caller that reads images only now and then (a policy
        # executing an action chunk open-loop) turns this off for the steps in between: those steps
        # then return the last captured images. Rendering dominates a step with cameras.
        self.capture_sensors = True
        self._last_sensor_data: dict | None = None
        # ManiSkill asks for a CUDA renderer by default and warns on every env where there is none
        # (rendering works on the CPU through Vulkan, lavapipe included): ask for what is there
        kwargs.setdefault("render_backend", "gpu" if torch.cuda.is_available() else "cpu")
        super().__init__(*args, robot_uids=robot_uids, **kwargs)
        keep_renderer(self._render_device)  # the next env in this process reuses the renderer
        # the full description, ManiSkill's part included: records store it, make_env re-creates the env
        self.config = dataclasses.replace(
            config, task=self.task_spec.env_id, obs_mode=self.obs_mode, control_mode=self.control_mode,
            num_envs=self.num_envs, sim_backend=self.backend.sim_backend, render_mode=self.render_mode,
        )
        self._install_action_space()

    # ------------------------------------------------------------------ configuration
    @property
    def _default_sim_config(self):
        return SimConfig(
            sim_freq=120,
            control_freq=15,
            spacing=10,
            # sleep_threshold 0: PhysX's sleep state survives a teleport and a wake-up, so a body that
            # slept in one episode settles differently in the next; nothing ever sleeps instead
            scene_config=SceneConfig(solver_position_iterations=15, solver_velocity_iterations=1, sleep_threshold=0.0),
            gpu_memory_config=GPUMemoryConfig(max_rigid_contact_count=2**20, max_rigid_patch_count=2**18, found_lost_pairs_capacity=2**25),
        )

    def _camera_config(self, cam: CameraSpec, size: tuple[int, int], shader: str) -> CameraConfig:
        w, h = size
        pose = sapien_utils.look_at(eye=list(cam.eye), target=list(cam.target))
        if cam.uid != "render_camera":  # perturbation hook (V-VIEW): batched per sub-env extrinsics
            pose = self.perturbations.camera_pose(cam.uid, pose)
        return CameraConfig(
            cam.uid, pose=pose, width=w, height=h, fov=vertical_fov(cam.hfov_deg, w, h), near=0.01, far=10.0,
            shader_config=camera_shader_config(shader, self.cameras.denoiser),
        )

    @property
    def _default_sensor_configs(self):
        size = (self.cameras.width, self.cameras.height)
        return [self._camera_config(c, size, self.cameras.shader) for c in self.task_spec.cameras]

    @property
    def _default_human_render_camera_configs(self):
        cam = CameraSpec("render_camera", eye=(-0.25, 0.75, 0.75), target=(0.55, 0.0, 0.05), hfov_deg=80)
        return self._camera_config(cam, (640, 360), "default")

    def get_language_instruction(self) -> list[str]:
        specs = self.perturbations.specs  # perturbation hook: per sub-env instruction
        return [s.instruction for s in specs] if len(specs) == self.num_envs else [self.instruction] * self.num_envs

    # ------------------------------------------------------------------ loading
    def _load_agent(self, options: dict):
        pose = sapien.Pose(p=[0, 0, self.scene_def.robot_base_z])
        if self.robot_uids != PandaDroid.uid:
            return super()._load_agent(options, pose)
        # built here (not by uid) so this env's control settings and cameras reach the agent
        self.agent = PandaDroid(self.scene, self._control_freq, self._control_mode, initial_pose=pose,
                                droid_control=self.config.control, camera=self.cameras)
        if self.robot_model is not None:
            self.agent.set_robot_model(self.robot_model)

    def _load_scene(self, options: dict):
        from realm_ms.tasks.objects import build_task_object

        self._contacts_dirty = False  # a new PhysX scene has no contact history
        self.scene_def.build(self)
        # --- perturbation hook: draw for every sub-env, then build each sub-env's perturbed task
        self.perturbations.draw(self, range(self.num_envs))
        self._pert_fresh = True
        specs = self.perturbations.specs
        self.active_spec = spec = specs[0]
        self.instruction = spec.instruction
        # ---
        self.objects = {}
        for o in spec.objects:
            self.objects[o.name] = build_task_object(self, o, variants=[next(x for x in s.objects if x.name == o.name) for s in specs])
        self.main = self.objects[spec.main.name]
        targets = spec.by_role("target")
        self.target = self.objects[targets[0].name] if targets else None
        self.tracker = ProgressionTracker(spec.skill, self.num_envs, self.device, self.thresholds)

    def _load_lighting(self, options: dict):
        self.scene_def.load_lighting(self)
        # nominal light colours per sub-scene: perturbations (V-LIGHT) scale from these, never compound
        self.lights = [
            [(c, tuple(float(v) for v in c.color)) for e in s.entities for c in e.components if isinstance(c, sapien.render.RenderLightComponent)]
            for s in self.scene.sub_scenes
        ]

    # ------------------------------------------------------------------ episodes
    def _initialize_episode(self, env_idx: torch.Tensor, options: dict):
        with torch.device(self.device):
            b = len(env_idx)
            # --- perturbation hook: a reset without reconfiguration redraws the episode-level factors
            if not self._pert_fresh:
                self.perturbations.draw(self, env_idx, scene_changing_only=True)
            self._pert_fresh = False
            self.active_spec = spec = self.perturbations.specs[0]
            self.instruction = spec.instruction
            # ---
            self._forget_contacts(env_idx)
            qpos = self.agent.reset_qpos(torch.as_tensor(spec.init_qpos, dtype=torch.float32).expand(b, -1))
            self.agent.reset(qpos)
            self.agent.robot.set_pose(Pose.create_from_pq(torch.tensor([0.0, 0.0, self.scene_def.robot_base_z]).expand(b, 3)))
            movable = [o for o in spec.objects if o.role != "fixture"]
            rngs = [self._batched_episode_rng[int(i)] for i in env_idx.cpu()]
            xy, yaw = sample_placements(
                rngs,
                radii=[self.objects[o.name].footprint_radius for o in movable],
                regions=[o.region or spec.spawn_region for o in movable],
                yaw_ranges=[o.yaw for o in movable],
                min_separation=spec.min_separation,
                obstacles=[(o.pose[0], o.pose[1], self.objects[o.name].footprint_radius) for o in spec.by_role("fixture")],
                # articulated mains place by their body, their handle's reach is set by their region
                reach=[spec.reach if o.role in ("main", "target") and not self.objects[o.name].is_articulated else None for o in movable],
            )
            for k, o in enumerate(movable):
                obj = self.objects[o.name]
                p = torch.zeros(b, 3)
                p[:, :2] = torch.as_tensor(xy[:, k], dtype=torch.float32)
                p[:, 2] = self.scene_def.table_top_z + obj.rest_height
                obj.set_pose(p, torch.as_tensor(yaw[:, k], dtype=torch.float32))
            for o in spec.by_role("fixture"):
                self.objects[o.name].reset_fixture(env_idx, o, self.scene_def)
            self.scene_def.on_episode_init(self, env_idx)  # scene hook: per-episode materials
            self.perturbations.on_episode_init(self, env_idx)  # perturbation hook: masses, poses, lights
            self.tracker.reset(env_idx)
            if not hasattr(self, "_settle_left"):
                self._settle_left = torch.zeros(self.num_envs, dtype=torch.long)
                self._success_steps = torch.zeros(self.num_envs, dtype=torch.long)
                self._obj_pos0 = torch.zeros(self.num_envs, 3)
                self._obj_quat0 = torch.zeros(self.num_envs, 4)
                self._openness0 = torch.zeros(self.num_envs)
            self._settle_left[env_idx] = self.settle_steps
            self._success_steps[env_idx] = 0
            # until the settled reference exists, observe the placed pose, never the last episode's
            placed = torch.zeros(self.num_envs, dtype=torch.bool)
            placed[env_idx] = True
            self._capture_reference(placed)

    def _forget_contacts(self, env_idx: torch.Tensor) -> None:
        """Drop PhysX's contact pairs before a new episode is placed.

        PhysX keeps a pair's cached contact/friction patches while its shapes stay close, so an
        object teleported onto the table where such a pair survived settles differently from the
        same object in a fresh env (seen: 1e-2 rad of arm drift and success one step later after a
        grasp episode). Moving every body apart and stepping once ends every pair. It narrows, but
        does not close, the gap (pair order still differs), so the default rebuilds the scene
        instead (``RealmEnvConfig.isolate_episodes``) and this runs only for teleporting resets.
        CPU sim, whole-batch resets (a GPU step would advance the other sub-envs of a partial
        reset); skipped when nothing has been simulated since the scene was built.
        """
        if not self._contacts_dirty or self.gpu_sim_enabled or len(env_idx) != self.num_envs:
            return
        b, far = len(env_idx), 100.0
        for k, obj in enumerate(self.objects.values()):  # 3 m apart: no two bodies can touch
            obj.set_pose(torch.tensor([far + 3.0 * k, far, far]).expand(b, 3), torch.zeros(b))
        self.agent.robot.set_pose(Pose.create_from_pq(torch.tensor([-far, -far, far]).expand(b, 3)))
        self.scene.px.step()
        self._contacts_dirty = False

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
            x.placed_into = lambda: target.holds(main, self.scene)
            x.placed_onto = lambda: target.supports(main, self.scene)
        if main.is_articulated:
            x.openness, x.openness0 = main.openness, self._openness0
            x.toggled = main.toggled
            x.extra["opening"] = self.active_spec.skill != "close_drawer"
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

    # ------------------------------------------------------------------ perturbation hooks
    def reset(self, seed=None, options=None):
        """``options``: ``perturbation`` switches the perturbation from this reset on,
        ``perturbation_params`` replays a recorded ``info["perturbation"]["params"]``."""
        options = dict(options or {})
        if "perturbation" in options:
            self.perturbation_spec = options["perturbation"]
            self.perturbations = PerturbationSet.resolve(options["perturbation"])
            options["reconfigure"] = True  # back to (or away from) the pristine scene
        self.perturbations.override = options.get("perturbation_params")
        if self.perturbations.needs_reconfigure:
            options["reconfigure"] = True  # scene-changing draws rebuild the scene every reset
        if self.config.isolate_episodes and self._contacts_dirty and not self.gpu_sim_enabled and "env_idx" not in options:
            options["reconfigure"] = True  # a new PhysX scene: see RealmEnvConfig.isolate_episodes
        self._pert_fresh = False
        self._last_sensor_data = None  # a reset always captures
        obs, info = super().reset(seed=seed, options=options)
        self.perturbations.override = None
        info["perturbation"] = self.perturbations.record()
        return obs, info

    def capture_sensor_data(self):
        """ManiSkill submits every camera's frame, then waits for them all. On a software Vulkan device
        (lavapipe, Mesa 25.0) several ray-traced frames in flight at once crash its queue thread
        (SIGSEGV in about one capture in two) or corrupt the first frame: there each ray-traced frame
        is finished before the next is submitted. (The second read of the picture in ``get_obs`` is a
        host copy; raster frames do not race and keep ManiSkill's overlap.)"""
        if self.backend.render_device is None or self.backend.render_device.is_cuda():
            return super().capture_sensor_data()
        for sensor in self._sensors.values():
            sensor.capture()
            if isinstance(sensor, Camera) and is_ray_traced(sensor.config.shader_config.shader_pack):
                for cam in sensor.camera._render_cameras:
                    cam.get_picture(cam.get_picture_names()[0])

    def _get_obs_sensor_data(self, apply_texture_transforms: bool = True) -> dict:
        if not self.capture_sensors and self._last_sensor_data is not None:
            return self._last_sensor_data
        data = self.perturbations.on_observation(self, super()._get_obs_sensor_data(apply_texture_transforms))
        self._last_sensor_data = data
        return data

    def step(self, action):
        obs, reward, _, truncated, info = super().step(self._checked_action(action))
        self._contacts_dirty = True
        self._success_steps = torch.where(info["success"], self._success_steps + 1, 0)
        terminated = self._success_steps > self.success_tail
        return obs, reward, terminated, truncated, info

    def _checked_action(self, action):
        """Validate an action before ManiSkill sees it.

        Rejected (``ValueError``): a shape other than (action_dim,) or (num_envs, action_dim), NaN or
        Inf, anything not numeric (a finite value beyond float32, 1e39, is a value outside the space). Clipped to the action space with one warning per env and kind:
        joint targets beyond the joint limits, a gripper command outside [0, 1] (the robot cannot do
        more; a policy's small overshoot is normal).
        """
        if action is None or isinstance(action, dict):
            return action
        space = self.single_action_space
        try:
            with np.errstate(over="ignore"):  # a finite value beyond float32 becomes inf: handled below
                a = torch.as_tensor(np.asarray(action, dtype=np.float32) if not isinstance(action, torch.Tensor) else action,
                                    dtype=torch.float32, device=self.device)
        except (TypeError, ValueError) as e:
            raise ValueError(f"action must be numeric with shape {space.shape} or ({self.num_envs}, {space.shape[0]}): {e}") from None
        if a.shape not in (tuple(space.shape), (self.num_envs, *space.shape)):
            raise ValueError(f"action has shape {tuple(a.shape)}; expected {tuple(space.shape)} or "
                             f"({self.num_envs}, {space.shape[0]}) for control mode {self.control_mode!r}")
        if not torch.isfinite(a).all():
            raw = action.detach().cpu().double() if isinstance(action, torch.Tensor) else torch.as_tensor(np.asarray(action, dtype=np.float64))
            if not torch.isfinite(raw).all():
                raise ValueError(f"action contains NaN or Inf: {raw.tolist()}")
            # finite but beyond float32 (1e39): as far outside the space as any huge target, handled below
            big = float(np.finfo(np.float32).max)
            a = raw.clamp(-big, big).to(dtype=torch.float32, device=a.device)
        if self.droid_actions is not None:  # DROID's rescaling/IK replaces the per-dim clip below
            return self.droid_actions(self.agent, a)
        lo = torch.as_tensor(space.low, device=a.device)
        hi = torch.as_tensor(space.high, device=a.device)
        outside = (a < lo) | (a > hi)
        if outside.any():
            dims = sorted(set(torch.nonzero(outside)[:, -1].tolist()))
            key = ",".join(map(str, dims))
            if key not in self._action_warned:
                self._action_warned.add(key)
                warnings.warn(f"action dims {dims} outside the action space [{space.low[dims]}, {space.high[dims]}] "
                              f"(joint limits in rad; gripper in [0, 1]) are clipped; this warning is shown once",
                              RuntimeWarning, stacklevel=3)
            a = torch.maximum(torch.minimum(a, hi), lo)
        return a

    def _install_action_space(self) -> None:
        """A DROID action space other than joint_position: its gym space, and the converter
        ``_checked_action`` applies (``realm_ms.agents.droid_action_spaces``)."""
        from realm_ms.agents.droid_action_spaces import EnvActionConverter, make_action_space

        self.droid_action_space = space = make_action_space(self.config.action_space, self.config.gripper_action_space)
        self.droid_actions = None
        if space.action_space == "joint_position" and space.gripper == "position":
            return  # droid_joint_pos itself: ManiSkill's space, untouched
        from gymnasium.vector.utils import batch_space

        self.droid_actions = EnvActionConverter(space)
        self.single_action_space = space.gym_space()
        self.action_space = batch_space(self.single_action_space, self.num_envs) if self.num_envs > 1 else self.single_action_space

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


def register_task(spec: TaskSpec, base: type[RealmEnv] = RealmEnv) -> type[RealmEnv]:
    """Make ``spec``'s env class (a ``RealmEnv`` with ManiSkill's three-part docstring), register it
    with ManiSkill/gymnasium under ``spec.env_id`` with the task's horizon, and return it. Call it
    from the task's own module: the class reports that module."""
    from mani_skill.utils.registration import register_env

    from realm_ms.tasks.progression import RUBRICS

    TASKS.register(spec.env_id, spec)
    name = spec.env_id.replace("REALM-", "").replace("-v1", "").replace("-", "") + "Env"
    doc = (
        f"**Task Description:** {spec.description or spec.instruction}. Instruction: \"{spec.instruction}\".\n\n"
        f"**Randomizations:** {', '.join(o.name for o in spec.objects if o.role != 'fixture')} placed collision-free "
        f"in x {spec.spawn_region[:2]}, y {spec.spawn_region[2:]} m (robot base frame) with random yaw; "
        f"seeded per episode.\n\n"
        f"**Success Conditions:** REALM '{spec.skill}' rubric, all stages latched: "
        f"{' -> '.join(s.value for s in RUBRICS.get(spec.skill))}."
    )
    module = sys._getframe(1).f_globals.get("__name__", base.__module__)
    cls = type(name, (base,), {"task_spec": spec, "__doc__": doc, "__module__": module})
    _drop_placeholder(spec)
    register_env(spec.env_id, max_episode_steps=spec.horizon)(cls)
    return cls


def _drop_placeholder(spec: TaskSpec) -> None:
    """``import realm_ms`` registered ``spec.env_id`` as a placeholder that loads the task pack on
    first make (``realm_ms.registration``): drop it so ManiSkill registers the id without an
    "Overriding environment" warning. The placeholder's horizon must be the task's, or the first env
    of a process would be cut at another step."""
    import gymnasium as gym

    placeholder = gym.registry.get(spec.env_id)
    if placeholder is None or not getattr(placeholder.entry_point, "realm_placeholder", False):
        return
    if placeholder.max_episode_steps != spec.horizon:
        raise ValueError(f"{spec.env_id}: horizon {spec.horizon} differs from its placeholder's "
                         f"({placeholder.max_episode_steps}, realm_ms.task_index.HORIZON): keep them equal")
    del gym.registry[spec.env_id]
