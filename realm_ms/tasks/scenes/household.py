"""Household tabletop scenes in the spirit of REALM's BEHAVIOR scenes (different tables, floors,
walls, lighting and background furniture), all built from boxes/cylinders + procedural textures.

| scene | REALM counterpart | look |
|---|---|---|
| ``kitchen`` | Benevolence_1_int / Kitchen_Counter | stone-grey counter on base cabinets, tiled floor, fridge, wall shelf, warm light |
| ``dining_room`` | Wainscott_0_int, Pomaria_1_int / (Dining_)Table | oak dining table, plank floor, chairs, sideboard, window light |
| ``office`` | office_cubicles_left / Office_Desk, Circular_Table | white desk, carpet, cubicle partitions, filing cabinet, cool overhead light |
| ``living_room`` | Merom_1_int / Table | dark walnut table, rug on planks, sofa, plant, lamp |
| ``pomaria`` | Pomaria_1_int / Drawers_Near_Table | breakfast table by a window, tiled floor, bright disk-like light |

Everything in the workspace (x 0.17..1.07 m, |y| < 0.75 m in front of the robot) is the table top;
furniture stands outside it, so task placement never collides with the backdrop.

Materials: the table, floor and walls are material *slots*. Each slot has ``MATERIAL_VARIANTS``
looks: the scene's own (variant 0) and others of the same kind from ``PALETTES`` (wood species,
stones, tiles, carpets, wall paints), each with its own grain/tile pattern. With
``materials="episode"`` (default) every episode draws one variant per slot from its seed, per
sub-env; the static geometry is built once per sub-env, and a draw only swaps its materials'
textures, so it costs no rebuild and changes no physics.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np
import sapien

from realm_ms.tasks.scenes.scene import TabletopScene, add_box, add_lights, episode_stream, material, register_scene
from realm_ms.tasks.scenes import textures as tx

_OAK, _WALNUT = ((0.68, 0.50, 0.31), (0.48, 0.33, 0.19)), ((0.40, 0.26, 0.15), (0.22, 0.13, 0.07))
_MAPLE, _CHERRY = ((0.82, 0.70, 0.52), (0.66, 0.53, 0.36)), ((0.58, 0.30, 0.20), (0.40, 0.18, 0.11))
_ASH, _GREY_OAK = ((0.80, 0.76, 0.68), (0.64, 0.58, 0.50)), ((0.56, 0.52, 0.47), (0.40, 0.37, 0.33))
_WOODS = (_OAK, _WALNUT, _MAPLE, _CHERRY, _ASH, _GREY_OAK)
_PAINTS = tuple((c, c) for c in ((0.93, 0.93, 0.91), (0.93, 0.90, 0.82), (0.82, 0.86, 0.80), (0.80, 0.74, 0.66),
                                 (0.78, 0.84, 0.90), (0.90, 0.80, 0.78), (0.86, 0.86, 0.84)))
#: per texture kind, the (colour a, colour b) looks a slot's variants are drawn from
PALETTES = {
    "wood": _WOODS,
    "planks": _WOODS,
    "tiles": (((0.85, 0.83, 0.78), (0.30, 0.30, 0.32)), ((0.78, 0.72, 0.62), (0.62, 0.56, 0.48)),
              ((0.88, 0.90, 0.90), (0.70, 0.76, 0.80)), ((0.72, 0.42, 0.30), (0.60, 0.32, 0.22))),
    "plain_tiles": (((0.55, 0.55, 0.57), (0.35, 0.35, 0.37)), ((0.84, 0.82, 0.78), (0.62, 0.60, 0.56)),
                    ((0.26, 0.26, 0.28), (0.12, 0.12, 0.13)), ((0.72, 0.64, 0.54), (0.52, 0.44, 0.36))),
    "fabric": tuple((c, c) for c in ((0.30, 0.32, 0.36), (0.45, 0.40, 0.35), (0.26, 0.34, 0.30), (0.52, 0.52, 0.54), (0.35, 0.38, 0.55))),
    "plaster": _PAINTS,
}
MATERIAL_VARIANTS = 4  # looks per slot: the scene's own + 3 from its palette
SLOTS = ("table", "floor", "wall")


def _cyl(b, radius, half_len, pose: sapien.Pose, mat, collision=True):
    # SAPIEN cylinders run along x; rotate to stand upright
    q = sapien.Pose(q=[0.7071068, 0, 0.7071068, 0])
    p = pose * q
    if collision:
        b.add_cylinder_collision(pose=p, radius=radius, half_length=half_len)
    b.add_cylinder_visual(pose=p, radius=radius, half_length=half_len, material=mat)


@dataclass(frozen=True)
class HouseholdScene(TabletopScene):
    table_style: str = "legs"  # legs | counter | pedestal
    table_tex: tuple = ("wood", (0.62, 0.45, 0.28), (0.42, 0.28, 0.16))  # kind, colour a, colour b
    floor_tex: tuple = ("planks", (0.55, 0.40, 0.26), (0.35, 0.24, 0.15))
    wall_rgb: tuple = (0.86, 0.84, 0.80)
    wall2_rgb: tuple | None = None  # lower wall (wainscot) colour
    furniture: tuple = ()  # names of background pieces
    ambient: tuple = (0.35, 0.35, 0.35)
    sun_dir: tuple = (0.3, 0.4, -1.0)
    sun_rgb: tuple = (0.9, 0.87, 0.82)
    lamps: tuple = ((0.6, 0.0, 1.6, 1.2, 1.1, 1.0),)  # x, y, z above the table top, r, g, b
    seed: int = 0

    # ------------------------------------------------------------------ materials
    def slot_specs(self, slot: str) -> tuple:
        """The ``MATERIAL_VARIANTS`` texture specs ``(kind, a, b, seed)`` of a slot: the scene's own
        first, then looks of the same kind picked (per scene, fixed) from ``PALETTES``."""
        kind, a, b = {"table": self.table_tex, "floor": self.floor_tex, "wall": ("plaster", self.wall_rgb, self.wall_rgb)}[slot]
        own = (tuple(a), tuple(b))
        others = [p for p in PALETTES[kind] if p != own]
        pick = np.random.default_rng([self.seed, zlib.crc32(slot.encode())]).choice(len(others), MATERIAL_VARIANTS - 1, replace=False)
        looks = [own] + [others[k] for k in pick]
        return tuple((kind, la, lb, self.seed + 101 * v) for v, (la, lb) in enumerate(looks))

    def _texture(self, spec):
        """(cache key, maker, fallback colour) of a texture spec ``(kind, a, b[, seed])``."""
        kind, a, b, *rest = spec
        s = rest[0] if rest else self.seed
        makers = {
            "wood": lambda: tx.wood(a, b, seed=s, rings=45),
            "planks": lambda: tx.wood(a, b, seed=s + 1, rings=40, planks=8),
            "tiles": lambda: tx.tiles(a, b, (0.75, 0.75, 0.72), n=8, seed=s),
            "plain_tiles": lambda: tx.tiles(a, a, b, n=12, seed=s, checker=False),
            "fabric": lambda: tx.fabric(a, seed=s),
            "plaster": lambda: tx.plaster(a, seed=s),
        }
        key = f"{kind}/{tuple(a)}/{tuple(b)}/{s}"
        return key, makers[kind], tuple(a) + (1.0,)

    def _mat(self, spec, roughness=0.6, metallic=0.0):
        return tx.textured_material(*self._texture(spec), roughness, metallic)

    def on_episode_init(self, env, env_idx) -> None:
        """Draw each slot's look for the sub-envs ``env_idx`` from their episode seeds."""
        if self.materials != "episode":
            return
        for i in (int(k) for k in env_idx):
            rng = episode_stream(env, i, f"scene-materials/{self.name}")
            for slot in SLOTS:
                v = int(rng.integers(MATERIAL_VARIANTS))
                tx.apply_texture(env.scene_slots[i][slot], *self._texture(self.slot_specs(slot)[v]))
                env.scene_looks[i][slot] = v

    # ------------------------------------------------------------------ building
    def build(self, env) -> None:
        """One static actor per sub-env, each with its own slot materials (``env.scene_slots[i]``),
        so that an episode's material draw can differ between sub-envs."""
        env.scene_slots = [self._build_one(env, i) for i in range(env.num_envs)]
        env.scene_looks = [{slot: 0 for slot in SLOTS} for _ in range(env.num_envs)]

    def _build_one(self, env, i: int) -> dict:
        b = env.scene.create_actor_builder()
        b.set_scene_idxs([i])
        hx, hy, hz = self.table_half_size
        cx, cy = self.table_center_xy
        top, fz = self.table_top_z, self.floor_z
        slots = {slot: self._mat(self.slot_specs(slot)[0], roughness=r) for slot, r in zip(SLOTS, (0.45, 0.7, 0.95))}
        table_m = slots["table"]
        add_box(b, (hx, hy, hz), sapien.Pose([cx, cy, top - hz]), table_m)
        body_h = (top - 2 * hz - fz) / 2
        if self.table_style == "counter":
            cab = self._mat(("wood", (0.80, 0.78, 0.74), (0.70, 0.68, 0.64)), roughness=0.5)
            add_box(b, (hx - 0.04, hy, body_h), sapien.Pose([cx + 0.04, cy, fz + body_h]), cab)
            knob = material((0.6, 0.6, 0.62, 1), 0.3, 0.8)
            for k in range(4):
                y = cy - hy + (k + 0.5) * 2 * hy / 4
                add_box(b, (0.005, 2 * hy / 8 - 0.01, body_h - 0.05), sapien.Pose([cx - hx + 0.035, y, fz + body_h]), cab, collision=False)
                add_box(b, (0.01, 0.05, 0.006), sapien.Pose([cx - hx + 0.025, y, top - 0.12]), knob, collision=False)
        elif self.table_style == "pedestal":
            leg_m = material((0.15, 0.15, 0.16, 1), 0.4, 0.6)
            _cyl(b, 0.05, body_h, sapien.Pose([cx, cy, fz + body_h]), leg_m)
            _cyl(b, 0.30, 0.01, sapien.Pose([cx, cy, fz + 0.01]), leg_m)
        else:
            for sx in (-1, 1):
                for sy in (-1, 1):
                    add_box(b, (0.03, 0.03, body_h), sapien.Pose([cx + sx * (hx - 0.05), cy + sy * (hy - 0.05), fz + body_h]), table_m)
            add_box(b, (hx - 0.06, 0.015, 0.04), sapien.Pose([cx, cy + hy - 0.05, top - 2 * hz - 0.04]), table_m, collision=False)
            add_box(b, (hx - 0.06, 0.015, 0.04), sapien.Pose([cx, cy - hy + 0.05, top - 2 * hz - 0.04]), table_m, collision=False)
        # robot pedestal
        add_box(b, (0.12, 0.12, self.robot_stand_height / 2 - 0.005), sapien.Pose([0, 0, fz + self.robot_stand_height / 2 - 0.005]), material((0.2, 0.2, 0.22, 1), 0.4, 0.3))
        # floor and walls
        add_box(b, (4.0, 4.0, 0.01), sapien.Pose([0.5, 0, fz - 0.01]), slots["floor"])
        wall = slots["wall"]
        add_box(b, (0.02, 3.0, 1.5), sapien.Pose([2.3, 0, fz + 1.5]), wall, collision=False)
        add_box(b, (2.5, 0.02, 1.5), sapien.Pose([0.3, 2.2, fz + 1.5]), wall, collision=False)
        add_box(b, (2.5, 0.02, 1.5), sapien.Pose([0.3, -2.2, fz + 1.5]), wall, collision=False)
        if self.wall2_rgb is not None:
            low = material(tuple(self.wall2_rgb) + (1,), 0.8)
            add_box(b, (0.01, 3.0, 0.45), sapien.Pose([2.27, 0, fz + 0.45]), low, collision=False)
            add_box(b, (2.5, 0.01, 0.45), sapien.Pose([0.3, 2.17, fz + 0.45]), low, collision=False)
        add_box(b, (0.03, 3.0, 0.04), sapien.Pose([2.26, 0, fz + 0.04]), material((0.95, 0.95, 0.93, 1), 0.6), collision=False)
        for name in self.furniture:
            getattr(self, f"_f_{name}")(b, fz)
        b.initial_pose = sapien.Pose()
        b.build_static(name=f"scene_static-{i}")
        return slots

    # ------------------------------------------------------------------ background furniture
    def _f_fridge(self, b, fz):
        m = material((0.88, 0.89, 0.90, 1), 0.25, 0.4)
        add_box(b, (0.33, 0.36, 0.9), sapien.Pose([1.9, 1.3, fz + 0.9]), m, collision=False)
        add_box(b, (0.01, 0.015, 0.25), sapien.Pose([1.56, 1.05, fz + 1.2]), material((0.5, 0.5, 0.52, 1), 0.3, 0.9), collision=False)

    def _f_wall_shelf(self, b, fz):
        wd = self._mat(("wood", (0.70, 0.55, 0.38), (0.5, 0.36, 0.22)))
        for z in (1.45, 1.8):
            add_box(b, (0.12, 0.6, 0.015), sapien.Pose([2.15, -0.4, fz + z]), wd, collision=False)
        for k, rgb in enumerate([(0.8, 0.2, 0.2), (0.2, 0.5, 0.8), (0.9, 0.8, 0.3), (0.3, 0.6, 0.3)]):
            _cyl(b, 0.04, 0.07, sapien.Pose([2.15, -0.8 + 0.25 * k, fz + 1.54]), material(rgb + (1,), 0.5), collision=False)

    def _f_chairs(self, b, fz):
        wd = self._mat(("wood", (0.55, 0.38, 0.22), (0.38, 0.25, 0.14)))
        for cy in (-0.95, 0.95):
            add_box(b, (0.2, 0.2, 0.02), sapien.Pose([0.7, cy, fz + 0.45]), wd, collision=False)
            add_box(b, (0.2, 0.02, 0.25), sapien.Pose([0.7, cy + np.sign(cy) * 0.19, fz + 0.72]), wd, collision=False)
            for sx in (-1, 1):
                for sy in (-1, 1):
                    add_box(b, (0.015, 0.015, 0.22), sapien.Pose([0.7 + sx * 0.17, cy + sy * 0.17, fz + 0.22]), wd, collision=False)

    def _f_sideboard(self, b, fz):
        wd = self._mat(("wood", (0.45, 0.30, 0.18), (0.30, 0.19, 0.10)))
        add_box(b, (0.22, 0.8, 0.42), sapien.Pose([2.05, -0.6, fz + 0.42]), wd, collision=False)
        _cyl(b, 0.08, 0.12, sapien.Pose([2.05, -0.9, fz + 0.96]), material((0.2, 0.35, 0.6, 1), 0.2), collision=False)

    def _f_window(self, b, fz):
        add_box(b, (0.01, 0.7, 0.5), sapien.Pose([2.27, 0.5, fz + 1.5]), material((0.75, 0.85, 0.95, 1), 0.05), collision=False)
        frame = material((0.96, 0.96, 0.95, 1), 0.5)
        for dz in (-0.5, 0.5):
            add_box(b, (0.02, 0.72, 0.025), sapien.Pose([2.26, 0.5, fz + 1.5 + dz]), frame, collision=False)
        for dy in (-0.7, 0.0, 0.7):
            add_box(b, (0.02, 0.025, 0.52), sapien.Pose([2.26, 0.5 + dy, fz + 1.5]), frame, collision=False)

    def _f_partitions(self, b, fz):
        m = self._mat(("fabric", (0.45, 0.50, 0.56), (0.45, 0.50, 0.56)), roughness=0.95)
        add_box(b, (0.03, 1.2, 0.65), sapien.Pose([1.45, 0.0, fz + 0.65]), m, collision=False)
        add_box(b, (0.8, 0.03, 0.65), sapien.Pose([0.6, 1.25, fz + 0.65]), m, collision=False)
        add_box(b, (0.8, 0.03, 0.65), sapien.Pose([0.6, -1.25, fz + 0.65]), m, collision=False)

    def _f_filing_cabinet(self, b, fz):
        m = material((0.35, 0.37, 0.40, 1), 0.4, 0.6)
        add_box(b, (0.25, 0.2, 0.35), sapien.Pose([1.1, -1.0, fz + 0.35]), m, collision=False)
        for z in (0.2, 0.45):
            add_box(b, (0.005, 0.06, 0.01), sapien.Pose([0.845, -1.0, fz + z]), material((0.7, 0.7, 0.72, 1), 0.3, 0.9), collision=False)

    def _f_sofa(self, b, fz):
        m = self._mat(("fabric", (0.55, 0.22, 0.20), (0.55, 0.22, 0.20)), roughness=0.95)
        add_box(b, (0.45, 1.0, 0.22), sapien.Pose([1.9, -0.3, fz + 0.22]), m, collision=False)
        add_box(b, (0.12, 1.0, 0.45), sapien.Pose([2.25, -0.3, fz + 0.45]), m, collision=False)

    def _f_plant(self, b, fz):
        _cyl(b, 0.14, 0.18, sapien.Pose([1.5, 1.4, fz + 0.18]), material((0.7, 0.45, 0.3, 1), 0.8), collision=False)
        leaf = material((0.2, 0.5, 0.2, 1), 0.7)
        for k, (dx, dy, dz, r) in enumerate([(0, 0, 0.55, 0.22), (0.1, 0.08, 0.75, 0.16), (-0.1, -0.05, 0.7, 0.15)]):
            b.add_sphere_visual(pose=sapien.Pose([1.5 + dx, 1.4 + dy, fz + dz]), radius=r, material=leaf)

    def _f_floor_lamp(self, b, fz):
        m = material((0.2, 0.2, 0.2, 1), 0.4, 0.7)
        _cyl(b, 0.015, 0.75, sapien.Pose([1.8, 1.0, fz + 0.75]), m, collision=False)
        _cyl(b, 0.2, 0.15, sapien.Pose([1.8, 1.0, fz + 1.55]), material((0.98, 0.93, 0.8, 1), 0.9), collision=False)

    def _f_rug(self, b, fz):
        add_box(b, (1.2, 1.0, 0.004), sapien.Pose([0.8, 0.0, fz + 0.004]), self._mat(("fabric", (0.35, 0.38, 0.55), (0.35, 0.38, 0.55)), roughness=1.0), collision=False)

    # ------------------------------------------------------------------ lighting
    def load_lighting(self, env) -> None:
        add_lights(env, self.table_top_z, self.ambient, self.sun_dir, self.sun_rgb, (0.25, 0.25, 0.27), self.lamps)


KITCHEN = register_scene(HouseholdScene(
    "kitchen", table_height=0.8, table_style="counter", table_half_size=(0.45, 0.9, 0.02),
    table_tex=("plain_tiles", (0.55, 0.55, 0.57), (0.35, 0.35, 0.37)),
    floor_tex=("tiles", (0.85, 0.83, 0.78), (0.30, 0.30, 0.32)), wall_rgb=(0.93, 0.90, 0.82),
    furniture=("fridge", "wall_shelf"), ambient=(0.38, 0.36, 0.33), sun_rgb=(0.95, 0.85, 0.70),
    lamps=((0.6, 0.0, 1.5, 1.3, 1.05, 0.8),), seed=1,
))
DINING_ROOM = register_scene(HouseholdScene(
    "dining_room", table_height=0.75, table_tex=("wood", (0.68, 0.50, 0.31), (0.48, 0.33, 0.19)),
    floor_tex=("planks", (0.60, 0.44, 0.28), (0.38, 0.26, 0.16)), wall_rgb=(0.82, 0.86, 0.80), wall2_rgb=(0.95, 0.95, 0.92),
    furniture=("chairs", "sideboard", "window"), ambient=(0.4, 0.4, 0.42), sun_dir=(0.6, 0.2, -0.8), sun_rgb=(1.0, 0.97, 0.9),
    lamps=((0.6, 0.0, 1.4, 1.1, 1.0, 0.9),), seed=2,
))
OFFICE = register_scene(HouseholdScene(
    "office", table_height=0.74, switch_mount="table", table_half_size=(0.42, 0.8, 0.015), table_tex=("plaster", (0.93, 0.93, 0.91), (0.93, 0.93, 0.91)),
    floor_tex=("fabric", (0.30, 0.32, 0.36), (0.30, 0.32, 0.36)), wall_rgb=(0.90, 0.91, 0.93),
    furniture=("partitions", "filing_cabinet", "plant"), ambient=(0.42, 0.43, 0.46), sun_dir=(0.0, 0.1, -1.0), sun_rgb=(0.85, 0.88, 0.95),
    lamps=((0.4, 0.4, 1.7, 1.0, 1.05, 1.15), (0.8, -0.4, 1.7, 1.0, 1.05, 1.15)), seed=3,
))
LIVING_ROOM = register_scene(HouseholdScene(
    "living_room", table_height=0.72, table_style="pedestal", table_half_size=(0.45, 0.7, 0.025),
    table_tex=("wood", (0.40, 0.26, 0.15), (0.22, 0.13, 0.07)),
    floor_tex=("planks", (0.72, 0.58, 0.40), (0.50, 0.38, 0.25)), wall_rgb=(0.80, 0.74, 0.66),
    furniture=("sofa", "plant", "floor_lamp", "rug"), ambient=(0.33, 0.31, 0.29), sun_dir=(-0.3, 0.5, -0.8), sun_rgb=(0.9, 0.8, 0.65),
    lamps=((0.5, 0.3, 1.3, 1.2, 1.0, 0.75),), seed=4,
))
POMARIA = register_scene(HouseholdScene(
    "pomaria", table_height=0.76, table_tex=("wood", (0.80, 0.68, 0.50), (0.62, 0.50, 0.34)),
    floor_tex=("tiles", (0.78, 0.72, 0.62), (0.62, 0.56, 0.48)), wall_rgb=(0.95, 0.93, 0.88), wall2_rgb=(0.55, 0.62, 0.58),
    furniture=("window", "chairs", "plant"), ambient=(0.45, 0.45, 0.45), sun_dir=(0.5, -0.3, -0.9), sun_rgb=(1.0, 0.98, 0.95),
    lamps=((0.7, 0.0, 1.2, 2.0, 1.9, 1.8),), seed=5,
))
