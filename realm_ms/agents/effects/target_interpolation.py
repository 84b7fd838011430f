"""Target interpolation in the command pipeline: each new joint target is reached along a ramp of
``duration`` seconds from where the tracked target was when it arrived (constant speed, or with
``min_jerk: true`` the quintic 10s³ - 15s⁴ + 6s⁵, zero speed at both ends), as a command path that
interpolates between the 15 Hz targets instead of stepping to each. A target that arrives before the
ramp ends starts a new ramp from the point reached."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from realm_ms.agents.effects.effect import Effect, EffectConfig
from realm_ms.agents.effects.parameter import ParamSpec


@dataclass
class TargetInterpolationConfig(EffectConfig):
    min_jerk: bool = False  # the ramp's shape: False = constant speed


class TargetInterpolation(Effect):
    name = "target_interpolation"
    step_cost = (1.2, 0.0)
    summary = "target interpolation"
    signature = ("residual ≈ -(T/2)·q̇ on all joints with one shared ramp time T, and the 15 Hz target steps "
                 "smoothed into ramps: an interpolator between the command and the controller")
    order = 21  # after the transport delay: the interpolator ramps what arrives
    # a look-alike of target_filter and latency (CONFOUNDS): position-space diagnosis screens it on
    # request (--candidates), and auto fits it when either of those leads
    screened = False
    Config = TargetInterpolationConfig

    @classmethod
    def param_specs(cls, config):
        # 0.5 s: 7.5 periods of a 15 Hz command per ramp: slower than any robot that follows commands
        return [ParamSpec("duration", "s", 0.067, 0.0, 0.5, 0.0, per_joint=False,
                          doc="time a ramp takes from the tracked target to a new target (0 = step to it)")]

    def reset(self, num_envs, device, env_idx, q):
        if env_idx is None or getattr(self, "_out", None) is None or self._out.shape[0] != num_envs:
            self._out = None
            self._reset_q = q.clone()
        else:
            for x in (self._out, self._start, self._goal):
                x[env_idx] = q[env_idx].to(x.dtype)
            self._elapsed[env_idx] = 0.0

    def command(self, q_target, state):
        if getattr(self, "_out", None) is None:
            base = (self._reset_q if getattr(self, "_reset_q", None) is not None else q_target).to(q_target)
            self._out, self._start, self._goal = base.clone(), base.clone(), base.clone()
            self._elapsed = torch.zeros(q_target.shape[0], 1, dtype=q_target.dtype, device=q_target.device)
        new = (q_target != self._goal).any(dim=1, keepdim=True)
        self._start = torch.where(new, self._out, self._start)
        self._goal = torch.where(new, q_target, self._goal)
        self._elapsed = torch.where(new, torch.zeros_like(self._elapsed), self._elapsed) + state.dt
        duration = self.p("duration", q_target)
        s = torch.where(duration > 0, (self._elapsed / duration.clamp_min(1e-9)).clamp(0.0, 1.0),
                        torch.ones_like(self._elapsed))
        if self.config.min_jerk:
            s = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
        self._out = self._start + s * (self._goal - self._start)
        return self._out
