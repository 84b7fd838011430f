"""Stribeck friction with stiction: F(v) = Fc + (Fs - Fc) exp(-(v/vs)^2), stick-slip integrated."""

from __future__ import annotations

import torch

from realm_ms.sysid.effects.base import ImplicitJointTorque
from realm_ms.sysid.parameter import ParamSpec


class StribeckFriction(ImplicitJointTorque):
    name = "stribeck_friction"
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

    def plant_torque(self, state):
        v_free, inertia = self.free_velocity(state)
        fs, ratio, vs = self.p("fs", v_free), self.p("fc_ratio", v_free), self.p("vs", v_free)
        speed = torch.abs(state.qd)
        f = fs * (ratio + (1 - ratio) * torch.exp(-((speed / vs) ** 2)))
        stop = inertia * v_free / state.dt
        return -torch.maximum(torch.minimum(stop, f), -f)

    def evidence(self, values, features):
        return features.sentence_for(self, values)
