"""GPU replay: one arm per PhysX sub-scene on ``physx_cuda``, the same driver batched on CUDA.

Torque-path parameters are batched per env (one CMA-ES candidate x segment per env, no rebuild).
Build-time parameters (armature, payload) are set on each sub-scene's articulation *before*
``gpu_init``; PhysX GPU articulations cannot change them afterwards, so a rollout whose build-time
values differ from the current scene's rebuilds the GPU system (seconds; the population of a
generation shares one rebuild). Same URDF, joint contract and driver as the CPU simulator
(``simulator.py``); ``tests/sysid/test_gpu.py`` checks both agree where CUDA exists.
"""

from __future__ import annotations

import time

import numpy as np
import torch

from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.effects import Effect
from realm_ms.agents.effects.build_target import BuildTarget
from realm_ms.sysid.simulator import SimConfig, StepProfile


class GpuReplaySimulator:
    def __init__(self, config: SimConfig | None = None, device: str = "cuda"):
        from realm_ms.agents.arm_model import ArmModel
        from realm_ms.sysid.locked_urdf import (BASE_LINK, TIP_LINK, flange_offset_in_link7, locked_arm_urdf_path,
                                                source_urdf_path)

        if not torch.cuda.is_available():
            raise RuntimeError("GpuReplaySimulator needs CUDA; use the CPU ReplaySimulator")
        self.config = config or SimConfig()
        self.device = torch.device(device)
        self.dt = 1.0 / self.config.physics_hz
        src, self.robot_name = source_urdf_path()
        self.urdf = locked_arm_urdf_path(src)
        self._flange_offset = flange_offset_in_link7(src)  # the flange is lumped into link 7
        self.model = ArmModel.from_urdf(src, BASE_LINK, TIP_LINK)
        self.px = None
        self.arts: list = []
        self._capacity = 0
        self._build_key = None
        self.profile = StepProfile()

    def _driver(self, num_envs: int, actuation: ActuationModel):
        from realm_ms.agents.control import DroidArmDriver

        return DroidArmDriver(self.model, self.config.control_config(), num_envs, self.device, actuation)

    def _build(self, n: int, build_effects: list[Effect]) -> None:
        """(Re)create the GPU system with ``n`` sub-scenes and the build-time values applied."""
        import sapien
        from sapien import physx

        from realm_ms.agents.control.maniskill import configure_arm_joints

        self.px = None
        self.arts = []
        px = physx.PhysxGpuSystem(device=str(self.device))
        px.set_timestep(self.dt)
        side = int(np.ceil(np.sqrt(n)))
        driver = self._driver(1, ActuationModel())
        self._scenes = []
        for i in range(n):
            scene = sapien.Scene([px])
            px.set_scene_offset(scene, [3.0 * (i % side), 3.0 * (i // side), 0.0])
            loader = scene.create_urdf_loader()
            loader.fix_root_link = True
            art = loader.load(str(self.urdf))
            configure_arm_joints([[j] for j in art.get_active_joints()], driver)
            for link in art.get_links():
                link.set_disable_gravity(False)
            target = BuildTarget(art, list(range(7)), self._flange_offset)
            for fx in build_effects:
                fx.build_target(target, min(i, fx.theta.shape[0] - 1))
            self.arts.append(art)
            self._scenes.append(scene)
        px.gpu_init()
        self.px = px
        self._index = torch.as_tensor([a.get_gpu_index() for a in self.arts], device=self.device, dtype=torch.long)
        self._capacity = n

    def rollout(self, q0: np.ndarray, qd0: np.ndarray, cmd: np.ndarray, effects: list[Effect]) -> np.ndarray:
        e_count, steps = cmd.shape[0], cmd.shape[1]
        t0 = time.perf_counter()
        build = [fx for fx in effects if fx.build_time]
        key = (e_count, tuple((fx.name, fx.theta.cpu().numpy().tobytes()) for fx in build))
        if self.px is None or key != self._build_key or self._capacity != e_count:
            self._build(e_count, build)
            self._build_key = key
        px, idx, dev = self.px, self._index, self.device
        qpos = px.cuda_articulation_qpos.torch()
        qvel = px.cuda_articulation_qvel.torch()
        qf = px.cuda_articulation_qf.torch()
        qpos[idx, :7] = torch.as_tensor(q0, device=dev, dtype=torch.float32)
        qvel[idx, :7] = torch.as_tensor(qd0, device=dev, dtype=torch.float32)
        qf[idx, :7] = 0
        px.gpu_apply_articulation_qpos()
        px.gpu_apply_articulation_qvel()
        px.gpu_apply_articulation_qf()
        px.gpu_update_articulation_kinematics()
        actuation = ActuationModel(sorted(effects, key=lambda fx: fx.order))
        driver = self._driver(e_count, actuation)
        driver.reset(torch.as_tensor(q0, device=dev, dtype=torch.float32))
        cmd_t = torch.as_tensor(cmd, device=dev, dtype=torch.float32)
        out = torch.empty((e_count, steps + 1, 7), device=dev, dtype=torch.float32)
        out[:, 0] = torch.as_tensor(q0, device=dev, dtype=torch.float32)
        self.profile.build_s += time.perf_counter() - t0
        t1 = time.perf_counter()
        with torch.inference_mode():
            for k in range(steps):
                px.gpu_fetch_articulation_qpos()
                px.gpu_fetch_articulation_qvel()
                q, qd = qpos[idx, :7], qvel[idx, :7]
                out[:, k] = q
                driver.set_target(cmd_t[:, k])
                qf[idx, :7] = driver.torque(q, qd, self.dt)
                px.gpu_apply_articulation_qf()
                px.step()
            px.gpu_fetch_articulation_qpos()
            out[:, steps] = qpos[idx, :7]
        torch.cuda.synchronize(dev)
        self.profile.torch_s += time.perf_counter() - t1
        self.profile.arm_steps += e_count * steps
        res = out.double().cpu().numpy()
        bad = ~np.isfinite(res).all(axis=(1, 2))
        res[bad] = np.nan
        return res
