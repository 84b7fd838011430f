"""Markers, pens, pencils and erasers: lying cylinders with caps/tips."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

PEN = dict(family="writing", theme="stationery", friction=0.6)
INKS = ("black", "red", "blue", "green", "orange", "purple", "yellow", "pink")

_X = (np.pi / 2, (0, 1, 0))  # lay the long axis along +x


def _lying_cylinder(r: float, L: float, x0: float, sections: int = 16):
    return g.moved(g.cylinder(r, L, sections=sections), (x0, 0, r), rot=_X)


@category("marker", colors=INKS, density=700, material="plastic", shapes=("cylindrical", "long", "thin"),
          uses=("something to write on a whiteboard with", "something to draw with"), fact="dries out if left uncapped",
          names=("marker", "marker pen", "felt-tip pen"), **PEN)
@category("highlighter", colors=("yellow", "green", "pink", "orange", "light blue"), density=700, material="plastic",
          shapes=("cylindrical", "long"), uses=("something to mark text with",), fact="uses bright fluorescent ink", **PEN)
def marker(rng, color):
    L = rng.uniform(0.13, 0.17)
    r = rng.uniform(0.007, 0.01)
    body_col = "white" if rng.random() < 0.5 else color
    cap_L = L * 0.3
    body = _lying_cylinder(r, L - cap_L, -cap_L / 2)
    cap = _lying_cylinder(r * 1.1, cap_L, (L - cap_L) / 2 + 0.0, 16)
    cap.apply_translation((0, 0, -r * 0.1))
    return Geometry([part(body, body_col, rng, 0.4), part(cap, color, rng, 0.4)], colors=(color, body_col) if body_col != color else (color,), lying=True)


@category("pen", colors=("black", "blue", "red", "silver", "white"), density=900, material="plastic",
          shapes=("cylindrical", "long", "thin"), uses=("something to write with", "something to sign a letter with"),
          fact="uses a tiny rolling ball to spread ink", **PEN)
@category("pencil", colors=("yellow", "red", "blue", "green"), density=600, material="wood", shapes=("hexagonal", "long", "thin"),
          uses=("something to write with", "something to sketch with"), fact="has a core of graphite, not lead", **PEN)
def pen(rng, color):
    L = rng.uniform(0.13, 0.16)
    r = rng.uniform(0.004, 0.0055)
    body = _lying_cylinder(r, L * 0.9, -L * 0.05, 8)
    tip = g.moved(g.revolve([(0, 0), (r, 0), (0.0008, L * 0.1), (0, L * 0.1)], 8), (L * 0.4, 0, r), rot=_X)
    return Geometry([part(body, color, rng, 0.4), part(tip, "beige" if color != "beige" else "black", rng)],
                    colors=(color,), lying=True)


@category("crayon", colors=INKS, density=900, material="wax", shapes=("cylindrical", "short"),
          uses=("something to colour with",), fact="is made of coloured wax", **PEN)
def crayon(rng, color):
    L, r = rng.uniform(0.08, 0.095), rng.uniform(0.004, 0.0055)
    body = _lying_cylinder(r, L * 0.9, -L * 0.05, 10)
    tip = g.moved(g.revolve([(0, 0), (r, 0), (0.001, L * 0.1), (0, L * 0.1)], 10), (L * 0.4, 0, r), rot=_X)
    return Geometry([part(body, color, rng, 0.6), part(tip, color, rng, 0.6)], colors=(color,), lying=True)


@category("eraser", colors=("pink", "white", "blue", "green"), density=1200, material="rubber", shapes=("rectangular", "small"),
          uses=("something to rub out pencil marks",), fact="was once made from bread crumbs", **PEN)
def eraser(rng, color):
    e = (rng.uniform(0.02, 0.03), rng.uniform(0.04, 0.06), rng.uniform(0.008, 0.013))
    return Geometry([part(g.rounded_box(e, 0.002), color, rng, 0.9)], lying=True)
