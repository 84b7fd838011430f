"""The scene interface and small builders shared by scenes (boxes with materials, textures)."""

from __future__ import annotations

import dataclasses
import zlib
from dataclasses import dataclass

import numpy as np
import sapien

from realm_ms.registry import Registry

SCENES: Registry["TabletopScene"] = Registry("scene")

# DROID's tables are ordinary household / lab tables: table tops 0.72-0.80 m above the floor
TABLE_HEIGHT_RANGE = (0.72, 0.80)
SWITCH_MOUNTS = ("wall", "table")
MATERIAL_MODES = ("episode", "nominal")


def register_scene(scene: "TabletopScene") -> "TabletopScene":
    return SCENES.register(scene.name, scene)


def add_lights(env, table_top_z, ambient, sun_dir, sun_rgb, fill_rgb, lamps) -> None:
    """Ambient + a shadow-casting sun + a fill light + point lamps ``(x, y, z above table, r, g, b)``,
    all scaled by ``realm_ms.rendering.light_gain(env.cameras.shader)`` (rt/raster exposure balance)."""
    from realm_ms.rendering import light_gain

    g = light_gain(env.cameras.shader)
    s = env.scene
    s.set_ambient_light([g * c for c in ambient])
    s.add_directional_light(list(sun_dir), [g * c for c in sun_rgb], shadow=env.enable_shadow, shadow_scale=3, shadow_map_size=2048)
    s.add_directional_light([-0.5, -0.2, -1.0], [g * c for c in fill_rgb])
    for x, y, z, r, gr, b in lamps:
        s.add_point_light([x, y, table_top_z + z], [g * r, g * gr, g * b])


def material(rgba, roughness: float = 0.7, metallic: float = 0.0) -> sapien.render.RenderMaterial:
    return sapien.render.RenderMaterial(base_color=list(rgba), roughness=roughness, metallic=metallic)


def add_box(builder, half_size, pose: sapien.Pose, mat, collision: bool = True) -> None:
    if collision:
        builder.add_box_collision(pose=pose, half_size=list(half_size))
    builder.add_box_visual(pose=pose, half_size=list(half_size), material=mat)


def episode_stream(env, i: int, name: str) -> np.random.Generator:
    """A generator seeded by sub-env ``i``'s episode seed and ``name`` only: the same seed draws the
    same scene, and the draw never shifts the episode RNG that placement and perturbations use."""
    return np.random.default_rng([int(env._episode_seed[i]), zlib.crc32(name.encode())])


def _option_value(key: str, raw: str, cur):
    """A scene option's text (from ``NAME?key=value``) as the type of its current value ``cur``:
    numbers must be finite, a tuple of numbers is given comma-separated with as many entries."""
    import math

    def number(text: str, kind: type):
        try:
            v = kind(text)
        except ValueError:
            raise ValueError(f"scene option {key}={raw!r}: expected {'an int' if kind is int else 'a float'}") from None
        if not math.isfinite(v):
            raise ValueError(f"scene option {key}={raw!r}: expected a finite number")
        return v

    if isinstance(cur, bool):
        if raw.lower() not in ("true", "false", "1", "0"):
            raise ValueError(f"scene option {key}={raw!r}: expected true or false")
        return raw.lower() in ("true", "1")
    if isinstance(cur, (int, float)):
        return number(raw, type(cur))
    if isinstance(cur, str):
        return raw
    if isinstance(cur, tuple) and cur and all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in cur):
        parts = [t.strip() for t in raw.split(",")]
        if len(parts) != len(cur):
            raise ValueError(f"scene option {key}={raw!r}: expected {len(cur)} comma-separated numbers (now {','.join(map(str, cur))})")
        vals = tuple(number(t, float) for t in parts)
        if key.endswith("half_size") and min(vals) <= 0:
            raise ValueError(f"scene option {key}={raw!r}: half sizes must be > 0 m")
        return vals
    raise ValueError(f"scene option {key!r} cannot be set in a scene name; make the scene in Python (dataclasses.replace)")


@dataclass(frozen=True)
class TabletopScene:
    """Static surroundings of a task: floor, walls, table, furniture, lights.

    Frame: the robot base is the world origin (cameras and spawn regions are given in it). The
    table top is ``base_above_table`` below the base (0: level with it, as every scene has it by
    default) and ``table_height`` above the floor; the robot's pedestal fills the rest.
    """

    name: str
    table_height: float = 0.76  # floor -> table top (m); DROID class: TABLE_HEIGHT_RANGE
    base_above_table: float = 0.0  # robot base above the table top (m); moves the table and all it holds
    table_half_size: tuple[float, float, float] = (0.45, 0.75, 0.02)  # x, y, thickness/2
    table_center_xy: tuple[float, float] = (0.62, 0.0)
    switch_mount: str = "wall"  # where a light switch sits: "wall" (a wall panel, REALM) or "table"
    switch_height: float = 0.15  # wall mount: switch centre above the table top (m)
    materials: str = "episode"  # "episode": material variants drawn per episode; "nominal": the scene's own look

    def __post_init__(self) -> None:
        if self.switch_mount not in SWITCH_MOUNTS:
            raise ValueError(f"scene {self.name!r}: switch_mount={self.switch_mount!r}; use one of {SWITCH_MOUNTS}")
        if self.materials not in MATERIAL_MODES:
            raise ValueError(f"scene {self.name!r}: materials={self.materials!r}; use one of {MATERIAL_MODES}")
        if not 0.4 <= self.table_height <= 1.2:
            raise ValueError(f"scene {self.name!r}: table_height={self.table_height} m is not a table; DROID's are {TABLE_HEIGHT_RANGE}")
        if not -0.3 <= self.base_above_table <= 0.3:
            raise ValueError(f"scene {self.name!r}: base_above_table={self.base_above_table} m is outside [-0.3, 0.3]")

    robot_base_z = 0.0  # the world origin

    @property
    def table_top_z(self) -> float:
        return -self.base_above_table

    @property
    def robot_stand_height(self) -> float:
        """Pedestal under the robot base, down to the floor."""
        return self.table_height + self.base_above_table

    @property
    def floor_z(self) -> float:
        return self.table_top_z - self.table_height

    def with_options(self, **options) -> "TabletopScene":
        """This scene with some fields changed (``get_scene("kitchen?table_height=0.74")``)."""
        fields = {f.name: f for f in dataclasses.fields(self) if f.name != "name"}
        changes = {}
        for key, raw in options.items():
            if key not in fields:
                raise ValueError(f"scene {self.name!r} has no option {key!r}; options: {', '.join(sorted(fields))}")
            changes[key] = _option_value(key, raw, getattr(self, key)) if isinstance(raw, str) else raw
        return dataclasses.replace(self, **changes)

    def build(self, env) -> None:
        """Add static actors to ``env.scene`` (all sub-scenes)."""
        raise NotImplementedError

    def load_lighting(self, env) -> None:
        raise NotImplementedError

    def on_episode_init(self, env, env_idx) -> None:
        """Per-episode draws of the sub-envs ``env_idx`` (materials); physics-neutral."""
