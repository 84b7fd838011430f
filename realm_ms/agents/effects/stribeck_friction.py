"""Stribeck friction with stiction: F(v) = Fc + (Fs - Fc) exp(-(v/vs)^2), stick-slip integrated."""

from __future__ import annotations

import torch

from realm_ms.agents.effects.implicit_torque import ImplicitJointTorque
from realm_ms.agents.effects.parameter import ParamSpec


class StribeckFriction(ImplicitJointTorque):
    name = "stribeck_friction"
    step_cost = (5.0, 0.02)
    summary = "Stribeck friction / stiction"
    signature = (
        "dwell and extra lag at reversals and in slow motion, steady-state error inside ±Fs/Kp in holds; "
        "offset larger at low speed than at high speed"
    )
    order = 92

    @classmethod
    def param_specs(cls, config):
        return [
            ParamSpec("fs", "N·m", 0.5, 0.0, 3.0, 0.0, doc="static (breakaway) friction torque"),
            ParamSpec("fc_ratio", "1", 0.4, 0.0, 1.0, 0.4, per_joint=False, doc="Coulomb level as a fraction of Fs"),
            ParamSpec("vs", "rad/s", 0.05, 0.005, 0.5, 0.05, per_joint=False, scale="log", doc="Stribeck velocity"),
        ]

    def friction_torque(self, v_free, inertia, state, rows):
        fs, ratio, vs = self.p("fs", v_free, rows), self.p("fc_ratio", v_free, rows), self.p("vs", v_free, rows)
        speed = torch.abs(state.qd if rows is None else state.qd[rows])
        f = fs * (ratio + (1 - ratio) * torch.exp(-((speed / vs) ** 2)))
        stop = inertia * v_free / state.dt
        return -torch.maximum(torch.minimum(stop, f), -f)
