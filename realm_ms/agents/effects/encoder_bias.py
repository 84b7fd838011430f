"""Encoder bias: the sensor the controller servos on reads the logged joint angle plus a constant
offset, so the arm settles ``bias`` away from where the log says it was commanded."""

from __future__ import annotations

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class EncoderBias(Effect):
    name = "encoder_bias"
    summary = "encoder bias"
    signature = "constant offset per joint, the same in every configuration, at every speed and at rest"
    order = 4

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("bias", "rad", 0.003, -0.02, 0.02, 0.0, doc="servo-sensor offset (logged = servo - bias)")]

    def measure(self, q, qd, state):
        return q + self.p("bias", q), qd

    def evidence(self, values, features):
        return features.sentence_for(self, values)
