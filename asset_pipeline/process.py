"""One object through all stages: the unit of work of a build (a local worker or a Ray task)."""

from __future__ import annotations

import hashlib
import json
import signal
import time
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from asset_pipeline.categories import category_info
from asset_pipeline.config import BuildConfig
from asset_pipeline.export import AtomicDir, write_convex_obj, write_glb
from asset_pipeline.procedural.materialize import object_dirname
from asset_pipeline.record import CatalogRecord
from asset_pipeline.semantics import size_class
from asset_pipeline.sources.source import SourceItem
from asset_pipeline.stages import MeshError
from asset_pipeline.stages.appearance import dominant_colors, render_thumbnail
from asset_pipeline.stages.decompose import Decomposition, clean_hulls, decompose
from asset_pipeline.stages.load import load_item
from asset_pipeline.stages.normalize import normalize
from asset_pipeline.stages.physics import mass_for, solid_volume
from asset_pipeline.stages.repair import combined, repair_scene
from asset_pipeline.stages.stable import stable_poses


@lru_cache(maxsize=1)
def pipeline_version() -> str:
    """Hash of the pipeline's own code: changing a stage invalidates cached objects."""
    root = Path(__file__).parent
    h = hashlib.sha1()
    for p in sorted(list(root.glob("*.py")) + list(root.glob("stages/*.py")) + list(root.glob("procedural/*.py"))):
        h.update(p.read_bytes())
    return h.hexdigest()[:12]


def item_hash(item: SourceItem, cfg: BuildConfig) -> str:
    return hashlib.sha1(f"{item.content_key()}:{cfg.output_key()}:{pipeline_version()}".encode()).hexdigest()[:20]


@dataclass
class Outcome:
    id: str
    status: str  # built | cached | failed
    seconds: float
    record: dict | None = None
    error: str | None = None
    decomposition: str | None = None
    cpu_seconds: float = 0.0  # this process + CoACD children: independent of machine contention


class ObjectTimeout(BaseException):  # BaseException: library `except Exception` must not swallow it
    pass


@contextmanager
def time_limit(seconds: float):
    """SIGALRM-based limit for the Python stages (CoACD has its own killable budget)."""
    if seconds <= 0 or not hasattr(signal, "SIGALRM"):
        yield
        return

    def _raise(signum, frame):
        raise ObjectTimeout(f"object exceeded {seconds:.0f} s")

    try:
        old = signal.signal(signal.SIGALRM, _raise)
    except ValueError:  # not in the main thread (e.g. some Ray setups): run unlimited
        yield
        return
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def object_folder(out: Path, oid: str) -> Path:
    return Path(out) / "objects" / object_dirname(oid)


def build_object(item: SourceItem, out: Path, cfg: BuildConfig, content_hash: str) -> tuple[CatalogRecord, Decomposition]:
    # Procedural objects carry exact semantics, size and mass: the category table is for real meshes.
    info = category_info(item.category) if item.procedural is None else None
    lo = load_item(item)
    rep = repair_scene(lo.scene) if item.procedural is None else None
    if info is not None:
        norm = normalize(lo.scene, lo.hulls, item.id, info, item.known_scale)
        extents = norm.extents
    else:
        v = np.vstack([g.vertices for g in lo.scene.geometry.values()])
        extents = [float(x) for x in v.max(0) - v.min(0)]
    mesh = combined(lo.scene)
    if lo.hulls is not None:
        hulls = clean_hulls(lo.hulls)
        dec = Decomposition(hulls, "procedural" if item.procedural else "prebuilt", 0.0)
        if not hulls:
            raise MeshError("prebuilt collision parts are all degenerate")
    else:
        cache = Path(out) / "cache" / "coacd"
        dec = decompose(mesh, cfg.coacd, cache, use_coacd=cfg.use_coacd)
    col_volume = float(sum(h.volume for h in dec.hulls))
    # Category densities are effective densities over the *filled* (collision) volume, the same
    # convention as the procedural generators, so hollow shells (bowls, lids) get plausible masses.
    mass = lo.mass if lo.mass is not None else mass_for(col_volume if col_volume > 0 else solid_volume(mesh), info)  # type: ignore[arg-type]
    sem = lo.semantics or info.semantics  # type: ignore[union-attr]
    colors = list(sem.colors) if lo.semantics else ([item.color] if item.color else dominant_colors(lo.scene))
    folder = object_folder(out, item.id)
    rec = CatalogRecord(
        id=item.id, source=item.source, licence=item.licence, category=item.category,
        visual=f"objects/{folder.name}/visual.glb", collision=f"objects/{folder.name}/collision.obj",
        mass=float(mass), collision_volume=col_volume, extents=extents, friction=lo.friction or info.friction,  # type: ignore[union-attr]
        colors=colors, shapes=list(sem.shapes), material=sem.material, uses=list(sem.uses), fact=sem.fact, seen=sem.seen,
        theme=sem.theme, names=list(sem.names), size_class=size_class(max(extents)), n_hulls=len(dec.hulls),
        decomposition=dec.method, real_mesh=item.real_mesh, textured=lo.textured, lying=lo.lying,
        content_hash=content_hash, source_path=item.mesh or f"procedural:{item.procedural}",
    )
    if cfg.stable_poses:
        rec.stable_poses = stable_poses(dec.hulls, mesh.center_mass if mesh.is_watertight else None)
    with AtomicDir(folder) as tmp:
        write_glb(lo.scene, tmp / "visual.glb")
        write_convex_obj(dec.hulls, tmp / "collision.obj")
        if cfg.thumbnails:
            render_thumbnail(lo.scene, tmp / "thumb.png")
            rec.thumbnail = f"objects/{folder.name}/thumb.png"
        meta = json.loads(rec.to_json())
        meta["_build"] = {"repair": rep.__dict__ if rep else None, "decomposition_s": round(dec.seconds, 3), "coacd_cached": dec.cached}
        (tmp / "record.json").write_text(json.dumps(meta, indent=1))
    return rec, dec


def cached_record(item: SourceItem, out: Path, content_hash: str) -> dict | None:
    f = object_folder(out, item.id) / "record.json"
    if not f.exists():
        return None
    try:
        d = json.loads(f.read_text())
    except (OSError, json.JSONDecodeError):
        return None
    return d if d.get("content_hash") == content_hash else None


def _cpu_now() -> float:
    import resource

    return time.process_time() + resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime + resource.getrusage(resource.RUSAGE_CHILDREN).ru_stime


def process_item(item: SourceItem, out: str | Path, cfg: BuildConfig) -> Outcome:
    """Build one object unless an identical one is cached; never raises (failures are outcomes)."""
    c0 = _cpu_now()
    o = _process_item(item, out, cfg)
    o.cpu_seconds = _cpu_now() - c0
    return o


def _process_item(item: SourceItem, out: str | Path, cfg: BuildConfig) -> Outcome:
    t0 = time.perf_counter()
    out = Path(out)
    h = item_hash(item, cfg)
    try:
        prev = cached_record(item, out, h)
        if prev is not None:
            return Outcome(item.id, "cached", time.perf_counter() - t0, prev, decomposition=prev.get("decomposition"))
        folder = object_folder(out, item.id)
        if folder.exists():  # stale version: replaced atomically below
            import shutil

            shutil.rmtree(folder, ignore_errors=True)
        with time_limit(cfg.object_timeout_s):
            rec, dec = build_object(item, out, cfg, h)
        return Outcome(item.id, "built", time.perf_counter() - t0, json.loads(rec.to_json()), decomposition=dec.method)
    except (Exception, ObjectTimeout) as e:  # isolation: one bad mesh must not stop the build
        return Outcome(item.id, "failed", time.perf_counter() - t0, error=f"{type(e).__name__}: {e}"[:500])
