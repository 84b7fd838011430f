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
    before = sum(len(g.faces) for g in scene.geometry.values())
    filled = False
    for name in list(scene.geometry):
        g = scene.geometry[name]
        repair_mesh(g)
        if not len(g.faces):
            scene.delete_geometry(name)
            continue
        if not g.is_watertight:
            filled |= bool(trimesh.repair.fill_holes(g))
    after = sum(len(g.faces) for g in scene.geometry.values())
    if after == 0:
        raise MeshError("mesh has no valid faces after repair")
    watertight = all(g.is_watertight for g in scene.geometry.values())
    return RepairReport(before, after, watertight, filled)


def combined(scene: trimesh.Scene) -> trimesh.Trimesh:
    """All geometry as one plain mesh (no visuals) for geometric computations."""
    ms = [trimesh.Trimesh(g.vertices, g.faces, process=False) for g in scene.geometry.values()]
    return trimesh.util.concatenate(ms) if len(ms) > 1 else ms[0]
