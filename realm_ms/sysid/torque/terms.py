"""Torque-space models of the effects: the joint torque each one adds to the rigid-body model.

For data with measured joint torque (``tau``, N·m) the workbench compares the measurement with the
URDF's inverse dynamics, ``r = tau - (M(q) q̈ + C(q, q̇) q̇ + g(q))``, and explains ``r`` by terms
``tau_extra(params; q, q̇, q̈)``. The parameters are the library's (same names, units and bounds as
``realm sysid effects``), so a torque-space fit is saved in the same MODEL.yaml. Sign: the torque
the motors must *add* (friction has the sign of q̇, as in Gaz et al. 2019).

| effect | tau_extra |
|---|---|
| coulomb_friction | (fc + fc_asym tanh(q̇/v_d)) tanh(q̇/eps) |
| viscous_damping | b q̇ |
| stribeck_friction | fs (r + (1 - r) exp(-(q̇/vs)²)) tanh(q̇/eps) |
| smooth_friction | fc (tanh((q̇ + v0)/vs) − tanh(v0/vs)) |
| lugre_friction | σ₀ z + σ₁ ż + σ₂ q̇, the bristle z integrated along each trajectory's measured q̇ (stateful) |
| armature | ia q̈ |
| payload | Y_7(q, q̇, q̈) π_p: the standard parameters π_p of the payload (mass, CoM, inertia) on body 7 |
| gravity_comp_error | scale g_model(q) (the model's gravity is off by ``scale``) |
| link_mass | Σ_k Y_k(q, q̇, q̈) (π_k(params) - π_k,nominal): link k's corrected mass, CoM and inertia, physical for
  every value in bounds (``agents/effects/link_mass.py``) |

Y_k is body k's inverse-dynamics regressor (``agents/effects/inertial.py``), computed once per
sample set, so a fit of inertial parameters costs no dynamics evaluations.

eps = 0.01 rad/s (the smooth sign). Tracking effects (latency, target_filter, target_interpolation, gain_mismatch,
torque_limit, backlash, encoder_bias) act through the position controller and have no torque-space form: they
need ``q_cmd`` (``TRACKING_ONLY``: the library effects without a term here). ``TERMS`` is the one
table of each effect's torque; its evidence sentence is ``signatures.SENTENCES``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import torch

from realm_ms.agents.effects import arm_effects

EPS = 0.01  # rad/s, smooth sign of the friction laws


@dataclass
class Series:
    """One trajectory's whole (smoothed) velocity, for terms with a state along time (LuGre's
    bristle): ``scored`` is the slice of it that the samples hold."""

    qd: torch.Tensor  # (T, 7)
    dt: float
    scored: slice


@dataclass
class Samples:
    """Torque-space samples, float64 torch tensors (N, 7) and the arm model; ``series`` (the
    trajectories the samples were scored from, in order) and ``index`` (the samples kept when the
    scored set was thinned, None: all) for stateful terms."""

    q: torch.Tensor
    qd: torch.Tensor
    qdd: torch.Tensor
    arm: object
    series: list[Series] | None = None
    index: torch.Tensor | None = None
    _cache: dict | None = None

    def cached(self, key: str, fn: Callable[[], torch.Tensor]) -> torch.Tensor:
        if self._cache is None:
            self._cache = {}
        if key not in self._cache:
            with torch.inference_mode():
                self._cache[key] = fn()
        return self._cache[key]


def _sign(v):
    return torch.tanh(v / EPS)


def _vec(values: dict, name: str, default: float = 0.0) -> torch.Tensor:
    return torch.tensor([values.get(f"{name}{j}", default) for j in range(1, 8)], dtype=torch.float64)


def coulomb(values, s: Samples, config) -> torch.Tensor:
    fc, fa = _vec(values, "fc"), _vec(values, "fc_asym")
    dv = float(getattr(config, "direction_velocity", 0.01))
    return (fc + fa * torch.tanh(s.qd / dv)) * _sign(s.qd)


def viscous(values, s, config):
    return _vec(values, "b") * s.qd


def stribeck(values, s, config):
    fs, r, vs = _vec(values, "fs"), values.get("fc_ratio", 0.4), values.get("vs", 0.05)
    return fs * (r + (1 - r) * torch.exp(-((s.qd / vs) ** 2))) * _sign(s.qd)


def smooth(values, s, config):
    from realm_ms.agents.effects.smooth_friction import friction

    return friction(s.qd, _vec(values, "fc"), _vec(values, "vs", 0.1), _vec(values, "v0"))


def linear_recurrence(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """x_k = a_k x_(k-1) + b_k with x_(-1) = 0 along dim 0, by a parallel prefix scan (log2(T)
    vectorised passes instead of T Python steps); stable for 0 <= a <= 1."""
    a, b = a.clone(), b.clone()
    d = 1
    while d < len(a):
        b[d:] = a[d:] * b[:-d] + b[d:]  # right-hand sides are evaluated before the assignment
        a[d:] = a[d:] * a[:-d]
        d *= 2
    return b


def lugre(values, s, config):
    """σ₀ z + σ₁ ż + σ₂ q̇ with the bristle z integrated along each whole trajectory from z = 0, each
    sample interval advanced exactly with its end velocity held (``lugre_friction.py``); ż is the
    interval's mean. Needs the samples' time series (``Samples.series``)."""
    from realm_ms.agents.effects.lugre_friction import bristle_terms, mean_torque

    if s.series is None:
        raise ValueError("lugre_friction needs contiguous time series (its bristle state follows the velocity history)")
    fc, s2 = _vec(values, "fc"), _vec(values, "sigma2")
    if not bool((fc > 0).any()):
        return s2 * s.qd
    fs, vs = fc * values.get("fs_ratio", 1.5), values.get("vs", 0.05)
    s0, s1 = values.get("sigma0", 1000.0), values.get("sigma1", 1.0)
    out = []
    for tr in s.series:
        z_ss, decay, _, _ = bristle_terms(tr.qd, tr.dt, fc, fs, vs, s0)
        z = linear_recurrence(decay, (1 - decay) * z_ss)
        z = torch.where(fc > 0, z, torch.zeros_like(z))
        z_prev = torch.cat([torch.zeros_like(z[:1]), z[:-1]])
        out.append(mean_torque(z_prev, z, tr.qd, tr.dt, s0, s1, s2)[tr.scored])
    f = torch.cat(out)
    return f if s.index is None else f[s.index]


def armature(values, s, config):
    return _vec(values, "ia") * s.qdd


def gravity_error(values, s, config):
    g = s.cached("g", lambda: s.arm.gravity_torque(s.q))
    return values.get("scale", 0.0) * g


def body_regressor(s: Samples, body: int) -> torch.Tensor:
    """(N, 7, 10) inverse-dynamics regressor of one body at the samples (cached)."""
    from realm_ms.agents.effects.inertial import regressor

    return s.cached(f"regressor{body}", lambda: regressor(s.arm, s.q, s.qd, s.qdd, body))


def payload(values, s, config):
    from realm_ms.agents.effects.payload import payload_pi

    m = values.get("mass", 0.0)
    if m == 0:
        return torch.zeros_like(s.q)
    f64 = lambda keys, d: torch.tensor([[values.get(k, x) for k, x in zip(keys, d)]], dtype=torch.float64)  # noqa: E731
    com = f64([f"com_{a}" for a in "xyz"], config.offset)
    gyr = f64([f"gyr_{a}" for a in "xyz"], (0.0, 0.0, 0.0))
    pi = payload_pi(torch.tensor([m], dtype=torch.float64), com, gyr, s.arm.tip_offset.to(torch.float64))
    return body_regressor(s, 6) @ pi[0]


def link_mass(values, s, config):
    from realm_ms.agents.effects import inertial
    from realm_ms.agents.effects.link_mass import COM_KEYS, SHEAR_KEYS, STRETCH_KEYS, corrected

    names = ("s",) + COM_KEYS + STRETCH_KEYS + SHEAR_KEYS
    v = torch.stack([_vec(values, k) for k in names], -1)  # (7 links, 10)
    if not bool((v != 0).any()):
        return torch.zeros_like(s.q)
    arm = s.arm
    m0, c0, i0 = (x.to(torch.float64) for x in (arm.masses, arm.coms, arm.inertias))
    d = inertial.standard(*corrected(m0, c0, i0, v)) - inertial.standard(m0, c0, i0)  # (7, 10), 0 where unchanged
    # all links' regressors side by side, (N, 7, 70): one product per evaluation
    y = s.cached("link_regressors", lambda: torch.cat([inertial.regressor(arm, s.q, s.qd, s.qdd, k) for k in range(7)], -1))
    return y @ d.reshape(-1)


#: effect name -> torque-space term
TERMS: dict[str, Callable] = {
    "coulomb_friction": coulomb, "viscous_damping": viscous, "stribeck_friction": stribeck, "smooth_friction": smooth,
    "lugre_friction": lugre,
    "armature": armature, "payload": payload, "gravity_comp_error": gravity_error, "link_mass": link_mass,
}

#: library effects with no torque-space term: they act through the position controller (tracking)
#: and need ``q_cmd`` in the data
TRACKING_ONLY = tuple(n for n in arm_effects() if n not in TERMS)
