"""Procedural object generators, one module per family; importing this package fills ``REGISTRY``.

Public entry points: :func:`make_object` (alias ``procedural_object``), :data:`REGISTRY`,
:func:`categories`.
"""

from __future__ import annotations

# registration order = REGISTRY order (kept stable: catalog listings follow it)
from asset_pipeline.procedural import (  # noqa: F401  (imported for registration side effects)
    balls,
    blocks,
    bottles,
    drinkware,
    fruit,
    nondroid,
    nondroid_curios,
    boxed_goods,
    tableware,
    utensils,
    writing,
)
from asset_pipeline.procedural.object_model import REGISTRY, CategoryDef, ProceduralObject, make_object, object_id, parse_object_id

procedural_object = make_object


def categories(seen: bool | None = None) -> list[str]:
    return sorted(n for n, c in REGISTRY.items() if seen is None or c.seen == seen)


__all__ = ["REGISTRY", "CategoryDef", "ProceduralObject", "make_object", "procedural_object", "object_id", "parse_object_id", "categories"]
