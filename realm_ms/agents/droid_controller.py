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
    # "physics": J, C(q, qd) and g(q) from the model every physics step (as Polymetis at 1 kHz).
    # "control": refreshed once per control step, gravity corrected to first order in between;
    # the feedback on q, qd still runs every physics step. Faster on CPU; see bench/step_rate.py.
    model_rate: str = "physics"
    law_hz: float = 1000.0  # "exact": the controller rate it reproduces (Polymetis / libfranka: 1 kHz)

    def __post_init__(self):
        if self.implicit_damping is not None:  # legacy boolean wins when given
            self.integrator = "implicit_damping" if self.implicit_damping else "explicit"
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {self.integrator!r}")


INTEGRATORS = ("exact", "implicit_damping", "explicit")


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
        self._terms = None  # cached (kp, kd, bias, q_ref, dg/dq) for model_rate="control"
        if config.model_rate not in ("physics", "control"):
            raise ValueError(f"model_rate must be 'physics' or 'control', got {config.model_rate!r}")
        self.time = torch.zeros(num_envs, device=self.device)
        self.motor_torque = torch.zeros(num_envs, model.dof, device=self.device)  # commanded after limits/actuator
        self.applied_torque = torch.zeros(num_envs, model.dof, device=self.device)  # + joint friction and plant effects
        # "exact": predicted end-of-step velocity minus the step-average velocity PhysX holds
        self.velocity_correction = torch.zeros(num_envs, model.dof, device=self.device)
        # "exact": last step's torques beyond the motor's (joint friction, plant effects), which the
        # closed loop is predicted to react to within the step (a constant load shifts its equilibrium)
        self.plant_prev = torch.zeros(num_envs, model.dof, device=self.device)
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
        self._terms = None
        self.motor_torque[idx] = 0.0
        self.applied_torque[idx] = 0.0
        self.velocity_correction[idx] = 0.0
        self.plant_prev[idx] = 0.0
        self.actuation.reset(self.num_envs, self.device, env_idx, q[:, : self.model.dof])

    def set_target(self, q_target: torch.Tensor) -> None:
        q_target = q_target.to(self.device, torch.float32)
        # a new command refreshes J, C, g (model_rate="control") and Phi ("exact"); a replay that
        # re-sends the held command every physics step keeps them, as the benchmark does
        if q_target.shape != self.q_target.shape or not torch.equal(q_target, self.q_target):
            self._terms = None
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
        jac = self.model.jacobian(q, frames)
        jt = jac.transpose(1, 2)
        kp = torch.diag_embed(gains.kq) + jt @ (gains.kx[..., None] * jac)
        kd = torch.diag_embed(gains.kqd) + jt @ (gains.kxd[..., None] * jac)
        return kp, kd, self._bias(q, qd, frames)

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
        if exact:
            # the closed loop's transition over this step from J(q), M(q) (model_rate="physics"), or
            # once per target (model_rate="control": cheaper, ~1-2 mrad RMS further from the 1 kHz law)
            if self.config.model_rate == "physics" or self._terms is None:
                frames = self.model.link_frames(q_m)
                kp, kd, bias = self._law_terms(q_m, qd_m, gains, frames)
                step = self._step_matrices(kp, kd, self._plant_mass(q_m, frames, state if act else None), dt)
                if self.config.model_rate == "control":
                    self._terms = (step, bias, q_m.clone(), self._gravity_jacobian(q_m))
            if self.config.model_rate == "control":
                step, bias, q_ref, dg = self._terms
                bias = bias + (dg @ (q_m - q_ref)[..., None])[..., 0]
        else:
            if self.config.model_rate == "physics" or self._terms is None:
                kp, kd, bias = self._law_terms(q_m, qd_m, gains)
                if self.config.model_rate == "control":
                    self._terms = (kp, kd, bias, q_m.clone(), self._gravity_jacobian(q_m))
            if self.config.model_rate == "control":
                kp, kd, bias, q_ref, dg = self._terms
                bias = bias + (dg @ (q_m - q_ref)[..., None])[..., 0]  # first-order gravity between refreshes
        if act:
            state.extra["bias"] = bias  # model feed-forward, reused by effects (saves them an RNEA)
        if exact:
            tau, v_end, v_avg = self._exact_torque(q_m - q_t, qd_m, qd_held + (qd_m - qd), step, bias)
            tau = tau + bias
        else:
            tau = (kp @ (q_t - q_m)[..., None] - kd @ qd_m[..., None])[..., 0] + bias
        clamped = torch.clamp(tau, self._neg_effort_limits, self.effort_limits)
        if act:
            clamped = act.actuator(clamped, state)
        if exact:
            # where the torque was limited the prediction does not hold: no correction there
            held = ((clamped - tau).abs() < 1e-4).all(-1, keepdim=True)
            self.velocity_correction = torch.where(held, v_end - v_avg, 0.0)
        tau = self.motor_torque = clamped
        # joint friction is physics, not command: it acts on the true velocity
        friction = self._neg_friction * torch.tanh(qd / self.joint_physics.friction_velocity)
        tau = tau + limit_dissipative(friction, qd, self.inertia_lower_bound, dt)
        if act:
            plant = act.plant_torque(state)
            if plant is not None:
                tau = tau + plant
        self.applied_torque = tau
        if exact:
            self.plant_prev = tau - self.motor_torque
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
        """``torque`` for the nominal exact law, in float64 numpy (same equations)."""
        from realm_ms.agents.arm_model import NumpyArmModel

        if getattr(self, "_np", None) is None:
            f = lambda t: t.detach().cpu().double().numpy()  # noqa: E731
            self._np = dict(model=NumpyArmModel(self.model), kq=f(self.gains.kq), kqd=f(self.gains.kqd),
                            kx=f(self.gains.kx), kxd=f(self.gains.kxd), arm=np.diag(f(self.armature)),
                            lim=f(self.effort_limits), fric=f(self.friction), inertia_lb=f(self.inertia_lower_bound))
        k, cfg = self._np, self.config
        npm = k["model"]
        n = q.shape[1]
        vc = self.velocity_correction.double().numpy()
        qd_held, qd = qd, qd + vc
        ticks = max(1, round(dt * cfg.law_hz))
        t = dt / ticks
        if cfg.model_rate == "physics" or self._terms is None:
            frames = npm.link_frames(q)
            jac = npm.jacobian(frames)
            jt = jac.transpose(0, 2, 1)
            kp = k["kq"][:, :, None] * np.eye(n) + jt @ (k["kx"][..., None] * jac)
            kd = k["kqd"][:, :, None] * np.eye(n) + jt @ (k["kxd"][..., None] * jac)
            bias, mass = npm.bias_and_mass(frames, qd if cfg.coriolis_feedforward else np.zeros_like(qd), cfg.gravity_compensation)
            if not (cfg.coriolis_feedforward or cfg.gravity_compensation):
                bias = np.zeros_like(q)
            mass = mass + k["arm"]
            minv = np.linalg.inv(mass)
            p_, d_ = minv @ kp, minv @ kd
            eye = k.setdefault("eye", np.eye(n))
            phi = np.empty((q.shape[0], 2 * n, 2 * n))
            phi[:, :n, :n] = eye - 0.5 * t * t * p_
            phi[:, :n, n:] = t * eye - 0.5 * t * t * d_
            phi[:, n:, :n] = -t * p_
            phi[:, n:, n:] = eye - t * d_
            phi = np.linalg.matrix_power(phi, ticks)
            if cfg.model_rate == "control":  # refreshed per target, gravity to first order in between
                self._terms = (kp, kd, bias, mass, minv, phi, q.copy(), self._gravity_jacobian_numpy(q))
        else:
            kp, kd, bias, mass, minv, phi, q_ref, dg = self._terms
            bias = bias + (dg @ (q - q_ref)[..., None])[..., 0]
        err = q - self.q_target.double().numpy()
        ext = self.plant_prev.double().numpy()
        e_star = np.linalg.solve(kp, ext[..., None])[..., 0]
        x0 = np.concatenate([err, qd], 1)
        x1 = (phi @ np.concatenate([err - e_star, qd], 1)[..., None])[..., 0]
        x1[:, :n] += e_star
        lim = k["lim"]
        ends = np.stack([x0, x1])
        tau_ends = -(kp @ ends[..., :n, None] + kd @ ends[..., n:, None])[..., 0] + bias
        sat = (np.abs(tau_ends) > lim).any(-1).any(0)
        for r in np.nonzero(sat)[0]:  # the law saturates: its ticks with the clipped torque
            e, v = err[r], qd[r]
            for _ in range(ticks):
                tau = np.clip(-(kp[r] @ e + kd[r] @ v) + bias[r], -lim, lim)
                a = minv[r] @ (tau - bias[r] + ext[r])
                e, v = e + t * v + 0.5 * t * t * a, v + t * a
            x1[r] = np.concatenate([e, v])
        v_avg = (x1[:, :n] - err) / dt
        tau = (mass @ ((v_avg - qd_held) / dt)[..., None])[..., 0] + bias - ext
        clamped = np.clip(tau, -lim, lim)
        held = (np.abs(clamped - tau) < 1e-4).all(-1, keepdims=True)
        self.velocity_correction = torch.from_numpy(np.where(held, x1[:, n:] - v_avg, 0.0).astype(np.float32))
        self.motor_torque = torch.from_numpy(clamped.astype(np.float32))
        friction = -k["fric"] * np.tanh(qd / self.joint_physics.friction_velocity)
        cap = k["inertia_lb"] * np.abs(qd) / dt
        out = clamped + np.clip(friction, -cap, cap)
        self.applied_torque = torch.from_numpy(out.astype(np.float32))
        self.plant_prev = torch.from_numpy((out - clamped).astype(np.float32))
        self.time = self.time + dt
        return out

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
        n = kp.shape[1]
        ticks = max(1, round(dt * self.config.law_hz))
        t = dt / ticks
        p, d = minv @ kp, minv @ kd
        eye = self._eye.to(kp.dtype)
        phi = torch.empty(kp.shape[0], 2 * n, 2 * n, device=kp.device, dtype=kp.dtype)
        phi[:, :n, :n] = eye - (0.5 * t * t) * p
        phi[:, :n, n:] = t * eye - (0.5 * t * t) * d
        phi[:, n:, :n] = -t * p
        phi[:, n:, n:] = eye - t * d
        return mass, minv, torch.linalg.matrix_power(phi, ticks), dt, kp, kd, ticks

    def _exact_torque(self, err: torch.Tensor, qd: torch.Tensor, qd_held: torch.Tensor, step: tuple, bias: torch.Tensor):
        """Motor torque (without feed-forward) that moves the plant to the closed loop's position after
        dt with one semi-implicit Euler step from the velocity the engine holds (``qd_held``), given
        that the plant also receives about last step's non-motor torque ``plant_prev`` (a constant
        load moves the loop's equilibrium to e* = Kp^-1 load); also the predicted end and average
        velocities."""
        mass, minv, phi, dt, kp, kd, ticks = step
        n = err.shape[1]
        ext = self.plant_prev
        e_star = torch.linalg.solve(kp, ext[..., None])[..., 0]
        x0 = torch.cat([err, qd], 1)
        x1 = (phi @ torch.cat([err - e_star, qd], 1)[..., None])[..., 0]
        x1[:, :n] += e_star
        # where the law saturates (checked at both ends of the step) the loop is not linear: run its
        # ticks explicitly with the clipped torque
        ends = torch.stack([x0, x1])
        tau_ends = -(kp @ ends[..., :n, None] + kd @ ends[..., n:, None])[..., 0] + bias
        sat = ((tau_ends > self.effort_limits) | (tau_ends < self._neg_effort_limits)).any(-1).any(0)
        if bool(sat.any()):
            rows = torch.nonzero(sat)[:, 0]
            x1[rows] = self._saturated_ticks(err[rows], qd[rows], minv[rows] if minv.shape[0] > 1 else minv,
                                             kp[rows], kd[rows], bias[rows], ext[rows], dt / ticks, ticks)
        v_avg = (x1[:, :n] - err) / dt
        tau = (mass @ ((v_avg - qd_held) / dt)[..., None])[..., 0] - ext
        return tau, x1[:, n:], v_avg

    def _saturated_ticks(self, e, v, minv, kp, kd, bias, ext, t: float, ticks: int) -> torch.Tensor:
        """The law's ticks with its torque clipped to the effort limits, on M qdd = tau - bias + ext."""
        for _ in range(ticks):
            tau = -(kp @ e[..., None] + kd @ v[..., None])[..., 0] + bias
            tau = torch.maximum(torch.minimum(tau, self.effort_limits), self._neg_effort_limits)
            a = (minv @ (tau - bias + ext)[..., None])[..., 0]
            e = e + t * v + (0.5 * t * t) * a
            v = v + t * a
        return torch.cat([e, v], 1)


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
            lo = torch.as_tensor(self.single_action_space.low, device=action.device)
            hi = torch.as_tensor(self.single_action_space.high, device=action.device)
            action = torch.maximum(torch.minimum(action, hi), lo)
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
                self._idx_np = self._idx.cpu().numpy()
                self._qf_cpu = np.zeros(obj.dof, dtype=np.float32)
            idx = self._idx_np
            q, qd = torch.from_numpy(obj.qpos[idx][None]), torch.from_numpy(obj.qvel[idx][None])
            self._qf_cpu[idx] = self.driver.torque(q, qd, self._dt)[0].numpy()
            obj.qf = self._qf_cpu

    def get_state(self) -> dict:
        return {"target_qpos": self.driver.q_target}

    def set_state(self, state: dict):
        self.driver.set_target(state["target_qpos"])


DroidJointImpedanceControllerConfig.controller_cls = DroidJointImpedanceController
