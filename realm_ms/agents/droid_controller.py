"""The DROID arm controller: Polymetis ``HybridJointImpedanceControl`` computed every physics step.

    tau = (Kq + J^T Kx J)(q* - q) - (Kqd + J^T Kxd J) qd + C(q, qd) qd + g(q)

with J the flange Jacobian, C and g from the robot's own model (``ArmModel``; libfranka compensates
gravity on the real robot, so the simulated arm keeps gravity and the controller cancels it with
its model), and the torque clipped to the Franka limits (87 / 12 N.m).

Numerics (``DroidControlConfig.integrator``). The real law runs at 1 kHz on a continuous plant; the
benchmark steps PhysX at 120 Hz, where an explicit damping torque on the light wrist is unstable
(h*Kd/I ~ 4 for joint 7 with the gripper, I ~ 5e-3 kg.m^2).

- ``"exact"`` (default): over each physics step the closed loop of the law on the robot's model
  is linear (M, Kp, Kd held, the Coriolis/gravity feed-forward cancels the plant's), so its state
  after h is ``expm(A h) x``. The driver applies the one torque that makes PhysX's semi-implicit
  Euler step land on that *position*; the velocity PhysX then holds is the step's average, and the
  difference to the predicted end velocity is carried to the next step's velocity estimate. This
  reproduces a 1 kHz controller on a continuous plant to < 1 mrad RMS at 120 Hz (MuJoCo reference,
  ``realm_ms/sysid/reference_mujoco.py``; docs/robot.md). Known plant inertia (joint armature,
  build-time effects) enters the prediction.
- ``"implicit_damping"`` (the former default): the diagonal damping rides on PhysX's implicit joint
  drive and the explicit torque pre-compensates it with +d*qd. Stable, but the drive acts on the
  *end* velocity, which adds an apparent armature d*h (0.025 kg.m^2 on joint 7 at 120 Hz, 5x its
  inertia): 16-32 mrad RMS off the 1 kHz reference on 10 s excitation logs.
- ``"explicit"``: the law as is, stable only at >= ~1 kHz.

Model terms (``DroidControlConfig.model_rate``). The exact step needs J, M, C and g at every physics
step. ``"path"`` (default) predicts the closed loop's states over the next action's physics steps and
evaluates the model at all of them in one batched call (a model evaluation is ~150 tiny array ops,
so 8 configurations cost about what one does); each step then uses the terms of its predicted state,
gravity corrected to first order for the measured one, and a row re-plans when its target changes or
its arm leaves the path by more than ``path_tolerance`` (contact, saturation). Same accuracy as
``"physics"`` (terms at the measured state every step) against the MuJoCo reference; on CPU with few
envs the numpy path folds each planned step into one affine map (``_affine_step_numpy``).

``DroidArmDriver`` is the backend-free core (batched torch); ``DroidJointImpedanceController`` binds
it to a ManiSkill articulation (physx_cpu and physx_cuda). The sysid replay simulator binds the same
driver to its own articulations, so an identified model is the model the benchmark runs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import torch
from gymnasium import spaces
from mani_skill.agents.controllers.base_controller import BaseController, ControllerConfig

from realm_ms.agents.actuation import ActuationModel, ControlState
from realm_ms.agents.arm_model import ArmModel
from realm_ms.agents.urdf import ARM_JOINTS, DROID_RESET_QPOS

FRANKA_EFFORT_LIMITS = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
# rad: PhysX ended the last step where the exact step put it (its velocity off the predicted one by
# at most this over a step): the arm moves freely, and the step's torque may exceed the motor limit
# (see ``torque``). Measured in free motion on 4 s excitation logs, nominal and with every sysid
# effect: median 0.6-3e-5, max 2.1e-4; a joint blocked by contact misses by the step's whole motion
# (estimated ½ a h² at the limit torque: ~1e-3 rad on the shoulder, ~1e-2 on the wrist).
FREE_MOTION_TOLERANCE = 5e-4


# ---------------------------------------------------------------------------- gains and presets
@dataclass(frozen=True)
class ImpedanceGains:
    """Polymetis hybrid joint impedance gains (joint: N.m/rad, N.m.s/rad; Cartesian: N/m, N.m/rad)."""

    kq: tuple[float, ...]
    kqd: tuple[float, ...]
    kx: tuple[float, ...]
    kxd: tuple[float, ...]


GAIN_PRESETS: dict[str, ImpedanceGains] = {
    # fairo franka_hardware.yaml since 2022-08-09 (commit 2de742c): what current DROID sites run
    "polymetis": ImpedanceGains((40, 30, 50, 25, 35, 25, 10), (4, 6, 5, 5, 3, 2, 1), (750,) * 3 + (15,) * 3, (37,) * 3 + (2,) * 3),
    # REALM's aligned control (realm/config/robots/franka_robotiq.yaml): Kq4 = 35, Kx = 400
    "realm": ImpedanceGains((40, 30, 50, 35, 35, 25, 10), (4, 6, 5, 5, 3, 2, 1), (400,) * 3 + (15,) * 3, (37,) * 3 + (2,) * 3),
    # fairo 2022-02 .. 2022-08
    "polymetis_2022_02": ImpedanceGains((80, 120, 100, 100, 70, 50, 20), (10, 10, 10, 10, 5, 5, 5), (150,) * 3 + (10,) * 3, (25,) * 3 + (7,) * 3),
}


@dataclass(frozen=True)
class JointPhysics:
    """Joint physics beyond the rigid URDF: smooth Coulomb ``friction`` in N.m (applied by the
    driver as an explicit torque) and rotor ``armature`` in kg.m^2 (an articulation property).

    REALM's friction numbers were PhysX joint-friction coefficients. In SAPIEN's PhysX that
    coefficient is unitless and load-proportional; applied literally it locks the wrist (a 0.3 rad
    step leaves 0.28 rad of error on joint 5; README, "The DROID controller"). Read as N.m they match the
    Franka's measured Coulomb friction (0.1-0.7 N.m, Gaz et al. 2019), which is how we apply them.
    """

    friction: tuple[float, ...]
    armature: tuple[float, ...]
    friction_velocity: float = 0.02  # rad/s, tanh smoothing of sgn(qd)


JOINT_PHYSICS_PRESETS: dict[str, JointPhysics] = {
    # REALM's identified values (realm_environment_dynamic.py; later DROID.yaml), friction as N.m
    "realm": JointPhysics((0.05, 0.10, 0.05, 0.10, 0.75, 0.425, 0.20), (0.25, 0.50, 0.25, 0.50, 0.25, 0.15, 0.0)),
    # the rigid URDF alone: the sysid workbench's baseline, every effect is then explicit
    "none": JointPhysics((0.0,) * 7, (0.0,) * 7),
}


def resolve(preset_or_value, presets: dict, what: str):
    if isinstance(preset_or_value, str):
        if preset_or_value not in presets:
            raise ValueError(f"unknown {what} preset {preset_or_value!r}; choose one of {sorted(presets)}")
        return presets[preset_or_value]
    return preset_or_value


@dataclass
class TorchGains:
    """Gains as batched tensors (B, 7) / (B, 6), so each env may run different gains (sysid)."""

    kq: torch.Tensor
    kqd: torch.Tensor
    kx: torch.Tensor
    kxd: torch.Tensor

    @classmethod
    def from_gains(cls, g: ImpedanceGains, num_envs: int, device, dtype=torch.float32) -> "TorchGains":
        t = lambda v: torch.as_tensor(v, device=device, dtype=dtype).expand(num_envs, -1).clone()  # noqa: E731
        return cls(t(g.kq), t(g.kqd), t(g.kx), t(g.kxd))

    def map(self, fn) -> "TorchGains":
        return TorchGains(fn(self.kq), fn(self.kqd), fn(self.kx), fn(self.kxd))


def limit_dissipative(tau: torch.Tensor, qd: torch.Tensor, inertia: torch.Tensor, dt: float) -> torch.Tensor:
    """Clamp a torque that opposes motion so it can at most stop the joint within one step.

    Explicit friction with a steep slope at qd = 0 is unstable on light joints (h * slope / I > 2);
    bounding it by the impulse I |qd| / h keeps it dissipative. ``inertia`` must not exceed the
    joint's true effective inertia (use a lower bound).
    """
    cap = inertia * qd.abs() / dt
    return torch.clamp(tau, -cap, cap)


# ---------------------------------------------------------------------------- backend-free core
@dataclass
class DroidControlConfig:
    gains: ImpedanceGains | str = "polymetis"
    effort_limits: tuple[float, ...] = FRANKA_EFFORT_LIMITS
    coriolis_feedforward: bool = True  # on in Polymetis and (via a YAML slip) in REALM
    gravity_compensation: bool = True  # libfranka compensates gravity with its model
    integrator: str = "exact"  # "exact" | "implicit_damping" | "explicit": see the module docstring
    implicit_damping: bool | None = None  # legacy switch: True = "implicit_damping", False = "explicit"
    # damping carried implicitly, N.m.s/rad per joint; None = the law's diagonal at ``reference_qpos``
    implicit_damping_values: tuple[float, ...] | None = None
    reference_qpos: tuple[float, ...] = DROID_RESET_QPOS
    joint_physics: JointPhysics | str = "realm"
    # Where the model terms (J, M, C(q, qd), g(q)) come from; the feedback on q, qd runs every physics step.
    # "path" (default): for every physics step, at the state the closed loop is predicted to reach then,
    #   all ``path_steps`` steps in one batched evaluation (g corrected to first order for the measured
    #   q); re-planned when the target changes or the arm leaves the path by > ``path_tolerance``.
    # "physics": at the measured state, every physics step (as Polymetis at 1 kHz).
    # "control": once per target, gravity corrected to first order in between (~2 mrad off).
    # Cost: bench/step_rate.py; accuracy against the MuJoCo reference: docs/robot.md.
    model_rate: str = "path"
    path_steps: int = 8  # physics steps per plan (the ManiSkill binding sets its substeps per action)
    path_tolerance: float = 1e-3  # rad; the terms' error grows with the distance to where they were taken
    law_hz: float = 1000.0  # "exact": the controller rate it reproduces (Polymetis / libfranka: 1 kHz)

    def __post_init__(self):
        if self.implicit_damping is not None:  # legacy boolean wins when given
            self.integrator = "implicit_damping" if self.implicit_damping else "explicit"
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {self.integrator!r}")
        if self.model_rate not in MODEL_RATES:
            raise ValueError(f"model_rate must be one of {MODEL_RATES}, got {self.model_rate!r}")
        if self.path_steps < 1 or not self.path_tolerance > 0:
            raise ValueError(f"path_steps must be >= 1 and path_tolerance > 0, got {self.path_steps}, {self.path_tolerance}")

    @property
    def follows_path(self) -> bool:
        """Terms along the predicted path: needs the exact integrator's prediction (else "physics")."""
        return self.model_rate == "path" and self.integrator == "exact"


INTEGRATORS = ("exact", "implicit_damping", "explicit")
MODEL_RATES = ("path", "physics", "control")


class DroidArmDriver:
    """Polymetis law + actuation stages for B arms; knows nothing about the simulator."""

    def __init__(
        self,
        model: ArmModel,
        config: DroidControlConfig,
        num_envs: int,
        device: torch.device | str = "cpu",
        actuation: ActuationModel | None = None,
    ):
        self.model = model.to(device)
        self.config = config
        self.num_envs = num_envs
        self.device = torch.device(device)
        self.actuation = actuation if actuation is not None else ActuationModel()
        gains = resolve(config.gains, GAIN_PRESETS, "gain")
        self.gains = TorchGains.from_gains(gains, num_envs, self.device)
        self.effort_limits = torch.as_tensor(config.effort_limits, device=self.device, dtype=torch.float32)
        self.implicit_damping = self._implicit_damping(gains)
        self.joint_physics = resolve(config.joint_physics, JOINT_PHYSICS_PRESETS, "joint physics")
        t = lambda v: torch.as_tensor(v, device=self.device, dtype=torch.float32)  # noqa: E731
        self.friction = t(self.joint_physics.friction)
        self._neg_friction = -self.friction
        self._neg_effort_limits = -self.effort_limits
        self.armature = t(self.joint_physics.armature)
        # lower bound of each joint's effective inertia, for the friction limiter
        ref = t(config.reference_qpos)[None]
        self.inertia_lower_bound = 0.5 * torch.diagonal(self.model.mass_matrix(ref)[0]) + self.armature
        self.q_target = torch.zeros(num_envs, model.dof, device=self.device)
        self._terms = self._terms_np = None  # cached model terms for model_rate="control" (torch, numpy path)
        # model_rate="path": terms along the predicted path, (B, path_steps, ...); torch and numpy path
        self._plan = self._plan_np = self._plan_dt = self._plan_np_dt = None
        self._retarget = None  # (B,) bool: rows whose target changed since the numpy plan was made
        self.path_steps = config.path_steps
        self.time = torch.zeros(num_envs, device=self.device)
        self.motor_torque = torch.zeros(num_envs, model.dof, device=self.device)  # commanded after limits/actuator
        self.applied_torque = torch.zeros(num_envs, model.dof, device=self.device)  # + joint friction and plant effects
        # "exact": predicted end-of-step velocity minus the step-average velocity PhysX holds
        self.velocity_correction = torch.zeros(num_envs, model.dof, device=self.device)
        # "exact": last step's torques beyond the motor's (joint friction, plant effects), which the
        # closed loop is predicted to react to within the step (a constant load shifts its equilibrium)
        self.plant_prev = torch.zeros(num_envs, model.dof, device=self.device)
        # last step-average torque of the within-step effects (path prediction only)
        self.within_prev = torch.zeros(num_envs, model.dof, device=self.device)
        # "exact": the step-average velocity the last step predicted (NaN: unknown, after a reset)
        self.predicted_velocity = torch.full((num_envs, model.dof), float("nan"), device=self.device)
        self._eye = torch.eye(model.dof, device=self.device)

    def _implicit_damping(self, gains: ImpedanceGains) -> torch.Tensor:
        if self.config.integrator != "implicit_damping":
            return torch.zeros(self.model.dof, device=self.device)
        if self.config.implicit_damping_values is not None:
            return torch.as_tensor(self.config.implicit_damping_values, device=self.device, dtype=torch.float32)
        q = torch.as_tensor(self.config.reference_qpos, device=self.device, dtype=torch.float32)[None]
        g = TorchGains.from_gains(gains, 1, self.device)
        _, kd, _ = self._law_terms(q, torch.zeros_like(q), g)
        return torch.diagonal(kd[0]).clone()

    def reset(self, q: torch.Tensor, env_idx: torch.Tensor | None = None) -> None:
        """Hold the current pose in the envs being reset."""
        idx = slice(None) if env_idx is None else env_idx
        self.q_target[idx] = q[idx, : self.model.dof]
        self.time[idx] = 0.0
        self._terms = self._terms_np = self._plan = self._plan_np = None
        self.motor_torque[idx] = 0.0
        self.applied_torque[idx] = 0.0
        self.velocity_correction[idx] = 0.0
        self.plant_prev[idx] = 0.0
        self.predicted_velocity[idx] = float("nan")
        self.within_prev[idx] = 0.0
        self.actuation.reset(self.num_envs, self.device, env_idx, q[:, : self.model.dof])

    def set_target(self, q_target: torch.Tensor) -> None:
        q_target = q_target.to(self.device, torch.float32)
        # a new command refreshes J, C, g (model_rate="control") and Phi ("exact"); a replay that
        # re-sends the held command every physics step keeps them, as the benchmark does
        if q_target.shape != self.q_target.shape or not torch.equal(q_target, self.q_target):
            self._terms = self._terms_np = None
            if q_target.shape == self.q_target.shape:  # rows with a new target re-plan (model_rate="path")
                rows = (q_target != self.q_target).any(-1)
                self._retarget = rows if self._retarget is None else self._retarget | rows
            else:
                self._plan = self._plan_np = None
        self.q_target = q_target

    def _bias(self, q: torch.Tensor, qd: torch.Tensor, frames: torch.Tensor) -> torch.Tensor:
        """Feed-forward from the robot's model: Coriolis and/or gravity, as configured."""
        cfg = self.config
        if not (cfg.coriolis_feedforward or cfg.gravity_compensation):
            return torch.zeros_like(q)
        return self.model.rnea(q, qd if cfg.coriolis_feedforward else torch.zeros_like(qd), gravity=cfg.gravity_compensation, frames=frames)

    def _law_terms(self, q: torch.Tensor, qd: torch.Tensor, gains: TorchGains, frames: torch.Tensor | None = None):
        """Stiffness and damping matrices and the feed-forward at configuration q: (kp, kd, bias)."""
        frames = self.model.link_frames(q) if frames is None else frames
        kp, kd = self._stiffness_damping(self.model.jacobian(q, frames), gains)
        return kp, kd, self._bias(q, qd, frames)

    @staticmethod
    def _stiffness_damping(jac: torch.Tensor, gains: TorchGains) -> tuple[torch.Tensor, torch.Tensor]:
        """Joint-space Kp = diag(Kq) + J^T Kx J and Kd = diag(Kqd) + J^T Kxd J."""
        jt = jac.transpose(1, 2)
        kp = torch.diag_embed(gains.kq) + jt @ (gains.kx[..., None] * jac)
        kd = torch.diag_embed(gains.kqd) + jt @ (gains.kxd[..., None] * jac)
        return kp, kd

    def _gravity_jacobian(self, q: torch.Tensor, eps: float = 1e-3) -> torch.Tensor:
        """d g / d q (B, n, n) by central differences, one batched RNEA."""
        if not self.config.gravity_compensation:
            return torch.zeros(q.shape[0], q.shape[1], q.shape[1], device=q.device)
        n = q.shape[1]
        d = eps * torch.eye(n, device=q.device)
        qs = torch.cat([(q[:, None] + d).reshape(-1, n), (q[:, None] - d).reshape(-1, n)])
        g = self.model.rnea(qs, torch.zeros_like(qs)).view(2, q.shape[0], n, n)
        return ((g[0] - g[1]) / (2 * eps)).transpose(1, 2)

    def torque(self, q: torch.Tensor, qd: torch.Tensor, dt: float) -> torch.Tensor:
        """Joint torque to apply this physics step (with ``"implicit_damping"`` the drive adds the rest)."""
        if self._numpy_path():
            return torch.from_numpy(self.torque_numpy(q.double().numpy(), qd.double().numpy(), dt)).float()
        act = self.actuation
        exact = self.config.integrator == "exact"
        if exact:  # the plant's velocity at the step start (PhysX holds the last step's average)
            qd_held = qd
            qd = qd + self.velocity_correction
        if act:
            state = ControlState(q=q, qd=qd, q_target=self.q_target, dt=dt, model=self.model, time=self.time)
            q_m, qd_m = act.measure(q, qd, state)
            q_t = state.q_target = act.command(self.q_target, state)
        else:  # nominal robot: skip the stage plumbing (this runs 8x per action)
            q_m, qd_m, q_t = q, qd, self.q_target
        gains = act.gains(self.gains) if act else self.gains
        ext = self.plant_prev  # torques the plant receives beyond the law's, as the exact step predicts them
        load = act.plant_load(state) if exact and act else None
        if load is not None:
            ext = ext + load
        if exact and self.config.follows_path:
            step, bias = self._path_step(q_m, qd_m, q_t, gains, state if act else None, ext + self.within_prev, dt)
        elif exact:
            # the closed loop's transition over this step from J(q), M(q) (model_rate="physics"), or
            # once per target (model_rate="control": cheaper, ~1-2 mrad RMS further from the 1 kHz law)
            if self.config.model_rate != "control" or self._terms is None:
                frames = self.model.link_frames(q_m)
                kp, kd, bias = self._law_terms(q_m, qd_m, gains, frames)
                step = self._step_matrices(kp, kd, self._plant_mass(q_m, frames, state if act else None), dt)
                if self.config.model_rate == "control":
                    self._terms = (step, bias, q_m.clone(), self._gravity_jacobian(q_m))
            if self.config.model_rate == "control":
                step, bias, q_ref, dg = self._terms
                bias = bias + (dg @ (q_m - q_ref)[..., None])[..., 0]
        else:
            if self.config.model_rate != "control" or self._terms is None:
                kp, kd, bias = self._law_terms(q_m, qd_m, gains)
                if self.config.model_rate == "control":
                    self._terms = (kp, kd, bias, q_m.clone(), self._gravity_jacobian(q_m))
            if self.config.model_rate == "control":
                kp, kd, bias, q_ref, dg = self._terms
                bias = bias + (dg @ (q_m - q_ref)[..., None])[..., 0]  # first-order gravity between refreshes
        within = None
        if act:
            state.extra["bias"] = bias  # model feed-forward, reused by effects (saves them an RNEA)
            if exact:
                ext = ext + self._measured_feedforward_load(q, qd, q_m, qd_m, bias)
                if act.within_step:
                    within = self._within_step_torque(state, q_m - q_t, qd - qd_m)
        f_step = None
        if exact:
            tau, v_end, v_avg, f_step = self._exact_torque(q_m - q_t, qd_m, qd_held + (qd_m - qd), step, bias, ext, within)
            tau = tau + bias
        else:
            tau = (kp @ (q_t - q_m)[..., None] - kd @ qd_m[..., None])[..., 0] + bias
        clamped = torch.clamp(tau, self._neg_effort_limits, self.effort_limits)
        law, excess = clamped, None
        if exact:
            # The exact step's torque is the law's motion over the step folded into one PhysX step, not
            # the motor's instantaneous torque (the law's ticks are clipped to the limits inside the
            # prediction): at a new target it can exceed the limit while the 1 kHz motor does not. It is
            # applied in full while the arm moves as predicted; in contact it is clipped, the prediction
            # no longer holds there and its velocity correction is dropped. (Tested before the actuator
            # stages, whose additions enter the next step as plant torque.)
            limited = ((clamped - tau).abs() >= 1e-4).any(-1, keepdim=True)
            free = ((qd_held - self.predicted_velocity).abs() * dt <= FREE_MOTION_TOLERANCE).all(-1, keepdim=True)
            clip = limited & ~free
            self.velocity_correction = torch.where(clip, 0.0, v_end - v_avg)
            self.predicted_velocity = v_avg
            excess = torch.where(clip, 0.0, tau - clamped)  # the step's torque beyond the limit
            law = clamped + excess
        if act:
            clamped = act.actuator(clamped, state)
        tau = self.motor_torque = clamped
        if excess is not None:
            tau = tau + excess
        # joint friction is physics, not command: it acts on the true velocity
        friction = self._neg_friction * torch.tanh(qd / self.joint_physics.friction_velocity)
        tau = tau + limit_dissipative(friction, qd, self.inertia_lower_bound, dt)
        if act:
            # within-step effects were integrated inside the exact step: their step-average torque
            plant = act.plant_torque(state, within_step=False if within is not None else None)
            if plant is not None:
                tau = tau + plant
            if f_step is not None:
                tau = tau + f_step
        self.applied_torque = tau
        if exact:
            # all but the law's own torque (actuator stages included) and what the step predicted itself
            self.plant_prev = tau - law if f_step is None else tau - law - f_step
            self.within_prev = f_step if f_step is not None else self.within_prev.zero_()
        self.time = self.time + dt
        # the implicit drive will apply about -d*qd; pre-compensate so the total matches the law
        return tau + self.implicit_damping * qd if self.config.integrator == "implicit_damping" else tau

    # ------------------------------------------------------------------ numpy fast path (CPU, few envs)
    NUMPY_MAX_ENVS = 16
    # set by the ManiSkill binding (the benchmark's CPU env); the sysid replay stays on float32 torch
    # so a model with effects at their off-values replays bit-for-bit like the nominal one
    allow_numpy = False

    def _numpy_path(self) -> bool:
        """The nominal exact law on CPU for a few envs runs in numpy (eager torch costs ~2x more on
        these tiny ops); batched torch stays the path for GPU, many envs and actuation stages."""
        c = self.config
        return (self.allow_numpy and self.device.type == "cpu" and not self.actuation and c.integrator == "exact"
                and self.num_envs <= self.NUMPY_MAX_ENVS)

    def torque_numpy(self, q: np.ndarray, qd: np.ndarray, dt: float) -> np.ndarray:
        """``torque`` for the nominal exact law, in float64 numpy (same equations, as one affine map
        per step: see ``_affine_step_numpy``)."""
        k, cfg = self._numpy_constants(dt), self.config
        n = q.shape[1]
        # float32 [velocity correction, motor, applied, plant_prev torque, predicted velocity], as on the torch path
        state = k["state"]
        qd_held, qd = qd, qd + state[:, :n]
        ext = state[:, 3 * n : 4 * n]
        err = q - self.q_target.numpy()
        z = np.concatenate([err, qd, ext, qd_held, q], 1)[..., None]
        if cfg.follows_path:
            affine, const, terms = self._path_step_numpy(q, qd, ext, dt)
        else:
            if cfg.model_rate == "physics" or self._terms_np is None:
                kp, kd, bias, mass, minv, phi = self._terms_numpy(q, qd, (k["kq"], k["kqd"], k["kx"], k["kxd"]), dt)
                # "control": refreshed per target, gravity to first order in between
                dg = self._gravity_jacobian_numpy(q) if cfg.model_rate == "control" else np.zeros((q.shape[0], n, n))
                self._terms_np = (kp, kd, bias, mass, minv, *self._affine_step_numpy(kp, kd, mass, phi, bias, dg, q, None, dt), dg, q.copy())
            kp, kd, bias, mass, minv, affine, const, dg, q_ref = self._terms_np
            terms = lambda: (kp, kd, mass, minv, bias + (dg @ (q - q_ref)[..., None])[..., 0])  # noqa: E731
        y = (affine @ z)[..., 0] + const
        # rows: law torque at the step's start and end, distance to the planned path, motor torque;
        # one bound check for all four (the common case: none is exceeded)
        tau = y[:, 3 * n : 4 * n]
        clamped = tau
        clip = None
        if (np.abs(y[:, : 4 * n]) > k["bounds"]).any():
            off = (np.abs(y[:, 2 * n : 3 * n]) > k["bounds"][2 * n : 3 * n]).any(-1)
            if cfg.follows_path and off.any():  # off the path: re-plan those rows
                self._plan_np["k"] -= 1
                affine, const, terms = self._path_step_numpy(q, qd, ext, dt, off=off)
                y = (affine @ z)[..., 0] + const
                tau = y[:, 3 * n : 4 * n]
            sat = (np.abs(y[:, : 2 * n]) > k["bounds"][: 2 * n]).any(-1)
            if sat.any():  # the law saturates within the step: its ticks with the clipped torque
                self._saturated_ticks_numpy(y, sat, err, qd, qd_held, ext, terms(), dt)
            lim = k["lim"]
            clamped = np.minimum(np.maximum(tau, -lim), lim)
            limited = (np.abs(clamped - tau) >= 1e-4).any(-1)
            free = (np.abs(qd_held - state[:, 4 * n :]) * dt <= FREE_MOTION_TOLERANCE).all(-1)
            clip = limited & ~free  # in contact: clipped, no correction (see ``torque``)
            y[clip, 4 * n : 5 * n] = 0.0
        applied = tau if clip is None or not clip.any() else np.where(clip[:, None], clamped, tau)
        friction = k["neg_fric"] * np.tanh(qd * k["inv_fric_v"])
        cap = k["inertia_lb_dt"] * np.abs(qd)
        friction = np.minimum(np.maximum(friction, -cap), cap)
        state[:, :n] = y[:, 4 * n : 5 * n]
        state[:, n : 2 * n] = clamped
        state[:, 2 * n : 3 * n] = out = applied + friction
        state[:, 3 * n : 4 * n] = friction
        state[:, 4 * n :] = y[:, 5 * n :]
        k["time"] += dt
        return out

    def _saturated_ticks_numpy(self, y, sat, err, qd, qd_held, ext, terms: tuple, dt: float) -> None:
        """Rows of y (see ``torque_numpy``) where the law saturates, from its ticks with the clipped torque."""
        kp, kd, mass, minv, bias = terms
        lim, n, ticks = self._np["lim"], err.shape[1], self._ticks(dt)
        t = dt / ticks
        for r in np.nonzero(sat)[0]:
            e, v = err[r], qd[r]
            for _ in range(ticks):
                tau = np.clip(-(kp[r] @ e + kd[r] @ v) + bias[r], -lim, lim)
                a = minv[r] @ (tau - bias[r] + ext[r])
                e, v = e + t * v + 0.5 * t * t * a, v + t * a
            v_avg = (e - err[r]) / dt
            y[r, 3 * n : 4 * n] = mass[r] @ ((v_avg - qd_held[r]) / dt) + bias[r] - ext[r]
            y[r, 4 * n : 5 * n] = v - v_avg
            y[r, 5 * n :] = v_avg

    def _affine_step_numpy(self, kp, kd, mass, phi, bias, dg, q_ref, q_path, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The exact step (``_exact_torque`` + feed-forward) as one affine map, batched over the leading
        axis: y = G z + c with z = [q - q*, qd, load, qd_held, q] (5n) and y = [law torque at the step's
        start, at its end, q - q_path (0 without a path), motor torque, velocity correction, step-average
        velocity] (6n). The closed loop's end
        state is x1 = Phi x0 + W load (W = (I - Phi)[:, :n] Kp^-1: the load's equilibrium shift), and
        the feed-forward is g0 + dg (q - q_ref). One matmul per physics step instead of ~60 tiny ops."""
        m, n = kp.shape[:2]
        eye = self._np["eye"]
        a = np.concatenate([phi, (np.eye(2 * n) - phi)[:, :, :n] @ np.linalg.inv(kp)], 2)  # x1 = A [e, qd, load]
        law = np.concatenate([kp, kd], 2)
        dq = a[:, :n].copy()  # q1 - e = (A_q - [I 0 0]) [e, qd, load]
        dq[:, :, :n] -= eye
        g = np.zeros((m, 6 * n, 5 * n))
        g[:, :n, : 2 * n] = -law
        g[:, n : 2 * n, : 3 * n] = -law @ a
        if q_path is not None:
            g[:, 2 * n : 3 * n, 4 * n :] = eye
        g[:, 3 * n : 4 * n, : 3 * n] = mass @ dq / (dt * dt)  # M (v_avg - qd_held) / dt + ff - load
        g[:, 3 * n : 4 * n, 2 * n : 3 * n] -= eye
        g[:, 3 * n : 4 * n, 3 * n : 4 * n] = -mass / dt
        g[:, 4 * n : 5 * n, : 3 * n] = a[:, n:] - dq / dt  # v1 - v_avg
        g[:, 5 * n :, : 3 * n] = dq / dt  # v_avg
        for i in (0, 1, 3):
            g[:, i * n : (i + 1) * n, 4 * n :] = dg
        c = bias - (dg @ q_ref[..., None])[..., 0]
        zero = np.zeros_like(c)
        return g, np.concatenate([c, c, zero if q_path is None else -q_path, c, zero, zero], 1)

    def _numpy_constants(self, dt: float) -> dict:
        if getattr(self, "_np", None) is None:
            from realm_ms.agents.arm_model import NumpyArmModel

            f = lambda t: t.detach().cpu().double().numpy()  # noqa: E731
            self._np = dict(model=NumpyArmModel(self.model), kq=f(self.gains.kq), kqd=f(self.gains.kqd),
                            kx=f(self.gains.kx), kxd=f(self.gains.kxd), arm=np.diag(f(self.armature)),
                            lim=f(self.effort_limits), lim2=np.tile(f(self.effort_limits), 2), eye=np.eye(self.model.dof),
                            neg_fric=-f(self.friction), inv_fric_v=1.0 / self.joint_physics.friction_velocity)
        k = self._np
        if k.get("dt") != dt:  # the friction limiter's impulse bound per step
            k["dt"], k["inertia_lb_dt"] = dt, self.inertia_lower_bound.double().numpy() / dt
            lim = k["lim"]
            k["bounds"] = np.concatenate([lim, lim, np.full_like(lim, self.config.path_tolerance), lim])
        names = ("velocity_correction", "motor_torque", "applied_torque", "plant_prev", "predicted_velocity")
        if k.get("views") is None or any(v is not getattr(self, name) for v, name in zip(k["views"], names)):
            # one float32 buffer behind the state tensors (reset() writes them in place)
            buf = torch.cat([getattr(self, name).float() for name in names], 1).contiguous()
            views = torch.chunk(buf, len(names), 1)
            for name, v in zip(names, views):
                setattr(self, name, v)
            k["views"], k["state"] = views, buf.numpy()
        if k.get("time_of") is not self.time:
            k["time_of"], k["time"] = self.time, self.time.numpy()  # advanced in place (reset() zeroes it in place)
        return self._np

    def _terms_numpy(self, q, qd, gains: tuple, dt: float) -> tuple:
        """(Kp, Kd, feed-forward, M, M^-1, Phi) at (q, qd): ``_law_terms`` + ``_step_matrices``."""
        k, cfg = self._np, self.config
        npm = k["model"]
        frames = npm.link_frames(q)
        kp, kd = self._stiffness_damping_numpy(npm.jacobian(frames), gains)
        world = npm.world(frames)
        if cfg.coriolis_feedforward or cfg.gravity_compensation:
            ff = npm.bias(world, qd if cfg.coriolis_feedforward else np.zeros_like(qd), cfg.gravity_compensation)
        else:
            ff = np.zeros_like(q)
        mass = npm.mass(world) + k["arm"]
        minv = np.linalg.inv(mass)
        return kp, kd, ff, mass, minv, self._transition_numpy(minv, kp, kd, dt)

    def _stiffness_damping_numpy(self, jac, gains: tuple) -> tuple:
        kq, kqd, kx, kxd = gains
        eye, jt = self._np["eye"], jac.transpose(0, 2, 1)
        return kq[:, :, None] * eye + jt @ (kx[..., None] * jac), kqd[:, :, None] * eye + jt @ (kxd[..., None] * jac)

    def _transition_numpy(self, minv, kp, kd, dt: float) -> np.ndarray:
        eye, n, ticks = self._np["eye"], kp.shape[1], self._ticks(dt)
        t = dt / ticks
        p_, d_ = minv @ kp, minv @ kd
        phi = np.empty((kp.shape[0], 2 * n, 2 * n))
        phi[:, :n, :n] = eye - 0.5 * t * t * p_
        phi[:, :n, n:] = t * eye - 0.5 * t * t * d_
        phi[:, n:, :n] = -t * p_
        phi[:, n:, n:] = eye - t * d_
        return np.linalg.matrix_power(phi, ticks)

    def _plan_path_numpy(self, q, qd, q_t, ext, gains: tuple, dt: float, steps: int, predictor=None, eps: float = 1e-3) -> dict:
        """``_plan_path`` in numpy; the gravity Jacobian's 2n configurations join the path's batch."""
        k, cfg = self._np, self.config
        npm, arm, (b, n) = k["model"], k["arm"], q.shape
        if predictor is None:
            frames = npm.link_frames(q)
            kp, kd = self._stiffness_damping_numpy(npm.jacobian(frames), gains)
            phi = self._transition_numpy(np.linalg.inv(npm.mass_matrix(frames) + arm), kp, kd, dt)
        else:
            phi, kp = predictor
        e_star = np.linalg.solve(kp, ext[..., None])[..., 0]
        x = np.concatenate([q - q_t - e_star, qd], 1)[..., None]
        xs = [x]
        for _ in range(steps - 1):
            x = phi @ x
            xs.append(x)
        xs = np.concatenate(xs, -1).transpose(0, 2, 1)
        q_path = xs[..., :n] + (q_t + e_star)[:, None]
        q_path[:, 0] = q
        m = b * steps
        qs = q_path.reshape(m, n)
        qds = xs[..., n:].reshape(m, n) if cfg.coriolis_feedforward else np.zeros((m, n))
        if cfg.gravity_compensation:  # dg/dq at q by central differences, in the same batch
            d = eps * k["eye"]
            qs = np.concatenate([qs, (q[:, None] + d).reshape(-1, n), (q[:, None] - d).reshape(-1, n)])
            qds = np.concatenate([qds, np.zeros((2 * b * n, n))])
        frames = npm.link_frames(qs)
        world = npm.world(frames)
        kp, kd = self._stiffness_damping_numpy(npm.jacobian(frames[:m]), tuple(np.repeat(g, steps, 0) for g in gains))
        mass = npm.mass(tuple(w[:m] for w in world)) + arm
        minv = np.linalg.inv(mass)
        dg = np.zeros((b, n, n))
        if cfg.coriolis_feedforward or cfg.gravity_compensation:
            ff = npm.bias(world, qds, cfg.gravity_compensation)
            bias = ff[:m]
            if cfg.gravity_compensation:
                dg = ((ff[m : m + b * n] - ff[m + b * n :]) / (2 * eps)).reshape(b, n, n).transpose(0, 2, 1)
        else:
            bias = np.zeros((m, n))
        phi = self._transition_numpy(minv, kp, kd, dt)
        affine, const = self._affine_step_numpy(kp, kd, mass, phi, bias, np.repeat(dg, steps, 0), qs[:m], qs[:m], dt)
        terms = dict(bias=bias, mass=mass, minv=minv, kp=kp, kd=kd, phi=phi, affine=affine, const=const)
        plan = {key: v.reshape(b, steps, *v.shape[1:]) for key, v in terms.items()}
        plan.update(q=q_path, dg=dg, k=np.zeros(b, dtype=np.int64))
        return plan

    def _path_step_numpy(self, q, qd, ext, dt: float, off: np.ndarray | None = None) -> tuple:
        """``_path_step`` in numpy: this physics step's affine map and, for the saturated case, a
        function giving its (Kp, Kd, M, M^-1, feed-forward). ``off``: rows found off the path."""
        p, steps, b = self._plan_np, self.path_steps, q.shape[0]
        r = np.arange(b)
        full, rows, pred = p is None or self._plan_np_dt != dt, None, None
        if not full:
            j = np.minimum(p["k"], steps - 1)
            need = p["k"] >= steps
            if off is not None:
                need = need | off
            if self._retarget is not None:
                need = need | self._retarget.numpy()
            if need.any():
                rows = np.nonzero(need)[0]
                full = len(rows) == b
                pred = (p["phi"][r, j], p["kp"][r, j])
        self._retarget = None
        if full or rows is not None:
            c, q_t = self._np, self.q_target.numpy()
            gains = (c["kq"], c["kqd"], c["kx"], c["kxd"])
            if full:
                self._plan_np, self._plan_np_dt = self._plan_path_numpy(q, qd, q_t, ext, gains, dt, steps, pred), dt
                p = self._plan_np
            else:
                new = self._plan_path_numpy(q[rows], qd[rows], q_t[rows], ext[rows], tuple(g[rows] for g in gains), dt, steps,
                                            tuple(x[rows] for x in pred))
                for key, v in new.items():
                    p[key][rows] = v
        k = p["k"]
        p["k"] = k + 1
        terms = lambda: (p["kp"][r, k], p["kd"][r, k], p["mass"][r, k], p["minv"][r, k],  # noqa: E731
                         p["bias"][r, k] + (p["dg"] @ (q - p["q"][r, k])[..., None])[..., 0])
        return p["affine"][r, k], p["const"][r, k], terms

    def _gravity_jacobian_numpy(self, q: np.ndarray, eps: float = 1e-3) -> np.ndarray:
        """``_gravity_jacobian`` in numpy: d g / d q (B, n, n) by central differences."""
        b, n = q.shape
        if not self.config.gravity_compensation:
            return np.zeros((b, n, n))
        npm = self._np["model"]
        d = eps * np.eye(n)
        qs = np.concatenate([(q[:, None] + d).reshape(-1, n), (q[:, None] - d).reshape(-1, n)])
        g = npm.rnea(npm.link_frames(qs), np.zeros_like(qs)).reshape(2, b, n, n)
        return ((g[0] - g[1]) / (2 * eps)).transpose(0, 2, 1)

    def _plant_mass(self, q: torch.Tensor, frames: torch.Tensor, state) -> tuple[torch.Tensor, torch.Tensor]:
        """(M, M^-1): the model's inertia plus what the driver knows of the plant's (joint armature,
        build-time effects' ``plant_inertia``)."""
        mass = self.model.mass_matrix(q, frames) + torch.diag_embed(self.armature)
        extra = self.actuation.plant_inertia(state) if state is not None else None
        if extra is not None:
            mass = mass + extra
        return mass, torch.linalg.inv(mass)

    def _step_matrices(self, kp: torch.Tensor, kd: torch.Tensor, plant_mass: tuple, dt: float) -> tuple:
        """(M, Phi, dt) with Phi the state transition over one physics step dt of the law's closed loop,
        x = (q - q*, qd). The law is sampled at ``law_hz`` with a zero-order hold and the plant
        between ticks is M qdd = tau (the feed-forward cancels Coriolis and gravity), so one tick T is
        exactly  Phi_T = [[I - T^2/2 P, T I - T^2/2 D], [-T P, I - T D]],  P = M^-1 Kp, D = M^-1 Kd,
        and Phi = Phi_T^n with n = round(dt * law_hz) ticks of T = dt / n."""
        mass, minv = plant_mass
        ticks = self._ticks(dt)
        return mass, minv, self._transition(minv, kp, kd, dt), dt, kp, kd, ticks

    def _ticks(self, dt: float) -> int:
        return max(1, round(dt * self.config.law_hz))

    def _transition(self, minv: torch.Tensor, kp: torch.Tensor, kd: torch.Tensor, dt: float) -> torch.Tensor:
        """Phi_T^n (see ``_step_matrices``), batched (B, 2n, 2n)."""
        n = kp.shape[1]
        ticks = self._ticks(dt)
        t = dt / ticks
        p, d = minv @ kp, minv @ kd
        eye = self._eye.to(kp.dtype)
        phi = torch.empty(kp.shape[0], 2 * n, 2 * n, device=kp.device, dtype=kp.dtype)
        phi[:, :n, :n] = eye - (0.5 * t * t) * p
        phi[:, :n, n:] = t * eye - (0.5 * t * t) * d
        phi[:, n:, :n] = -t * p
        phi[:, n:, n:] = eye - t * d
        return torch.linalg.matrix_power(phi, ticks)

    # ------------------------------------------------------------------ model_rate="path"
    # a plan: "q", "bias", "mass", "minv", "phi", "kp", "kd" (B, steps, ...); "target", "dg", "k" (step index) per row

    def _plan_path(self, q, qd, q_t, gains: TorchGains, extra_inertia, ext, dt: float, steps: int, predictor=None) -> dict:
        """Model terms for the next ``steps`` physics steps, each at the state the closed loop is
        predicted to reach at that step: one batched evaluation instead of one per step.

        The path is predicted with the terms at q held (the model moves little over a control step,
        and the prediction only decides where the terms are taken); the terms along it are then the
        model's own. ``dg`` (dg/dq at q) corrects gravity to first order for the measured q.
        ``predictor``: (Phi, Kp) from the previous plan at the state it predicted for now (saves a
        model evaluation; the prediction only decides where the terms are taken)."""
        m, (b, n) = self.model, q.shape
        arm = torch.diag_embed(self.armature)
        if predictor is None:
            frames = m.link_frames(q)
            kp, kd = self._stiffness_damping(m.jacobian(q, frames), gains)
            mass = m.mass_matrix(q, frames) + arm + (0.0 if extra_inertia is None else extra_inertia)
            phi = self._transition(torch.linalg.inv(mass), kp, kd, dt)
        else:
            phi, kp = predictor
        e_star = torch.linalg.solve(kp, ext[..., None])[..., 0]  # a constant load shifts the equilibrium
        x = torch.cat([q - q_t - e_star, qd], 1)[..., None]
        xs = [x]
        for _ in range(steps - 1):
            x = phi @ x
            xs.append(x)
        xs = torch.cat(xs, -1).transpose(1, 2)  # (b, steps, 2n)
        q_path = xs[..., :n] + (q_t + e_star)[:, None]
        q_path[:, 0] = q  # exact at the first step
        qs, qds = q_path.reshape(b * steps, n), xs[..., n:].reshape(b * steps, n)
        rep = lambda x: x.repeat_interleave(steps, 0)  # noqa: E731
        frames = m.link_frames(qs)
        kp, kd = self._stiffness_damping(m.jacobian(qs, frames), gains.map(rep))
        mass = m.mass_matrix(qs, frames) + arm + (0.0 if extra_inertia is None else rep(extra_inertia))
        minv = torch.linalg.inv(mass)
        terms = dict(bias=self._bias(qs, qds, frames), mass=mass, minv=minv, phi=self._transition(minv, kp, kd, dt), kp=kp, kd=kd)
        plan = {key: v.reshape(b, steps, *v.shape[1:]) for key, v in terms.items()}
        plan.update(q=q_path, target=q_t.clone(), dg=self._gravity_jacobian(q), k=torch.zeros(b, dtype=torch.long, device=q.device))
        return plan

    def _path_step(self, q_m, qd_m, q_t, gains: TorchGains, state, ext, dt: float) -> tuple[tuple, torch.Tensor]:
        """(step matrices, feed-forward) for this physics step from the plan. Each row has its own
        step index and gets a new plan when its plan is used up, its target changed or its arm left
        the path by > ``path_tolerance`` (contact, saturation, latency): a row's plans depend on its
        own history only, so batched rows equal single runs."""
        p, steps, b = self._plan, self.path_steps, q_m.shape[0]
        r = self._rows(b, q_m.device)
        full, rows, pred = p is None or self._plan_dt != dt, None, None
        if not full:
            j = p["k"].clamp(max=steps - 1)
            off = (q_m - p["q"][r, j]).abs().amax(-1)
            need = (p["k"] >= steps) | (q_t != p["target"]).any(-1) | (off > self.config.path_tolerance)
            if bool(need.any()):
                rows = torch.nonzero(need)[:, 0]
                full = len(rows) == b
                # the previous plan's step nearest to now predicts the new path
                pred = (p["phi"][r, j], p["kp"][r, j])
        if full or rows is not None:
            extra = self.actuation.plant_inertia(state) if state is not None else None
            if full:
                self._plan, self._plan_dt = self._plan_path(q_m, qd_m, q_t, gains, extra, ext, dt, steps, pred), dt
                p = self._plan
            else:
                new = self._plan_path(q_m[rows], qd_m[rows], q_t[rows], gains.map(lambda x: x[rows]),
                                      None if extra is None else extra[rows], ext[rows], dt, steps,
                                      tuple(x[rows] for x in pred))
                for key, v in new.items():
                    p[key][rows] = v
        k = p["k"]
        mass, minv, phi, kp, kd = (p[key][r, k] for key in ("mass", "minv", "phi", "kp", "kd"))
        bias = p["bias"][r, k] + (p["dg"] @ (q_m - p["q"][r, k])[..., None])[..., 0]
        p["k"] = k + 1
        return (mass, minv, phi, dt, kp, kd, self._ticks(dt)), bias

    def _rows(self, b: int, device) -> torch.Tensor:
        if getattr(self, "_row_index", None) is None or len(self._row_index) != b:
            self._row_index = torch.arange(b, device=device)
        return self._row_index

    def _exact_torque(self, err: torch.Tensor, qd: torch.Tensor, qd_held: torch.Tensor, step: tuple, bias: torch.Tensor,
                      ext: torch.Tensor, within=None):
        """Motor torque (without feed-forward) that moves the plant to the closed loop's position after
        dt with one semi-implicit Euler step from the velocity the engine holds (``qd_held``), given
        that the plant also receives the load ``ext`` (last step's non-motor torque and the plant's
        known loads; a constant load moves the loop's equilibrium to e* = Kp^-1 load); also the
        predicted end and average velocities, and the step-average torque of the ``within``-step
        effects (None without them)."""
        mass, minv, phi, dt, kp, kd, ticks = step
        n = err.shape[1]
        e_star = torch.linalg.solve(kp, ext[..., None])[..., 0]
        x0 = torch.cat([err, qd], 1)
        x1 = (phi @ torch.cat([err - e_star, qd], 1)[..., None])[..., 0]
        x1[:, :n] += e_star
        # where the law saturates (checked at both ends of the step) the loop is not linear: run its
        # ticks explicitly with the clipped torque
        ends = torch.stack([x0, x1])
        tau_ends = -(kp @ ends[..., :n, None] + kd @ ends[..., n:, None])[..., 0] + bias
        sat = ((tau_ends > self.effort_limits) | (tau_ends < self._neg_effort_limits)).any(-1).any(0)
        f_step = None
        if within is not None:
            # the within-step effects' torque changes inside the step: run the law's ticks; rows
            # where they stay zero (effects at their off-values) keep the closed form bit for bit
            x_ticks, f_step = self._law_ticks(err, qd, minv, kp, kd, bias, ext, dt / ticks, ticks, within)
            rows = (f_step != 0).any(-1) | sat
            x1 = torch.where(rows[:, None], x_ticks, x1)
        elif bool(sat.any()):
            rows = torch.nonzero(sat)[:, 0]
            x1[rows] = self._law_ticks(err[rows], qd[rows], minv[rows] if minv.shape[0] > 1 else minv,
                                       kp[rows], kd[rows], bias[rows], ext[rows], dt / ticks, ticks)[0]
        v_avg = (x1[:, :n] - err) / dt
        tau = (mass @ ((v_avg - qd_held) / dt)[..., None])[..., 0] - ext
        if f_step is not None:
            tau = tau - f_step
        return tau, x1[:, n:], v_avg, f_step

    def _law_ticks(self, e, v, minv, kp, kd, bias, ext, t: float, ticks: int, within=None):
        """The law's ticks with its torque clipped to the effort limits, on M qdd = tau - bias + ext
        (+ the ``within``-step effects' torque at each tick). Returns the end state [e, v] and the
        within-step torque averaged over the ticks (None without ``within``)."""
        f_sum = None
        for _ in range(ticks):
            tau = -(kp @ e[..., None] + kd @ v[..., None])[..., 0] + bias
            tau = torch.maximum(torch.minimum(tau, self.effort_limits), self._neg_effort_limits)
            net = tau - bias + ext
            if within is not None:
                f = within(e, v, tau, t)
                f_sum = f if f_sum is None else f_sum + f
                net = net + f
            a = (minv @ net[..., None])[..., 0]
            e = e + t * v + (0.5 * t * t) * a
            v = v + t * a
        return torch.cat([e, v], 1), (None if f_sum is None else f_sum / ticks)

    def _within_step_torque(self, state: ControlState, err0: torch.Tensor, qd_offset: torch.Tensor):
        """(e, v, law torque, tick) -> the within-step stages' plant torque at that tick, from the true
        state the tick reaches (``qd_offset``: true minus measured velocity, held over the step)."""
        act, q0 = self.actuation, state.q

        def torque(e, v, tau, t):
            tick = ControlState(q=q0 + (e - err0), qd=v + qd_offset, q_target=state.q_target, dt=t, model=self.model,
                                time=state.time, extra={"tau_motor": tau, "bias": state.extra["bias"]})
            f = act.plant_torque(tick, within_step=True)
            return torch.zeros_like(e) if f is None else f

        return torque

    def _measured_feedforward_load(self, q, qd, q_m, qd_m, bias) -> torch.Tensor | float:
        """Where the controller measures a state other than the true one (encoder bias, backlash), its
        feed-forward (taken at the measured state) does not cancel the plant's own Coriolis and
        gravity (at the true state): the difference is a load on the true plant."""
        if q_m is q and qd_m is qd:
            return 0.0
        rows = ((q_m != q) | (qd_m != qd)).any(-1)
        if not bool(rows.any()):
            return 0.0
        return torch.where(rows[:, None], bias - self._bias(q, qd, self.model.link_frames(q)), 0.0)


def configure_arm_joints(joints_per_arm_joint, driver: DroidArmDriver) -> None:
    """Set the PhysX side of the driver's contract on SAPIEN joints: a zero-stiffness drive (carrying
    the implicit damping with ``integrator="implicit_damping"``, else none), the armature, no PhysX
    friction (the driver applies friction in N.m) and no link damping on the joint's child link.
    ``joints_per_arm_joint[i]`` is a list of ``PhysxArticulationJoint`` for arm joint i (one per env).
    """
    damping = driver.implicit_damping.cpu().numpy()
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


# ---------------------------------------------------------------------------- ManiSkill binding
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
        self.driver = DroidArmDriver(config.model_factory(), config.control, scene.num_envs, self.device, self.actuation)
        self.driver.allow_numpy = True
        self.driver.path_steps = self._sim_steps  # one plan per action
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
        else:  # physx_cpu: one articulation; numpy in/out, the same torch law
            obj = self.articulation._objs[0]
            if self._qf_cpu is None:
                idx = self._idx.cpu().numpy()
                contiguous = np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx)))
                self._idx_np = slice(int(idx[0]), int(idx[0]) + len(idx)) if contiguous else idx  # a view, no gather
                self._qf_cpu = np.zeros(obj.dof, dtype=np.float32)
            idx, drv = self._idx_np, self.driver
            q, qd = obj.qpos[idx][None], obj.qvel[idx][None]
            if drv._numpy_path():
                self._qf_cpu[idx] = drv.torque_numpy(q.astype(np.float64), qd.astype(np.float64), self._dt)[0]
            else:
                self._qf_cpu[idx] = drv.torque(torch.from_numpy(q), torch.from_numpy(qd), self._dt)[0].numpy()
            obj.qf = self._qf_cpu

    def get_state(self) -> dict:
        return {"target_qpos": self.driver.q_target}

    def set_state(self, state: dict):
        self.driver.set_target(state["target_qpos"])


DroidJointImpedanceControllerConfig.controller_cls = DroidJointImpedanceController
