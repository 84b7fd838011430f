"""Stable resting poses (quasi-static) from the convex hull and the centre of mass.

A hull facet is a stable support when the centre of mass projects inside it; its probability is
the solid angle the facet subtends from the centre of mass (the chance a random drop ends on it).
Own implementation: ``trimesh.poses.compute_stable_poses`` can loop on symmetric hulls.
"""

from __future__ import annotations

import numpy as np
import trimesh


def _inside(p: np.ndarray, poly: np.ndarray) -> bool:
    """Point in convex 2D polygon (any vertex order)."""
    from scipy.spatial import ConvexHull

    try:
        h = ConvexHull(poly)
    except Exception:
        return False
    return bool(np.all(h.equations[:, :2] @ p + h.equations[:, 2] <= 1e-9))


def _solid_angle(tris: np.ndarray, c: np.ndarray) -> float:
    """Sum of triangle solid angles seen from c (Van Oosterom-Strackee)."""
    a, b, d = tris[:, 0] - c, tris[:, 1] - c, tris[:, 2] - c
    la, lb, ld = (np.linalg.norm(x, axis=1) for x in (a, b, d))
    num = np.abs(np.einsum("ij,ij->i", a, np.cross(b, d)))
    den = la * lb * ld + np.einsum("ij,ij->i", a, b) * ld + np.einsum("ij,ij->i", a, d) * lb + np.einsum("ij,ij->i", b, d) * la
    return float(np.sum(2 * np.arctan2(num, den)))


def _rotation_to(n: np.ndarray, target: np.ndarray = np.array([0.0, 0.0, -1.0])) -> np.ndarray:
    """Rotation matrix taking unit vector n onto target."""
    v = np.cross(n, target)
    c = float(np.dot(n, target))
    if np.linalg.norm(v) < 1e-9:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx * (1 / (1 + c))


def stable_poses(hulls: list[trimesh.Trimesh], center_mass: np.ndarray | None = None, top: int = 3) -> list[list[float]]:
    """Up to ``top`` poses as ``[qw, qx, qy, qz, probability]``: rotations that put the object on a
    stable facet (the object frame is then re-centred by the user; identity = as modelled)."""
    hull = trimesh.convex.convex_hull(np.vstack([h.vertices for h in hulls]))
    com = np.asarray(hull.center_mass if center_mass is None else center_mass, float)
    groups = [list(f) for f in hull.facets]
    grouped = set(i for f in groups for i in f)
    groups += [[i] for i in range(len(hull.faces)) if i not in grouped]
    cands = []
    for g in groups:
        n = hull.face_normals[g[0]]
        tris = hull.triangles[g]
        pts = tris.reshape(-1, 3)
        # Project COM and facet onto the facet plane, in 2D.
        u = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        u /= np.linalg.norm(u)
        w = np.cross(n, u)
        p2 = np.stack([pts @ u, pts @ w], 1)
        c2 = np.array([com @ u, com @ w])
        if _inside(c2, p2):
            cands.append((_solid_angle(tris, com), n))
    if not cands:
        return [[1.0, 0.0, 0.0, 0.0, 1.0]]
    total = sum(a for a, _ in cands)
    cands.sort(key=lambda x: -x[0])
    out = []
    for a, n in cands[:top]:
        T = np.eye(4)
        T[:3, :3] = _rotation_to(n)
        q = trimesh.transformations.quaternion_from_matrix(T)
        out.append([float(round(x, 6)) for x in q] + [float(round(a / total, 4))])
    return out
