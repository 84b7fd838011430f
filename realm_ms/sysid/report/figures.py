"""Matplotlib helpers: figures become base64 PNGs embedded in the page."""

from __future__ import annotations

import base64
import io


def new(rows: int = 1, cols: int = 1, w: float = 11, h: float = 3.0):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(rows, cols, figsize=(w, h * rows), squeeze=False)
    return fig, ax


def to_img(fig, alt: str = "") -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=80)
    plt.close(fig)
    b64 = base64.b64encode(buf.getvalue()).decode()
    return f'<img alt="{alt}" src="data:image/png;base64,{b64}"/>'
