"""Catalog access: a built catalog on disk, or the procedural registry materialised on demand.

``get_object_spec("proc/apple/0")`` never needs a build: procedural ids are generated and cached
under :func:`realm_ms.assets.paths.cache_dir`. Other ids are looked up in the built catalog.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from asset_pipeline.record import CATALOG_FILE, CatalogRecord, read_catalog
from realm_ms.registry import Registry
from realm_ms.assets.paths import cache_dir, default_catalog_dir
from realm_ms.assets.object_spec import ObjectSpec

# Variants per procedural category in the default catalog (89 categories x 40 = 3,560 objects).
PROCEDURAL_VARIANTS = 40

_lock = threading.Lock()


@dataclass(frozen=True)
class ObjectQuery:
    """Attribute filter shared by both catalog kinds; ``None`` = no constraint, tuples = any-of."""

    categories: tuple[str, ...] | None = None
    exclude_categories: tuple[str, ...] = ()
    seen: bool | None = None
    themes: tuple[str, ...] | None = None
    colors: tuple[str, ...] | None = None
    shapes: tuple[str, ...] | None = None
    materials: tuple[str, ...] | None = None
    uses: tuple[str, ...] | None = None  # substring match against affordance phrases
    real_mesh: bool | None = None
    sources: tuple[str, ...] | None = None
    max_extent: float | None = None  # only for built catalogs (procedural sizes are known after generation)

    def match_category_level(self, category: str, seen: bool, theme: str, shapes: Iterable[str], material: str, uses: Iterable[str]) -> bool:
        if self.categories is not None and category not in self.categories:
            return False
        if category in self.exclude_categories:
            return False
        if self.seen is not None and seen != self.seen:
            return False
        if self.themes is not None and theme not in self.themes:
            return False
        if self.shapes is not None and not set(self.shapes) & set(shapes):
            return False
        if self.materials is not None and material not in self.materials:
            return False
        if self.uses is not None and not any(q.lower() in u.lower() for q in self.uses for u in uses):
            return False
        return True

    def match_record(self, r: CatalogRecord) -> bool:
        if not self.match_category_level(r.category, r.seen, r.theme, r.shapes, r.material, r.uses):
            return False
        if self.colors is not None and not set(self.colors) & set(r.colors):
            return False
        if self.real_mesh is not None and r.real_mesh != self.real_mesh:
            return False
        if self.sources is not None and r.source not in self.sources:
            return False
        if self.max_extent is not None and max(r.extents) > self.max_extent:
            return False
        return True


class BuiltCatalog:
    """A catalog directory written by ``realm assets build``."""

    def __init__(self, root: str | Path):
        self.root = Path(root)
        self.records = read_catalog(self.root)
        self._by_id = {r.id: r for r in self.records}

    def __len__(self) -> int:
        return len(self.records)

    def candidates(self, q: ObjectQuery) -> dict[str, list[str]]:
        """Matching ids grouped by category."""
        out: dict[str, list[str]] = {}
        for r in self.records:
            if q.match_record(r):
                out.setdefault(r.category, []).append(r.id)
        return out

    def get(self, oid: str) -> ObjectSpec:
        if oid in self._by_id:
            return ObjectSpec(self._by_id[oid], self.root)
        if oid.startswith("proc/"):
            return procedural_spec(oid)
        raise KeyError(f"object {oid!r} is not in the catalog at {self.root}")


class ProceduralCatalog:
    """The procedural registry seen as a catalog of ``variants`` objects per category (no build needed)."""

    def __init__(self, variants: int = PROCEDURAL_VARIANTS):
        from asset_pipeline.procedural import REGISTRY

        self.registry = REGISTRY
        self.variants = variants
        self.root = cache_dir()

    def __len__(self) -> int:
        return len(self.registry) * self.variants

    def candidates(self, q: ObjectQuery) -> dict[str, list[str]]:
        if q.real_mesh or (q.sources is not None and "procedural" not in q.sources):
            return {}
        out: dict[str, list[str]] = {}
        for name, c in self.registry.items():
            if not q.match_category_level(name, c.seen, c.theme, c.shapes, c.material, c.uses):
                continue
            if q.colors is None:
                out[name] = [f"proc/{name}/{s}" for s in range(self.variants)]
            else:  # force one of the requested colours the category can take: exact colour words
                cols = [col for col in q.colors if col in c.colors]
                if cols:
                    out[name] = [f"proc/{name}/{s}?color={cols[s % len(cols)]}" for s in range(self.variants)]
        return out

    def get(self, oid: str) -> ObjectSpec:
        return procedural_spec(oid)


def procedural_spec(oid: str) -> ObjectSpec:
    """Generate (or reuse from the on-disk cache) the procedural object ``oid``."""
    return _procedural_spec_cached(oid, str(cache_dir()))


@lru_cache(maxsize=4096)
def _procedural_spec_cached(oid: str, cache_root: str) -> ObjectSpec:
    import json

    from asset_pipeline.procedural import make_object, parse_object_id
    from asset_pipeline.procedural.materialize import generator_version, object_dirname, write_procedural

    folder = Path(cache_root) / generator_version() / object_dirname(oid)
    rec_file = folder / "record.json"
    if rec_file.exists():
        return ObjectSpec(CatalogRecord.from_dict(json.loads(rec_file.read_text())), folder)
    cat, seed, params = parse_object_id(oid)
    obj = make_object(cat, seed, **params)
    with _lock:
        rec = write_procedural(obj, folder)
    return ObjectSpec(rec, folder)


def procedural_object_spec(category: str, seed: int = 0, color: str | None = None, size: float | None = None) -> ObjectSpec:
    """``procedural_object_spec("cube", 0, color="green", size=0.03)`` -> spec of a 3 cm green cube."""
    from asset_pipeline.procedural import object_id

    return procedural_spec(object_id(category, seed, color=color, size=size))


_catalog_cache: dict[str, object] = {}


def load_catalog(path: str | Path | None = None) -> BuiltCatalog | ProceduralCatalog:
    """The catalog at ``path`` (default: ``$REALM_ASSETS_DIR``); the procedural catalog if none is built."""
    root = Path(path) if path is not None else default_catalog_dir()
    key = str(root)
    if key not in _catalog_cache:
        if (root / CATALOG_FILE).exists():
            _catalog_cache[key] = BuiltCatalog(root)
        elif path is not None:
            raise FileNotFoundError(f"no {CATALOG_FILE} in {root}; build one with `realm assets build --out {root}`")
        else:
            _catalog_cache[key] = ProceduralCatalog()
    return _catalog_cache[key]  # type: ignore[return-value]


# id prefix -> resolver(oid) -> ObjectSpec, for ids outside procedural/built catalogs; modules
# register themselves (``real/``: default-installed real meshes, ``realm_ms.assets.real_objects``)
ID_RESOLVERS: Registry = Registry("object id prefix")


def get_object_spec(oid: str, catalog: BuiltCatalog | ProceduralCatalog | str | Path | None = None) -> ObjectSpec:
    if oid.startswith("proc/") and catalog is None:
        return procedural_spec(oid)
    for prefix, resolve in ID_RESOLVERS.items():  # e.g. "real/" (realm_ms.assets.real_objects)
        if oid.startswith(prefix):
            return resolve(oid)
    cat = catalog if isinstance(catalog, (BuiltCatalog, ProceduralCatalog)) else load_catalog(catalog)
    return cat.get(oid)
