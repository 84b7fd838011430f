"""An unmodelled payload: a rigid body at the flange with its mass, centre of mass (``com_x/y/z``, m,
in the flange frame; fitted unless ``fit_com=false``) and rotational inertia (``gyr_x/y/z``: the
standard deviation of its mass distribution along the flange axes, so ``Σ = m diag(gyr²)`` and
``I_c = tr(Σ) 1 - Σ``; fitted with ``fit_inertia=true``). Gravity compensation keeps the nominal
model, so the arm sags by J^T m g / Kp and accelerates more sluggishly (build time).

Physically consistent for every value in bounds: mass >= 0, I_c positive semidefinite and within
the triangle inequalities by construction (``inertial.py``); the principal axes are the flange's.
With ``gyr = 0`` (the default) it is a point mass: the inertia of a 1 kg, 10 cm part about its CoM
(~2e-3 kg·m²) is below what 15 Hz position logs resolve next to m r² at r = 0.1-0.2 m, but a
torque log at 1 kHz sees it.

Its dynamics is that of the standard parameters it adds to body 7 (``inertial.regressor``), so
the driver's prediction (``plant_inertia``, ``plant_load``) and the torque-space term agree."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from realm_ms.agents.effects import inertial
from realm_ms.agents.effects.effect import Effect, EffectConfig
from realm_ms.agents.effects.parameter import ParamSpec


@dataclass
class PayloadConfig(EffectConfig):
    offset: tuple[float, float, float] = (0.0, 0.0, 0.15)  # m, in the flange frame: the CoM's start/default
    fit_com: bool = True  # fit the centre of mass (com_x/y/z) with the mass
    fit_inertia: bool = False  # fit the rotational inertia (gyr_x/y/z) too


def payload_pi(mass: torch.Tensor, com: torch.Tensor, gyr: torch.Tensor, tip_offset: torch.Tensor) -> torch.Tensor:
    """(B, 10) standard parameters a payload adds to body 7: mass (B,), CoM and gyration (B, 3) in
    the flange frame, ``tip_offset`` body 7 -> flange (4, 4)."""
    rot, pos = tip_offset[:3, :3].to(com.dtype), tip_offset[:3, 3].to(com.dtype)
    r = com @ rot.T + pos
    sigma = torch.diag_embed(mass[:, None] * gyr**2)
    return inertial.standard(mass, r, rot @ inertial.inertia_of(sigma) @ rot.T)


class Payload(Effect):
    name = "payload"
    step_cost = (4.5, 0.0)
    summary = "payload at the flange"
    signature = "configuration-dependent sag following J^T m g (largest on joints 2 and 4), present at rest"
    order = 11
    build_time = True
    Config = PayloadConfig

    @classmethod
    def param_specs(cls, config):
        off = tuple(float(x) for x in config.offset)
        bounds = ((-0.3, 0.3), (-0.3, 0.3), (-0.15, 0.45))
        com = [ParamSpec(f"com_{ax}", "m", o, lo, hi, o, per_joint=False, fit_by_default=config.fit_com,
                         doc=f"payload centre of mass, {ax} in the flange frame")
               for ax, o, (lo, hi) in zip("xyz", off, bounds)]
        gyr = [ParamSpec(f"gyr_{ax}", "m", 0.03, 0.0, 0.15, 0.0, per_joint=False, fit_by_default=config.fit_inertia,
                         doc=f"spread of the payload's mass along flange {ax} (standard deviation; 0: point mass)")
               for ax in "xyz"]
        return [ParamSpec("mass", "kg", 0.5, 0.0, 3.0, 0.0, per_joint=False, doc="payload mass")] + com + gyr

    def pi(self, model, like: torch.Tensor) -> torch.Tensor:
        """(B, 10) standard parameters added to body 7, in ``like``'s dtype."""
        cat = lambda keys: torch.cat([self.p(k, like=like) for k in keys], dim=1).to(like.dtype)  # noqa: E731
        return payload_pi(self.p("mass", like=like)[:, 0].to(like.dtype), cat([f"com_{a}" for a in "xyz"]),
                          cat([f"gyr_{a}" for a in "xyz"]), model.tip_offset)

    def plant_inertia(self, state):
        """The payload's joint-space inertia, for the driver's prediction."""
        return inertial.body_mass_matrix(state.model, state.q, state.model.dof - 1, self.pi(state.model, state.q))

    def plant_load(self, state):
        """The payload's gravity and Coriolis/centrifugal load, which the controller's nominal
        feed-forward does not cancel."""
        q = state.q
        y = inertial.regressor(state.model, q, state.qd, None, state.model.dof - 1)
        return -(y @ self.pi(state.model, q).expand(q.shape[0], -1)[..., None])[..., 0]

    def build_target(self, target, row):
        v = {k: float(self.theta[row, self._slices[k]][0]) for k in self._slices}
        com = np.array([v[f"com_{ax}"] for ax in "xyz"])
        sigma = v["mass"] * np.diag([v[f"gyr_{ax}"] ** 2 for ax in "xyz"])
        target.add_body(v["mass"], com, np.trace(sigma) * np.eye(3) - sigma)
