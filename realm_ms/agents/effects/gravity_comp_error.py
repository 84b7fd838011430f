"""Gravity-compensation error: the robot's gravity model is off by a factor (1 + scale)."""

from __future__ import annotations

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.model_terms import model_gravity, scatter_rows
from realm_ms.agents.effects.parameter import ParamSpec


class GravityCompError(Effect):
    name = "gravity_comp_error"
    step_cost = (2.8, 0.0)
    summary = "gravity-compensation error"
    signature = "static offset proportional to each joint's gravity torque g_i(q), present at rest"
    order = 30

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("scale", "1", 0.1, -0.5, 0.5, 0.0, per_joint=False,
                          doc="relative error of the compensated gravity torque")]

    def actuator(self, tau, state):
        rows = self.active_rows(tau.device)
        if rows is not None and rows.numel() == 0:
            return tau
        return tau + scatter_rows(tau, rows, self.p("scale", tau, rows) * model_gravity(state, rows))
