"""Actuation stages: everything between the policy's joint command and the torque on the joints.

The DROID controller (``realm_ms.agents.control``) runs the Polymetis law on what the robot *measures*
and hands the resulting torque through a chain of stages. The nominal robot has no stages; the
sysid workbench's physical effects (friction, latency, encoder bias, payload, ...) are stages, so a
fitted robot model plugs into the benchmark envs and the sysid replay simulator the same way.

Hook order, every physics step (all tensors batched, shape (B, 7) unless noted)::

    q_meas, qd_meas = measure(q, qd)          # what encoders report (bias, backlash, ...)
    q_target        = command(q_target)        # what the controller tracks (latency, ...)
    gains           = gains(nominal gains)     # the real loop's gains (mismatch)
    tau             = polymetis_law(...)       # clipped to the nominal effort limits
    tau             = actuator(tau)            # what the motors deliver (saturation, rate limit)
    tau            += plant_torque()           # physics the rigid model lacks (friction)

Build-time effects (armature, payload) act on the articulation once, in ``build``; what they add to
the plant is declared to the driver (``plant_inertia``, ``plant_load``) so its step-exact
integration predicts the plant it drives. A stage with ``within_step = True`` (friction: its torque
depends on the velocity *within* a 120 Hz physics step) is evaluated by the exact integrator at
every tick of the 1 kHz law inside the step, as the real controller's plant would feel it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import torch

if TYPE_CHECKING:
    from realm_ms.agents.arm_model import ArmModel


@dataclass
class ControlState:
    """Per-physics-step state shared with every stage (true state, not measured)."""

    q: torch.Tensor
    qd: torch.Tensor
    q_target: torch.Tensor  # after command stages
    dt: float
    model: "ArmModel"
    time: torch.Tensor  # (B,) seconds since the env's reset
    extra: dict[str, Any] = field(default_factory=dict)


class ActuationStage:
    """Base class: every hook is the identity. Subclasses override what they change."""

    within_step = False  # plant_torque is evaluated at the law's ticks inside the step (see module doc)

    def reset(self, num_envs: int, device: torch.device, env_idx: torch.Tensor | None, q: torch.Tensor) -> None:
        """Clear internal state (delay lines, backlash position) for the envs in ``env_idx``."""

    def build(self, articulation: Any, joint_indices: list[int]) -> None:
        """Change the simulated articulation itself (armature, link masses). Called once after load."""

    def measure(self, q: torch.Tensor, qd: torch.Tensor, state: ControlState) -> tuple[torch.Tensor, torch.Tensor]:
        return q, qd

    def command(self, q_target: torch.Tensor, state: ControlState) -> torch.Tensor:
        return q_target

    def gains(self, gains):
        """The real loop's gains from the nominal ones (``realm_ms.agents.control.BatchedGains``;
        this module stays below the controller, so the type is named here, not imported)."""
        return gains

    def actuator(self, tau: torch.Tensor, state: ControlState) -> torch.Tensor:
        return tau

    def plant_torque(self, state: ControlState) -> torch.Tensor | None:
        return None

    def plant_inertia(self, state: ControlState) -> torch.Tensor | None:
        """Joint-space inertia (B, n, n) this stage adds to the plant (armature, payload), so the
        driver's step-exact integration predicts the plant it drives; None = none."""
        return None

    def plant_load(self, state: ControlState) -> torch.Tensor | None:
        """Joint torque (B, n) the simulated plant itself applies beyond the rigid model the
        controller cancels (a payload's gravity and Coriolis): physics applies it, the driver only
        predicts it; None = none."""
        return None


class ActuationModel(ActuationStage):
    """An ordered chain of stages that behaves as one stage."""

    def __init__(self, stages: list[ActuationStage] | None = None):
        self.stages = list(stages or [])

    def __bool__(self) -> bool:
        return bool(self.stages)

    def reset(self, num_envs, device, env_idx, q):
        for s in self.stages:
            s.reset(num_envs, device, env_idx, q)

    def build(self, articulation, joint_indices):
        for s in self.stages:
            s.build(articulation, joint_indices)

    def measure(self, q, qd, state):
        for s in self.stages:
            q, qd = s.measure(q, qd, state)
        return q, qd

    def command(self, q_target, state):
        for s in self.stages:
            q_target = s.command(q_target, state)
        return q_target

    def gains(self, gains):
        for s in self.stages:
            gains = s.gains(gains)
        return gains

    def actuator(self, tau, state):
        for s in self.stages:
            tau = s.actuator(tau, state)
        return tau

    @property
    def within_step(self) -> bool:
        return any(s.within_step for s in self.stages)

    def plant_torque(self, state, within_step: bool | None = None):
        """All stages' plant torque, or only those with ``within_step`` equal to the flag."""
        return self._sum_over_stages("plant_torque", state, within_step)

    def plant_inertia(self, state):
        return self._sum_over_stages("plant_inertia", state)

    def plant_load(self, state):
        return self._sum_over_stages("plant_load", state)

    def _sum_over_stages(self, term: str, state, within_step: bool | None = None):
        """The stages' ``term`` added up; None when no stage contributes."""
        stages = [s for s in self.stages if within_step is None or s.within_step == within_step]
        parts = [t for t in (getattr(s, term)(state) for s in stages) if t is not None]
        return sum(parts[1:], parts[0]) if parts else None
