"""Catalog statistics and the contact sheet of thumbnails."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

from asset_pipeline.record import CatalogRecord


def catalog_stats(records: list[CatalogRecord]) -> dict:
    by_cat = Counter(r.category for r in records)
    by_src = Counter(r.source for r in records)
    return {
        "objects": len(records),
        "categories": len(by_cat),
        "real_mesh_objects": sum(r.real_mesh for r in records),
        "unique_real_shapes": unique_real_shapes(records),
        "unseen_objects": sum(not r.seen for r in records),
        "unseen_categories": len({r.category for r in records if not r.seen}),
        "textured_objects": sum(r.textured for r in records),
        "by_category": dict(sorted(by_cat.items())),
        "by_source": dict(sorted(by_src.items())),
        "by_decomposition": dict(sorted(Counter(r.decomposition for r in records).items())),
        "by_size_class": dict(sorted(Counter(r.size_class for r in records).items())),
    }


def unique_real_shapes(records: list[CatalogRecord]) -> int:
    """Distinct source meshes behind the real-mesh objects (colour variants of one file count once).

    Files are compared by content when still readable (the same mesh shipped by two packages counts
    once), else by path."""
    import hashlib

    keys: set[str] = set()
    for r in records:
        if not r.real_mesh:
            continue
        p = Path(r.source_path)
        try:
            keys.add(hashlib.sha1(p.read_bytes()).hexdigest())
        except OSError:
            keys.add(r.source_path)
    return len(keys)


def contact_sheet(root: Path, records: list[CatalogRecord], path: Path, per_category: int = 2, tile: int = 96, cols: int = 24) -> int:
    """A grid of thumbnails, ``per_category`` per category (sorted), labelled; returns tiles drawn."""
    from PIL import Image, ImageDraw

    chosen: list[CatalogRecord] = []
    count: Counter[str] = Counter()
    for r in sorted(records, key=lambda r: (r.category, not r.real_mesh, r.id)):
        if r.thumbnail and count[r.category] < per_category and (root / r.thumbnail).exists():
            chosen.append(r)
            count[r.category] += 1
    if not chosen:
        return 0
    rows = (len(chosen) + cols - 1) // cols
    sheet = Image.new("RGB", (cols * tile, rows * (tile + 12)), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for i, r in enumerate(chosen):
        x, y = (i % cols) * tile, (i // cols) * (tile + 12)
        im = Image.open(root / r.thumbnail).convert("RGB").resize((tile, tile))
        sheet.paste(im, (x, y))
        draw.text((x + 2, y + tile), r.category[:16], fill=(0, 0, 0))
    sheet.save(path)
    return len(chosen)
