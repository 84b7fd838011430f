"""Load a source item into a scene (visual, textures kept) plus optional prebuilt convex parts."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from asset_pipeline.export import coloured_parts_scene, pbr_material, read_convex_obj
from asset_pipeline.procedural.colors import PALETTE
from asset_pipeline.semantics import Semantics
from asset_pipeline.sources.source import SourceItem
from asset_pipeline.stages import MeshError

Y_UP_TO_Z_UP = trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0))


@dataclass
class Loaded:
    scene: trimesh.Scene
    hulls: list[trimesh.Trimesh] | None = None  # convex parts already known (procedural, MJCF boxes, pre-split)
    semantics: Semantics | None = None  # exact semantics (procedural only)
    mass: float | None = None
    friction: float | None = None
    lying: bool = False
    textured: bool = False
    notes: list[str] = field(default_factory=list)


def _box(b: dict) -> trimesh.Trimesh:
    m = trimesh.creation.box(extents=2 * np.asarray(b["size"], float))
    T = trimesh.transformations.quaternion_matrix(b.get("quat", [1, 0, 0, 0]))  # MJCF quat is w, x, y, z like trimesh
    T[:3, 3] = b.get("pos", [0, 0, 0])
    m.apply_transform(T)
    return m


def load_item(item: SourceItem) -> Loaded:
    if item.procedural is not None:
        from asset_pipeline.procedural import make_object

        obj = make_object(*item.procedural)
        return Loaded(coloured_parts_scene(obj.parts), [h.copy() for h in obj.collision], obj.semantics, obj.mass, obj.friction, obj.lying)
    if not item.mesh:
        raise MeshError("item has neither a mesh nor a generator")
    try:
        loaded = trimesh.load(item.mesh, force="scene", process=False)
    except Exception as e:  # trimesh raises many types for corrupt files
        raise MeshError(f"unreadable mesh {item.mesh}: {type(e).__name__}: {e}") from None
    geoms = [g for g in loaded.geometry.values() if isinstance(g, trimesh.Trimesh) and len(g.faces)]
    if not geoms:
        raise MeshError(f"no triangles in {item.mesh}")
    scene = trimesh.Scene()
    for node in loaded.graph.nodes_geometry:  # flatten the graph: bake node transforms into vertices
        T, gname = loaded.graph[node]
        g = loaded.geometry[gname]
        if not isinstance(g, trimesh.Trimesh) or not len(g.faces):
            continue
        g = g.copy()
        g.apply_transform(T)
        scene.add_geometry(g, geom_name=f"g{len(scene.geometry)}")
    S = np.diag(list(np.broadcast_to(np.asarray(item.mesh_scale, float), (3,))) + [1.0])
    up = Y_UP_TO_Z_UP if item.up == "y" else np.eye(4)
    for g in scene.geometry.values():
        g.apply_transform(up @ S)
    textured = any(isinstance(g.visual, trimesh.visual.TextureVisuals) and getattr(g.visual.material, "image", None) is not None
                   or getattr(getattr(g.visual, "material", None), "baseColorTexture", None) is not None for g in scene.geometry.values())
    if item.color is not None and item.color in PALETTE:
        for g in scene.geometry.values():
            g.visual = trimesh.visual.TextureVisuals(material=pbr_material((*PALETTE[item.color], 1.0)))
        textured = False
    hulls = None
    if item.collision_boxes:
        hulls = [_box(b) for b in item.collision_boxes]
    elif item.collision_file:
        try:
            # One convex part per OBJ object (trimesh merges objects that share a material).
            parts = read_convex_obj(item.collision_file) if str(item.collision_file).lower().endswith(".obj") else \
                list(trimesh.load(item.collision_file, force="scene", process=False).geometry.values())
            hulls = [trimesh.convex.convex_hull(g.vertices) for g in parts if len(g.vertices) >= 4]
            for h in hulls:
                h.apply_transform(up @ S)
        except Exception as e:
            hulls = None
            note = f"prebuilt collision unreadable ({type(e).__name__}); decomposing instead"
            return Loaded(scene, None, textured=textured, notes=[note])
    return Loaded(scene, hulls, textured=textured)
