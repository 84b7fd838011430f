"""Mesh repair with trimesh: drop non-finite/degenerate/duplicate faces, fix winding, fill holes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from asset_pipeline.stages import MeshError


@dataclass
class RepairReport:
    faces_before: int
    faces_after: int
    watertight: bool
    holes_filled: bool


def repair_mesh(m: trimesh.Trimesh) -> None:
    finite = np.isfinite(m.vertices).all(axis=1)
    if not finite.all():
        m.update_faces(finite[m.faces].all(axis=1))
    m.update_faces(m.nondegenerate_faces())
    m.update_faces(m.unique_faces())
    m.remove_unreferenced_vertices()
    if len(m.faces) and len(m.faces) < 200_000:  # winding repair is O(faces) graph work; skip on giant scans
        trimesh.repair.fix_winding(m)


def repair_scene(scene: trimesh.Scene) -> RepairReport:
    """Clean the *visual* meshes in place (UV seams are kept: vertices merge only with equal UVs);
    hole filling happens on the geometry copy from :func:`combined`, never on textured meshes."""
    before = sum(len(g.faces) for g in scene.geometry.values())
    for name in list(scene.geometry):
        g = scene.geometry[name]
        g.merge_vertices()
        repair_mesh(g)
        if not len(g.faces):
            scene.delete_geometry(name)
    after = sum(len(g.faces) for g in scene.geometry.values())
    if after == 0:
        raise MeshError("mesh has no valid faces after repair")
    geo = combined(scene)
    return RepairReport(before, after, geo.is_watertight, bool(geo.metadata.get("holes_filled", False)))


def combined(scene: trimesh.Scene) -> trimesh.Trimesh:
    """All geometry as one plain mesh merged by position (no visuals), winding fixed and holes
    filled: the input for volume, mass and convex decomposition."""
    ms = [trimesh.Trimesh(g.vertices, g.faces, process=True) for g in scene.geometry.values()]
    m = trimesh.util.concatenate(ms) if len(ms) > 1 else ms[0]
    repair_mesh(m)
    filled = False
    if not m.is_watertight:
        filled = bool(trimesh.repair.fill_holes(m))
    m.metadata["holes_filled"] = filled
    return m
