"""A plain lab corner: wooden table, grey floor, two walls. The default backdrop."""

from __future__ import annotations

from dataclasses import dataclass

import sapien

from realm_ms.tasks.scenes.scene import TabletopScene, add_box, add_lights, material, register_scene


@dataclass(frozen=True)
class Studio(TabletopScene):
    table_rgba: tuple = (0.55, 0.38, 0.22, 1.0)
    floor_rgba: tuple = (0.45, 0.45, 0.47, 1.0)
    wall_rgba: tuple = (0.86, 0.84, 0.80, 1.0)

    def build(self, env) -> None:
        b = env.scene.create_actor_builder()
        hx, hy, hz = self.table_half_size
        cx, cy = self.table_center_xy
        top = self.table_top_z
        wood = material(self.table_rgba, roughness=0.55)
        add_box(b, (hx, hy, hz), sapien.Pose([cx, cy, top - hz]), wood)
        leg_h = (top - 2 * hz - self.floor_z) / 2
        for sx in (-1, 1):
            for sy in (-1, 1):
                add_box(b, (0.03, 0.03, leg_h), sapien.Pose([cx + sx * (hx - 0.05), cy + sy * (hy - 0.05), self.floor_z + leg_h]), wood)
        # robot pedestal
        add_box(b, (0.12, 0.12, self.robot_stand_height / 2 - 0.005), sapien.Pose([0, 0, self.floor_z + self.robot_stand_height / 2 - 0.005]), material((0.2, 0.2, 0.22, 1), 0.4, 0.3))
        add_box(b, (4.0, 4.0, 0.01), sapien.Pose([0.5, 0, self.floor_z - 0.01]), material(self.floor_rgba, 0.9))
        wall = material(self.wall_rgba, 0.95)
        add_box(b, (0.02, 3.0, 1.5), sapien.Pose([2.3, 0, self.floor_z + 1.5]), wall, collision=False)
        add_box(b, (2.5, 0.02, 1.5), sapien.Pose([0.3, 2.2, self.floor_z + 1.5]), wall, collision=False)
        b.initial_pose = sapien.Pose()
        b.build_static(name="scene_static")

    def load_lighting(self, env) -> None:
        add_lights(env, self.table_top_z, (0.35, 0.35, 0.35), (0.3, 0.4, -1.0), (0.9, 0.87, 0.82), (0.3, 0.3, 0.32), ((0.6, 0.0, 1.6, 1.2, 1.1, 1.0),))


register_scene(Studio("studio"))
