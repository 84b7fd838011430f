"""Matplotlib helpers: figures become PNGs embedded in the page (``realm_ms.html_kit``)."""

from __future__ import annotations

from realm_ms.html_kit import img, png


def new(rows: int = 1, cols: int = 1, w: float = 11, h: float = 3.0):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(rows, cols, figsize=(w, h * rows), squeeze=False)
    return fig, ax


def to_img(fig, alt: str = "") -> str:
    fig.tight_layout()
    return img(png(fig, dpi=80), alt)
