"""Mesh building blocks for the procedural generators.

Conventions: metres, +Z up, the object's resting footprint on z = 0 and centred on the Z axis.
Every helper returns a watertight ``trimesh.Trimesh``; helpers named ``*_pieces`` return lists of
*convex* meshes meant for collision, so procedural objects never need CoACD.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import trimesh

Profile = Sequence[tuple[float, float]]  # (radius, z) pairs, bottom to top


def box(extents: Sequence[float], z0: float = 0.0) -> trimesh.Trimesh:
    m = trimesh.creation.box(extents=extents)
    m.apply_translation((0, 0, z0 + extents[2] / 2))
    return m


def cylinder(radius: float, height: float, z0: float = 0.0, sections: int = 24) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    m.apply_translation((0, 0, z0 + height / 2))
    return m


def ellipsoid(rx: float, ry: float, rz: float, z0: float = 0.0, subdivisions: int = 2) -> trimesh.Trimesh:
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    m.apply_scale((rx, ry, rz))
    m.apply_translation((0, 0, z0 + rz))
    return m


def rounded_box(extents: Sequence[float], radius: float, z0: float = 0.0) -> trimesh.Trimesh:
    """Convex hull of eight corner spheres: a convex box with soft edges."""
    ex = np.asarray(extents, float) / 2 - radius
    ball = trimesh.creation.icosphere(subdivisions=1, radius=radius).vertices
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * ex
    pts = (corners[:, None, :] + ball[None]).reshape(-1, 3)
    m = trimesh.convex.convex_hull(pts)
    m.apply_translation((0, 0, z0 + extents[2] / 2))
    return m


def revolve(profile: Profile, sections: int = 32) -> trimesh.Trimesh:
    """Solid of revolution of a (radius, z) profile; end points with radius 0 close the solid."""
    pts = np.asarray(profile, float)
    m = trimesh.creation.revolve(pts, sections=sections)
    if m.volume < 0:  # profile drawn the other way round: flip normals
        m.invert()
    return m


def vessel(outer: Profile, thickness: float, sections: int = 32) -> trimesh.Trimesh:
    """Open-topped hollow vessel (cup, bowl, glass): outer wall, rim, inner wall, closed bottom."""
    out = np.asarray(outer, float)
    inner = out.copy()
    inner[:, 0] = np.maximum(out[:, 0] - thickness, 1e-4)
    inner[0, 1] = out[0, 1] + thickness  # inner floor sits one wall-thickness above the base
    inner = inner[inner[:, 1] >= inner[0, 1] - 1e-9]
    # Profile: axis at the base -> outer wall up -> rim -> inner wall down -> axis at the inner floor.
    prof = np.vstack([[0.0, out[0, 1]], out, inner[::-1], [0.0, inner[0, 1]]])
    return revolve(prof, sections)


def vessel_pieces(outer: Profile, thickness: float, sectors: int = 10, bands: int = 3) -> list[trimesh.Trimesh]:
    """Convex collision pieces for :func:`vessel`: a floor disc plus ``sectors x bands`` wall slabs."""
    out = np.asarray(outer, float)
    z = np.linspace(out[0, 1] + thickness, out[-1, 1], bands + 1)
    r_out = np.interp(z, out[:, 1], out[:, 0])
    floor_r = max(out[0, 0], 1e-3)
    pieces = [cylinder(floor_r, thickness, z0=out[0, 1], sections=16)]
    th = np.linspace(0, 2 * np.pi, sectors + 1)
    for b in range(bands):
        for s in range(sectors):
            pts = []
            for zi in (b, b + 1):
                for ti in (s, s + 1):
                    for r in (r_out[zi], max(r_out[zi] - thickness, 1e-4)):
                        pts.append((r * np.cos(th[ti]), r * np.sin(th[ti]), z[zi]))
            pieces.append(trimesh.convex.convex_hull(np.array(pts)))
    return pieces


def tube(path: np.ndarray, radii: Sequence[float] | float, sections: int = 12, caps: bool = True) -> trimesh.Trimesh:
    """Closed tube swept along a 3D polyline with per-point radii (handles, banana, wires)."""
    path = np.asarray(path, float)
    n = len(path)
    radii = np.broadcast_to(np.asarray(radii, float), (n,))
    tang = np.gradient(path, axis=0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    rings = []
    for i in range(n):
        ref = np.array([0.0, 0.0, 1.0]) if abs(tang[i, 2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        u = np.cross(tang[i], ref)
        u /= np.linalg.norm(u)
        v = np.cross(tang[i], u)
        a = np.linspace(0, 2 * np.pi, sections, endpoint=False)
        rings.append(path[i] + radii[i] * (np.cos(a)[:, None] * u + np.sin(a)[:, None] * v))
    verts = np.vstack(rings + [path[:1], path[-1:]])
    faces = []
    for i in range(n - 1):
        for j in range(sections):
            a, b = i * sections + j, i * sections + (j + 1) % sections
            c, d = a + sections, b + sections
            faces += [(a, b, d), (a, d, c)]
    if caps:
        s0, s1 = n * sections, n * sections + 1
        for j in range(sections):
            faces.append((s0, (j + 1) % sections, j))
            faces.append((s1, (n - 1) * sections + j, (n - 1) * sections + (j + 1) % sections))
    m = trimesh.Trimesh(verts, np.array(faces), process=True)
    trimesh.repair.fix_normals(m)
    return m


def tube_pieces(path: np.ndarray, radii: Sequence[float] | float, step: int = 2, sections: int = 8) -> list[trimesh.Trimesh]:
    """Convex hulls of consecutive tube segments: collision for curved thin parts."""
    path = np.asarray(path, float)
    radii = np.broadcast_to(np.asarray(radii, float), (len(path),))
    out = []
    idx = list(range(0, len(path) - 1, step)) + [len(path) - 1]
    for i0, i1 in zip(idx[:-1], idx[1:]):
        seg = tube(path[i0 : i1 + 1], radii[i0 : i1 + 1], sections=sections)
        out.append(trimesh.convex.convex_hull(seg.vertices))
    return out


def hull(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.convex.convex_hull(np.vstack([m.vertices for m in meshes]))


def moved(m: trimesh.Trimesh, xyz: Sequence[float] = (0, 0, 0), rot: tuple[float, Sequence[float]] | None = None) -> trimesh.Trimesh:
    """Copy of ``m`` rotated by ``rot = (angle, axis)`` about the origin, then translated."""
    m = m.copy()
    if rot is not None:
        m.apply_transform(trimesh.transformations.rotation_matrix(rot[0], rot[1]))
    m.apply_translation(xyz)
    return m


def arc(radius: float, a0: float, a1: float, n: int = 12, plane: str = "xz", center: Sequence[float] = (0, 0, 0)) -> np.ndarray:
    t = np.linspace(a0, a1, n)
    c = np.asarray(center, float)
    if plane == "xz":
        return c + np.stack([radius * np.cos(t), np.zeros_like(t), radius * np.sin(t)], 1)
    return c + np.stack([radius * np.cos(t), radius * np.sin(t), np.zeros_like(t)], 1)
