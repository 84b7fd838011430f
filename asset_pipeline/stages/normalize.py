"""Units, plausible per-category size, and the bottom-centre origin."""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np
import trimesh

from asset_pipeline.categories import CategoryInfo
from asset_pipeline.stages import MeshError


@dataclass
class NormalizeReport:
    unit_guess: str  # "m", "cm", "mm"
    scale: float  # total uniform factor applied
    extents: list[float]


def guess_units(max_extent: float) -> tuple[str, float]:
    """Household objects are 1 cm .. 1 m: larger numbers mean centimetres or millimetres."""
    if max_extent > 25.0:
        return "mm", 0.001
    if max_extent > 2.5:
        return "cm", 0.01
    return "m", 1.0


def target_size(oid: str, info: CategoryInfo) -> float:
    lo, hi = info.size
    u = (zlib.crc32(oid.encode()) % 10_000) / 10_000  # deterministic per object
    return lo + (hi - lo) * u


def normalize(scene: trimesh.Scene, hulls: list[trimesh.Trimesh] | None, oid: str, info: CategoryInfo, known_scale: bool) -> NormalizeReport:
    v = np.vstack([g.vertices for g in scene.geometry.values()])
    lo, hi = v.min(0), v.max(0)
    ext = float((hi - lo).max())
    if not np.isfinite(ext) or ext <= 0:
        raise MeshError("degenerate bounding box")
    unit, k = ("m", 1.0) if known_scale else guess_units(ext)
    size_lo, size_hi = info.size
    tol = 3.0 if known_scale else 1.5  # trust metric sources unless clearly off
    if not (size_lo / tol <= ext * k <= size_hi * tol):
        k = target_size(oid, info) / ext
    T = np.eye(4)
    T[:3, :3] *= k
    T[:3, 3] = -k * np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    for g in scene.geometry.values():
        g.apply_transform(T)
    for h in hulls or []:
        h.apply_transform(T)
    return NormalizeReport(unit, float(k), [float(x) for x in (hi - lo) * k])
