"""Smooth friction without stiction, per joint: τ = −fc (tanh((q̇ + v0)/vs) − tanh(v0/vs)): exactly the sigmoid Gaz et
al. 2019 identified from a Panda's measured torques, φ₁/(1 + e^(−φ₂(q̇+φ₃))) − φ₁/(1 + e^(−φ₂φ₃)),
with fc = φ₁/2, vs = 2/φ₂ (0.1-0.4 rad/s on their joints), v0 = φ₃. Zero at rest, a steep viscous
slope near it, levels fc (1 ∓ tanh(v0/vs)) in the two directions above a few vs.

Unlike ``coulomb_friction`` (exact stiction: a joint whose load stays under fc does not move),
nothing sticks: under a constant load below fc a joint creeps at the velocity where the friction
balances it. That difference is what a position log of such a robot shows in every hold.

Integrated by backward Euler per joint (``ImplicitJointTorque``): the end velocity v solves
I (v − v_free)/h = τ(v), stable however steep fc/vs is. The friction has v's sign and grows with
it, so the root is unique and lies between 0 and v_free: Newton's method inside that bracket.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from realm_ms.agents.effects.effect import EffectConfig
from realm_ms.agents.effects.implicit_torque import ImplicitJointTorque
from realm_ms.agents.effects.parameter import ParamSpec

NEWTON_STEPS = 8
COUPLED_NEWTON_STEPS = 3
# the per-joint start of the coupled step: beyond 3 steps it moves the coupled result by < 2e-6 rad/s
# (random arms and laws, fc 0.05-0.65 N·m, vs 5 ms⁻¹-1 rad/s), float32 round-off
COUPLED_START_STEPS = 3


def friction(v: torch.Tensor, fc: torch.Tensor, vs: torch.Tensor, v0: torch.Tensor) -> torch.Tensor:
    """fc (tanh((v + v0)/vs) − tanh(v0/vs)): zero at rest, levels fc (1 ∓ tanh(v0/vs)) when fast."""
    return fc * (torch.tanh((v + v0) / vs) - torch.tanh(v0 / vs))


def backward_euler_velocity(v_free: torch.Tensor, a: torch.Tensor, fc: torch.Tensor, vs: torch.Tensor,
                            v0: torch.Tensor | float = 0.0, steps: int = NEWTON_STEPS) -> torch.Tensor:
    """v with g(v) = a (v − v_free) + friction(v) = 0, a = I/h > 0, fc >= 0, vs > 0 (elementwise).

    g rises with v, is concave right of the inflection v = −v0 and convex left of it, so Newton's
    method started on the root's outer side of the inflection (g < 0 on the concave side, g > 0 on
    the convex side) converges monotonically. The start is also pulled towards the root by the
    sliding bounds v_free − L₊/a <= v <= v_free + L₋/a (L: the friction's level each way)."""
    v0 = torch.as_tensor(v0, dtype=v_free.dtype, device=v_free.device)
    zero = torch.zeros_like(v_free)
    c = torch.tanh(v0 / vs)

    def g(x):
        return a * (x - v_free) + fc * (torch.tanh((x + v0) / vs) - c)

    # the root lies between 0 and v_free (the friction has v's sign)
    p = torch.minimum(torch.maximum(-v0 + zero, torch.minimum(v_free, zero)), torch.maximum(v_free, zero))
    below = g(p) < 0
    x = torch.where(below, torch.maximum(p, v_free - fc * (1 - c) / a), torch.minimum(p, v_free + fc * (1 + c) / a))
    for _ in range(steps):
        t = torch.tanh((x + v0) / vs)
        x = x - (a * (x - v_free) + fc * (t - c)) / (a + fc * (1.0 - t * t) / vs)
    return x


@dataclass
class SmoothFrictionConfig(EffectConfig):
    asymmetric: bool = True  # fit v0 (the two directions' levels differ, as on Gaz et al.'s Panda)


class SmoothFriction(ImplicitJointTorque):
    name = "smooth_friction"
    step_cost = (12.8, 0.02)
    summary = "smooth friction, no stiction (tanh, Gaz-style)"
    signature = (
        "lag that grows with speed up to a few vs and then levels off; in holds the joint creeps to the "
        "target instead of sticking inside ±Fc/Kp"
    )
    order = 93
    Config = SmoothFrictionConfig

    @classmethod
    def param_specs(cls, config):
        return [
            ParamSpec("fc", "N·m", 0.3, 0.0, 3.0, 0.0, doc="friction level at high speed"),
            ParamSpec("vs", "rad/s", 0.1, 0.005, 1.0, 0.1, scale="log",
                      doc="velocity scale of the tanh: below it the friction is a viscous slope fc/vs"),
            ParamSpec("v0", "rad/s", 0.0, -0.1, 0.1, 0.0, fit_by_default=config.asymmetric,
                      doc="velocity shift of the curve (Gaz's φ₃): unequal levels in the two directions"),
        ]

    coupled = True

    def coupled_torque(self, state, rows, qd, mass, net, v_free, inertia):
        """Backward Euler with the arm's mass matrix M (at the segment's reset, as viscous damping):
        v' solves M (v' − v_free)/h + τ(v') = 0, v_free = q̇ + h M⁻¹(τ_motor − b(q, q̇)). Near rest
        this friction is a steep viscous slope, and the joints are coupled through M: the per-joint
        solution is the start of COUPLED_NEWTON_STEPS Newton steps on the whole vector (the
        residual is the gradient of a strictly convex function, so the root is unique)."""
        if inertia is None:  # the per-joint step's own start (I_j cached at the reset)
            v_start, inertia = self.free_velocity(state, rows)
        else:
            v_start = v_free
        fc, vs, v0 = (self.p(k, qd, rows).to(qd.dtype).expand_as(qd) for k in ("fc", "vs", "v0"))
        v = backward_euler_velocity(v_start, inertia / state.dt, fc, vs, v0, COUPLED_START_STEPS)
        m_h, c = mass / state.dt, torch.tanh(v0 / vs)
        for _ in range(COUPLED_NEWTON_STEPS):
            t = torch.tanh((v + v0) / vs)
            residual = (m_h @ (v - v_free).unsqueeze(-1)).squeeze(-1) + fc * (t - c)  # + friction(v)
            v = v - torch.linalg.solve(m_h + torch.diag_embed(fc * (1 - t * t) / vs), residual)
        return -friction(v, fc, vs, v0)

    def friction_torque(self, v_free, inertia, state, rows):
        fc, vs, v0 = self.p("fc", v_free, rows), self.p("vs", v_free, rows), self.p("v0", v_free, rows)
        v = backward_euler_velocity(v_free, inertia / state.dt, fc, vs, v0)
        return -friction(v, fc, vs, v0)
