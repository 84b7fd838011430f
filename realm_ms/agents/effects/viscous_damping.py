"""Viscous joint damping in N·m·s/rad (backward-Euler, stable at any value)."""

from __future__ import annotations

from realm_ms.agents.effects.implicit_torque import ImplicitJointTorque
from realm_ms.agents.effects.parameter import ParamSpec


class ViscousDamping(ImplicitJointTorque):
    name = "viscous_damping"
    summary = "viscous damping"
    signature = "lag / offset proportional to joint velocity (≈ b q̇ / Kp), amplitude drop at high frequency"
    order = 91

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("b", "N·m·s/rad", 0.5, 0.0, 10.0, 0.0, doc="viscous friction coefficient")]

    def friction_torque(self, v_free, inertia, state, rows):
        b = self.p("b", v_free, rows)
        return -b * v_free / (1.0 + state.dt * b / inertia)

    def evidence(self, values, features):
        return features.sentence_for(self, values)
