"""Instruction variants (realm_ms.tasks.language): complete, well-formed, on-task data and a loader
that fails clearly on bad names or malformed files."""

from __future__ import annotations

import itertools
import re

import pytest

from realm_ms.registry import UnknownNameError
from realm_ms.tasks import TASKS
from realm_ms.tasks import language as L

ARTICLES = re.compile(r"\b(a|an|the)\b", re.IGNORECASE)


def norm(s: str) -> str:
    return " ".join(re.sub(r"[^\w\s'-]", " ", s.lower()).split())


def mentions(text: str, terms) -> bool:
    return any(re.search(rf"\b{re.escape(t.lower())}(s|es)?\b", text.lower()) for t in terms)  # plurals count


def test_every_registered_task_has_data_and_no_stray_files():
    assert set(TASKS) == set(L.task_ids())
    for env_id, spec in TASKS.items():
        lang = L.task_language(env_id)
        assert lang.default == spec.instruction, env_id
        assert mentions(lang.default, lang.names), f"{env_id}: the Default must use one of {lang.names}"


@pytest.mark.parametrize("env_id", sorted(TASKS))
def test_five_factors_of_ten_well_formed_distinct_variants(env_id):
    lang = L.task_language(env_id)
    assert tuple(lang.variants) == L.FACTORS == ("S-PROP", "S-LANG", "S-MO", "S-AFF", "S-INT")
    seen: dict[str, str] = {norm(lang.default): "Default"}
    for factor in L.FACTORS:
        variants = L.instruction_variants(env_id, factor)
        assert len(variants) == L.VARIANTS_PER_FACTOR == 10
        for v in variants:
            where = f"{env_id} {factor} {v!r}"
            assert v.isascii() and v == v.strip() and "  " not in v, where
            assert not v.endswith((".", ",", ";")), where
            assert 2 <= len(v.split()) <= 30, where
            assert norm(v) not in seen, f"{where} repeats {seen.get(norm(v))}"
            seen[norm(v)] = factor


@pytest.mark.parametrize("env_id", sorted(TASKS))
def test_variants_refer_to_the_main_object_as_their_factor_requires(env_id):
    lang = L.task_language(env_id)
    # S-LANG and S-MO keep the object's noun (they vary verbs / add relations) ...
    for factor in ("S-LANG", "S-MO"):
        for v in lang.variants[factor]:
            assert mentions(v, lang.nouns), f"{env_id} {factor} {v!r} names none of {lang.nouns}"
    # ... S-PROP, S-AFF and S-INT must identify it without the Default's name.
    for factor in ("S-PROP", "S-AFF", "S-INT"):
        for v in lang.variants[factor]:
            assert not mentions(v, lang.names), f"{env_id} {factor} {v!r} uses the Default name {lang.names}"


@pytest.mark.parametrize("env_id", sorted(TASKS))
def test_s_lang_is_article_free_or_synonym_substitution_for_drawers(env_id):
    lang = L.task_language(env_id)
    if "drawer" not in TASKS[env_id].skill:
        assert not lang.synonyms
        for v in lang.variants["S-LANG"]:
            assert not ARTICLES.search(v), f"{env_id} S-LANG {v!r} keeps an article"
        return
    # REALM: every key word of the Default may be replaced by one of its synonyms, at least one is
    words = lang.default.split()
    assert set(lang.synonyms) <= set(words)
    options = [(w, *lang.synonyms.get(w, ())) for w in words]
    substituted = {" ".join(c) for c in itertools.product(*options)} - {lang.default}
    assert len(substituted) > L.VARIANTS_PER_FACTOR
    for v in lang.variants["S-LANG"]:
        assert v in substituted, f"{env_id} S-LANG {v!r} is not a synonym substitution of {lang.default!r}"


def test_lookup_by_name_id_and_case_is_cached_and_complete():
    a = L.instruction_variants("REALM-OpenDrawer-v1", "S-LANG")
    assert L.instruction_variants("REALM-OpenDrawer-v1", "S-LANG") is a  # cached
    assert L.instruction_variants("REALM-OpenDrawer-v1", 6) == a == L.instruction_variants("realm-opendrawer-v1", "s-lang")
    assert [L.canonical_factor(i) for i in range(5, 10)] == list(L.FACTORS)
    everything = L.all_variants()
    assert set(everything) == set(TASKS) and all(tuple(v) == L.FACTORS for v in everything.values())
    assert L.synonyms("REALM-CloseDrawer-v1")["close"] == ("shut", "retract", "push in")
    assert dict(L.synonyms("REALM-PickApple-v1")) == {}


def test_unknown_task_or_factor_errors_list_the_known_names():
    with pytest.raises(UnknownNameError, match=r"REALM-Nope-v1.*known: .*REALM-PickApple-v1"):
        L.instruction_variants("REALM-Nope-v1", "S-LANG")
    with pytest.raises(UnknownNameError, match=r"S-FOO.*known: S-PROP, S-LANG, S-MO, S-AFF, S-INT"):
        L.instruction_variants("REALM-PickApple-v1", "S-FOO")
    with pytest.raises(ValueError, match="semantic factor '4'"):  # V-LIGHT is not a semantic factor
        L.canonical_factor(4)


GOOD = {
    "task": "REALM-X-v1",
    "default": "pick up the x",
    "names": ["x"],
    "nouns": ["x"],
    **{f: [f"{f} variant {i}" for i in range(10)] for f in L.FACTORS},
}


@pytest.mark.parametrize(
    "change, message",
    [
        ({"S-MO": [f"v {i}" for i in range(9)]}, "'S-MO' has 9 entries, needs exactly 10"),
        ({"S-AFF": ["same"] * 10}, "'S-AFF' repeats an entry"),
        ({"S-INT": ["ok"] * 9 + [""]}, "'S-INT' must be a list of non-empty strings"),
        ({"S-PROP": None}, "'S-PROP' must be a list"),
        ({"S-SMO": ["x"]}, r"unknown keys \['S-SMO'\]"),
        ({"S-LANG": "__delete__"}, r"missing keys \['S-LANG'\]"),
        ({"synonyms": ["top"]}, "'synonyms' must map"),
    ],
)
def test_malformed_files_are_rejected_with_the_file_name(change, message):
    import yaml

    data = {**GOOD, **change}
    data = {k: v for k, v in data.items() if v != "__delete__"}
    with pytest.raises(ValueError, match=rf"REALM-X-v1\.yaml: .*{message}"):
        L._parse("REALM-X-v1.yaml", yaml.safe_dump(data))


def test_a_well_formed_file_parses():
    import yaml

    lang = L._parse("REALM-X-v1.yaml", yaml.safe_dump(GOOD))
    assert lang.env_id == "REALM-X-v1" and lang.variants["S-INT"][9] == "S-INT variant 9" and not lang.synonyms
