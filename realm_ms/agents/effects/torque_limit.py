"""Motor torque saturation (fraction of the 87/12 N·m limits) and torque rate limit (N·m/s)."""

from __future__ import annotations

import torch

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec

NOMINAL_LIMITS = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)


class TorqueLimit(Effect):
    name = "torque_limit"
    step_cost = (3.4, 0.0)
    summary = "torque saturation / rate limit"
    signature = "delay that grows with the size of the 15 Hz target jumps; divergence only where |τ| is at its limit"
    order = 80

    @classmethod
    def param_specs(cls, config):
        return [
            ParamSpec("rate_limit", "N·m/s", 1000.0, 50.0, 1e5, 1e5, per_joint=False, scale="log",
                      doc="maximum torque rate (libfranka: 1000 N·m/s); 1e5 = off"),
            ParamSpec("effort_scale", "1", 0.8, 0.05, 1.0, 1.0, per_joint=False,
                      doc="saturation as a fraction of the nominal 87/12 N·m limits; 1 = off"),
        ]

    def reset(self, num_envs, device, env_idx, q):
        if env_idx is None or getattr(self, "_prev", None) is None or self._prev.shape[0] != num_envs:
            self._prev = None
        else:
            self._fresh[env_idx] = True

    def actuator(self, tau, state):
        limits = torch.as_tensor(NOMINAL_LIMITS, device=tau.device, dtype=tau.dtype)
        cap = self.p("effort_scale", tau) * limits
        tau = torch.maximum(torch.minimum(tau, cap), -cap)
        if self._prev is None:
            self._prev = tau.clone()
            self._fresh = torch.zeros(tau.shape[0], dtype=torch.bool, device=tau.device)
        if bool(self._fresh.any()):
            self._prev[self._fresh] = tau[self._fresh]
            self._fresh[:] = False
        step = self.p("rate_limit", tau) * state.dt
        tau = self._prev + torch.maximum(torch.minimum(tau - self._prev, step), -step)
        self._prev = tau
        return tau
