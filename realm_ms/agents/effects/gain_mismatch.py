"""Controller gain mismatch: the real loop's stiffness/damping gains differ by a common factor."""

from __future__ import annotations

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class GainMismatch(Effect):
    name = "gain_mismatch"
    step_cost = (1.5, 0.0)
    summary = "controller gain mismatch"
    signature = "residual ∝ tracking error (static error under load ∝ 1/Kp), different bandwidth and damping"
    order = 25

    @classmethod
    def param_specs(cls, config):
        return [
            ParamSpec("stiffness_error", "1", 0.2, -0.5, 0.5, 0.0, per_joint=False,
                      doc="relative error of Kq and Kx (real = (1 + e) nominal)"),
            ParamSpec("damping_error", "1", 0.2, -0.4, 0.4, 0.0, per_joint=False,
                      doc="relative error of Kqd and Kxd (bounded for explicit-integration stability at 120 Hz)"),
        ]

    def gains(self, gains):
        ks = 1.0 + self.p("stiffness_error", gains.kq)
        kd = 1.0 + self.p("damping_error", gains.kq)
        from realm_ms.agents.control import BatchedGains

        return BatchedGains(gains.kq * ks, gains.kqd * kd, gains.kx * ks, gains.kxd * kd)
