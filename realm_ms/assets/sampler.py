"""Attribute sampling used by tasks and perturbations (distractors, unseen objects, receivers)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from realm_ms.assets.catalog import BuiltCatalog, ObjectQuery, ProceduralCatalog, load_catalog
from realm_ms.assets.object_spec import ObjectSpec


def sample_objects(
    n: int,
    rng: np.random.Generator | int | None = None,
    *,
    catalog: BuiltCatalog | ProceduralCatalog | str | None = None,
    query: ObjectQuery | None = None,
    by: str = "category",
    distinct_categories: bool = False,
    **filters,
) -> list[ObjectSpec]:
    """Draw ``n`` objects without replacement.

    ``filters`` are :class:`ObjectQuery` fields (``categories=``, ``exclude_categories=``, ``seen=``,
    ``colors=``, ``shapes=``, ``materials=``, ``uses=``, ``themes=``, ``real_mesh=``, ...); strings are
    accepted where tuples are expected. ``by="category"`` first draws a category uniformly (so
    categories with many variants do not dominate), ``by="object"`` draws uniformly over objects.
    Raises ``ValueError`` when fewer than ``n`` objects match.
    """
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    q = query or ObjectQuery(**{k: ((v,) if isinstance(v, str) and k not in ("seen",) else (tuple(v) if isinstance(v, (list, set)) else v)) for k, v in filters.items()})
    cat = catalog if isinstance(catalog, (BuiltCatalog, ProceduralCatalog)) else load_catalog(catalog)
    pools = {k: list(v) for k, v in cat.candidates(q).items() if v}
    total = sum(len(v) for v in pools.values())
    need_cats = n if distinct_categories else 1
    if total < n or len(pools) < need_cats:
        raise ValueError(f"only {total} objects in {len(pools)} categories match {q}; asked for {n}")
    picked: list[str] = []
    for _ in range(n):
        names = sorted(pools)
        if by == "category":
            c = names[rng.integers(len(names))]
        else:
            w = np.array([len(pools[k]) for k in names], float)
            c = names[rng.choice(len(names), p=w / w.sum())]
        ids = pools[c]
        picked.append(ids.pop(int(rng.integers(len(ids)))))
        if distinct_categories or not ids:
            del pools[c]
    return [cat.get(i) for i in picked]


def categories(catalog: BuiltCatalog | ProceduralCatalog | str | None = None, **filters) -> list[str]:
    q = ObjectQuery(**{k: ((v,) if isinstance(v, str) else v) for k, v in filters.items()})
    cat = catalog if isinstance(catalog, (BuiltCatalog, ProceduralCatalog)) else load_catalog(catalog)
    return sorted(cat.candidates(q))


def describe(spec: ObjectSpec, attribute: str, rng: np.random.Generator | None = None) -> str:
    """A referring phrase for S-PROP/S-AFF/S-INT-style instructions: "the red mug",
    "something to drink from", "the thing that grows on trees"."""
    r = spec.record
    rng = rng or np.random.default_rng(0)
    pick = lambda xs: xs[int(rng.integers(len(xs)))] if xs else None  # noqa: E731
    if attribute == "color" and r.colors:
        return f"the {r.colors[0]} {spec.noun}"
    if attribute == "shape" and r.shapes:
        return f"the {pick(r.shapes)} object"
    if attribute == "use" and r.uses:
        return str(pick(r.uses))
    if attribute == "fact" and r.fact:
        return f"the thing that {r.fact}"
    if attribute == "material":
        return f"the {r.material} object"
    return f"the {spec.noun}"


__all__: Sequence[str] = ("sample_objects", "categories", "describe")
