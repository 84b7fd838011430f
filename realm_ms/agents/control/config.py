"""``DroidControlConfig``: how the DROID arm's law is computed (see ``realm_ms.agents.control``)."""

from __future__ import annotations

from dataclasses import dataclass

from realm_ms.agents.control.presets import FRANKA_EFFORT_LIMITS, ImpedanceGains, JointPhysics, check_lengths
from realm_ms.agents.urdf import DROID_RESET_QPOS
from realm_ms.errors import InputError

INTEGRATORS = ("exact", "implicit_damping", "explicit")
MODEL_RATES = ("path", "physics", "control")


@dataclass
class DroidControlConfig:
    gains: ImpedanceGains | str = "polymetis"
    effort_limits: tuple[float, ...] = FRANKA_EFFORT_LIMITS
    coriolis_feedforward: bool = True  # on in Polymetis and (via a YAML slip) in REALM
    gravity_compensation: bool = True  # libfranka compensates gravity with its model
    integrator: str = "exact"  # "exact" | "implicit_damping" | "explicit": see ``integrators.py``
    # integrator="implicit_damping": the damping PhysX's joint drive carries, N.m.s/rad per joint;
    # None = the law's damping diagonal at ``reference_qpos``
    drive_damping: tuple[float, ...] | None = None
    reference_qpos: tuple[float, ...] = DROID_RESET_QPOS
    joint_physics: JointPhysics | str = "realm"
    # Where the model terms (J, M, C(q, qd), g(q)) come from; the feedback on q, qd runs every physics step.
    # "path" (default): for every physics step, at the state the closed loop is predicted to reach then,
    #   all ``path_steps`` steps in one batched evaluation (g corrected to first order for the measured
    #   q); re-planned when the target changes or the arm leaves the path by > ``path_tolerance``.
    # "physics": at the measured state, every physics step (as Polymetis at 1 kHz).
    # "control": once per target, gravity corrected to first order in between (~2 mrad off).
    # Cost: bench/step_rate.py; accuracy against the MuJoCo reference: docs/robot.md.
    model_rate: str = "path"
    path_steps: int = 8  # physics steps per plan (the ManiSkill binding sets its substeps per action)
    path_tolerance: float = 1e-3  # rad; the terms' error grows with the distance to where they were taken
    law_hz: float = 1000.0  # "exact": the controller rate it reproduces (Polymetis / libfranka: 1 kHz)

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise InputError(f"integrator must be one of {INTEGRATORS}, got {self.integrator!r}")
        if self.model_rate not in MODEL_RATES:
            raise InputError(f"model_rate must be one of {MODEL_RATES}, got {self.model_rate!r}")
        if self.path_steps < 1 or not self.path_tolerance > 0:
            raise InputError(f"path_steps must be >= 1 and path_tolerance > 0, got {self.path_steps}, {self.path_tolerance}")
        check_lengths("droid_control", self, {"effort_limits": 7, "drive_damping": 7, "reference_qpos": 7})

    @property
    def follows_path(self) -> bool:
        """Terms along the predicted path: needs the exact integrator's prediction (else "physics")."""
        return self.model_rate == "path" and self.integrator == "exact"
