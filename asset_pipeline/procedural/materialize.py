"""Turn a :class:`ProceduralObject` into files + a :class:`CatalogRecord` (shared by the runtime cache
and the catalog build, so both produce identical objects)."""

from __future__ import annotations

import hashlib
import json
from functools import lru_cache
from pathlib import Path

from asset_pipeline.export import AtomicDir, coloured_parts_scene, write_convex_obj, write_glb
from asset_pipeline.procedural.object_model import ProceduralObject
from asset_pipeline.record import CatalogRecord
from asset_pipeline.semantics import size_class

PROCEDURAL_LICENCE = "MIT (realm-ms procedural generator)"


@lru_cache(maxsize=1)
def generator_version() -> str:
    """Hash of the generator sources: editing a generator invalidates cached meshes automatically."""
    h = hashlib.sha1()
    for p in sorted(Path(__file__).parent.glob("*.py")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:12]


def object_dirname(oid: str) -> str:
    """Filesystem-safe, unique folder name for an object id."""
    safe = oid.replace("/", "__").replace("?", "__").replace("&", "_").replace("=", "-")
    return safe[:120]


def procedural_record(obj: ProceduralObject, visual: str, collision: str) -> CatalogRecord:
    s = obj.semantics
    ext = [float(x) for x in obj.extents]
    return CatalogRecord(
        id=obj.id,
        source="procedural",
        licence=PROCEDURAL_LICENCE,
        category=s.category,
        visual=visual,
        collision=collision,
        mass=obj.mass,
        collision_volume=float(sum(abs(h.volume) for h in obj.collision)),
        extents=ext,
        friction=obj.friction,
        colors=list(s.colors),
        shapes=list(s.shapes),
        material=s.material,
        uses=list(s.uses),
        fact=s.fact,
        seen=s.seen,
        theme=s.theme,
        names=list(s.names),
        size_class=size_class(max(ext)),
        n_hulls=len(obj.collision),
        decomposition="procedural",
        real_mesh=False,
        lying=obj.lying,
        content_hash=generator_version(),
        source_path=f"asset_pipeline/procedural ({obj.category})",
    )


def write_procedural(obj: ProceduralObject, folder: Path, rel_prefix: str = "") -> CatalogRecord:
    """Write ``visual.glb``/``collision.obj``/``record.json`` atomically into ``folder``."""
    folder = Path(folder)
    rec = procedural_record(obj, f"{rel_prefix}visual.glb", f"{rel_prefix}collision.obj")
    if (folder / "record.json").exists():
        return rec
    with AtomicDir(folder) as tmp:
        write_glb(coloured_parts_scene(obj.parts), tmp / "visual.glb")
        write_convex_obj(obj.collision, tmp / "collision.obj")
        (tmp / "record.json").write_text(json.dumps(json.loads(rec.to_json()), indent=1))
    return rec
