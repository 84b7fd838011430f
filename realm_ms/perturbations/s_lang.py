"""6 S-LANG: the same request in other words (paraphrase, word order, register).

Non-drawer tasks: a uniform pick among the task's 10 cached variants. Drawer tasks (REALM): with
probability n_cached / (n_synonym_combos + n_cached) a cached variant, otherwise synonym
substitution, each synonym key replaced with p = 0.5 and at least one forced (top -> highest,
topmost, upmost, upper; drawer -> compartment, drawer; close -> shut, retract, push in), output
capitalised. Explicit branches (the original fell through from one to the other).
"""

from __future__ import annotations

import re
from dataclasses import replace

from realm_ms.perturbations.semantic import InstructionVariant, variants

SYNONYMS = {
    "top": ("highest", "topmost", "upmost", "upper"),
    "drawer": ("compartment", "drawer"),
    "close": ("shut", "retract", "push in"),
}


def synonym_table(env_id: str) -> dict[str, tuple[str, ...]]:
    """The task's synonym lists (task language data), else REALM's."""
    try:
        from realm_ms.tasks.language import synonyms

        table = dict(synonyms(env_id))
    except (ImportError, ValueError):
        table = {}
    return table or dict(SYNONYMS)


def synonym_keys(text: str, table=SYNONYMS) -> list[str]:
    return [k for k in table if re.search(rf"\b{k}\b", text)]


def n_synonym_combos(text: str, table=SYNONYMS) -> int:
    n = 1
    for k in synonym_keys(text, table):
        n *= len(table[k]) + 1
    return n - 1  # at least one key replaced


def substitute(text: str, rng, table=SYNONYMS) -> tuple[str, dict]:
    keys = synonym_keys(text, table)
    chosen = [k for k in keys if rng.random() < 0.5] or [keys[int(rng.integers(len(keys)))]]
    picks = {}
    for k in chosen:
        word = table[k][int(rng.integers(len(table[k])))]
        picks[k] = word
        text = re.sub(rf"\b{k}\b", word, text, count=1)
    return text[:1].upper() + text[1:], picks


class SLang(InstructionVariant):
    pid = 6
    name = "S-LANG"
    ranges = "uniform pick among 10 cached variants; drawers: or synonym substitution (p = 0.5 per key, >= 1)"

    def draw(self, rng, ctx):
        cached = variants(ctx.env_id, self.name)
        base = ctx.spec.instruction
        table = synonym_table(ctx.env_id)
        combos = n_synonym_combos(base, table) if ctx.spec.skill in ("open_drawer", "close_drawer") else 0
        if combos and rng.random() >= len(cached) / (combos + len(cached)):
            text, picks = substitute(base, rng, table)
            return dict(source="synonyms", synonyms=picks, instruction=text)
        k = int(rng.integers(len(cached)))
        return dict(source="cached", index=k, instruction=cached[k])

    def edit_spec(self, spec, params, ctx):
        return replace(spec, instruction=params["instruction"])


__all__ = ["SLang", "SYNONYMS"]
