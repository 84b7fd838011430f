"""Declarative task specs: a REALM task is data (objects, regions, instruction, rubric, cameras, pose).

A task file declares one ``TaskSpec`` and passes it to ``realm_ms.tasks.env.register_task``, which
makes the env class and registers it with ManiSkill and gymnasium under ``spec.env_id``; this module
holds only data (no env import).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.agents.urdf import DROID_RESET_QPOS
from realm_ms.task_index import HORIZON
from realm_ms.registry import Registry
from realm_ms.tasks.skills import Skill, as_skill



@dataclass(frozen=True)
class SceneObject:
    """One object in a task scene.

    ``asset`` names an object of ``realm_ms.assets`` (e.g. ``"proc/apple/0"``); ``role`` is
    ``main`` (the rubric's object), ``target`` (receptacle / base), ``distractor`` or ``fixture``
    (placed at ``pose`` and never re-sampled).
    """

    name: str
    asset: str
    role: str = "distractor"
    region: tuple[float, float, float, float] | None = None  # x_min, x_max, y_min, y_max (robot base frame)
    yaw: tuple[float, float] = (-np.pi, np.pi)  # uniform yaw range (rad)
    pose: tuple[float, ...] | None = None  # fixtures: x, y, z, yaw
    fixed: bool = False  # kinematic (e.g. a cabinet bolted to the wall)
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)  # per-axis scale of the asset (perturbations: VB-MOBJ, V-SC)


@dataclass(frozen=True)
class CameraSpec:
    """An external camera by eye and look-at point in the robot base frame (metres)."""

    uid: str
    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    hfov_deg: float = 93.7  # DROID exterior ZED 2 at 1280x720


DEFAULT_CAMERAS = (
    CameraSpec("exterior_1", eye=(0.35, 0.72, 0.50), target=(0.50, 0.0, 0.0)),
    CameraSpec("exterior_2", eye=(0.35, -0.72, 0.50), target=(0.50, 0.0, 0.0)),
)


@dataclass(frozen=True)
class TaskSpec:
    env_id: str
    skill: Skill  # the rubric and the expert's program (a ``Skill`` or its value)
    instruction: str
    objects: tuple[SceneObject, ...]
    scene: str = "studio"
    spawn_region: tuple[float, float, float, float] = (0.35, 0.75, -0.30, 0.30)  # REALM: ~40 x 60 cm
    init_qpos: tuple[float, ...] = DROID_RESET_QPOS
    cameras: tuple[CameraSpec, ...] = DEFAULT_CAMERAS
    horizon: int = HORIZON  # control steps (REALM paper: 800 = 53 s at 15 Hz)
    min_separation: float = 0.05  # m between placed objects' bounding circles
    # m from the robot base: a rigid main object and target spawn within the arm's top-down reach
    # over the table (REALM's regions reach 0.9 m into the corners; a bottle at 0.85 m is out of reach)
    reach: float = 0.78
    description: str = ""
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "skill", as_skill(self.skill))

    def by_role(self, role: str) -> tuple[SceneObject, ...]:
        return tuple(o for o in self.objects if o.role == role)

    @property
    def main(self) -> SceneObject:
        (m,) = self.by_role("main") or (None,)
        if m is None:
            raise ValueError(f"{self.env_id}: exactly one object needs role='main'")
        return m


#: every declared task by env id (``realm_ms.tasks.env.register_task`` adds to it)
TASKS: Registry[TaskSpec] = Registry("task")
