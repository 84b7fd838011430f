"""Source model: a source enumerates :class:`SourceItem` s; the build turns each into a catalog object."""

from __future__ import annotations

import hashlib
import importlib.util
import json
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path


@dataclass
class SourceItem:
    id: str  # unique in the catalog, e.g. "ycb/025_mug"
    source: str
    licence: str
    category: str
    mesh: str | None = None  # visual mesh file (OBJ/GLB/GLTF/STL/PLY/DAE)
    mesh_scale: float | list[float] = 1.0  # applied before anything else (MJCF ``scale``)
    up: str = "z"  # up axis of the file: "z" or "y" (glTF convention)
    collision_file: str | None = None  # OBJ whose objects are already convex parts
    collision_boxes: list[dict] = field(default_factory=list)  # MJCF boxes {"size","pos","quat"} (half sizes)
    procedural: tuple[str, int] | None = None  # (category, seed) for generated objects
    real_mesh: bool = True
    name: str = ""
    known_scale: bool = False  # file units are trustworthy metres: skip the size heuristics
    color: str | None = None  # palette colour for untextured meshes (None: keep file colours)
    extra_files: list[str] = field(default_factory=list)  # textures/MTL: part of the content hash

    def content_key(self) -> str:
        """Hash of everything that determines the output (file bytes + item description)."""
        h = hashlib.sha1(json.dumps(asdict(self), sort_keys=True, default=str).encode())
        for f in [self.mesh, self.collision_file, *self.extra_files]:
            if f:
                h.update(_file_digest(f).encode())
        return h.hexdigest()


_digests: dict[str, str] = {}


def _file_digest(path: str) -> str:
    p = Path(path)
    key = f"{p}:{p.stat().st_mtime_ns}:{p.stat().st_size}" if p.exists() else str(p)
    if key not in _digests:
        _digests[key] = hashlib.sha1(p.read_bytes()).hexdigest() if p.exists() else "missing"
    return _digests[key]


@dataclass(frozen=True)
class SourceDef:
    name: str
    licence: str
    package: str | None  # registry package providing the files (None: built in / user folder)
    description: str
    items: Callable[..., Iterator[SourceItem]]
    locate: Callable[[], Path | None]


SOURCES: dict[str, SourceDef] = {}


def register_source(name: str, *, licence: str, package: str | None, description: str, locate: Callable[[], Path | None]):
    def deco(fn: Callable[..., Iterator[SourceItem]]):
        SOURCES[name] = SourceDef(name, licence, package, description, fn, locate)
        return fn

    return deco


def package_dir(module: str, *sub: str) -> Path | None:
    """Folder of an installed package *without importing it* (robosuite etc. import heavy deps)."""
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    locs = list(spec.submodule_search_locations or [])
    if not locs and spec.origin:
        locs = [str(Path(spec.origin).parent)]
    for loc in locs:
        p = Path(loc, *sub)
        if p.exists():
            return p
    return None
