"""Objects for REALM tasks and perturbations: procedural objects (no build needed) and built catalogs.

Public API::

    from realm_ms.assets import (
        get_object_spec,         # "proc/apple/0" (generated on the fly, cached) or a built-catalog id
        procedural_object_spec,  # procedural_object_spec("cube", 0, color="green", size=0.03)
        build_actor,             # build_actor(scene, spec_or_id, "name", pose=..., scale=..., mass=..., body_type=...)
        sample_objects,          # sample_objects(3, rng, seen=False, exclude_categories=("mug",), colors=("red",))
        categories,              # categories(seen=False) -> category names matching filters
        describe,                # describe(spec, "use") -> "something to drink from"
        load_catalog,            # built catalog at $REALM_ASSETS_DIR, else the procedural catalog
        ObjectSpec, ObjectQuery, TASK_OBJECTS,
    )

``real/<noun>`` ids (``real/apple``, ``real/mug``, ...) are real meshes shipped as package data,
fitted to real sizes (``realm_ms.assets.real_objects``; procedural fallback when missing).
Procedural ids are ``proc/<category>/<seed>[?color=<name>&size=<metres>]``; ``size`` is the largest
extent. Objects are upright with the origin at the bottom centre, so a pose at table height rests
them on the table. ``TASK_OBJECTS`` maps REALM task nouns to ids (e.g. ``"green cube"``).
Catalog location: ``$REALM_ASSETS_DIR`` (default ``~/.cache/realm_ms/catalog``); procedural mesh
cache: ``$REALM_ASSETS_CACHE`` (default ``~/.cache/realm_ms/procedural``).
"""

from __future__ import annotations

from realm_ms.assets.catalog import (
    BuiltCatalog,
    ObjectQuery,
    ProceduralCatalog,
    get_object_spec,
    load_catalog,
    procedural_object_spec,
    procedural_spec,
)
from realm_ms.assets.loader import build_actor, make_cpu_scene
from realm_ms.assets import real_objects  # noqa: F401  (registers "real/<noun>" ids)
from realm_ms.assets.sampler import categories, describe, sample_objects
from realm_ms.assets.object_spec import ObjectSpec
from realm_ms.assets.task_objects import TASK_OBJECTS, task_object_spec

__all__ = [
    "BuiltCatalog",
    "ObjectQuery",
    "ObjectSpec",
    "ProceduralCatalog",
    "TASK_OBJECTS",
    "build_actor",
    "categories",
    "describe",
    "get_object_spec",
    "load_catalog",
    "make_cpu_scene",
    "procedural_object_spec",
    "procedural_spec",
    "sample_objects",
    "task_object_spec",
]
