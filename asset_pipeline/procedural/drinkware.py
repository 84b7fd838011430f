"""Mugs, cups and glasses: revolved vessels with optional swept handles."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

DRINK = dict(family="drinkware", theme="containers")
CERAMIC = ("white", "red", "blue", "green", "yellow", "black", "grey", "pink", "teal", "orange", "cream", "navy")


def _handle(rng, r_body: float, h: float):
    hr = h * rng.uniform(0.28, 0.36)
    path = g.arc(hr, -np.pi / 2, np.pi / 2, 12, "xz", center=(r_body - 0.002, 0, h * 0.5))
    rad = rng.uniform(0.005, 0.008)
    return g.tube(path, rad, sections=8), g.tube_pieces(path, rad, step=3)


@category("mug", colors=CERAMIC, density=1100, material="ceramic", shapes=("cylindrical", "with a handle"),
          uses=("something to drink from", "something to hold hot coffee"), fact="is used for hot drinks like coffee and tea",
          friction=0.6, mass_range=(0.15, 0.5), **DRINK)
def mug(rng, color):
    r = rng.uniform(0.035, 0.048)
    h = rng.uniform(0.08, 0.11)
    taper = rng.uniform(0.9, 1.05)
    prof = np.array([[r * taper, 0.0], [r, h]])
    t = 0.005
    handle, hpieces = _handle(rng, r, h)
    return Geometry([part(g.vessel(prof, t, 32), color, rng, 0.25), part(handle, color, rng, 0.25)],
                    collision=g.vessel_pieces(prof, t, sectors=10, bands=2) + hpieces, colors=(color,))


@category("cup", colors=("white", "red", "blue", "green", "yellow", "brown", "beige"), density=300, material="paper",
          shapes=("cylindrical", "tapered"), uses=("something to drink from",), fact="is often thrown away after one use",
          names=("cup", "paper cup"), friction=0.6, mass_range=(0.01, 0.1), **DRINK)
def cup(rng, color):
    r = rng.uniform(0.03, 0.045)
    h = rng.uniform(0.08, 0.12)
    prof = np.array([[r * 0.72, 0.0], [r, h]])
    return Geometry([part(g.vessel(prof, 0.003, 28), color, rng, 0.7)], collision=g.vessel_pieces(prof, 0.003, sectors=10, bands=2))


@category("water_glass", colors=("clear",), density=700, material="glass", shapes=("cylindrical", "transparent"),
          uses=("something to drink water from",), fact="is made from melted sand", names=("water glass", "glass", "tumbler"),
          friction=0.5, mass_range=(0.1, 0.4), **DRINK)
def water_glass(rng, color):
    r = rng.uniform(0.03, 0.04)
    h = rng.uniform(0.09, 0.13)
    prof = np.array([[r * rng.uniform(0.8, 1.0), 0.0], [r, h]])
    return Geometry([part(g.vessel(prof, 0.004, 28), color, rng, 0.05)], collision=g.vessel_pieces(prof, 0.004, sectors=10, bands=2))


@category("wineglass", colors=("clear",), density=700, material="glass", shapes=("stemmed", "transparent", "fragile"),
          uses=("something to drink wine from",), fact="is held by the stem so the wine stays cool",
          names=("wine glass", "wineglass", "glass"), friction=0.5, mass_range=(0.1, 0.3), **DRINK)
def wineglass(rng, color):
    rb = rng.uniform(0.03, 0.038)
    stem_h = rng.uniform(0.06, 0.08)
    bowl_h = rng.uniform(0.08, 0.1)
    base = g.cylinder(rb, 0.004, sections=24)
    stem = g.cylinder(0.0045, stem_h, z0=0.004, sections=10)
    t = np.linspace(0, 1, 7)
    r_cup = rng.uniform(0.035, 0.045)
    prof = np.stack([0.006 + (r_cup - 0.006) * np.sin(t * np.pi * 0.6) / np.sin(np.pi * 0.6), stem_h + t * bowl_h], 1)
    bowl = g.vessel(prof, 0.002, 28)
    coll = [g.hull(base), g.hull(stem)] + g.vessel_pieces(prof, 0.003, sectors=10, bands=2)
    return Geometry([part(m, color, rng, 0.05) for m in (base, stem, bowl)], collision=coll)


@category("beaker", colors=("clear",), density=700, material="glass", shapes=("cylindrical", "transparent"),
          uses=("something to measure liquid in", "laboratory glassware"), fact="is used in chemistry labs",
          seen=False, theme="non_droid", friction=0.5, mass_range=(0.05, 0.4), **{"family": "drinkware"})
def beaker(rng, color):
    r = rng.uniform(0.03, 0.045)
    h = r * rng.uniform(2.0, 2.8)
    prof = np.array([[r, 0.0], [r, h]])
    spout = g.moved(g.box((0.012, 0.014, 0.004)), (r, 0, h - 0.004))
    return Geometry([part(g.vessel(prof, 0.003, 28), color, rng, 0.05), part(spout, color, rng, 0.05)],
                    collision=g.vessel_pieces(prof, 0.003, sectors=10, bands=2) + [g.hull(spout)], colors=(color,))


@category("measuring_cup", colors=("clear", "red", "white"), density=600, material="plastic", shapes=("cylindrical", "with a handle"),
          uses=("something to measure flour or milk",), fact="has volume markings on its side", theme="kitchen_tools",
          friction=0.6, **{"family": "drinkware"})
def measuring_cup(rng, color):
    r = rng.uniform(0.04, 0.05)
    h = rng.uniform(0.07, 0.1)
    prof = np.array([[r * 0.92, 0.0], [r, h]])
    handle, hp = _handle(rng, r, h)
    return Geometry([part(g.vessel(prof, 0.003, 28), color, rng, 0.2), part(handle, color, rng)],
                    collision=g.vessel_pieces(prof, 0.003, sectors=10, bands=2) + hp, colors=(color,))
