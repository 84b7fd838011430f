"""Cutlery and small kitchen tools: flat handles plus a bowl/blade/tines, each a few convex pieces."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

UT = dict(family="utensils", theme="utensils", friction=0.5)
METAL = ("silver",)


def _handle(L: float, w: float, t: float, x0: float):
    """Flat handle along +x from x0, tapering towards the head."""
    pts = np.array([[x0, -w / 2, 0], [x0, w / 2, 0], [x0 + L, -w * 0.3, 0], [x0 + L, w * 0.3, 0]])
    return g.hull(*(g.moved(g.box((0.001, 0.001, t)), p) for p in pts))


@category("spoon", colors=METAL + ("white", "black"), density=7800, material="metal", shapes=("long", "thin", "concave"),
          uses=("something to eat soup with", "something to stir with"), fact="is used to eat cereal and soup",
          mass_range=(0.01, 0.12), **UT)
@category("teaspoon", colors=METAL, density=7800, material="metal", shapes=("long", "thin"),
          uses=("something to stir tea with",), fact="holds about five millilitres", mass_range=(0.005, 0.05), **UT)
def spoon(rng, color):
    L = rng.uniform(0.15, 0.2)
    hl = L * 0.65
    handle = _handle(hl, rng.uniform(0.01, 0.016), 0.003, -L / 2)
    br = (L - hl) / 2
    head = g.ellipsoid(br, br * 0.7, 0.006, subdivisions=2)
    head.vertices[:, 2] = np.clip(head.vertices[:, 2], 0, 0.008)
    head = g.moved(head, (-L / 2 + hl + br * 0.9, 0, 0))
    return Geometry([part(handle, color, rng, 0.2), part(head, color, rng, 0.2)], colors=(color,), lying=True)


@category("fork", colors=METAL + ("white", "black"), density=7800, material="metal", shapes=("long", "thin", "pronged"),
          uses=("something to eat with", "something to pick up food with"), fact="usually has four tines",
          mass_range=(0.01, 0.12), **UT)
def fork(rng, color):
    L = rng.uniform(0.17, 0.21)
    hl = L * 0.65
    handle = _handle(hl, rng.uniform(0.01, 0.015), 0.003, -L / 2)
    x1 = -L / 2 + hl
    w = rng.uniform(0.02, 0.026)
    neck = g.moved(g.box((0.015, w, 0.003)), (x1 + 0.0075, 0, 0))
    tl = L - hl - 0.015
    tines = [g.moved(g.box((tl, 0.0025, 0.003)), (x1 + 0.015 + tl / 2, y, 0)) for y in np.linspace(-w / 2 + 0.0013, w / 2 - 0.0013, 4)]
    parts = [part(m, color, rng, 0.2) for m in (handle, neck, *tines)]
    return Geometry(parts, colors=(color,), lying=True)


@category("knife", colors=METAL, density=7800, material="metal", shapes=("long", "thin", "sharp"),
          uses=("something to cut with", "something to spread butter with"), fact="should be handled by the handle",
          mass_range=(0.01, 0.2), **UT)
def knife(rng, color):
    L = rng.uniform(0.19, 0.24)
    hl = L * rng.uniform(0.42, 0.5)
    hcol = str(rng.choice(["black", "brown", "silver", "white"]))
    handle = g.moved(g.rounded_box((hl, 0.018, 0.012), 0.004), (-L / 2 + hl / 2, 0, 0))
    bl = L - hl
    blade = g.hull(g.moved(g.box((0.002, 0.02, 0.002)), (-L / 2 + hl, 0.0, 0.004)), g.moved(g.box((0.002, 0.004, 0.002)), (L / 2, -0.006, 0.004)))
    del bl
    return Geometry([part(handle, hcol, rng, 0.5), part(blade, color, rng, 0.15)], colors=(color, hcol) if hcol != color else (color,), lying=True)


@category("spatula", colors=("black", "red", "white", "silver"), density=1400, material="plastic", shapes=("long", "flat"),
          uses=("something to flip pancakes with",), fact="is used to turn food in a pan", theme="kitchen_tools", **{k: v for k, v in UT.items() if k != "theme"})
@category("wooden_spoon", colors=("brown", "beige"), density=700, material="wood", shapes=("long", "rounded"),
          uses=("something to stir a pot with",), fact="does not scratch non-stick pans", theme="kitchen_tools", **{k: v for k, v in UT.items() if k != "theme"})
def spatula(rng, color):
    L = rng.uniform(0.26, 0.32)
    hl = L * 0.6
    handle = g.moved(g.rounded_box((hl, 0.02, 0.012), 0.004), (-L / 2 + hl / 2, 0, 0))
    hw = rng.uniform(0.05, 0.07)
    head = g.moved(g.rounded_box((L - hl, hw, 0.004), 0.0015), (L / 2 - (L - hl) / 2, 0, 0))
    return Geometry([part(handle, color, rng, 0.5), part(head, color, rng, 0.5)], colors=(color,), lying=True)


@category("corkscrew", colors=("silver", "black", "brown", "red"), density=3000, material="metal", shapes=("spiral", "T-shaped"),
          uses=("something to open a wine bottle with",), fact="pulls corks out of wine bottles", theme="kitchen_tools",
          mass_range=(0.03, 0.3), **{k: v for k, v in UT.items() if k != "theme"})
def corkscrew(rng, color):
    # Lying on its side: T-handle along y, spiral worm along +x.
    hl = rng.uniform(0.09, 0.12)
    handle = g.moved(g.rounded_box((0.022, hl, 0.02), 0.008), (-0.03, 0, 0))
    shaft = g.moved(g.cylinder(0.004, 0.025, sections=8), (-0.012, 0, 0.01), rot=(np.pi / 2, (0, 1, 0)))
    n = 40
    t = np.linspace(0, 5 * 2 * np.pi, n)
    wl = rng.uniform(0.05, 0.065)
    path = np.stack([np.linspace(0.0, wl, n), 0.005 * np.cos(t), 0.01 + 0.005 * np.sin(t)], 1)
    worm = g.tube(path, 0.0013, sections=6)
    worm_hull = g.hull(worm)
    return Geometry([part(handle, color, rng, 0.5), part(shaft, "silver", rng, 0.2), part(worm, "silver", rng, 0.2)],
                    collision=[g.hull(handle), g.hull(shaft), worm_hull], colors=(color, "silver") if color != "silver" else (color,), lying=True)
