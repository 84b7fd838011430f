"""The gripper's own response: how the Robotiq 2F-85 follows its position request.

The simulated gripper (``robotiq_2f85.RobotiqGripperController``) moves its drive target towards the
requested position at ``max_speed`` and its PD drive tracks that target within a physics step. A real
gripper may answer later (its own command path: ``delay``), slower (``speed``: a fraction of the
simulated stroke speed, DROID sites may run the 2F-85 below its top speed) and with a rounded start
(``tau``: a first-order lag on the drive target). :class:`GripperLaw` is that law, one physics step at
a time; the controller runs it on its drive targets and the workbench's gripper channel
(``sysid/gripper.py``) runs the same law to fit the parameters from measured strokes.

It is an effect of the robot model (``MODEL.yaml``) like the arm's, but it acts on the gripper alone:
every arm hook is the identity, so the arm replay neither sees nor screens it.
"""

from __future__ import annotations

import math

import torch

from realm_ms.agents.effects.effect import Effect
from realm_ms.agents.effects.parameter import ParamSpec


class GripperResponse(Effect):
    name = "gripper_response"
    summary = "gripper response"
    signature = ("the measured gripper strokes slower (or later) than the simulated gripper's answer to the same "
                 "request; the arm's residual is unchanged")
    order = 90
    screened = False  # the arm replay cannot see it: the workbench's gripper channel fits it (sysid/gripper.py)
    acts_on = "gripper"
    step_cost = (0.0, 0.0)

    @classmethod
    def param_specs(cls, config):
        return [
            # 0.3 s: the arm's command delay bound (latency.py); the request travels the same path
            ParamSpec("delay", "s", 0.05, 0.0, 0.3, 0.0, per_joint=False,
                      doc="transport delay of the gripper's position request"),
            # 0.2-2: a fifth to twice the simulated 2F-85's stroke speed (full stroke in 0.6 s)
            ParamSpec("speed", "1", 0.8, 0.2, 2.0, 1.0, per_joint=False,
                      doc="stroke speed as a fraction of the simulated gripper's (its max_speed)"),
            ParamSpec("tau", "s", 0.05, 0.0, 0.3, 0.0, per_joint=False, fit_by_default=False,
                      doc="first-order lag of the drive target (a rounded stroke start); 15 Hz strokes "
                          "cannot tell it from delay, so fits leave it unless asked"),
        ]

    def law(self) -> "GripperLaw":
        v = self.values()
        return GripperLaw(v["delay"], v["speed"], v["tau"])


class GripperLaw:
    """The gripper's drive target, one physics step at a time: the request ``delay`` s ago (linear
    interpolation in a per-physics-step history), rate limited at ``speed * max_speed``, then a
    first-order lag ``tau``. Tensors (B, n): any number of envs and driver joints; ``delay``,
    ``speed`` and ``tau`` are numbers or (B, 1) tensors (a batch of candidates)."""

    def __init__(self, delay=0.0, speed=1.0, tau=0.0):
        self.delay, self.speed, self.tau = delay, speed, tau
        self._hist = None
        self._consts = None

    def reset(self, target: torch.Tensor, rows: torch.Tensor | None = None) -> None:
        """Start at rest on ``target`` (B, n): the history, the rate limiter and the lag; ``rows``
        (a (B,) bool mask): only those envs (a partial reset), the others keep their requests in flight."""
        if rows is None or self._hist is None or bool(rows.all()):
            self._hist = None
            self._ramp = target.clone()
            self._out = target.clone()
            return
        self._ramp[rows] = target[rows]
        self._out[rows] = target[rows]
        self._hist[:, rows] = target[rows]

    def _constants(self, like: torch.Tensor, dt: float, max_speed: float):
        """Per (dt, max_speed): history rows and weight of the delayed request, step limit, lag factor."""
        key = (dt, max_speed, like.dtype, like.device)
        if self._consts is None or self._consts[0] != key:
            kw = dict(dtype=like.dtype, device=like.device)
            steps = (torch.as_tensor(self.delay, **kw) / dt).clamp(0, self._hist.shape[0] - 2)
            k = torch.floor(steps)
            tau = torch.as_tensor(self.tau, **kw)
            alpha = torch.where(tau > 0, -torch.expm1(-dt / tau.clamp_min(1e-9)), torch.ones_like(tau))
            max_dq = torch.as_tensor(self.speed, **kw) * (max_speed * dt)
            self._consts = (key, k.long().reshape(-1), (steps - k), max_dq, alpha)
        return self._consts[1:]

    def step(self, goal: torch.Tensor, dt: float, max_speed: float) -> torch.Tensor:
        if self._hist is None:  # a ring of requests, one per physics step; row ``_head`` is the newest
            n = int(math.ceil(GripperResponse.param_specs(None)[0].hi / dt)) + 2
            self._hist = self._ramp.unsqueeze(0).repeat(n, *([1] * self._ramp.dim()))
            self._head = 0
        n = self._hist.shape[0]
        self._head = (self._head - 1) % n
        self._hist[self._head] = goal
        k, frac, max_dq, alpha = self._constants(goal, dt, max_speed)
        if k.numel() == 1:
            a, b = self._hist[(self._head + int(k)) % n], self._hist[(self._head + int(k) + 1) % n]
        else:  # one delay per row (B, 1)
            rows = torch.arange(goal.shape[0], device=goal.device)
            a, b = self._hist[(self._head + k) % n, rows], self._hist[(self._head + k + 1) % n, rows]
        delayed = a + frac * (b - a)
        self._ramp = self._ramp + torch.clamp(delayed - self._ramp, -max_dq, max_dq)
        # exact for a target held over the step; tau = 0 passes the ramp through
        self._out = self._out + alpha * (self._ramp - self._out)
        return self._out
