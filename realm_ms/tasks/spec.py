"""Declarative task specs: a REALM task is data (objects, regions, instruction, rubric, cameras, pose).

``register_task(TaskSpec(...))`` creates a ``RealmEnv`` subclass and registers it with ManiSkill and
gymnasium under ``spec.env_id``. Task files hold only their declaration.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.agents.urdf import DROID_RESET_QPOS



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
    skill: str  # key of progression.RUBRICS
    instruction: str
    objects: tuple[SceneObject, ...]
    scene: str = "studio"
    spawn_region: tuple[float, float, float, float] = (0.35, 0.75, -0.30, 0.30)  # REALM: ~40 x 60 cm
    init_qpos: tuple[float, ...] = DROID_RESET_QPOS
    cameras: tuple[CameraSpec, ...] = DEFAULT_CAMERAS
    horizon: int = 800  # control steps (REALM paper: 800 = 53 s at 15 Hz)
    min_separation: float = 0.05  # m between placed objects' bounding circles
    description: str = ""
    extra: dict = field(default_factory=dict)

    def by_role(self, role: str) -> tuple[SceneObject, ...]:
        return tuple(o for o in self.objects if o.role == role)

    @property
    def main(self) -> SceneObject:
        (m,) = self.by_role("main") or (None,)
        if m is None:
            raise ValueError(f"{self.env_id}: exactly one object needs role='main'")
        return m


TASKS: dict[str, TaskSpec] = {}


def register_task(spec: TaskSpec, base=None):
    """Create and register the env class for ``spec``; returns it."""
    from mani_skill.utils.registration import register_env

    from realm_ms.tasks.env import RealmEnv

    if spec.env_id in TASKS:
        raise ValueError(f"task {spec.env_id} declared twice")
    TASKS[spec.env_id] = spec
    base = base or RealmEnv
    name = spec.env_id.replace("REALM-", "").replace("-v1", "").replace("-", "") + "Env"
    doc = (
        f"**Task Description:** {spec.description or spec.instruction}. Instruction: \"{spec.instruction}\".\n\n"
        f"**Randomizations:** {', '.join(o.name for o in spec.objects if o.role != 'fixture')} placed collision-free "
        f"in x {spec.spawn_region[:2]}, y {spec.spawn_region[2:]} m (robot base frame) with random yaw; "
        f"seeded per episode.\n\n"
        f"**Success Conditions:** REALM '{spec.skill}' rubric, all stages latched: "
        f"{' -> '.join(s.value for s in _rubric(spec.skill))}."
    )
    cls = type(name, (base,), {"task_spec": spec, "__doc__": doc, "__module__": base.__module__})
    register_env(spec.env_id, max_episode_steps=spec.horizon)(cls)
    return cls


def _rubric(skill: str):
    from realm_ms.tasks.progression import RUBRICS

    return RUBRICS[skill]
