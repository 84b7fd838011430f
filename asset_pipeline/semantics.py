"""Semantic attributes carried by every catalog object (what perturbations and instructions query)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

# Size classes by largest extent (m): used by samplers ("something small") and the stats table.
SIZE_CLASSES: tuple[tuple[str, float], ...] = (("tiny", 0.04), ("small", 0.10), ("medium", 0.20), ("large", 0.40))


def size_class(max_extent: float) -> str:
    for name, limit in SIZE_CLASSES:
        if max_extent <= limit:
            return name
    return "huge"


@dataclass(frozen=True)
class Semantics:
    category: str
    colors: tuple[str, ...] = ()
    shapes: tuple[str, ...] = ()
    material: str = "unknown"
    uses: tuple[str, ...] = ()  # affordances as phrases: "something to drink from"
    fact: str | None = None  # world knowledge: "grows on trees"
    seen: bool = True  # DROID-like category; False = "unseen" (VSB-NOBJ pool)
    theme: str = "misc"  # DROID theme (REALM get_droid_categories_by_theme) or "non_droid"
    names: tuple[str, ...] = field(default=())  # words for instructions, first is the canonical noun

    @property
    def noun(self) -> str:
        return self.names[0] if self.names else self.category.replace("_", " ")

    def to_dict(self) -> dict:
        d = asdict(self)
        for k, v in d.items():
            if isinstance(v, tuple):
                d[k] = list(v)
        return d
