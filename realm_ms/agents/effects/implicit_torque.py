"""Semi-implicit integration of friction-like joint torques (the base of Coulomb, Stribeck and
viscous friction): stable at 120 Hz on the light wrist joints where an explicit law explodes."""

from __future__ import annotations

from types import SimpleNamespace

import torch

from realm_ms.agents.actuation import ControlState
from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.model_terms import model_bias, scatter_rows


class ImplicitJointTorque(Effect):
    """Base of friction-like effects that must stay stable at 120 Hz on light wrist joints.

    An explicit friction torque -F tanh(qd/eps) with eps small is a stiff damper (h F / (eps I) >> 2
    on joint 7, I ~ 5e-3 kg.m^2) and explodes. These effects are integrated *semi-implicitly* per
    joint with the joint's apparent inertia I_j = 1/(M^-1)_jj: the velocity the joint would reach
    this step without the effect is v_free = qd + h (tau_motor - b_model(q, qd)) / I_j, and the
    effect's torque is computed from v_free (Karnopp stick-slip for dry friction, backward Euler
    for viscous damping). I_j is evaluated at the configuration of each reset (a few percent error
    along a segment only softens the stick phase, it never destabilises it: a 0.8 safety factor
    keeps the deadbeat stop from overshooting).

    Effects with ``coupled = True`` (viscous damping, smooth friction: steep viscous slopes) take
    a backward-Euler step with the whole mass matrix instead (``coupled_torque``) whenever the
    tick's motor torque is known: the joints are coupled through M, and the per-joint step misses it.

    With the exact integrator (the default) the driver evaluates these effects at every 1 kHz tick
    of the law inside the physics step (``within_step``), from the tick's velocity and law torque:
    a friction torque held over a whole 8.3 ms step, or lagged by one, cannot follow the wrist's
    loop, which settles within a step (h Kd / I ~ 3), and sticks or slides at the wrong moments.
    The driver then also hands over the plant it integrates the ticks on (``state.extra["plant"]``:
    M with the known plant inertia, M⁻¹, and the loads beyond the law, such as a payload's
    gravity), and the step uses those: with the nominal M and no load, a payload the controller
    does not compensate reads as motion the friction must stop, and the arm holds still where it
    should sag or slides where it should stick.
    """

    order = 90
    within_step = True
    SAFETY = 0.8

    def reset(self, num_envs, device, env_idx, q):
        self._num_envs = num_envs
        if env_idx is None or getattr(self, "_inertia", None) is None or self._inertia.shape[0] != num_envs:
            self._inertia = None
        else:
            self._stale[env_idx] = True

    def _joint_inertia(self, state: ControlState) -> torch.Tensor:
        """SAFETY / (M^-1)_jj for every env (rows where the effect is off keep a placeholder 1)."""
        rows = self.active_rows(state.q.device)
        if getattr(self, "_inertia", None) is None or self._inertia.shape[0] != state.q.shape[0]:
            self._inertia = torch.ones_like(state.q)
            self._mass = torch.eye(state.q.shape[1], dtype=state.q.dtype, device=state.q.device).repeat(state.q.shape[0], 1, 1)
            self._stale = torch.ones(state.q.shape[0], dtype=torch.bool, device=state.q.device)
        need = self._stale.clone()
        if rows is not None:
            mask = torch.zeros_like(need)
            mask[rows] = True
            need &= mask
        if bool(need.any()):
            idx = torch.nonzero(need)[:, 0]
            mass = state.model.mass_matrix(state.q[idx])
            minv = torch.linalg.inv(mass)
            self._mass[idx] = mass.to(self._mass.dtype)
            self._inertia[idx] = self.SAFETY / torch.diagonal(minv, dim1=1, dim2=2)
            self._stale[idx] = False
        return self._inertia

    def mass_matrix(self, state: ControlState, rows: torch.Tensor | None = None) -> torch.Tensor:
        """The arm's mass matrix M(q) at the configuration of each reset (cached with I_j), on ``rows``."""
        self._joint_inertia(state)
        return self._mass if rows is None else self._mass[rows]

    def actuator(self, tau, state):
        state.extra["tau_motor"] = tau
        return tau

    def plant(self, state: ControlState, rows: torch.Tensor | None = None):
        """(M, M⁻¹, net torque τ_motor − b(q, q̇) + loads) of the plant the driver integrates this
        tick, on ``rows``; None when the driver gave no plant (the step's M is then the nominal
        arm's at the segment's reset, and no load is known)."""
        plant, tau = state.extra.get("plant"), state.extra.get("tau_motor")
        if plant is None or tau is None:
            return None
        mass, minv, ext, _ = self._step_plant(plant, state.q.shape[0], rows)
        # every within-step effect of this tick reads the same net torque: computed once per tick
        # (the driver's ticks hand over the law's own sum)
        cached = state.extra.get("_plant_net")
        if cached is not None and cached[0] is tau:
            net = cached[1]
        else:
            net = tau - model_bias(state) + ext
            state.extra["_plant_net"] = (tau, net)
        return mass, minv, net if rows is None else net[rows]

    def _step_plant(self, plant: tuple, b: int, rows: torch.Tensor | None) -> list:
        """[M, M⁻¹ (on ``rows``), loads (all rows), I_j (on ``rows``, filled on first use)] of the
        driver's plant: one tuple per physics step, the same at each of its ticks, so sliced once
        per step rather than once per tick."""
        c = self.__dict__.get("_step_plant_cache")
        if c is not None and c[0] is plant and c[1] is rows:
            return c[2]
        mass, minv, ext = (x.expand(b, *x.shape[1:]) if x.shape[0] != b else x for x in plant)
        if rows is not None:
            mass, minv = mass[rows], minv[rows]
        out = [mass, minv, ext, None]
        self._step_plant_cache = (plant, rows, out)
        return out

    def free_velocity(self, state: ControlState, rows: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """(v_free, I_j) on ``rows``: the velocity this step would end with without this effect,
        and the apparent inertia SAFETY / (M⁻¹)_jj of each joint."""
        qd = state.qd if rows is None else state.qd[rows]
        plant = self.plant(state, rows)
        if plant is not None:
            _, minv, net = plant
            return self._free_from_plant(state, rows, qd, minv.to(qd.dtype), net.to(qd.dtype))
        inertia = self._joint_inertia(state)
        if rows is not None:
            inertia = inertia[rows]
        tau = state.extra.get("tau_motor")
        if tau is None:
            return qd, inertia
        if rows is not None:
            tau = tau[rows]
        net = tau - model_bias(state, rows)
        return qd + state.dt * net / inertia, inertia

    def _free_from_plant(self, state, rows, qd, minv, net) -> tuple[torch.Tensor, torch.Tensor]:
        """(v_free = q̇ + h M⁻¹ net, I_j = SAFETY / (M⁻¹)_jj) on the driver's plant (I_j once per step)."""
        step = self._step_plant(state.extra["plant"], state.q.shape[0], rows)
        if step[3] is None or step[3].dtype != qd.dtype:
            step[3] = self.SAFETY / torch.diagonal(minv, dim1=1, dim2=2)
        return qd + state.dt * (minv @ net.unsqueeze(-1)).squeeze(-1), step[3]

    #: the effect has a backward-Euler step coupled through the whole mass matrix (``coupled_torque``)
    coupled = False

    def plant_torque(self, state):
        rows = self.active_rows(state.q.device)
        if rows is not None and rows.numel() == 0:
            return None
        tau = state.extra.get("tau_motor")
        if self.coupled and tau is not None:
            qd = state.qd if rows is None else state.qd[rows]
            plant = self.plant(state, rows)
            if plant is None:
                mass, inertia = self.mass_matrix(state, rows).to(qd.dtype), None
                net = ((tau if rows is None else tau[rows]) - model_bias(state, rows)).to(qd.dtype)
                v_free = qd + state.dt * torch.linalg.solve(mass, net)
            else:
                mass, minv, net = (x.to(qd.dtype) for x in plant)
                v_free, inertia = self._free_from_plant(state, rows, qd, minv, net)
            return scatter_rows(state.q, rows, self.coupled_torque(state, rows, qd, mass, net, v_free, inertia))
        # no motor torque this tick, or a per-joint effect: the per-joint form
        v_free, inertia = self.free_velocity(state, rows)
        return scatter_rows(state.q, rows, self.friction_torque(v_free, inertia, state, rows))

    def coupled_torque(self, state, rows, qd, mass, net, v_free, inertia) -> torch.Tensor:
        """The effect's torque on ``rows`` from a step coupled through M: q̇, M, the net torque
        τ_motor − b(q, q̇), the free end velocity v_free = q̇ + h M⁻¹ net on those rows, and the
        apparent inertia I_j of ``free_velocity`` where the driver handed over its plant (None: M is
        the nominal arm's at the segment's reset)."""
        raise NotImplementedError

    def friction_torque(self, v_free, inertia, state, rows) -> torch.Tensor:
        raise NotImplementedError

    def sliding_friction(self, v: torch.Tensor) -> torch.Tensor:
        """The torque that keeps each joint sliding at v (same sign as v): the per-joint step with a
        huge inertia over 1 s, so nothing sticks within it. Laws with state override it with their
        settled state."""
        state = SimpleNamespace(qd=v, dt=1.0)  # what the memoryless laws read
        return -self.friction_torque(v, torch.full_like(v, 1e12), state, None)
