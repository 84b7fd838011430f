"""A folder of user meshes (Objaverse / Google Scanned Objects exports, own scans).

Layout: ``ROOT/<category>/<object>.(obj|glb|gltf|stl|ply)`` or ``ROOT/<category>/<object>/<mesh>``;
the category comes from the folder name (REALM's convention), else from the file name. GLB/GLTF
are y-up by the glTF spec; other formats are taken as z-up. Units are guessed and sizes made
plausible per category by the build.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from asset_pipeline.categories import infer_category
from asset_pipeline.sources.source import SourceItem, register_source

MESH_EXTS = (".obj", ".glb", ".gltf", ".stl", ".ply", ".dae", ".off")


def _slug(s: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in s.lower()).strip("_")


@register_source("folder", licence="user-provided (record the licence of each collection)", package=None,
                 description="any folder of OBJ/GLB/GLTF/STL/PLY meshes", locate=lambda: None)
def folder_items(root: Path, licence: str = "user-provided") -> Iterator[SourceItem]:
    root = Path(root)
    for f in sorted(p for p in root.rglob("*") if p.suffix.lower() in MESH_EXTS and not p.name.startswith(".")):
        if f.stem.endswith(("_col", "_collision", "_coll")):
            continue
        rel = f.relative_to(root)
        parts = rel.parts
        folder_cat = _slug(parts[0]) if len(parts) > 1 else None
        cat = folder_cat or infer_category(f.stem) or _slug(f.stem)
        oid = "/".join(_slug(p) for p in rel.with_suffix("").parts)
        extra = [str(p) for p in f.parent.iterdir() if p.suffix.lower() in (".mtl", ".png", ".jpg", ".jpeg", ".bin")] if len(parts) > 1 else []
        yield SourceItem(id=f"user/{oid}", source=f"folder:{root.name}", licence=licence, category=cat, mesh=str(f),
                         up="y" if f.suffix.lower() in (".glb", ".gltf") else "z", name=f.stem, extra_files=sorted(extra)[:16])
