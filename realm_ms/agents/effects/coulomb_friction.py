"""Coulomb (dry) friction in N·m, symmetric or asymmetric, integrated stick-slip (Karnopp)."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from realm_ms.agents.effects.effect import EffectConfig
from realm_ms.agents.effects.implicit_torque import ImplicitJointTorque
from realm_ms.agents.effects.parameter import ParamSpec


@dataclass
class CoulombConfig(EffectConfig):
    asymmetric: bool = False  # fit fc_asym (F+ = fc + fc_asym, F- = fc - fc_asym)
    direction_velocity: float = 0.01  # rad/s, tanh width of the F+/F- switch (smooth asymmetry)


class CoulombFriction(ImplicitJointTorque):
    name = "coulomb_friction"
    summary = "Coulomb friction"
    signature = (
        "constant-size offset (≈ Fc / Kp) that flips sign with joint velocity, same size at all speeds; "
        "lag after each reversal"
    )
    Config = CoulombConfig

    @classmethod
    def param_specs(cls, config):
        return [
            ParamSpec("fc", "N·m", 0.3, 0.0, 3.0, 0.0, doc="dry friction torque (mean of both directions)"),
            ParamSpec("fc_asym", "N·m", 0.1, -1.0, 1.0, 0.0, fit_by_default=config.asymmetric,
                      doc="half the difference F+ - F-"),
        ]

    def friction_torque(self, v_free, inertia, state, rows):
        fc, fa = self.p("fc", v_free, rows), self.p("fc_asym", v_free, rows)
        # F+ / F- blended smoothly around v = 0 (tanh), so the asymmetry has no discontinuity
        direction = torch.tanh(v_free / self.config.direction_velocity)
        level = torch.clamp(fc + fa * direction, min=0)
        stop = inertia * v_free / state.dt  # torque that stops the joint this step (stick)
        return -torch.maximum(torch.minimum(stop, level), -level)

    def evidence(self, values, features):
        return features.sentence_for(self, values)
