"""Instruction variants for REALM's five semantic perturbations, stored as data (one YAML per task).

Each ``<env_id>.yaml`` here (e.g. ``REALM-PickApple-v1.yaml``) holds ``task`` (the env id),
``default`` (the Default instruction), ``names`` (how the Default names the main object), ``nouns``
(head nouns of the main object), optional ``synonyms`` (drawer tasks: REALM's substitution lists)
and the five factor keys, each a list of exactly 10 instructions that keep the task's object and goal:
  S-PROP  refer to the main object by its properties (colour, shape, size, material, state).
  S-LANG  same object, similar verbs and no articles; drawers: REALM's synonym substitution.
  S-MO    refer to it through relations to other objects in the scene (among, not, nearer than).
  S-AFF   refer to it through a human need or use case ("something I can eat").
  S-INT   refer to it through world facts that need internet-scale knowledge ("the fruit Newton ...").
Variants are written against each task's Default scene; a file's header comment states its objects
and any assumption. The S-* perturbations draw uniformly from these lists (REALM: cached lists).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from types import MappingProxyType

import yaml

from realm_ms.registry import Registry

# REALM perturbation ids of the semantic factors (0 Default ... 15 VSB-NOBJ)
FACTOR_IDS: Mapping[str, int] = MappingProxyType({"S-PROP": 5, "S-LANG": 6, "S-MO": 7, "S-AFF": 8, "S-INT": 9})
FACTORS: tuple[str, ...] = tuple(FACTOR_IDS)
VARIANTS_PER_FACTOR = 10
_META_KEYS = ("task", "default", "names", "nouns", "synonyms")

_factors: Registry[str] = Registry("semantic factor")
for _name, _id in FACTOR_IDS.items():
    _factors.register(_name, _name, aliases=(str(_id),))


@dataclass(frozen=True)
class TaskLanguage:
    """The language data of one task (see the module docstring for the fields)."""

    env_id: str
    default: str
    names: tuple[str, ...]
    nouns: tuple[str, ...]
    synonyms: Mapping[str, tuple[str, ...]]
    variants: Mapping[str, tuple[str, ...]]  # factor -> VARIANTS_PER_FACTOR instructions


def canonical_factor(factor: str | int) -> str:
    """``"s-lang"``, ``"S-LANG"`` or REALM's id ``6`` -> ``"S-LANG"``; anything else raises
    :class:`~realm_ms.registry.UnknownNameError` listing the factors."""
    return _factors.canonical(factor)


def _str_list(path: str, key: str, value, *, n: int | None = None) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(s, str) and s.strip() for s in value):
        raise ValueError(f"{path}: {key!r} must be a list of non-empty strings")
    if n is not None and len(value) != n:
        raise ValueError(f"{path}: {key!r} has {len(value)} entries, needs exactly {n}")
    if len(set(value)) != len(value):
        raise ValueError(f"{path}: {key!r} repeats an entry")
    return tuple(value)


def _parse(path: str, text: str) -> TaskLanguage:
    data = yaml.safe_load(text)
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping at the top level")
    unknown = sorted(set(data) - set(FACTORS) - set(_META_KEYS))
    missing = sorted(k for k in (*FACTORS, "task", "default", "names", "nouns") if k not in data)
    if unknown or missing:
        raise ValueError(f"{path}: unknown keys {unknown}, missing keys {missing}")
    syn = data.get("synonyms") or {}
    if not isinstance(syn, dict):
        raise ValueError(f"{path}: 'synonyms' must map a word to a list of replacements")
    return TaskLanguage(
        env_id=str(data["task"]),
        default=str(data["default"]),
        names=_str_list(path, "names", data["names"]),
        nouns=_str_list(path, "nouns", data["nouns"]),
        synonyms=MappingProxyType({str(k): _str_list(path, f"synonyms.{k}", v) for k, v in syn.items()}),
        variants=MappingProxyType({f: _str_list(path, f, data[f], n=VARIANTS_PER_FACTOR) for f in FACTORS}),
    )


@lru_cache(maxsize=1)
def _tasks() -> Registry[TaskLanguage]:
    reg: Registry[TaskLanguage] = Registry("task with instruction variants")
    for res in sorted(resources.files(__name__).iterdir(), key=lambda r: r.name):
        if not res.name.endswith(".yaml"):
            continue
        lang = _parse(res.name, res.read_text(encoding="utf-8"))
        if lang.env_id != res.name.removesuffix(".yaml"):
            raise ValueError(f"{res.name}: 'task' is {lang.env_id!r}, must match the file name")
        reg.register(lang.env_id, lang)
    return reg


def task_ids() -> tuple[str, ...]:
    """Env ids that have instruction variants."""
    return tuple(_tasks().names())


def task_language(env_id: str) -> TaskLanguage:
    """All language data of ``env_id``; an unknown id raises ``UnknownNameError`` listing the known ones."""
    return _tasks().get(env_id)


@lru_cache(maxsize=None)
def instruction_variants(env_id: str, factor: str | int) -> tuple[str, ...]:
    """The 10 instructions of ``env_id`` under semantic ``factor`` (name or REALM id, e.g. ``"S-LANG"``/6)."""
    return task_language(env_id).variants[canonical_factor(factor)]


def synonyms(env_id: str) -> Mapping[str, tuple[str, ...]]:
    """REALM's S-LANG synonym table of ``env_id`` (word -> replacements); empty for non-drawer tasks."""
    return task_language(env_id).synonyms


def all_variants() -> dict[str, dict[str, tuple[str, ...]]]:
    """``{env_id: {factor: variants}}`` for every task."""
    return {env_id: dict(t.variants) for env_id, t in _tasks().items()}
