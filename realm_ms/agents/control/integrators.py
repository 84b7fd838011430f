"""How the law's torque is integrated over a physics step: one strategy per
``DroidControlConfig.integrator``, on the batched torch backend with the actuation stages.

The real law runs at 1 kHz on a continuous plant; the benchmark steps PhysX at 120 Hz, where an
explicit damping torque on the light wrist is unstable (h*Kd/I ~ 4 for joint 7 with the gripper,
I ~ 5e-3 kg.m^2).

- ``Exact`` (default): over each physics step the closed loop of the law on the robot's model is
  linear (M, Kp, Kd held, the Coriolis/gravity feed-forward cancels the plant's), so its state after
  h is ``Phi x`` (``law.transition``). The driver applies the one torque that makes PhysX's
  semi-implicit Euler step land on that *position*; the velocity PhysX then holds is the step's
  average, and the difference to the predicted end velocity is carried to the next step's velocity
  estimate. This reproduces a 1 kHz controller on a continuous plant to < 1 mrad RMS at 120 Hz
  (MuJoCo reference, ``realm_ms/sysid/reference_mujoco.py``; docs/robot.md). Known plant inertia
  (joint armature, build-time effects) enters the prediction.
- ``ImplicitDamping``: the law's damping diagonal rides on PhysX's implicit joint drive (its
  ``drive_damping``) and the explicit torque pre-compensates it with +d*qd. Stable, but the drive
  acts on the *end* velocity, which adds an apparent armature d*h (0.025 kg.m^2 on joint 7 at 120
  Hz, 5x its inertia): 16-32 mrad RMS off the 1 kHz reference on 10 s excitation logs.
- ``Explicit``: the law as is, stable only at >= ~1 kHz.
"""

from __future__ import annotations

import torch

from realm_ms.agents.actuation import ControlState
from realm_ms.agents.control.law import feedforward, friction, in_contact, land, law_ticks, terms_at, tick_count


class Explicit:
    """The law's torque at the step's start, held over the step."""

    exact = False

    def drive_damping(self, drv, gains) -> torch.Tensor:
        """Damping PhysX's joint drive carries (N.m.s/rad per joint): none."""
        return torch.zeros(drv.model.dof, device=drv.device)

    def torque(self, drv, q, qd, dt: float) -> torch.Tensor:
        state, q_m, qd_m, q_t, gains = _measure(drv, q, qd, dt)
        t = drv.rate.terms(drv.be, q_m, qd_m, q_t, gains, drv.arm, None, None, dt, False)
        bias = t.bias_at(q_m)
        if state is not None:
            state.extra["bias"] = bias  # model feed-forward, reused by effects (saves them an RNEA)
            if drv.actuation.within_step:
                state.extra["plant"] = _plant(drv, state)
        tau = (t["kp"] @ (q_t - q_m)[..., None] - t["kd"] @ qd_m[..., None])[..., 0] + bias
        tau = _deliver(drv, drv.be.clip(tau, drv.neg_effort_limits, drv.effort_limits), None, qd, state, None, dt)
        drv.time = drv.time + dt
        return tau


class ImplicitDamping(Explicit):
    """The explicit law with its damping diagonal on PhysX's implicit drive."""

    def drive_damping(self, drv, gains) -> torch.Tensor:
        if drv.config.drive_damping is not None:
            return torch.as_tensor(drv.config.drive_damping, device=drv.device, dtype=torch.float32)
        q = torch.as_tensor(drv.config.reference_qpos, device=drv.device, dtype=torch.float32)[None]
        kd = terms_at(drv.be, drv.config, q, torch.zeros_like(q), gains.map(lambda g: g[:1]), drv.arm)["kd"]
        return torch.diagonal(kd[0]).clone()

    def torque(self, drv, q, qd, dt: float) -> torch.Tensor:
        # the implicit drive will apply about -d*qd; pre-compensate so the total matches the law
        return super().torque(drv, q, qd, dt) + drv.drive_damping * qd


class Exact(Explicit):
    """The torque that lands PhysX's step where the 1 kHz law's closed loop is after dt."""

    exact = True

    def torque(self, drv, q, qd, dt: float) -> torch.Tensor:
        be, act = drv.be, drv.actuation
        qd_held, qd = qd, qd + drv.velocity_correction  # the plant's velocity at the step start (PhysX holds the last step's average)
        state, q_m, qd_m, q_t, gains = _measure(drv, q, qd, dt)
        ext = drv.plant_prev  # torques the plant receives beyond the law's, as the exact step predicts them
        load = act.plant_load(state) if state is not None else None
        if load is not None:
            ext = ext + load
        extra = (lambda: act.plant_inertia(state)) if state is not None else None  # noqa: E731
        t = drv.rate.terms(be, q_m, qd_m, q_t, gains, drv.arm, extra, ext + drv.within_prev, dt, True)
        bias, within = t.bias_at(q_m), None
        if state is not None:
            state.extra["bias"] = bias
            ext = ext + _measured_feedforward_load(drv, q, qd, q_m, qd_m, bias)
            if act.within_step:
                within = _within_step_torque(drv, state, q_m - q_t, qd - qd_m, (t["mass"], t["minv"], ext))
        tau, v_end, v_avg, f_step = self._step(drv, q_m - q_t, qd_m, qd_held + (qd_m - qd), t, bias, ext, dt, within)
        tau = tau + bias
        clamped = be.clip(tau, drv.neg_effort_limits, drv.effort_limits)
        # (tested before the actuator stages, whose additions enter the next step as plant torque)
        clip = in_contact(be, tau, clamped, qd_held, drv.predicted_velocity, dt)[:, None]
        drv.velocity_correction = torch.where(clip, 0.0, v_end - v_avg)
        drv.predicted_velocity = v_avg
        excess = torch.where(clip, 0.0, tau - clamped)  # the step's torque beyond the limit
        tau = _deliver(drv, clamped, excess, qd, state, f_step, dt, within is not None)
        # all but the law's own torque (actuator stages included) and what the step predicted itself
        law = clamped + excess
        drv.plant_prev = tau - law if f_step is None else tau - law - f_step
        drv.within_prev = f_step if f_step is not None else drv.within_prev.zero_()
        drv.time = drv.time + dt
        return tau

    @staticmethod
    def _step(drv, err, qd, qd_held, t, bias, ext, dt: float, within=None):
        """Motor torque (without feed-forward) that moves the plant to the closed loop's position
        after dt with one semi-implicit Euler step from the velocity the engine holds (``qd_held``),
        given that the plant also receives the load ``ext`` (last step's non-motor torque and the
        plant's known loads; a constant load moves the loop's equilibrium to e* = Kp^-1 load); also
        the predicted end and average velocities, and the step-average torque of the ``within``-step
        effects (None without them)."""
        be, lim = drv.be, drv.effort_limits
        mass, minv, phi, kp, kd = t["mass"], t["minv"], t["phi"], t["kp"], t["kd"]
        n, ticks = err.shape[1], tick_count(dt, drv.config.law_hz)
        e_star = be.solve(kp, ext)
        x0 = torch.cat([err, qd], 1)
        x1 = (phi @ torch.cat([err - e_star, qd], 1)[..., None])[..., 0]
        x1[:, :n] += e_star
        # where the law saturates (checked at both ends of the step) the loop is not linear: run its
        # ticks explicitly with the clipped torque
        ends = torch.stack([x0, x1])
        tau_ends = -(kp @ ends[..., :n, None] + kd @ ends[..., n:, None])[..., 0] + bias
        sat = ((tau_ends > lim) | (tau_ends < drv.neg_effort_limits)).any(-1).any(0)
        f_step = None
        if within is not None:
            # the within-step effects' torque changes inside the step: run the law's ticks; rows
            # where they stay zero (effects at their off-values) keep the closed form bit for bit
            x_ticks, f_step = law_ticks(be, err, qd, minv, kp, kd, bias, ext, lim, dt / ticks, ticks, within)
            x1 = torch.where(((f_step != 0).any(-1) | sat)[:, None], x_ticks, x1)
        elif bool(sat.any()):
            rows = torch.nonzero(sat)[:, 0]
            x1[rows] = law_ticks(be, err[rows], qd[rows], minv[rows] if minv.shape[0] > 1 else minv,
                                 kp[rows], kd[rows], bias[rows], ext[rows], lim, dt / ticks, ticks)[0]
        tau, v_end, v_avg = land(x1, err, qd_held, mass, ext, dt)
        if f_step is not None:
            tau = tau - f_step
        return tau, v_end, v_avg, f_step


INTEGRATORS = {"exact": Exact, "implicit_damping": ImplicitDamping, "explicit": Explicit}


def _measure(drv, q, qd, dt: float):
    """(stage state or None, measured q, qd, commanded target, gains) after the actuation stages."""
    act = drv.actuation
    if not act:  # nominal robot: skip the stage plumbing (this runs 8x per action)
        return None, q, qd, drv.q_target, drv.gains
    state = ControlState(q=q, qd=qd, q_target=drv.q_target, dt=dt, model=drv.model, time=drv.time)
    q_m, qd_m = act.measure(q, qd, state)
    state.q_target = act.command(drv.q_target, state)
    return state, q_m, qd_m, state.q_target, act.gains(drv.gains)


def _deliver(drv, clamped, excess, qd, state, f_step, dt: float, within_step: bool = False):
    """The torque on the joints: the motor's (after the actuator stages; ``excess``: the exact
    step's torque beyond the limit), joint friction and the stages' plant torques."""
    act = drv.actuation
    if state is not None:
        clamped = act.actuator(clamped, state)
    tau = drv.motor_torque = clamped
    if excess is not None:
        tau = tau + excess
    # joint friction is physics, not command: it acts on the true velocity
    tau = tau + friction(drv.be, drv.neg_friction, qd, drv.joint_physics.friction_velocity, drv.inertia_lower_bound, dt)
    if state is not None:
        # within-step effects were integrated inside the exact step: their step-average torque
        plant = act.plant_torque(state, within_step=False if within_step else None)
        if plant is not None:
            tau = tau + plant
        if f_step is not None:
            tau = tau + f_step
    drv.applied_torque = tau
    return tau


def _plant(drv, state: ControlState):
    """(M, M⁻¹, loads) of the plant at the true state: the arm's mass matrix with armature and the
    stages' known plant inertia, and the loads the controller does not cancel, for the stages'
    implicit friction steps (the exact step hands over its own, ``_within_step_torque``)."""
    act, be = drv.actuation, drv.be
    mass = be.mass(be.kin(state.q)) + drv.arm
    extra, load = act.plant_inertia(state), act.plant_load(state)
    if extra is not None:
        mass = mass + extra
    return mass, be.inv(mass), torch.zeros_like(state.q) if load is None else load


def _within_step_torque(drv, state: ControlState, err0: torch.Tensor, qd_offset: torch.Tensor, plant):
    """(e, v, law torque, tick, net) -> the within-step stages' plant torque at that tick, from the
    true state the tick reaches (``qd_offset``: true minus measured velocity, held over the step).
    ``plant``: (M, M⁻¹, load) the ticks integrate M q̈ = τ − b + load + f on, for the stages' own
    implicit steps; ``net``: the tick's τ − b + load, which the law has already summed."""
    act, q0 = drv.actuation, state.q

    def torque(e, v, tau, t, net):
        tick = ControlState(q=q0 + (e - err0), qd=v + qd_offset, q_target=state.q_target, dt=t, model=drv.model,
                            time=state.time, extra={"tau_motor": tau, "bias": state.extra["bias"], "plant": plant,
                                                    "_plant_net": (tau, net)})
        f = act.plant_torque(tick, within_step=True)
        return torch.zeros_like(e) if f is None else f

    return torque


def _measured_feedforward_load(drv, q, qd, q_m, qd_m, bias) -> torch.Tensor | float:
    """Where the controller measures a state other than the true one (encoder bias, backlash), its
    feed-forward (taken at the measured state) does not cancel the plant's own Coriolis and
    gravity (at the true state): the difference is a load on the true plant."""
    if q_m is q and qd_m is qd:
        return 0.0
    rows = ((q_m != q) | (qd_m != qd)).any(-1)
    if not bool(rows.any()):
        return 0.0
    return torch.where(rows[:, None], bias - feedforward(drv.be, drv.config, drv.be.kin(q), qd), 0.0)
