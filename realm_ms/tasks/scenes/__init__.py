"""Household tabletop scenes. One file per scene; every scene implements ``TabletopScene``.

Frame convention: the robot base is the world origin, x forward, z up; the table top is at
``table_top_z`` and extends in +x in front of the robot. Tasks place objects in their spawn region
(robot base frame), so one task can run in any scene.

A scene name may carry options like an asset name: ``"kitchen?table_height=0.74&switch_mount=table"``
(any field of the scene's dataclass: ``table_height``, ``base_above_table``, ``switch_mount``,
``switch_height``, ``materials``).
"""

from __future__ import annotations

from urllib.parse import parse_qsl

from realm_ms.tasks.scenes.scene import SCENES, TABLE_HEIGHT_RANGE, TabletopScene, register_scene  # noqa: F401
from realm_ms.tasks.scenes import studio  # noqa: F401  (registers its scenes)
from realm_ms.tasks.scenes import household  # noqa: F401  (kitchen, dining_room, office, living_room, pomaria)


def get_scene(name: str) -> TabletopScene:
    """The registered scene ``name``, with ``?key=value&...`` options applied. A key given twice,
    or a malformed query, is an error (never the last one silently)."""
    base, _, query = str(name).partition("?")
    scene = SCENES.get(base)
    if not query:
        return scene
    try:
        pairs = parse_qsl(query, keep_blank_values=True, strict_parsing=True)
    except ValueError:
        raise ValueError(f"scene {name!r}: malformed options {query!r}; write NAME?key=value&key=value") from None
    options: dict[str, str] = {}
    for key, value in pairs:
        if key in options:
            raise ValueError(f"scene {name!r}: option {key!r} is given twice ({options[key]!r}, {value!r}); give it once")
        options[key] = value
    return scene.with_options(**options)
