"""``DroidArmDriver``: the Polymetis law + actuation stages for B arms; knows nothing about the simulator.

It holds the law's state (target, velocity correction, last torques) and delegates the step to the
configured integrator (``integrators.py``) with its model-rate strategy (``rates.py``), on batched
torch; the nominal exact law on CPU for a few envs runs folded in numpy (``folded.py``). The
ManiSkill binding (``maniskill.py``) and the sysid replay simulator bind the same driver to their
articulations, so an identified model is the model the benchmark runs.
"""

from __future__ import annotations

import numpy as np
import torch

from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.arm_model import ArmModel
from realm_ms.agents.control.backend import TorchBackend
from realm_ms.agents.control.config import DroidControlConfig
from realm_ms.agents.control.folded import FoldedExact
from realm_ms.agents.control.integrators import INTEGRATORS
from realm_ms.agents.control.presets import GAIN_PRESETS, JOINT_PHYSICS_PRESETS, BatchedGains, resolve
from realm_ms.agents.control.rates import rate_for


class DroidArmDriver:
    """Polymetis law + actuation stages for B arms; knows nothing about the simulator."""

    NUMPY_MAX_ENVS = 16
    # set by the ManiSkill binding (the benchmark's CPU env); the sysid replay stays on float32 torch
    # so a model with effects at their off-values replays bit-for-bit like the nominal one
    allow_numpy = False

    def __init__(self, model: ArmModel, config: DroidControlConfig, num_envs: int, device: torch.device | str = "cpu",
                 actuation: ActuationModel | None = None):
        self.model = model.to(device)
        self.config = config
        self.num_envs = num_envs
        self.device = torch.device(device)
        self.actuation = actuation if actuation is not None else ActuationModel()
        self.be = TorchBackend(self.model)
        self.integrator = INTEGRATORS[config.integrator]()
        self.rate = rate_for(config)
        self.gains = BatchedGains.from_gains(resolve(config.gains, GAIN_PRESETS, "gain"), num_envs, self.device)
        t = lambda v: torch.as_tensor(v, device=self.device, dtype=torch.float32)  # noqa: E731
        self.effort_limits = t(config.effort_limits)
        self.neg_effort_limits = -self.effort_limits
        self.joint_physics = resolve(config.joint_physics, JOINT_PHYSICS_PRESETS, "joint physics")
        self.friction = t(self.joint_physics.friction)
        self.neg_friction = -self.friction
        self.armature = t(self.joint_physics.armature)
        self.arm = torch.diag_embed(self.armature)
        # lower bound of each joint's effective inertia, for the friction limiter
        self.inertia_lower_bound = 0.5 * torch.diagonal(self.model.mass_matrix(t(config.reference_qpos)[None])[0]) + self.armature
        # the damping PhysX's implicit drive carries (integrator="implicit_damping", else zero)
        self.drive_damping = self.integrator.drive_damping(self, self.gains)
        self._folded = None  # FoldedExact, made on first use
        zeros = lambda: torch.zeros(num_envs, model.dof, device=self.device)  # noqa: E731
        self.q_target = zeros()
        self.time = torch.zeros(num_envs, device=self.device)
        self.motor_torque = zeros()  # commanded after limits/actuator
        self.applied_torque = zeros()  # + joint friction and plant effects
        # "exact": predicted end-of-step velocity minus the step-average velocity PhysX holds
        self.velocity_correction = zeros()
        # "exact": last step's torques beyond the motor's (joint friction, plant effects), which the
        # closed loop is predicted to react to within the step (a constant load shifts its equilibrium)
        self.plant_prev = zeros()
        # last step-average torque of the within-step effects (path prediction only)
        self.within_prev = zeros()
        # "exact": the step-average velocity the last step predicted (NaN: unknown, after a reset)
        self.predicted_velocity = torch.full((num_envs, model.dof), float("nan"), device=self.device)

    @property
    def folded(self) -> FoldedExact:
        if self._folded is None:
            self._folded = FoldedExact(self)
        return self._folded

    def reset(self, q: torch.Tensor, env_idx: torch.Tensor | None = None) -> None:
        """Hold the current pose in the envs being reset."""
        idx = slice(None) if env_idx is None else env_idx
        self.q_target[idx] = q[idx, : self.model.dof]
        self.time[idx] = 0.0
        self._rates_do("reset")
        self.motor_torque[idx] = 0.0
        self.applied_torque[idx] = 0.0
        self.velocity_correction[idx] = 0.0
        self.plant_prev[idx] = 0.0
        self.predicted_velocity[idx] = float("nan")
        self.within_prev[idx] = 0.0
        self.actuation.reset(self.num_envs, self.device, env_idx, q[:, : self.model.dof])

    def set_target(self, q_target: torch.Tensor) -> None:
        q_target = q_target.to(self.device, torch.float32)
        # a new command refreshes the terms taken per target (model_rate="control") and re-plans the
        # rows whose target changed ("path"); a replay that re-sends the held command every physics
        # step keeps them, as the benchmark does
        if q_target.shape != self.q_target.shape:
            self._rates_do("reset")
        elif not torch.equal(q_target, self.q_target):
            self._rates_do("retarget")
        self.q_target = q_target

    def _rates_do(self, what: str) -> None:
        getattr(self.rate, what)()
        if self._folded is not None:
            getattr(self._folded.rate, what)()

    def numpy_path(self) -> bool:
        """The nominal exact law on CPU for a few envs runs folded in numpy (eager torch costs ~2x
        more on these tiny ops); batched torch stays the path for GPU, many envs and actuation stages."""
        return (self.allow_numpy and self.device.type == "cpu" and not self.actuation and self.integrator.exact
                and self.num_envs <= self.NUMPY_MAX_ENVS)

    def torque(self, q, qd, dt: float):
        """Joint torque to apply this physics step (torch or numpy in, the same out; with
        ``integrator="implicit_damping"`` the drive adds the rest)."""
        if isinstance(q, np.ndarray):
            if self.numpy_path():
                return self.folded.torque(q.astype(np.float64), qd.astype(np.float64), dt)
            return self.integrator.torque(self, torch.as_tensor(q, dtype=torch.float32), torch.as_tensor(qd, dtype=torch.float32), dt).numpy()
        if self.numpy_path():
            return torch.from_numpy(self.folded.torque(q.double().numpy(), qd.double().numpy(), dt)).float()
        return self.integrator.torque(self, q, qd, dt)
