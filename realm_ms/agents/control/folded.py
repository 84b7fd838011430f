"""The exact step of the nominal robot (no actuation stages) folded into one affine map per physics
step, in float64 numpy: the benchmark's CPU env with a few envs. The law, its terms and their rates
are the shared ones (``law.py``, ``rates.py`` on the numpy backend); what is folded is
``integrators.Exact``'s step: one matmul per physics step instead of ~60 tiny array ops.
"""

from __future__ import annotations

import numpy as np
import torch

from realm_ms.agents.control.backend import NumpyBackend
from realm_ms.agents.control.law import friction, in_contact, land, law_ticks, tick_count
from realm_ms.agents.control.rates import rate_for

# the driver's state tensors the folded step keeps in one float32 buffer, in this order
STATE = ("velocity_correction", "motor_torque", "applied_torque", "plant_prev", "predicted_velocity")


def affine_step(kp, kd, mass, phi, bias, dg, q_ref, q_path, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The exact step (``Exact._step`` + feed-forward) as one affine map, batched over the leading
    axis: y = G z + c with z = [q - q*, qd, load, qd_held, q] (5n) and y = [law torque at the step's
    start, at its end, q - q_path (0 without a path), motor torque, velocity correction, step-average
    velocity] (6n). The closed loop's end state is x1 = Phi x0 + W load (W = (I - Phi)[:, :n] Kp^-1:
    the load's equilibrium shift), and the feed-forward is g0 + dg (q - q_ref) (dg None: g0)."""
    m, n = kp.shape[:2]
    eye = np.eye(n)
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
    c = bias
    if dg is not None:
        for i in (0, 1, 3):
            g[:, i * n : (i + 1) * n, 4 * n :] = dg
        c = bias - (dg @ q_ref[..., None])[..., 0]
    zero = np.zeros_like(c)
    return g, np.concatenate([c, c, zero if q_path is None else -q_path, c, zero, zero], 1)


class FoldedExact:
    """``integrators.Exact`` for the nominal robot as one affine map per step (numpy, float64)."""

    def __init__(self, drv):
        self.drv, self.be = drv, NumpyBackend(drv.model)
        f = lambda t: t.detach().cpu().double().numpy()  # noqa: E731
        self.gains, self.arm = drv.gains.map(f), np.diag(f(drv.armature))
        self.lim, self.neg_friction = f(drv.effort_limits), -f(drv.friction)
        self.inertia_lower_bound = f(drv.inertia_lower_bound)
        cfg = drv.config
        # no actuation stages: the tracked target is the driver's, changed only through ``retarget``
        self.rate = rate_for(cfg, self._extend_plan if cfg.follows_path else self._extend_terms, targets_move=False)
        self.bounds = np.concatenate([self.lim, self.lim, np.full_like(self.lim, cfg.path_tolerance), self.lim])
        self._views = self._state = self._time_of = None

    def _extend_plan(self, plan: dict, dt: float) -> None:
        b, steps = plan["kp"].shape[:2]
        flat = lambda x: x.reshape(b * steps, *x.shape[2:])  # noqa: E731
        qs = flat(plan["q"])
        g, c = affine_step(*(flat(plan[key]) for key in ("kp", "kd", "mass", "phi", "bias")), np.repeat(plan["dg"], steps, 0), qs, qs, dt)
        plan["affine"], plan["const"] = g.reshape(b, steps, *g.shape[1:]), c.reshape(b, steps, -1)

    @staticmethod
    def _extend_terms(t, dt: float) -> None:
        t["affine"], t["const"] = affine_step(t["kp"], t["kd"], t["mass"], t["phi"], t["bias"], t.dg, t.q_ref, None, dt)

    def state(self) -> np.ndarray:
        """One float32 buffer behind the driver's state tensors (``STATE``; reset() writes them in place)."""
        drv = self.drv
        if self._views is None or any(v is not getattr(drv, name) for v, name in zip(self._views, STATE)):
            buf = torch.cat([getattr(drv, name).float() for name in STATE], 1).contiguous()
            self._views = torch.chunk(buf, len(STATE), 1)
            for name, v in zip(STATE, self._views):
                setattr(drv, name, v)
            self._state = buf.numpy()
        return self._state

    def torque(self, q: np.ndarray, qd: np.ndarray, dt: float) -> np.ndarray:
        drv, be, cfg, n = self.drv, self.be, self.drv.config, q.shape[1]
        state = self.state()  # float32 [velocity correction, motor, applied, plant_prev torque, predicted velocity]
        qd_held, qd = qd, qd + state[:, :n]
        ext = state[:, 3 * n : 4 * n]
        q_t = drv.q_target.numpy()
        err = q - q_t
        z = np.concatenate([err, qd, ext, qd_held, q], 1)[..., None]
        # off-path rows show in y (checked below): the plan only compares the targets here
        t = self.rate.terms(be, q, qd, q_t, self.gains, self.arm, None, ext, dt, True, off=False)
        y = (t["affine"] @ z)[..., 0] + t["const"]
        # rows: law torque at the step's start and end, distance to the planned path, motor torque;
        # one bound check for all four (the common case: none is exceeded)
        tau = y[:, 3 * n : 4 * n]
        clamped, clip, bounds = tau, None, self.bounds
        if (np.abs(y[:, : 4 * n]) > bounds).any():
            off = (np.abs(y[:, 2 * n : 3 * n]) > bounds[2 * n : 3 * n]).any(-1)
            if cfg.follows_path and off.any():  # off the path: re-plan those rows
                self.rate.plan["k"] -= 1
                t = self.rate.terms(be, q, qd, q_t, self.gains, self.arm, None, ext, dt, True, off=off)
                y = (t["affine"] @ z)[..., 0] + t["const"]
                tau = y[:, 3 * n : 4 * n]
            sat = (np.abs(y[:, : 2 * n]) > bounds[: 2 * n]).any(-1)
            if sat.any():  # the law saturates within the step: its ticks with the clipped torque
                self._saturated_ticks(y, np.nonzero(sat)[0], err, qd, qd_held, ext, t, q, dt)
            clamped = np.minimum(np.maximum(tau, -self.lim), self.lim)
            clip = in_contact(be, tau, clamped, qd_held, state[:, 4 * n :], dt)  # clipped, no correction
            y[clip, 4 * n : 5 * n] = 0.0
        applied = tau if clip is None or not clip.any() else np.where(clip[:, None], clamped, tau)
        fric = friction(be, self.neg_friction, qd, drv.joint_physics.friction_velocity, self.inertia_lower_bound, dt)
        state[:, :n] = y[:, 4 * n : 5 * n]
        state[:, n : 2 * n] = clamped
        state[:, 2 * n : 3 * n] = out = applied + fric
        state[:, 3 * n : 4 * n] = fric
        state[:, 4 * n :] = y[:, 5 * n :]
        if self._time_of is not drv.time:  # advanced in place (reset() zeroes it in place)
            self._time_of, self._time = drv.time, drv.time.numpy()
        self._time += dt
        return out

    def _saturated_ticks(self, y, rows, err, qd, qd_held, ext, t, q, dt: float) -> None:
        """Rows of y (see ``torque``) where the law saturates, from its ticks with the clipped torque."""
        n, ticks = err.shape[1], tick_count(dt, self.drv.config.law_hz)
        bias, e, ext = t.bias_at(q)[rows], err[rows], ext[rows]
        x1 = law_ticks(self.be, e, qd[rows], t["minv"][rows], t["kp"][rows], t["kd"][rows], bias, ext, self.lim, dt / ticks, ticks)[0]
        tau, v_end, v_avg = land(x1, e, qd_held[rows], t["mass"][rows], ext, dt)
        y[rows, 3 * n : 4 * n] = tau + bias
        y[rows, 4 * n : 5 * n] = v_end - v_avg
        y[rows, 5 * n :] = v_avg
