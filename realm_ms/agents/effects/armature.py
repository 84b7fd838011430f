"""Rotor (reflected) inertia in kg·m², added to the joints of the articulation (build time)."""

from __future__ import annotations

import numpy as np
import torch

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class Armature(Effect):
    name = "armature"
    step_cost = (0.8, 0.0)
    summary = "armature (rotor inertia)"
    signature = "no static effect; slower rise and overshoot after target steps, residual ∝ q̈, zero in holds"
    order = 10
    build_time = True

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("ia", "kg·m²", 0.2, 0.0, 2.0, 0.0, doc="armature added to the joint")]

    def plant_inertia(self, state):
        ia = self.p("ia", like=state.q)
        return torch.diag_embed(ia.expand(state.q.shape[0], -1))

    def build_target(self, target, row):
        target.add_armature(self.theta[row, self._slices["ia"]].cpu().numpy().astype(np.float64))
