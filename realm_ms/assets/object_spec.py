"""Runtime view of a catalog object: a :class:`CatalogRecord` plus the folder its paths resolve in."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from asset_pipeline.record import CatalogRecord


@dataclass(frozen=True)
class ObjectSpec:
    record: CatalogRecord
    root: Path

    # Convenience pass-throughs for the fields tasks use most.
    @property
    def id(self) -> str:
        return self.record.id

    @property
    def category(self) -> str:
        return self.record.category

    @property
    def noun(self) -> str:
        """Instruction noun (REALM uses the category with underscores as spaces)."""
        return self.record.names[0] if self.record.names else self.record.category.replace("_", " ")

    @property
    def visual_path(self) -> Path:
        return self.root / self.record.visual

    @property
    def collision_path(self) -> Path:
        return self.root / self.record.collision

    @property
    def extents(self) -> np.ndarray:
        return np.asarray(self.record.extents, float)

    @property
    def max_extent(self) -> float:
        return float(max(self.record.extents))

    @property
    def mass(self) -> float:
        return float(self.record.mass)

    @property
    def density(self) -> float:
        return self.record.mass / max(self.record.collision_volume, 1e-9)

    def scale_for_max_extent(self, max_extent: float, only_shrink: bool = True) -> float:
        """Uniform scale bringing the largest extent to ``max_extent`` (REALM ``replace_obj`` only shrinks)."""
        k = max_extent / self.max_extent
        return min(k, 1.0) if only_shrink else k

    def scale_for_bbox(self, bbox: Sequence[float], lo: float = 0.02, hi: float = 0.175) -> np.ndarray:
        """Per-axis scale making the AABB ``clip(bbox, lo, hi)`` (VB-MOBJ on dataset objects)."""
        target = np.clip(np.asarray(bbox, float), lo, hi)
        return target / np.maximum(self.extents, 1e-6)
