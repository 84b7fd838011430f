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

    def plant_inertia(self, state):
        """m Jp^T Jp of the point mass (Jp: its translational Jacobian), for the driver's prediction."""
        model, q = state.model, state.q
        frames = model.link_frames(q)
        jac = model.jacobian(q, frames)
        tip = frames[:, -1] @ model.tip_offset
        r = tip[:, :3, :3] @ torch.as_tensor(self.config.offset, dtype=q.dtype, device=q.device)
        jp = jac[:, :3] + torch.linalg.cross(jac[:, 3:], r[:, :, None].expand_as(jac[:, 3:]), dim=1)
        m = self.p("mass", like=q).expand(q.shape[0], -1)[..., None]
        return m * (jp.transpose(1, 2) @ jp)

    def build_target(self, target, row):
        target.add_point_mass(float(self.theta[row, 0]), np.asarray(self.config.offset, dtype=float))

    def evidence(self, values, features):
        return features.sentence_for(self, values)
