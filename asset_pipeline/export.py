"""Writers for the on-disk object format SAPIEN loads: a GLB visual and a multi-object convex OBJ.

SAPIEN's ``PhysxCollisionShapeConvexMesh.load_multiple`` makes one convex shape per *object* in the
file (not per connected component), so each hull is written as its own OBJ object.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import trimesh


def pbr_material(rgba: Sequence[float], roughness: float = 0.6, metallic: float = 0.0) -> trimesh.visual.material.PBRMaterial:
    a = float(rgba[3])
    return trimesh.visual.material.PBRMaterial(
        baseColorFactor=[int(round(c * 255)) for c in rgba],
        roughnessFactor=float(roughness),
        metallicFactor=float(metallic),
        alphaMode="BLEND" if a < 1.0 else "OPAQUE",
        doubleSided=a < 1.0,
    )


def coloured_parts_scene(parts) -> trimesh.Scene:
    """Scene with one node per procedural part, each carrying its own PBR material."""
    scene = trimesh.Scene()
    for i, p in enumerate(parts):
        m = p.mesh.copy()
        m.visual = trimesh.visual.TextureVisuals(material=pbr_material(p.rgba, p.roughness, p.metallic))
        scene.add_geometry(m, node_name=f"part{i}", geom_name=f"part{i}")
    return scene


def write_glb(scene_or_mesh: trimesh.Scene | trimesh.Trimesh, path: Path) -> None:
    data = trimesh.exchange.gltf.export_glb(scene_or_mesh if isinstance(scene_or_mesh, trimesh.Scene) else trimesh.Scene(scene_or_mesh))
    Path(path).write_bytes(data)


def write_convex_obj(hulls: Sequence[trimesh.Trimesh], path: Path) -> None:
    lines = []
    base = 1
    for i, h in enumerate(hulls):
        lines.append(f"o hull{i}")
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.asarray(h.vertices)]
        lines += [f"f {a + base} {b + base} {c + base}" for a, b, c in np.asarray(h.faces)]
        base += len(h.vertices)
    Path(path).write_text("\n".join(lines) + "\n")


def read_convex_obj(path: Path) -> list[trimesh.Trimesh]:
    """Inverse of :func:`write_convex_obj` (global vertex numbering, ``o`` separates hulls)."""
    verts: list[list[float]] = []
    groups: list[list[list[int]]] = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("o "):
            groups.append([])
        elif line.startswith("v "):
            verts.append([float(t) for t in line.split()[1:4]])
        elif line.startswith("f "):
            if not groups:
                groups.append([])
            groups[-1].append([int(t.split("/")[0]) - 1 for t in line.split()[1:4]])
    V = np.asarray(verts)
    out = []
    for faces in groups:
        F = np.asarray(faces)
        used = np.unique(F)
        remap = np.full(len(V), -1)
        remap[used] = np.arange(len(used))
        out.append(trimesh.Trimesh(V[used], remap[F], process=False))
    return out


class AtomicDir:
    """Write an object folder under a temp name and rename it into place, so readers and concurrent
    writers never see half-written objects (crash-safe, resumable)."""

    def __init__(self, final: Path):
        self.final = Path(final)

    def __enter__(self) -> Path:
        self.final.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(prefix=".tmp-", dir=self.final.parent))
        return self.tmp

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return
        try:
            os.replace(self.tmp, self.final)
        except OSError:  # another writer won the race; theirs is equivalent
            shutil.rmtree(self.tmp, ignore_errors=True)
