"""The scene interface and small builders shared by scenes (boxes with materials, textures)."""

from __future__ import annotations

from dataclasses import dataclass

import sapien

from realm_ms.registry import Registry

SCENES: Registry["TabletopScene"] = Registry("scene")


def register_scene(scene: "TabletopScene") -> "TabletopScene":
    return SCENES.register(scene.name, scene)


def add_lights(env, table_top_z, ambient, sun_dir, sun_rgb, fill_rgb, lamps) -> None:
    """Ambient + a shadow-casting sun + a fill light + point lamps ``(x, y, z above table, r, g, b)``,
    all scaled by ``realm_ms.rendering.light_gain(env.shader)`` (rt/raster exposure balance)."""
    from realm_ms.rendering import light_gain

    g = light_gain(getattr(env, "shader", "default"))
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


@dataclass(frozen=True)
class TabletopScene:
    """Static surroundings of a task: floor, walls, table, furniture, lights."""

    name: str
    table_top_z: float = 0.0
    table_half_size: tuple[float, float, float] = (0.45, 0.75, 0.02)  # x, y, thickness/2
    table_center_xy: tuple[float, float] = (0.62, 0.0)
    robot_stand_height: float = 0.76  # pedestal under the robot base, down to the floor

    @property
    def floor_z(self) -> float:
        return self.table_top_z - self.robot_stand_height

    def build(self, env) -> None:
        """Add static actors to ``env.scene`` (all sub-scenes)."""
        raise NotImplementedError

    def load_lighting(self, env) -> None:
        raise NotImplementedError
