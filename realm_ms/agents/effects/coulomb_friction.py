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
    step_cost = (5.2, 0.01)
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
        level, neg_level = self._symmetric_level(fc, fa)
        if level is None:
            # F+ / F- blended smoothly around v = 0 (tanh), so the asymmetry has no discontinuity
            direction = torch.tanh(v_free / self.config.direction_velocity)
            level = torch.clamp(fc + fa * direction, min=0)
            neg_level = -level
        stop = inertia * v_free / state.dt  # torque that stops the joint this step (stick)
        return -torch.clamp(stop, neg_level, level)  # level >= 0: the same as max(min(stop, level), -level)

    def _symmetric_level(self, fc, fa):
        """(level, -level) when no row is asymmetric (fc_asym all zero: the level does not depend on
        the direction), else (None, None); decided once per parameter tensor, as this runs at every
        tick."""
        c = self.__dict__.get("_level_cache")
        if c is None or c[0] is not fc or c[1] is not fa:
            level = None if bool(fa.any()) else torch.clamp(fc, min=0)
            c = self._level_cache = (fc, fa, level, None if level is None else -level)
        return c[2], c[3]
