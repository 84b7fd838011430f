"""REALM's tiered progression: ordered stages per skill, latched per env, batched torch.

Progression = (number of consecutive stages met) / (number of stages); a met stage latches, so
progression is monotone within an episode. Thresholds are REALM's (realm-spec.md section 2.2),
with the original's pitfalls fixed (section 10):

- GRASP is a real two-pad grasp (both pads in contact with non-trivial force), not the original's
  always-true finger test;
- TOUCH_AND_MOVE_JOINT requires the drawer to have moved in the task's direction by more than
  0.025 of its range (the original's open-task condition was true at rest);
- REACH for drawers uses the handle like every other task uses its object (distance < 0.10 m or
  touching), instead of the original's dead touch-only branch;
- PLACE_INTO / PLACE_ONTO are geometric, not sim object states. PLACE_INTO is REALM's
  ``Inside or OnTop``: the object's centre inside the receptacle (footprint, below the rim + 2 cm),
  or the object resting on it (touching, centre over its footprint, bottom above its base: a tall
  glass standing in a bowl). PLACE_ONTO: bottom on the top face, over its footprint, touching.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Callable

import torch
from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix

from realm_ms.registry import Registry
from realm_ms.tasks.skills import Skill, as_skill


class Stage(str, enum.Enum):
    REACH = "REACH"
    GRASP = "GRASP"
    TOUCH = "TOUCH"
    LIFT_SLIGHT = "LIFT_SLIGHT"
    LIFT_LARGE = "LIFT_LARGE"
    ROTATED = "ROTATED"
    MOVE_CLOSE = "MOVE_CLOSE"
    PLACE_INTO = "PLACE_INTO"
    PLACE_ONTO = "PLACE_ONTO"
    TOGGLED_ON = "TOGGLED_ON"
    TOUCH_AND_MOVE_JOINT = "TOUCH_AND_MOVE_JOINT"
    OPEN_JOINT_SMALL = "OPEN_JOINT_SMALL"
    OPEN_JOINT_LARGE = "OPEN_JOINT_LARGE"
    OPEN_JOINT_FULL = "OPEN_JOINT_FULL"
    CLOSE_JOINT_SMALL = "CLOSE_JOINT_SMALL"
    CLOSE_JOINT_LARGE = "CLOSE_JOINT_LARGE"
    CLOSE_JOINT_FULL = "CLOSE_JOINT_FULL"


S = Stage
K = Skill
#: the ordered stages of each skill's rubric (REALM's task_progressions)
RUBRICS: Registry[tuple[Stage, ...]] = Registry("rubric")
RUBRICS.register(K.PUT, (S.REACH, S.GRASP, S.LIFT_SLIGHT, S.MOVE_CLOSE, S.PLACE_INTO))
RUBRICS.register(K.STACK, (S.REACH, S.GRASP, S.LIFT_SLIGHT, S.MOVE_CLOSE, S.PLACE_ONTO))
RUBRICS.register(K.PICK, (S.REACH, S.GRASP, S.LIFT_LARGE))
RUBRICS.register(K.ROTATE, (S.REACH, S.GRASP, S.ROTATED))
RUBRICS.register(K.PUSH, (S.REACH, S.TOUCH, S.TOGGLED_ON))
RUBRICS.register(K.OPEN_DRAWER, (S.REACH, S.TOUCH_AND_MOVE_JOINT, S.OPEN_JOINT_SMALL, S.OPEN_JOINT_LARGE, S.OPEN_JOINT_FULL))
RUBRICS.register(K.CLOSE_DRAWER, (S.REACH, S.TOUCH_AND_MOVE_JOINT, S.CLOSE_JOINT_SMALL, S.CLOSE_JOINT_LARGE, S.CLOSE_JOINT_FULL))


@dataclass(frozen=True)
class Thresholds:
    reach_dist: float = 0.10  # m, object origin to either inner finger pad
    lift_slight_dz: float = 0.01
    lift_slight_dist: float = 0.05
    lift_large_dz: float = 0.075
    lift_large_dist: float = 0.10
    move_close_dist: float = 0.125
    rotated_angle: float = 1.1  # rad about the vertical axis
    joint_move: float = 0.025  # fraction of the joint range
    open_fractions: tuple[float, float, float] = (0.125, 0.65, 0.95)
    close_fractions: tuple[float, float, float] = (0.875, 0.35, 0.05)


class StageInputs:
    """Batched quantities the predicates read (B = num_envs); the env fills what its skill needs.

    Each field is a tensor or a zero-argument callable evaluated on first use, so a step only pays
    for what the stages being checked read (contact queries cost more than the physics on CPU).

    obj_pos (B,3) main object (drawer handle / switch) anchor; obj_pos0 reference after settling;
    finger_pos (B,2,3) inner finger pads; touching, grasped (B,) bool; obj_quat, obj_quat0 (B,4)
    wxyz; target_pos (B,3); placed_into, placed_onto (B,) geometric checks; toggled (B,) switch
    state; openness, openness0 (B,) drawer opening in [0,1]; extra: dict.
    """

    FIELDS = (
        "obj_pos", "obj_pos0", "finger_pos", "touching", "grasped", "obj_quat", "obj_quat0", "target_pos",
        "placed_into", "placed_onto", "toggled", "openness", "openness0", "extra",
    )

    def __init__(self, **fields):
        unknown = set(fields) - set(self.FIELDS)
        if unknown:
            raise TypeError(f"unknown stage inputs {sorted(unknown)}; known: {self.FIELDS}")
        self.__dict__.update(dict.fromkeys(self.FIELDS), extra={})
        self.__dict__.update(fields)

    def __getattribute__(self, name: str):
        v = object.__getattribute__(self, name)
        if name in StageInputs.FIELDS and callable(v) and not isinstance(v, torch.Tensor):
            v = self.__dict__[name] = v()
        return v

    def __setattr__(self, name: str, value) -> None:
        if name not in self.FIELDS:
            raise AttributeError(f"unknown stage input {name!r}")
        self.__dict__[name] = value


def rotation_vector_z(quat: torch.Tensor, quat0: torch.Tensor) -> torch.Tensor:
    """z-component of the rotation vector of R_now * R_0^-1 (REALM's ROTATED measure, not Euler yaw)."""
    r = quaternion_to_matrix(quat) @ quaternion_to_matrix(quat0).transpose(-1, -2)
    cos = ((r.diagonal(dim1=-2, dim2=-1).sum(-1) - 1) / 2).clamp(-1, 1)
    angle = torch.acos(cos)
    axis_z = r[..., 1, 0] - r[..., 0, 1]
    sin = torch.sin(angle)
    small = sin.abs() < 1e-6
    # near 0 or pi the axis formula degenerates: fall back to the diagonal-based axis
    kz = torch.where(small, torch.sqrt(((r[..., 2, 2] + 1) / 2).clamp(min=0)), axis_z / (2 * sin.clamp(min=1e-6)))
    return angle * kz


def _reach(x: StageInputs, t: Thresholds) -> torch.Tensor:
    near = ((x.finger_pos - x.obj_pos[:, None]).norm(dim=-1) < t.reach_dist).any(-1)
    return near if bool(near.all()) else near | x.touching  # contact query only when needed


def _lift(x: StageInputs, dz: float, dist: float) -> torch.Tensor:
    d = x.obj_pos - x.obj_pos0
    return (d[:, 2] > dz) & (d.norm(dim=-1) > dist)


def _moved(x: StageInputs, t: Thresholds, opening: bool) -> torch.Tensor:
    delta = x.openness - x.openness0
    return x.touching & ((delta > t.joint_move) if opening else (-delta > t.joint_move))


Predicate = Callable[[StageInputs, Thresholds], torch.Tensor]
PREDICATES: dict[Stage, Predicate] = {
    S.REACH: lambda x, t: _reach(x, t),
    S.GRASP: lambda x, t: x.grasped,
    S.TOUCH: lambda x, t: x.touching,
    S.LIFT_SLIGHT: lambda x, t: _lift(x, t.lift_slight_dz, t.lift_slight_dist),
    S.LIFT_LARGE: lambda x, t: _lift(x, t.lift_large_dz, t.lift_large_dist),
    S.ROTATED: lambda x, t: rotation_vector_z(x.obj_quat, x.obj_quat0).abs() > t.rotated_angle,
    S.MOVE_CLOSE: lambda x, t: (x.obj_pos - x.target_pos).norm(dim=-1) < t.move_close_dist,
    S.PLACE_INTO: lambda x, t: x.placed_into & ~x.grasped,
    S.PLACE_ONTO: lambda x, t: x.placed_onto & ~x.grasped,
    S.TOGGLED_ON: lambda x, t: x.toggled,
    S.TOUCH_AND_MOVE_JOINT: lambda x, t: _moved(x, t, opening=x.extra.get("opening", True)),
    S.OPEN_JOINT_SMALL: lambda x, t: x.openness > t.open_fractions[0],
    S.OPEN_JOINT_LARGE: lambda x, t: x.openness > t.open_fractions[1],
    S.OPEN_JOINT_FULL: lambda x, t: x.openness > t.open_fractions[2],
    S.CLOSE_JOINT_SMALL: lambda x, t: x.openness < t.close_fractions[0],
    S.CLOSE_JOINT_LARGE: lambda x, t: x.openness < t.close_fractions[1],
    S.CLOSE_JOINT_FULL: lambda x, t: x.openness < t.close_fractions[2],
}


class ProgressionTracker:
    """Latched per-env stage state for one rubric."""

    def __init__(self, skill: str, num_envs: int, device, thresholds: Thresholds = Thresholds()):
        self.skill = as_skill(skill)
        self.stages = RUBRICS.get(self.skill)
        self.thresholds = thresholds
        self.met = torch.zeros(num_envs, len(self.stages), dtype=torch.bool, device=device)

    def reset(self, env_idx: torch.Tensor | None = None) -> None:
        if env_idx is None:
            self.met[:] = False
        else:
            self.met[env_idx] = False

    def update(self, x: StageInputs, active: torch.Tensor | None = None) -> torch.Tensor:
        """Latch newly met stages in order; returns progression (B,) in [0, 1].

        Only the frontier is evaluated: a stage whose predecessors are not all met, or which is
        already latched, in every env cannot change, so its predicate (and its inputs) are skipped.
        ``active`` (B,) masks envs whose stages may latch at all (e.g. reference not captured yet).
        """
        for k, stage in enumerate(self.stages):
            candidates = ~self.met[:, k]
            if k:
                candidates &= self.met[:, :k].all(dim=1)
            if active is not None:
                candidates &= active
            if not bool(candidates.any()):
                continue
            self.met[:, k] |= candidates & PREDICATES[stage](x, self.thresholds)
        return self.progression

    @property
    def progression(self) -> torch.Tensor:
        return self.met.sum(dim=1).float() / len(self.stages)

    @property
    def success(self) -> torch.Tensor:
        return self.met.all(dim=1)

    def stalled_stage(self) -> list[str]:
        """Name of the first unmet stage per env ("DONE" when complete), for failure reports."""
        n = self.met.sum(dim=1).tolist()
        return [self.stages[k].value if k < len(self.stages) else "DONE" for k in n]

    def info(self) -> dict[str, torch.Tensor]:
        out = {f"stage_{s.value.lower()}": self.met[:, k] for k, s in enumerate(self.stages)}
        out["stalled_stage_index"] = self.met.sum(dim=1)
        return out
