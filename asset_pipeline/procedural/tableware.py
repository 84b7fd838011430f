"""Bowls, plates, pans and lids: thin revolved shells, collided as ring segments (no CoACD)."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

KITCHEN = dict(family="tableware", theme="containers", friction=0.6)
CERAMIC = ("white", "cream", "blue", "light blue", "green", "red", "grey", "black", "yellow", "teal", "beige")


def _bowl_profile(r_top: float, h: float, r_base: float, n: int = 8) -> np.ndarray:
    t = np.linspace(0, 1, n)
    r = r_base + (r_top - r_base) * np.sin(t * np.pi / 2) ** 0.8
    return np.stack([r, t * h], 1)


@category("bowl", colors=CERAMIC, density=1400, material="ceramic", shapes=("round", "concave", "hollow"),
          uses=("something to put food in", "something to hold soup", "a container"),
          fact="is used to serve cereal and soup", **KITCHEN)
def bowl(rng, color):
    d = rng.uniform(0.13, 0.21)
    h = d * rng.uniform(0.3, 0.45)
    prof = _bowl_profile(d / 2, h, d * rng.uniform(0.22, 0.3))
    t = rng.uniform(0.004, 0.006)
    return Geometry([part(g.vessel(prof, t, 32), color, rng, 0.3)], collision=g.vessel_pieces(prof, t, sectors=12, bands=3))


@category("plate", colors=CERAMIC, density=1400, material="ceramic", shapes=("round", "flat"),
          uses=("something to put food on", "something to serve a meal on"), fact="is usually washed after every meal",
          **KITCHEN)
@category("saucer", colors=CERAMIC, density=1400, material="ceramic", shapes=("round", "flat", "small"),
          uses=("something to put a cup on",), fact="is placed under a teacup", **KITCHEN)
def plate(rng, color):
    d = rng.uniform(0.14, 0.27)
    h = rng.uniform(0.015, 0.025)
    prof = np.array([[d * 0.33, 0.0], [d * 0.38, h * 0.3], [d * 0.46, h * 0.7], [d / 2, h]])
    t = 0.004
    return Geometry([part(g.vessel(prof, t, 36), color, rng, 0.3)], collision=g.vessel_pieces(prof, t, sectors=12, bands=1))


@category("frying_pan", colors=("black", "grey", "silver", "red"), density=2500, material="metal",
          shapes=("round", "flat", "with a handle"), uses=("something to fry food in", "something to cook eggs in"),
          fact="is heated on a stove", names=("frying pan", "pan", "skillet"), theme="kitchen_tools", family="tableware",
          friction=0.5, mass_range=(0.3, 1.6))
def frying_pan(rng, color):
    d = rng.uniform(0.18, 0.26)
    h = rng.uniform(0.035, 0.05)
    prof = np.array([[d * 0.4, 0.0], [d * 0.45, h * 0.5], [d / 2, h]])
    t = 0.004
    L = d * rng.uniform(0.7, 0.9)
    handle = g.moved(g.box((L, 0.025, 0.012)), (d / 2 + L / 2 - 0.01, 0, h * 0.6), rot=(-0.12, (0, 1, 0)))
    return Geometry([part(g.vessel(prof, t, 36), color, rng, 0.4), part(handle, "black", rng, 0.6)],
                    collision=g.vessel_pieces(prof, t, sectors=12, bands=1) + [g.hull(handle)], colors=(color, "black"))


@category("lid", colors=("silver", "clear", "black", "red", "grey"), density=400, material="metal",
          shapes=("round", "flat", "domed"), uses=("something to cover a pot", "something to keep food warm"),
          fact="keeps heat and steam inside a pot", theme="kitchen_tools", family="tableware", friction=0.5)
def lid(rng, color):
    r = rng.uniform(0.07, 0.12)
    dome = rng.uniform(0.015, 0.03)
    t = np.linspace(0, np.pi / 2, 8)
    prof = [(0.0, 0.0)] + [(r * np.cos(a), 0.0 + dome * np.sin(a) + 0.004 * (a == 0)) for a in t]
    prof[1] = (r, 0.0)
    prof[-1] = (0.0, dome)
    body = g.revolve(prof, 32)
    knob = g.cylinder(rng.uniform(0.01, 0.015), 0.018, z0=dome - 0.002, sections=12)
    return Geometry([part(body, color, rng, 0.2), part(knob, "black", rng)], collision=[g.hull(body), g.hull(knob)],
                    colors=(color, "black"))


@category("tray", colors=("brown", "black", "white", "grey", "silver", "blue", "beige"), density=700, material="wood",
          shapes=("rectangular", "flat", "shallow"), uses=("something to carry things on", "a container"),
          fact="is used to carry several dishes at once", theme="containers", family="tableware", friction=0.6,
          mass_range=(0.1, 1.5))
def tray(rng, color):
    W, L, H = rng.uniform(0.2, 0.26), rng.uniform(0.3, 0.38), rng.uniform(0.035, 0.055)
    t = 0.006
    floor = g.box((W, L, t))
    walls = [g.moved(g.box((t, L, H)), (sx * (W - t) / 2, 0, 0)) for sx in (-1, 1)]
    walls += [g.moved(g.box((W - 2 * t, t, H)), (0, sy * (L - t) / 2, 0)) for sy in (-1, 1)]
    parts = [part(m, color, rng, 0.5) for m in [floor, *walls]]
    return Geometry(parts)
