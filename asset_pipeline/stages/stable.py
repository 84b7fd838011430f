"""Stable resting poses (quasi-static, from the convex hull and centre of mass)."""

from __future__ import annotations

import numpy as np
import trimesh


def stable_poses(hulls: list[trimesh.Trimesh], center_mass: np.ndarray | None = None, top: int = 3) -> list[list[float]]:
    """Up to ``top`` poses as ``[qw, qx, qy, qz, probability]`` (rotation of the object frame)."""
    pts = np.vstack([h.vertices for h in hulls])
    hull = trimesh.convex.convex_hull(pts)
    com = hull.center_mass if center_mass is None else center_mass
    try:
        transforms, probs = trimesh.poses.compute_stable_poses(hull, center_mass=com, n_samples=1)
    except Exception:
        return [[1.0, 0.0, 0.0, 0.0, 1.0]]
    out = []
    for T, p in list(zip(transforms, probs))[:top]:
        q = trimesh.transformations.quaternion_from_matrix(T)  # w, x, y, z
        out.append([float(round(x, 6)) for x in q] + [float(round(p, 4))])
    return out or [[1.0, 0.0, 0.0, 0.0, 1.0]]
