"""Helpers shared by perturbation modules: instruction nouns, object pools, graspability, regions."""

from __future__ import annotations

import re
from dataclasses import replace
from functools import lru_cache

import numpy as np

from realm_ms.tasks.task_spec import SceneObject, TaskSpec
from realm_ms.validate import InputError

# the instruction's phrase for the main / target object where the slot name is not it
MAIN_NOUNS = {
    "REALM-PickSpoon-v1": "spoon",
    "REALM-PickWaterBottle-v1": "water bottle",
    "REALM-OpenDrawer-v1": "drawer",
    "REALM-CloseDrawer-v1": "drawer",
}
TARGET_NOUNS = {"REALM-PutBananaInBox-v1": "box"}

# where added objects (clutter, receivers) may go: the table area the arm reaches top-down
WIDE_REGION = (0.30, 0.80, -0.42, 0.42)


def widened(spec: TaskSpec) -> TaskSpec:
    """The spec with its spawn region grown to at least ``WIDE_REGION``: added objects need room
    (REALM over-subscribed its spawn box and dropped objects from above)."""
    x0, x1, y0, y1 = spec.spawn_region
    w = WIDE_REGION
    return replace(spec, spawn_region=(min(x0, w[0]), max(x1, w[1]), min(y0, w[2]), max(y1, w[3])))


GRIPPER_OPENING = 0.085  # m, Robotiq 2F-85
GRASPABLE_WIDTH = 0.075  # m: the narrower horizontal extent must leave the fingers some room


def slot_noun(obj: SceneObject) -> str:
    """``toy_dice_1`` -> ``toy dice``: the task author's name for an object, as a noun phrase."""
    return re.sub(r"_\d+$", "", obj.name).replace("_", " ")


def main_noun(spec: TaskSpec) -> str:
    return MAIN_NOUNS.get(spec.env_id, slot_noun(spec.main))


def target_noun(spec: TaskSpec) -> str | None:
    t = spec.by_role("target")
    return TARGET_NOUNS.get(spec.env_id, slot_noun(t[0])) if t else None


def replace_noun(text: str, old: str, new: str) -> str:
    """Replace the whole-word noun phrase ``old`` (first occurrence) by ``new``."""
    out, n = re.subn(rf"\b{re.escape(old)}\b", new, text, count=1)
    return out if n else text


def with_object(spec: TaskSpec, name: str, **changes) -> TaskSpec:
    return replace(spec, objects=tuple(replace(o, **changes) if o.name == name else o for o in spec.objects))


def object_spec(asset: str):
    from realm_ms.assets import get_object_spec

    return get_object_spec(asset)


def cap_scale(asset: str, max_extent: float, scale=(1.0, 1.0, 1.0)) -> tuple[float, float, float]:
    """Uniform shrink (never grow, as REALM's ``replace_obj``) so the scaled object's largest extent
    is at most ``max_extent``."""
    ext = object_spec(asset).extents * np.asarray(scale, float)
    k = min(1.0, max_extent / float(ext.max()))
    return tuple(float(s * k) for s in np.broadcast_to(np.asarray(scale, float), (3,)))


GRASPABLE_MIN = 0.005  # m: every side; thinner, the pads (bottoms a few mm off the table) slide over it


def graspable(extents) -> bool:
    """A top-down two-finger grasp fits across the narrower horizontal side, and no side is so thin
    that the pads miss it (a toothbrush shrunk to 5 cm for stack: a 3.4 mm wide, 2.6 mm tall handle)."""
    e = np.asarray(extents, float)
    return float(min(e[0], e[1])) <= GRASPABLE_WIDTH and float(e.min()) >= GRASPABLE_MIN


class CatalogTooSmall(InputError):
    """The object catalog in use holds fewer matching objects than a perturbation draws."""


SAMPLING_OPTIONS = ("by", "distinct_categories", "catalog", "query")  # sample_objects keywords that are not filters


def sample_ids(rng: np.random.Generator, n: int, who: str | None = None, **filters) -> list[str]:
    """``n`` catalog ids (the built catalog, else the procedural one) drawn by category. Too few
    matches in a user catalog raise :class:`CatalogTooSmall` naming the missing categories
    (``who``: the perturbation, for the message)."""
    from realm_ms.assets import sample_objects

    try:
        return [o.id for o in sample_objects(n, rng, **filters)]
    except ValueError as e:
        if not str(e).startswith("only "):
            raise
        raise CatalogTooSmall(_too_small_message(n, who, filters)) from None


def _too_small_message(n: int, who: str | None, filters: dict) -> str:
    """What the catalog lacks, against the procedural set (which has every REALM category)."""
    from realm_ms.assets import ObjectQuery, load_catalog
    from realm_ms.assets.catalog import ProceduralCatalog
    from realm_ms.assets.paths import ENV_CATALOG, default_catalog_dir

    fields = {k: ((v,) if isinstance(v, str) and k != "seen" else tuple(v) if isinstance(v, (list, set)) else v)
              for k, v in filters.items() if k not in SAMPLING_OPTIONS}
    q = ObjectQuery(**fields)
    cat = load_catalog()
    have = {k: v for k, v in cat.candidates(q).items() if v}
    missing = sorted(set(ProceduralCatalog(1).candidates(q)) - set(have))
    distinct = bool(filters.get("distinct_categories"))
    what = ", ".join(f"{k}={'|'.join(map(str, v)) if isinstance(v, tuple) else v}" for k, v in fields.items() if v not in ((), None))
    root = getattr(cat, "root", default_catalog_dir())
    shown = ", ".join(missing[:12]) + (f" and {len(missing) - 12} more" if len(missing) > 12 else "")
    return (f"{who or 'a perturbation'} draws {n} object(s){' of different categories' if distinct else ''} ({what}), but the "
            f"catalog at {root} has {sum(map(len, have.values()))} in {len(have)} categor{'y' if len(have) == 1 else 'ies'}"
            f"{' (' + ', '.join(sorted(have)) + ')' if have else ''}; missing categories: {shown or 'none known'}; add them with "
            f"`realm assets build --source procedural --out {root}` (it merges into the catalog), or unset ${ENV_CATALOG} "
            "to use the procedural catalog")


@lru_cache(maxsize=None)
def catalog_extents(categories: tuple[str, ...], max_extent: float) -> tuple[tuple[str, tuple[float, float, float], tuple[float, float, float]], ...]:
    """Every catalog object of ``categories`` (the built catalog, else the procedural one) as
    ``(id, scale, extents)`` once shrunk to ``max_extent`` (``cap_scale``), sorted by id."""
    from realm_ms.assets import ObjectQuery, load_catalog

    ids = sorted(i for v in load_catalog().candidates(ObjectQuery(categories=tuple(categories))).values() for i in v)
    out = []
    for oid in ids:
        scale = cap_scale(oid, max_extent)
        out.append((oid, scale, tuple(float(e) for e in object_spec(oid).extents * np.asarray(scale))))
    return tuple(out)


def categories_of(spec: TaskSpec, roles=("main", "target")) -> tuple[str, ...]:
    out = []
    for o in spec.objects:
        if o.role in roles and not o.asset.startswith("articulated/"):
            out.append(object_spec(o.asset).category)
    return tuple(out)


def is_articulated(obj: SceneObject) -> bool:
    return obj.asset.startswith("articulated/")


def set_query(asset: str, **params) -> str:
    """``articulated/light_switch?on=0`` + ``look=2`` -> ``articulated/light_switch?on=0&look=2``."""
    from urllib.parse import parse_qsl, urlencode

    path, _, query = asset.partition("?")
    q = dict(parse_qsl(query))
    q.update({k: (f"{v:.4f}" if isinstance(v, float) else str(v)) for k, v in params.items()})
    return f"{path}?{urlencode(q)}"
