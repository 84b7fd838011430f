"""An unmodelled payload: a point mass at the flange with its centre of mass (``com_x/y/z``, m, in
the flange frame; fitted unless ``fit_com=false``). Gravity compensation keeps the nominal model,
so the arm sags by J^T m g / Kp and accelerates more sluggishly (build time).

A point mass is physically consistent by construction (mass >= 0, zero own inertia, PSD merged link
inertia). Its own rotational inertia about its centre of mass is left out: for a 1 kg, 10 cm part
it is ~2e-3 kg·m², below what 15 Hz position logs resolve next to m r² at r = 0.1-0.2 m."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from realm_ms.agents.effects.effect import Effect, EffectConfig
from realm_ms.agents.effects.parameter import ParamSpec


@dataclass
class PayloadConfig(EffectConfig):
    offset: tuple[float, float, float] = (0.0, 0.0, 0.15)  # m, in the flange frame: the CoM's start/default
    fit_com: bool = True  # fit the centre of mass (com_x/y/z) with the mass


class Payload(Effect):
    name = "payload"
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
        return [ParamSpec("mass", "kg", 0.5, 0.0, 3.0, 0.0, per_joint=False, doc="point mass at the centre of mass")] + com

    def _offset(self, like: torch.Tensor) -> torch.Tensor:
        """(B, 3) centre of mass in the flange frame, per row."""
        return torch.cat([self.p(f"com_{ax}", like=like) for ax in "xyz"], dim=1).to(like.dtype)

    def _point_jacobian(self, model, q: torch.Tensor, repeat: int = 1) -> torch.Tensor:
        """Translational Jacobian (B, 3, n) of the point mass (``repeat``: q stacks that many batches)."""
        frames = model.link_frames(q)
        jac = model.jacobian(q, frames)
        tip = frames[:, -1] @ model.tip_offset
        off = self._offset(q)
        off = off.repeat(repeat, 1) if off.shape[0] > 1 else off.expand(q.shape[0], -1)
        r = (tip[:, :3, :3] @ off[..., None])[..., 0]
        return jac[:, :3] + torch.linalg.cross(jac[:, 3:], r[:, :, None].expand_as(jac[:, 3:]), dim=1)

    def _mass(self, q: torch.Tensor) -> torch.Tensor:
        return self.p("mass", like=q).expand(q.shape[0], -1)[..., None]  # (B, 1, 1)

    def plant_inertia(self, state):
        """m Jp^T Jp of the point mass (Jp: its translational Jacobian), for the driver's prediction."""
        jp = self._point_jacobian(state.model, state.q)
        return self._mass(state.q) * (jp.transpose(1, 2) @ jp)

    def plant_load(self, state, eps: float = 1e-4):
        """Jp^T m (g - Jp' qd): the point mass's gravity and Coriolis/centrifugal load, which the
        controller's nominal feed-forward does not cancel (the time derivative of Jp along qd by
        central differences: one batched Jacobian for the three configurations)."""
        model, q, qd = state.model, state.q, state.qd
        b = q.shape[0]
        jp = self._point_jacobian(model, torch.cat([q, q + eps * qd, q - eps * qd]), 3).view(3, b, 3, -1)
        bias_accel = ((jp[1] - jp[2]) @ qd[..., None])[..., 0] / (2 * eps)  # Jp' qd
        force = self._mass(q)[..., 0] * (model.gravity.to(q.dtype) - bias_accel)
        return (jp[0].transpose(1, 2) @ force[..., None])[..., 0]

    def build_target(self, target, row):
        com = np.array([float(self.theta[row, self._slices[f"com_{ax}"]][0]) for ax in "xyz"])
        target.add_point_mass(float(self.theta[row, self._slices["mass"]][0]), com)

    def evidence(self, values, features):
        return features.sentence_for(self, values)
