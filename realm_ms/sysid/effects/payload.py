"""An unmodelled payload: a point mass at the flange. Gravity compensation keeps the nominal model,
so the arm sags by J^T m g / Kp and accelerates more sluggishly (build time)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from realm_ms.sysid.effects.base import Effect, EffectConfig
from realm_ms.sysid.parameter import ParamSpec


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

    def build_target(self, target, row):
        target.add_point_mass(float(self.theta[row, 0]), np.asarray(self.config.offset, dtype=float))

    def evidence(self, values, features):
        return features.sentence_for(self, values)
