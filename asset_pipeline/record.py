"""One catalog row: everything the runtime needs to build and describe an object.

The catalog is ``catalog.jsonl`` (one :class:`CatalogRecord` per line) next to per-object folders.
Paths inside a record are relative to the catalog directory so catalogs can be moved or shipped.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

CATALOG_FILE = "catalog.jsonl"
FAILURES_FILE = "failures.jsonl"
SCHEMA_VERSION = 1


@dataclass
class CatalogRecord:
    id: str
    source: str
    licence: str
    category: str
    visual: str  # GLB (materials/textures embedded), relative to the catalog dir
    collision: str  # OBJ whose objects are the convex parts
    mass: float  # kg at scale 1
    collision_volume: float  # m^3 of the convex parts at scale 1 (density = mass / volume)
    extents: list[float]  # AABB size (m) in the resting frame
    friction: float = 0.6
    colors: list[str] = field(default_factory=list)
    shapes: list[str] = field(default_factory=list)
    material: str = "unknown"
    uses: list[str] = field(default_factory=list)
    fact: str | None = None
    seen: bool = True
    theme: str = "misc"
    names: list[str] = field(default_factory=list)
    size_class: str = "small"
    n_hulls: int = 1
    decomposition: str = "procedural"  # procedural | prebuilt | coacd | hull
    real_mesh: bool = False  # geometry comes from a real (non-procedural) mesh
    textured: bool = False
    lying: bool = False
    stable_poses: list[list[float]] = field(default_factory=list)  # [qw, qx, qy, qz, probability]
    thumbnail: str | None = None
    content_hash: str = ""
    source_path: str = ""
    schema: int = SCHEMA_VERSION

    def to_json(self) -> str:
        return json.dumps(asdict(self), separators=(",", ":"))

    @classmethod
    def from_dict(cls, d: dict) -> "CatalogRecord":
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in known})


def read_catalog(catalog_dir: str | Path) -> list[CatalogRecord]:
    path = Path(catalog_dir) / CATALOG_FILE
    out = []
    with open(path) as f:
        for line in f:
            if line.strip():
                out.append(CatalogRecord.from_dict(json.loads(line)))
    return out
