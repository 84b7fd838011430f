"""Encoder bias: the sensor the controller servos on reads the logged joint angle plus a constant
offset, so the arm settles ``bias`` away from where the log says it was commanded.

Sign convention: ``q_servo = q_logged + bias``. The law drives ``q_servo`` to the command, so at rest
``q_logged = q_cmd - bias``: a positive bias makes the log sit *below* the command, and the residual
(measured - nominal simulation) reads about ``-bias``. A fitted ``bias`` is what to subtract from
the controller's sensor (or add to the logged angle) to make the two agree."""

from __future__ import annotations

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class EncoderBias(Effect):
    name = "encoder_bias"
    step_cost = (1.4, 0.0)
    summary = "encoder bias"
    signature = "constant offset per joint, the same in every configuration, at every speed and at rest"
    order = 4

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("bias", "rad", 0.003, -0.02, 0.02, 0.0, doc="servo-sensor offset: q_servo = q_logged + bias, so at rest q_logged = q_cmd - bias")]

    def measure(self, q, qd, state):
        return q + self.p("bias", q), qd
