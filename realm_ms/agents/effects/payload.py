"""An unmodelled payload: a point mass at the flange. Gravity compensation keeps the nominal model,
so the arm sags by J^T m g / Kp and accelerates more sluggishly (build time)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from realm_ms.agents.effects.effect import Effect, EffectConfig
from realm_ms.agents.effects.parameter import ParamSpec


@dataclass
class PayloadConfig(EffectConfig):
    offset: tuple[float, float, float] = (0.0, 0.0, 0.15)  # m, in the flange frame (about the TCP)


class Payload(Effect):
    name = "payload"
    summary = "payload at the flange"
    signature = "configuration-dependent sag following J^T m g (largest on joints 2 and 4), present at rest"
    order = 11
    build_time = True
    Config = PayloadConfig

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("mass", "kg", 0.5, 0.0, 3.0, 0.0, per_joint=False, doc="point mass at the flange offset")]

    def _point_jacobian(self, model, q: torch.Tensor) -> torch.Tensor:
        """Translational Jacobian (B, 3, n) of the point mass."""
        frames = model.link_frames(q)
        jac = model.jacobian(q, frames)
        tip = frames[:, -1] @ model.tip_offset
        r = tip[:, :3, :3] @ torch.as_tensor(self.config.offset, dtype=q.dtype, device=q.device)
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
        jp = self._point_jacobian(model, torch.cat([q, q + eps * qd, q - eps * qd])).view(3, b, 3, -1)
        bias_accel = ((jp[1] - jp[2]) @ qd[..., None])[..., 0] / (2 * eps)  # Jp' qd
        force = self._mass(q)[..., 0] * (model.gravity.to(q.dtype) - bias_accel)
        return (jp[0].transpose(1, 2) @ force[..., None])[..., 0]

    def build_target(self, target, row):
        target.add_point_mass(float(self.theta[row, 0]), np.asarray(self.config.offset, dtype=float))

    def evidence(self, values, features):
        return features.sentence_for(self, values)
