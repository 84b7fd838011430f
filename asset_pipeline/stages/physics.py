"""Volume and mass from a category density."""

from __future__ import annotations

import numpy as np
import trimesh

from asset_pipeline.categories import CategoryInfo

NON_WATERTIGHT_FILL = 0.5  # fraction of the hull assumed solid when the mesh has no closed volume


def solid_volume(mesh: trimesh.Trimesh) -> float:
    if mesh.is_watertight:
        v = abs(float(mesh.volume))
        if v > 1e-9:
            return v
    return float(mesh.convex_hull.volume) * NON_WATERTIGHT_FILL


def mass_for(volume: float, info: CategoryInfo) -> float:
    return float(np.clip(volume * info.density, *info.mass_range))
