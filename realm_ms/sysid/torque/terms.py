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
| armature | ia q̈ |
| payload | Jp^T m (a_p - g): a point mass m at com (flange frame), a_p = Jp q̈ + J̇p q̇ |
| gravity_comp_error | scale g_model(q) (the model's gravity is off by ``scale``) |
| link_mass | Σ_k s_k tau_k(q, q̇, q̈): link k's own inverse dynamics scaled by s_k (mass, first moment and
  inertia together, so every link stays physically consistent for s_k > -1: positive mass,
  positive-definite inertia, triangle inequalities) |

eps = 0.01 rad/s (the smooth sign). Tracking effects (latency, gain_mismatch, torque_limit,
backlash, encoder_bias) act through the position controller and have no torque-space form: they
need ``q_cmd`` (``TRACKING_ONLY``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import torch

from realm_ms.agents.effects.parameter import ParamSpec

EPS = 0.01  # rad/s, smooth sign of the friction laws
TRACKING_ONLY = ("latency", "gain_mismatch", "torque_limit", "backlash", "encoder_bias")


@dataclass
class Samples:
    """Torque-space samples, float64 torch tensors (N, 7) and the arm model."""

    q: torch.Tensor
    qd: torch.Tensor
    qdd: torch.Tensor
    arm: object
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


def armature(values, s, config):
    return _vec(values, "ia") * s.qdd


def gravity_error(values, s, config):
    g = s.cached("g", lambda: s.arm.gravity_torque(s.q))
    return values.get("scale", 0.0) * g


def payload(values, s, config, eps: float = 1e-4):
    m = values.get("mass", 0.0)
    if m == 0:
        return torch.zeros_like(s.q)
    com = torch.tensor([values.get(f"com_{a}", o) for a, o in zip("xyz", config.offset)], dtype=torch.float64)
    arm = s.arm

    def geometry():  # tip Jacobian and rotation at q, q + eps q̇, q - eps q̇ (independent of the payload)
        out = []
        for q in (s.q, s.q + eps * s.qd, s.q - eps * s.qd):
            frames = arm.link_frames(q)
            out.append((arm.jacobian(q, frames), (frames[:, -1] @ arm.tip_offset)[:, :3, :3]))
        return out

    geo = s.cached("payload_geometry", geometry)

    def jp(jac, rot):  # translational Jacobian of the point at ``com`` (flange frame)
        r = rot @ com
        return jac[:, :3] + torch.linalg.cross(jac[:, 3:], r[:, :, None].expand_as(jac[:, 3:]), dim=1)

    j0 = jp(*geo[0])
    jdot_qd = ((jp(*geo[1]) - jp(*geo[2])) @ s.qd[..., None])[..., 0] / (2 * eps)
    acc = (j0 @ s.qdd[..., None])[..., 0] + jdot_qd
    force = m * (acc - arm.gravity.to(torch.float64))
    return (j0.transpose(1, 2) @ force[..., None])[..., 0]


def link_torques(s: Samples) -> torch.Tensor:
    """(7 links, N, 7 joints): each link's own inverse dynamics (the others massless)."""
    def build():
        arm = s.arm
        masses, inertias = arm.masses.clone(), arm.inertias.clone()
        out = []
        try:
            for k in range(7):
                keep = torch.zeros_like(masses)
                keep[k] = 1.0
                arm.masses = masses * keep
                arm.inertias = inertias * keep[:, None, None]
                out.append(arm.rnea(s.q, s.qd, s.qdd))
        finally:
            arm.masses, arm.inertias = masses, inertias
        return torch.stack(out)
    return s.cached("links", build)


def link_mass(values, s, config):
    scale = _vec(values, "s")
    return torch.einsum("k,knj->nj", scale, link_torques(s))


#: effect name -> torque-space term
TERMS: dict[str, Callable] = {
    "coulomb_friction": coulomb, "viscous_damping": viscous, "stribeck_friction": stribeck, "armature": armature,
    "payload": payload, "gravity_comp_error": gravity_error, "link_mass": link_mass,
}

#: torque-space-only parameter specs (effects not in the simulation library)
EXTRA_SPECS = {
    "link_mass": [ParamSpec("s", "1", 0.2, -0.9, 2.0, 0.0, doc="relative change of link k's mass, first moment and "
                            "inertia (link k moves with joint k)")],
}
