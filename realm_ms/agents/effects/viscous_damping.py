"""Viscous joint damping in N·m·s/rad (backward-Euler, stable at any value)."""

from __future__ import annotations

import torch

from realm_ms.agents.effects.implicit_torque import ImplicitJointTorque
from realm_ms.agents.effects.parameter import ParamSpec


class ViscousDamping(ImplicitJointTorque):
    name = "viscous_damping"
    step_cost = (7.7, 0.0)
    summary = "viscous damping"
    signature = "lag / offset proportional to joint velocity (≈ b q̇ / Kp), amplitude drop at high frequency"
    order = 91

    @classmethod
    def param_specs(cls, config):
        return [ParamSpec("b", "N·m·s/rad", 0.5, 0.0, 10.0, 0.0, doc="viscous friction coefficient")]

    coupled = True

    def coupled_torque(self, state, rows, qd, mass, net, v_free, inertia):
        """Backward Euler with the arm's mass matrix M (at the segment's reset configuration):
        (M + h B) v' = M q̇ + h (τ_motor - b(q, q̇)), torque -B v'. The joints are coupled through
        M, so damping one joint also slows its neighbours; a per-joint apparent inertia misses that
        (on a MuJoCo plant with native dof_damping, true b: 0.56 mrad per-joint against 0.39 mrad)."""
        b = self.p("b", qd, rows).to(qd.dtype).expand_as(qd)
        rhs = (mass @ qd.unsqueeze(-1)).squeeze(-1) + state.dt * net
        return -b * torch.linalg.solve(mass + state.dt * torch.diag_embed(b), rhs)

    def friction_torque(self, v_free, inertia, state, rows):
        b = self.p("b", v_free, rows)
        return -b * v_free / (1.0 + state.dt * b / inertia)
