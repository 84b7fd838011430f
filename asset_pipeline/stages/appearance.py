"""Face colours of a (textured) scene: used for estimated colour words and thumbnails.

Thumbnails are drawn by a tiny painter's-algorithm rasteriser (numpy + Pillow), so the build needs
no GPU, Vulkan or OpenGL.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

MAX_THUMB_FACES = 20000  # painter cost is ~15 us per face; scans have 16k faces


def face_colors(g: trimesh.Trimesh) -> np.ndarray:
    """(F, 3) colours in [0, 1] for one geometry, from texture, material factor or face colours."""
    vis = g.visual
    try:
        if isinstance(vis, trimesh.visual.TextureVisuals):
            mat = vis.material
            img = getattr(mat, "image", None) or getattr(mat, "baseColorTexture", None)
            if isinstance(mat, trimesh.visual.material.PBRMaterial):  # glTF: texture x factor
                f = mat.baseColorFactor if mat.baseColorFactor is not None else [255, 255, 255, 255]
            else:  # OBJ/MTL: map_Kd replaces Kd in practice (exporters write a grey Kd)
                f = [255, 255, 255] if img is not None else getattr(mat, "main_color", [153, 153, 153])
            factor = np.asarray(f, float)[:3] / 255.0
            if img is not None and vis.uv is not None and len(vis.uv) == len(g.vertices):
                im = np.asarray(img.convert("RGB"), float) / 255.0
                uv = vis.uv[g.faces].mean(1) % 1.0
                px = (uv[:, 0] * (im.shape[1] - 1)).astype(int)
                py = ((1 - uv[:, 1]) * (im.shape[0] - 1)).astype(int)
                return im[py, px] * factor
            return np.tile(factor, (len(g.faces), 1))
        if isinstance(vis, trimesh.visual.ColorVisuals) and vis.kind is not None:
            return np.asarray(vis.face_colors, float)[:, :3] / 255.0
    except Exception:
        pass
    return np.full((len(g.faces), 3), 0.6)


def dominant_colors(scene: trimesh.Scene, k: int = 2) -> list[str]:
    """Colour words for a real mesh: palette names of the two largest area-weighted colour clusters."""
    from asset_pipeline.categories import nearest_colour_names

    cols, areas = [], []
    for g in scene.geometry.values():
        cols.append(face_colors(g))
        areas.append(g.area_faces)
    c, a = np.vstack(cols), np.concatenate(areas)
    names = [nearest_colour_names(x)[0] for x in np.round(c, 1)]  # quantise then name
    totals: dict[str, float] = {}
    for n, w in zip(names, a):
        totals[n] = totals.get(n, 0.0) + float(w)
    ranked = sorted(totals, key=totals.get, reverse=True)
    keep = [n for n in ranked[:k] if totals[n] >= 0.15 * a.sum()]
    return keep or ranked[:1]


def render_thumbnail(scene: trimesh.Scene, path: Path, size: int = 128) -> None:
    from PIL import Image, ImageDraw

    verts, faces, cols, off = [], [], [], 0
    for g in scene.geometry.values():
        verts.append(g.vertices)
        faces.append(g.faces + off)
        cols.append(face_colors(g))
        off += len(g.vertices)
    V, F, C = np.vstack(verts), np.vstack(faces), np.vstack(cols)
    if len(F) > MAX_THUMB_FACES:  # keep the largest faces: they carry the silhouette
        tri = V[F]
        area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        keep = np.argsort(-area)[:MAX_THUMB_FACES]
        F, C = F[keep], C[keep]
    # 3/4 view from the front-right, slightly above.
    R = trimesh.transformations.rotation_matrix(np.radians(-60), (1, 0, 0))[:3, :3] @ trimesh.transformations.rotation_matrix(np.radians(-35), (0, 0, 1))[:3, :3]
    P = (V - V.mean(0)) @ R.T
    tri = P[F]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
    light = np.array([0.3, -0.4, 0.85])
    shade = 0.35 + 0.65 * np.abs(n @ (light / np.linalg.norm(light)))
    span = max(np.ptp(P[:, 0]), np.ptp(P[:, 1]), 1e-6)
    xy = (tri[:, :, :2] / span * 0.85 + 0.5) * size
    xy[:, :, 1] = size - xy[:, :, 1]
    order = np.argsort(tri[:, :, 2].mean(1))  # far to near (camera looks down -z)
    img = Image.new("RGB", (size, size), (236, 236, 236))
    draw = ImageDraw.Draw(img)
    rgb = np.clip(C * shade[:, None] * 255, 0, 255).astype(int)
    for i in order:
        draw.polygon([tuple(p) for p in xy[i]], fill=tuple(rgb[i]))
    img.save(path)
