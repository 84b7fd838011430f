"""Target filtering in the command pipeline: the controller tracks a first-order low-pass of the
joint targets (time constant ``tau``), as a robot whose command path smooths or interpolates each
new target instead of stepping to it."""

from __future__ import annotations

import torch

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class TargetFilter(Effect):
    name = "target_filter"
    step_cost = (1.1, 0.0)
    summary = "target filter"
    signature = ("residual ≈ -τ·q̇ at low frequency on all joints with one shared τ, and the amplitude of fast "
                 "target changes reduced: a low-pass between the command and the controller")
    order = 21  # after the transport delay: the filter smooths what arrives

    @classmethod
    def param_specs(cls, config):
        # 0.5 s: a 15 Hz command would need 7 steps to reach 63 %: slower than any robot that follows commands
        return [ParamSpec("tau", "s", 0.05, 0.0, 0.5, 0.0, per_joint=False,
                          doc="time constant of the first-order low-pass on the joint targets")]

    def reset(self, num_envs, device, env_idx, q):
        if env_idx is None or getattr(self, "_state", None) is None or self._state.shape[0] != num_envs:
            self._state = None
            self._reset_q = q.clone()
        else:
            self._state[env_idx] = q[env_idx].to(self._state.dtype)

    def command(self, q_target, state):
        if getattr(self, "_state", None) is None:
            base = self._reset_q if getattr(self, "_reset_q", None) is not None else q_target
            self._state = base.to(q_target).clone()
        tau = self.p("tau", q_target)
        # exact for a target held over the step: alpha = 1 - exp(-dt / tau); tau = 0 passes through
        alpha = -torch.expm1(-state.dt / tau.clamp_min(1e-9))
        self._state = torch.where(tau > 0, self._state + alpha * (q_target - self._state), q_target)
        return self._state
