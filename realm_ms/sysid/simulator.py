"""The replay simulator: many copies of the benchmark arm in one PhysX CPU scene, one batched driver.

Same URDF (gripper locked, geometry dropped: ``urdf.py``), same joint setup (drive stiffness 0,
drive damping = ``driver.drive_damping``, joint friction/armature preset), same
``DroidArmDriver`` (Polymetis law + actuation stages) and the same physics rate (120 Hz = 8
substeps per 15 Hz step) as the benchmark, so an identified model is the model the benchmark runs.

Every env is one (segment, candidate) pair: multiple-shooting segments start from the measured
state, the commanded targets are held piecewise constant from ``t[i]`` to ``t[i+1]`` at physics
resolution, and the simulated positions are sampled at the data timestamps (linear interpolation
between physics steps, so any logging rate works). Arms not needed by a call are put to sleep
(PhysX skips them), so the pool only grows.

Where time goes (2-core CPU, one process): a nominal rollout of 300 arms spends ~45 % in the PhysX
step, ~10 % in per-articulation get/set and ~45 % in torch (the driver's plan and exact step); a
diagnosis's screening batches ~90 % in torch, mostly the friction laws evaluated at every 1 kHz tick
inside the step, each on the few rows where it is active: their cost is per-op overhead, not
arithmetic. ``StepProfile`` keeps the split.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
import torch

from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.effects import Effect
from realm_ms.agents.effects.build_target import BuildTarget


@dataclass
class SimConfig:
    physics_hz: float = 120.0
    gains: str = "polymetis"
    joint_physics: str = "none"
    coriolis_feedforward: bool = True
    model_rate: str | None = None  # DroidControlConfig.model_rate; None = the benchmark's default
    integrator: str | None = None  # DroidControlConfig.integrator; None = the benchmark's default

    def control_config(self):
        from realm_ms.agents.control import DroidControlConfig

        kw = {k: v for k, v in (("model_rate", self.model_rate), ("integrator", self.integrator)) if v is not None}
        return DroidControlConfig(gains=self.gains, coriolis_feedforward=self.coriolis_feedforward,
                                  joint_physics=self.joint_physics, **kw)

    @classmethod
    def from_model(cls, model) -> "SimConfig":
        return cls(physics_hz=model.physics_hz, gains=model.gains, joint_physics=model.joint_physics)


@dataclass
class StepProfile:
    physx_s: float = 0.0
    io_s: float = 0.0
    torch_s: float = 0.0
    build_s: float = 0.0
    arm_steps: int = 0

    def summary(self) -> str:
        tot = self.physx_s + self.io_s + self.torch_s + self.build_s
        us = 1e6 * tot / max(self.arm_steps, 1)
        return (f"{tot:.2f} s for {self.arm_steps} arm-steps ({us:.1f} µs each): PhysX {self.physx_s:.2f} s, "
                f"get/set {self.io_s:.2f} s, torch {self.torch_s:.2f} s, build {self.build_s:.2f} s")


class ReplaySimulator:
    """CPU PhysX backend. ``rollout`` simulates E arms for S physics steps."""

    def __init__(self, config: SimConfig | None = None):
        import sapien
        from sapien import physx

        from realm_ms.agents.arm_model import ArmModel
        from realm_ms.sysid.locked_urdf import (BASE_LINK, TIP_LINK, flange_offset_in_link7, locked_arm_urdf_path,
                                                source_urdf_path)

        self.config = config or SimConfig()
        self.dt = 1.0 / self.config.physics_hz
        src, self.robot_name = source_urdf_path()
        self.urdf = locked_arm_urdf_path(src)
        self._flange_offset = flange_offset_in_link7(src)  # the flange is lumped into link 7
        self.model = ArmModel.from_urdf(src, BASE_LINK, TIP_LINK)  # the controller's model: benchmark URDF
        self.scene = sapien.Scene([physx.PhysxCpuSystem()])
        self.scene.set_timestep(self.dt)
        self._loader = self.scene.create_urdf_loader()
        self._loader.fix_root_link = True
        self.arms: list = []
        self._targets: list[BuildTarget] = []
        self._dirty: set[int] = set()
        self.profile = StepProfile()
        self.show_progress = False  # tqdm over physics steps for large rollouts (CLI sets it)
        torch.set_num_threads(1)

    # ------------------------------------------------------------------ arm pool
    def _driver(self, num_envs: int, actuation: ActuationModel):
        from realm_ms.agents.control import DroidArmDriver

        return DroidArmDriver(self.model, self.config.control_config(), num_envs, "cpu", actuation)

    def _ensure(self, n: int) -> None:
        from realm_ms.agents.control.maniskill import configure_arm_joints

        if len(self.arms) >= n:
            return
        driver = self._driver(1, ActuationModel())
        while len(self.arms) < n:
            art = self._loader.load(str(self.urdf))
            art.set_sleep_threshold(0.0)
            # the benchmark's joint contract (DroidJointImpedanceController.set_drive_property)
            configure_arm_joints([[j] for j in art.get_active_joints()], driver)
            for link in art.get_links():
                link.set_disable_gravity(False)
            self.arms.append(art)
            self._targets.append(BuildTarget(art, list(range(7)), self._flange_offset))

    # ------------------------------------------------------------------ rollout
    def rollout(self, q0: np.ndarray, qd0: np.ndarray, cmd: np.ndarray | Callable[[int, np.ndarray], np.ndarray],
                effects: list[Effect], record_every: int = 1, steps: int | None = None) -> np.ndarray:
        """Simulate E arms from (q0, qd0) tracking ``cmd`` (E, S, 7) (one target per physics step).

        ``cmd`` may instead be a function ``cmd(k, q) -> (E, 7)`` of the physics step k and the arms'
        joint positions q (E, 7) before it, with ``steps`` = S: a closed-loop command (a DROID
        action turned into a joint target from the simulated state, as the robot did from its
        measured one). ``effects``: stages with theta of shape (E, n) or (1, n). Returns joint
        positions (E, S + 1, 7) after 0..S steps (float64).
        """
        closed_loop = callable(cmd)
        if closed_loop and steps is None:
            raise ValueError("a closed-loop command needs steps=")
        e_count, steps = (q0.shape[0], steps) if closed_loop else (cmd.shape[0], cmd.shape[1])
        self._ensure(e_count)
        arms = self.arms[:e_count]
        t0 = time.perf_counter()
        build = [fx for fx in effects if fx.build_time]
        for i in sorted(self._dirty | (set(range(e_count)) if build else set())):
            if i < len(self._targets):
                self._targets[i].reset()
        self._dirty = set(range(e_count)) if build else set()
        for fx in build:
            for i in range(e_count):
                fx.build_target(self._targets[i], min(i, fx.theta.shape[0] - 1))
        for i, art in enumerate(self.arms):
            if i < e_count:
                art.set_qpos(q0[i].astype(np.float32))
                art.set_qvel(qd0[i].astype(np.float32))
                art.set_qf(np.zeros(7, np.float32))
            else:
                art.get_links()[0].put_to_sleep()
        actuation = ActuationModel(sorted(effects, key=lambda fx: fx.order))
        driver = self._driver(e_count, actuation)
        driver.reset(torch.as_tensor(q0, dtype=torch.float32))
        cmd_t = None if closed_loop else torch.as_tensor(cmd, dtype=torch.float32)
        out = np.empty((e_count, steps + 1, 7), dtype=np.float64)
        out[:, 0] = q0
        prof = self.profile
        prof.build_s += time.perf_counter() - t0
        qbuf = q0.astype(np.float32).copy()
        vbuf = qd0.astype(np.float32).copy()
        bar = None
        if self.show_progress and e_count * steps > 150_000:
            from tqdm.auto import tqdm

            bar = tqdm(total=steps, desc=f"simulating {e_count} arms", unit="step", leave=False)
        with torch.inference_mode():
            for k in range(steps):
                if bar is not None and k % 40 == 0:
                    bar.update(min(40, steps - k))
                b = time.perf_counter()
                target = torch.as_tensor(cmd(k, qbuf), dtype=torch.float32) if closed_loop else cmd_t[:, k]
                driver.set_target(target)
                tau = driver.torque(torch.from_numpy(qbuf), torch.from_numpy(vbuf), self.dt).numpy()
                c = time.perf_counter()
                for i, art in enumerate(arms):
                    art.set_qf(tau[i])
                d = time.perf_counter()
                self.scene.step()
                e = time.perf_counter()
                for i, art in enumerate(arms):
                    qbuf[i] = art.get_qpos()
                    vbuf[i] = art.get_qvel()
                out[:, k + 1] = qbuf
                prof.io_s += (d - c) + (time.perf_counter() - e)
                prof.torch_s += c - b
                prof.physx_s += e - d
        if bar is not None:
            bar.close()
        prof.arm_steps += e_count * steps
        if not np.all(np.isfinite(out)):
            bad = np.where(~np.isfinite(out).all(axis=(1, 2)))[0]
            out[bad] = np.nan  # caller turns a diverged env into an infinite loss
        return out
