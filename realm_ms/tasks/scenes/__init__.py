"""Household tabletop scenes. One file per scene; every scene implements ``TabletopScene``.

Frame convention: the robot base is the world origin, x forward, z up; the table top is at
``table_top_z`` and extends in +x in front of the robot. Tasks place objects in their spawn region
(robot base frame), so one task can run in any scene.
"""

from __future__ import annotations

from realm_ms.tasks.scenes.scene import SCENES, TabletopScene, register_scene  # noqa: F401
from realm_ms.tasks.scenes import studio  # noqa: F401  (registers its scenes)
from realm_ms.tasks.scenes import household  # noqa: F401  (kitchen, dining_room, office, living_room, pomaria)


def get_scene(name: str) -> TabletopScene:
    return SCENES.get(name)
