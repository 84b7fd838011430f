"""Procedural object model and the category registry.

A generator is a function ``(rng, color) -> Geometry`` registered for one or more categories with
:func:`category`. The registry holds each category's exact semantics, so generated objects never
need labelling. :func:`make_object` turns (category, seed, overrides) into a finished
:class:`ProceduralObject`: upright, origin at the bottom centre, mass from volume x density.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import trimesh

from asset_pipeline.procedural.colors import METALLIC, PALETTE, rgba
from asset_pipeline.semantics import Semantics


@dataclass
class Part:
    """One visual piece with a single material."""

    mesh: trimesh.Trimesh
    color: str
    rgba: tuple[float, float, float, float]
    roughness: float = 0.6
    metallic: float = 0.0


@dataclass
class Geometry:
    """What a generator returns. ``collision`` holds convex meshes; ``None`` = hull of each visual part."""

    parts: list[Part]
    collision: list[trimesh.Trimesh] | None = None
    colors: tuple[str, ...] = ()  # colour words, most salient first; default: part colours by area
    shapes: tuple[str, ...] = ()  # extra shape words for this instance (added to the category's)
    lying: bool = False  # rests on its side (markers, bananas): informs stable-pose and placement


Generator = Callable[[np.random.Generator, str], Geometry]


@dataclass(frozen=True)
class CategoryDef:
    name: str
    family: str
    generate: Generator
    colors: tuple[str, ...]  # colour names a random instance may take
    density: float  # effective kg/m^3 over the collision volume (hollow things are low)
    material: str
    shapes: tuple[str, ...] = ()
    uses: tuple[str, ...] = ()
    fact: str | None = None
    seen: bool = True
    theme: str = "misc"
    names: tuple[str, ...] = ()
    friction: float = 0.6
    mass_range: tuple[float, float] = (0.005, 3.0)


REGISTRY: dict[str, CategoryDef] = {}


def category(name: str, *, family: str, colors: Sequence[str], density: float, material: str, **kw) -> Callable[[Generator], Generator]:
    """Register ``fn`` as the generator of ``name``; stack the decorator for sibling categories."""

    def deco(fn: Generator) -> Generator:
        if name in REGISTRY:
            raise ValueError(f"procedural category {name!r} registered twice")
        bad = [c for c in colors if c not in PALETTE]
        if bad:
            raise ValueError(f"{name}: unknown colour names {bad}")
        kw2 = {k: tuple(v) if isinstance(v, list) else v for k, v in kw.items()}
        REGISTRY[name] = CategoryDef(name=name, family=family, generate=fn, colors=tuple(colors), density=density, material=material, **kw2)
        return fn

    return deco


def part(mesh: trimesh.Trimesh, color: str, rng: np.random.Generator | None = None, roughness: float = 0.6) -> Part:
    return Part(mesh=mesh, color=color, rgba=rgba(color, rng), roughness=roughness, metallic=METALLIC.get(color, 0.0))


@dataclass
class ProceduralObject:
    id: str
    category: str
    seed: int
    semantics: Semantics
    parts: list[Part]
    collision: list[trimesh.Trimesh]
    mass: float
    friction: float
    lying: bool = False
    params: dict = field(default_factory=dict)

    @property
    def bounds(self) -> np.ndarray:
        v = np.vstack([p.mesh.vertices for p in self.parts])
        return np.stack([v.min(0), v.max(0)])

    @property
    def extents(self) -> np.ndarray:
        b = self.bounds
        return b[1] - b[0]

    def visual_mesh(self) -> trimesh.Trimesh:
        """All visual parts as one mesh with per-face colours (thumbnails, stats)."""
        meshes = []
        for p in self.parts:
            m = p.mesh.copy()
            m.visual = trimesh.visual.ColorVisuals(m, face_colors=np.array(p.rgba) * 255)
            meshes.append(m)
        return trimesh.util.concatenate(meshes)


def stable_seed(category: str, seed: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(category.encode()), int(seed)])


def _normalise(parts: list[Part], collision: list[trimesh.Trimesh], size: float | None) -> None:
    """In place: origin at the bottom centre, optional uniform rescale to a largest extent of ``size``."""
    v = np.vstack([p.mesh.vertices for p in parts])
    lo, hi = v.min(0), v.max(0)
    shift = -np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    k = 1.0 if size is None else float(size) / float((hi - lo).max())
    for m in [p.mesh for p in parts] + collision:
        m.apply_translation(shift)
        if k != 1.0:
            m.apply_scale(k)


def make_object(category_name: str, seed: int = 0, color: str | None = None, size: float | None = None) -> ProceduralObject:
    """Deterministic object ``proc/<category>/<seed>``; ``color``/``size`` override the random draw."""
    try:
        cat = REGISTRY[category_name]
    except KeyError:
        raise KeyError(f"unknown procedural category {category_name!r}; known: {sorted(REGISTRY)}") from None
    rng = stable_seed(category_name, seed)
    col = color if color is not None else str(rng.choice(cat.colors))
    if col not in PALETTE:
        raise KeyError(f"unknown colour {col!r}; known: {sorted(PALETTE)}")
    geo = cat.generate(rng, col)
    collision = geo.collision if geo.collision is not None else [trimesh.convex.convex_hull(p.mesh.vertices) for p in geo.parts]
    _normalise(geo.parts, collision, size)
    if geo.colors:
        colors = tuple(dict.fromkeys(geo.colors))
    else:  # most visible colour first
        area: dict[str, float] = {}
        for p in geo.parts:
            area[p.color] = area.get(p.color, 0.0) + p.mesh.area
        colors = tuple(sorted(area, key=area.get, reverse=True))
    volume = float(sum(abs(c.volume) for c in collision))
    mass = float(np.clip(volume * cat.density, *cat.mass_range))
    sem = Semantics(
        category=cat.name,
        colors=tuple(colors),
        shapes=tuple(dict.fromkeys(cat.shapes + geo.shapes)),
        material=cat.material,
        uses=cat.uses,
        fact=cat.fact,
        seen=cat.seen,
        theme=cat.theme,
        names=cat.names or (cat.name.replace("_", " "),),
    )
    params = {k: v for k, v in (("color", color), ("size", size)) if v is not None}
    oid = object_id(category_name, seed, **params)
    return ProceduralObject(oid, cat.name, int(seed), sem, geo.parts, collision, mass, cat.friction, geo.lying, params)


def object_id(category_name: str, seed: int, **params) -> str:
    q = "&".join(f"{k}={v}" for k, v in sorted(params.items()) if v is not None)
    return f"proc/{category_name}/{seed}" + (f"?{q}" if q else "")


def parse_object_id(oid: str) -> tuple[str, int, dict]:
    """``proc/cube/3?color=green&size=0.03`` -> ("cube", 3, {"color": "green", "size": 0.03})."""
    body, _, query = oid.partition("?")
    prefix, cat, seed = body.split("/")
    if prefix != "proc":
        raise ValueError(f"not a procedural id: {oid!r}")
    params: dict = {}
    for kv in filter(None, query.split("&")):
        k, _, v = kv.partition("=")
        params[k] = float(v) if k == "size" else v
    return cat, int(seed), params
