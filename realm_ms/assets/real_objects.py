"""Real (scanned/modelled, textured) meshes for REALM's task objects, from packages installed by default.

``get_object_spec("real/apple")`` resolves a task noun to a real mesh shipped inside a default
dependency (ManiSkill's wheel carries ReplicaCAD's apple and bowl): the asset pipeline processes it
once (repair, CoACD decomposition, cached by content hash under ``$REALM_ASSETS_CACHE/real``), then
the mesh is scaled uniformly to the real size of its procedural counterpart and given that
counterpart's mass and friction, so grasps, rubrics and the expert see the sizes they were tuned on.
When the package file is missing (another mani-skill version) or processing fails, the procedural
counterpart is used instead, with one warning.

Nouns without a default-installed real mesh (banana, mug, spoon, marker, blocks, box) stay
procedural; ``realm assets build`` adds YCB/LIBERO meshes to the catalog for perturbations.
"""

from __future__ import annotations

import functools
import hashlib
import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from realm_ms.assets.catalog import ID_RESOLVERS, procedural_spec
from realm_ms.assets.paths import cache_dir
from realm_ms.assets.object_spec import ObjectSpec

PREFIX = "real/"


@dataclass(frozen=True)
class RealObject:
    name: str  # id: real/<name>
    source: str  # asset_pipeline source providing the mesh
    item: str  # source item id
    fallback: str  # procedural id: size (largest extent), mass and friction of the real object
    licence: str
    concave: bool = False  # needs CoACD parts (a bowl's cavity): a convex-hull fallback is unusable


REAL_OBJECTS: dict[str, RealObject] = {
    o.name: o
    for o in (
        # ReplicaCAD apple: 7.5 cm, 150 g (a medium apple)
        RealObject("apple", "maniskill", "maniskill/apple_1", "proc/apple/0?color=red&size=0.075", "CC-BY-4.0 (ReplicaCAD, via mani-skill)"),
        # ReplicaCAD FRL apartment bowl: 17.5 cm across (REALM's bowl size)
        RealObject("bowl", "maniskill", "maniskill/frl_apartment_bowl_07", "proc/bowl/1", "CC-BY-4.0 (ReplicaCAD, via mani-skill)", concave=True),
    )
}


def real_ids() -> list[str]:
    return [PREFIX + n for n in REAL_OBJECTS]


def real_object_spec(oid: str) -> ObjectSpec:
    """The fitted real mesh for ``real/<name>``, or its procedural fallback (one warning)."""
    name = oid[len(PREFIX):] if oid.startswith(PREFIX) else oid
    if name not in REAL_OBJECTS:
        raise KeyError(f"no real object {oid!r}; known: {', '.join(real_ids())}")
    return _real_spec(name, str(cache_dir()))


@functools.lru_cache(maxsize=64)
def _real_spec(name: str, cache_root: str) -> ObjectSpec:
    obj = REAL_OBJECTS[name]
    ref = procedural_spec(obj.fallback)
    try:
        return _fitted(obj, ref, Path(cache_root) / "real")
    except Exception as e:  # noqa: BLE001 - any failure falls back to the procedural object
        warnings.warn(f"real mesh for {name!r} unavailable ({type(e).__name__}: {e}); using procedural {obj.fallback}", RuntimeWarning, stacklevel=2)
        return ref


def _source_item(obj: RealObject):
    from asset_pipeline.sources.source import SOURCES  # registered sources (import registers them)
    import asset_pipeline.sources  # noqa: F401

    src = SOURCES[obj.source]
    root = src.locate() if src.locate else None
    if root is None:
        raise FileNotFoundError(f"package for source {obj.source!r} not installed")
    for item in src.items(Path(root)):
        if item.id == obj.item:
            return item
    raise FileNotFoundError(f"{obj.item} not shipped by the installed {obj.source} package")


def _fitted(obj: RealObject, ref: ObjectSpec, root: Path) -> ObjectSpec:
    import trimesh

    from asset_pipeline.config import BuildConfig
    from asset_pipeline.export import AtomicDir, read_convex_obj, write_convex_obj, write_glb
    from asset_pipeline.process import process_item
    from asset_pipeline.record import CatalogRecord
    from asset_pipeline.stages.decompose import CoacdSettings

    item = _source_item(obj)
    # CoACD once, cached by content hash; a generous budget so that which mesh a task gets never
    # depends on how busy the machine is (the budget is not part of the cache key)
    out = process_item(item, root / "raw", BuildConfig(thumbnails=False, coacd=CoacdSettings(budget_s=1800.0)))
    if out.status == "failed" or out.record is None:
        raise RuntimeError(out.error or "asset pipeline failed")
    raw = CatalogRecord.from_dict(out.record)
    if obj.concave and raw.decomposition != "coacd":  # CoACD timed out (busy machine): retry next time
        import shutil

        shutil.rmtree(root / "raw" / Path(raw.visual).parent, ignore_errors=True)
        raise RuntimeError(f"CoACD did not decompose the concave mesh ({raw.decomposition})")
    fit = hashlib.sha1(f"{obj.fallback}:{ref.max_extent:.6f}:{ref.mass:.6f}:{ref.record.friction}".encode()).hexdigest()[:8]
    key = f"{raw.content_hash[:12]}-{fit}"
    folder = root / "fitted" / f"{obj.name}-{key}"
    rec_file = folder / "record.json"
    if rec_file.exists():
        return ObjectSpec(CatalogRecord.from_dict(json.loads(rec_file.read_text())), folder)
    raw_root = root / "raw"
    k = ref.max_extent / max(raw.extents)  # uniform: keep the real shape, take the real size
    visual = trimesh.load(raw_root / raw.visual, force="scene")
    visual.apply_transform(np.diag([k, k, k, 1.0]))
    hulls = read_convex_obj(raw_root / raw.collision)
    for h in hulls:
        h.apply_scale(k)
    rec = CatalogRecord.from_dict(out.record)
    rec.id = PREFIX + obj.name
    rec.licence = obj.licence
    rec.visual, rec.collision, rec.thumbnail = "visual.glb", "collision.obj", None
    rec.extents = [float(e * k) for e in raw.extents]
    rec.collision_volume = float(sum(h.volume for h in hulls))
    rec.mass, rec.friction = ref.mass, ref.record.friction
    rec.names = list(ref.record.names) or rec.names
    rec.stable_poses = []
    with AtomicDir(folder) as tmp:
        write_glb(visual, tmp / "visual.glb")
        write_convex_obj(hulls, tmp / "collision.obj")
        (tmp / "record.json").write_text(rec.to_json())
    return ObjectSpec(rec, folder)


ID_RESOLVERS.register(PREFIX, real_object_spec)
