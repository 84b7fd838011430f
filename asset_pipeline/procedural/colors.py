"""Named colours: generators pick names, so an object's colour words are exact by construction."""

from __future__ import annotations

import numpy as np

PALETTE: dict[str, tuple[float, float, float]] = {
    "red": (0.80, 0.08, 0.08),
    "dark red": (0.50, 0.05, 0.06),
    "green": (0.10, 0.65, 0.15),
    "light green": (0.55, 0.85, 0.35),
    "dark green": (0.05, 0.35, 0.10),
    "blue": (0.10, 0.25, 0.85),
    "light blue": (0.45, 0.70, 0.95),
    "navy": (0.05, 0.08, 0.35),
    "yellow": (0.95, 0.85, 0.10),
    "orange": (0.98, 0.50, 0.05),
    "purple": (0.50, 0.15, 0.65),
    "pink": (0.95, 0.50, 0.70),
    "brown": (0.45, 0.27, 0.10),
    "dark brown": (0.25, 0.14, 0.06),
    "beige": (0.90, 0.82, 0.65),
    "white": (0.94, 0.94, 0.92),
    "grey": (0.50, 0.50, 0.50),
    "silver": (0.75, 0.76, 0.78),
    "black": (0.06, 0.06, 0.06),
    "gold": (0.85, 0.65, 0.15),
    "teal": (0.05, 0.55, 0.55),
    "cream": (0.97, 0.93, 0.78),
    "clear": (0.85, 0.92, 0.95),
}

# Colours that read as transparent/metallic get PBR tweaks in the exporter.
ALPHA: dict[str, float] = {"clear": 0.35}
METALLIC: dict[str, float] = {"silver": 0.9, "gold": 0.9}


def rgba(name: str, rng: np.random.Generator | None = None, jitter: float = 0.04) -> tuple[float, float, float, float]:
    """RGBA for a colour name, with a small shade jitter so variants are not pixel-identical."""
    r, g, b = PALETTE[name]
    if rng is not None and jitter:
        d = rng.uniform(-jitter, jitter, 3)
        r, g, b = (float(np.clip(c + dc, 0, 1)) for c, dc in zip((r, g, b), d))
    return (r, g, b, ALPHA.get(name, 1.0))
