"""Command latency: the controller tracks the target of ``delay`` seconds ago, linearly interpolated
in a per-physics-step history (sub-step resolution, continuous in the delay)."""

from __future__ import annotations

import math

import torch

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class Latency(Effect):
    name = "latency"
    step_cost = (1.2, 0.0)
    summary = "command latency"
    signature = "residual ≈ -Δ·q̇ on all joints with one shared Δ; phase lag growing with frequency, no amplitude change"
    order = 20

    @classmethod
    def param_specs(cls, config):
        # 0.3 s: a DROID site's path from policy to torque loop (network, threads, 15 Hz hand-over) can
        # exceed 100 ms
        return [ParamSpec("delay", "s", 0.02, 0.0, 0.3, 0.0, per_joint=False, doc="transport delay of the joint targets")]

    def reset(self, num_envs, device, env_idx, q):
        if env_idx is None or getattr(self, "_hist", None) is None or self._hist.shape[1] != num_envs:
            self._hist = None
            self._reset_q = q.clone()
        else:
            self._hist[:, env_idx] = q[env_idx].to(self._hist.dtype)

    def command(self, q_target, state):
        if getattr(self, "_hist", None) is None:
            n = int(math.ceil(self.params[0].spec.hi / state.dt)) + 2
            base = self._reset_q if getattr(self, "_reset_q", None) is not None else q_target
            self._hist = base.to(q_target).unsqueeze(0).repeat(n, 1, 1)
        self._hist = torch.roll(self._hist, 1, dims=0)
        self._hist[0] = q_target
        steps = (self.p("delay", q_target)[:, 0] / state.dt).clamp(0, self._hist.shape[0] - 2)
        k = torch.floor(steps).long()
        frac = (steps - k)[:, None]
        env = torch.arange(q_target.shape[0], device=q_target.device)
        a, b = self._hist[k, env], self._hist[k + 1, env]
        return a + frac * (b - a)
