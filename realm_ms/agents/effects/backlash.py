"""Gear backlash: the controller servos on the motor side, the logged joint angle is the link side;
the link rests against one gear flank or the other depending on the sign of the load (gravity)
torque, so it lags the motor by ±gap/2 (smooth switch of width ``torque_width``)."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from realm_ms.agents.effects.effect import Effect, EffectConfig
from realm_ms.agents.effects.model_terms import model_gravity, scatter_rows
from realm_ms.agents.effects.parameter import ParamSpec


@dataclass
class BacklashConfig(EffectConfig):
    torque_width: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 0.2, 0.2, 0.2)  # N·m, tanh width of the flank switch


class Backlash(Effect):
    name = "backlash"
    step_cost = (4.0, 0.0)
    summary = "backlash"
    signature = "offset of ±gap/2 that flips with the sign of the load (gravity) torque, independent of speed and gains"
    order = 5
    Config = BacklashConfig

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("half_gap", "rad", 0.002, 0.0, 0.02, 0.0, doc="half of the dead band")]

    def measure(self, q, qd, state):
        rows = self.active_rows(q.device)
        if rows is not None and rows.numel() == 0:
            return q, qd
        width = torch.as_tensor(self.config.torque_width, device=q.device, dtype=q.dtype)
        side = torch.tanh(model_gravity(state, rows) / width)
        return q + scatter_rows(q, rows, self.p("half_gap", q, rows) * side), qd
