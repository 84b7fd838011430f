"""Bottles, cans, jars and cartons: closed revolved solids (treated as full for collision)."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

CONT = dict(family="bottles", theme="containers", friction=0.5)


def _bottle_profile(r: float, h: float, neck_r: float, shoulder: float, neck_h: float) -> list[tuple[float, float]]:
    zs = h - neck_h
    prof = [(0.0, 0.0), (r * 0.97, 0.0), (r, 0.004), (r, zs * shoulder)]
    for a in np.linspace(0, np.pi / 2, 5)[1:]:
        prof.append((neck_r + (r - neck_r) * np.cos(a), zs * shoulder + (zs - zs * shoulder) * np.sin(a)))
    prof += [(neck_r, h), (0.0, h)]
    return prof


def _bottle_collision(r: float, h: float, neck_r: float, shoulder: float, neck_h: float, sections: int = 16):
    zs = h - neck_h
    body = g.cylinder(r, zs * shoulder, sections=sections)
    shoulder_part = g.revolve(_bottle_profile(r, h, neck_r, shoulder, neck_h)[3:-2] + [(0.0, zs), (0.0, zs * shoulder)], sections)
    neck = g.cylinder(neck_r, neck_h, z0=zs, sections=12)
    return [g.hull(body), g.hull(shoulder_part), g.hull(neck)]


@category("water_bottle", colors=("clear", "blue", "light blue"), density=900, material="plastic",
          shapes=("cylindrical", "tall"), uses=("something to drink from", "something that holds water"),
          fact="should be recycled when empty", names=("water bottle", "bottle"), mass_range=(0.02, 0.7), **CONT)
def water_bottle(rng, color):
    r = rng.uniform(0.03, 0.037)
    h = rng.uniform(0.16, 0.22)
    neck_r, neck_h, sh = r * 0.45, h * 0.12, rng.uniform(0.6, 0.72)
    body = g.revolve(_bottle_profile(r, h, neck_r, sh, neck_h), 24)
    cap_col = str(rng.choice(["blue", "white", "green"]))
    cap = g.cylinder(neck_r * 1.15, 0.015, z0=h - 0.004, sections=16)
    return Geometry([part(body, color, rng, 0.1), part(cap, cap_col, rng)],
                    collision=_bottle_collision(r, h, neck_r, sh, neck_h) + [g.hull(cap)], colors=(color, cap_col))


@category("wine_bottle", colors=("dark green", "green", "dark red", "black", "clear"), density=1100, material="glass",
          shapes=("cylindrical", "tall", "narrow neck"), uses=("something that holds wine", "something to pour from"),
          fact="is sealed with a cork", names=("wine bottle", "bottle"), mass_range=(0.4, 1.6), **CONT)
def wine_bottle(rng, color):
    r = rng.uniform(0.036, 0.042)
    h = rng.uniform(0.28, 0.32)
    neck_r, neck_h, sh = rng.uniform(0.013, 0.016), h * 0.3, rng.uniform(0.75, 0.85)
    body = g.revolve(_bottle_profile(r, h, neck_r, sh, neck_h), 24)
    label = g.cylinder(r * 1.01, h * 0.25, z0=h * 0.2, sections=24)
    foil = g.cylinder(neck_r * 1.08, 0.04, z0=h - 0.04, sections=12)
    return Geometry([part(body, color, rng, 0.1), part(label, "cream", rng), part(foil, "gold", rng, 0.3)],
                    collision=_bottle_collision(r, h, neck_r, sh, neck_h), colors=(color, "cream"))


@category("can_of_soda", colors=("red", "silver", "blue", "green", "orange", "black", "yellow"), density=1000,
          material="metal", shapes=("cylindrical",), uses=("something to drink", "a fizzy drink"),
          fact="contains carbonated water and sugar", names=("can of soda", "soda can", "can"), mass_range=(0.015, 0.4), **CONT)
@category("food_can", colors=("red", "silver", "green", "yellow", "white", "blue"), density=1100, material="metal",
          shapes=("cylindrical",), uses=("something to open with a can opener", "canned food"),
          fact="keeps food fresh for years", names=("can", "tin can", "food can"), mass_range=(0.05, 0.8), **CONT)
def can(rng, color):
    r = rng.uniform(0.026, 0.04)
    h = rng.uniform(0.1, 0.125) if r < 0.034 else rng.uniform(0.07, 0.12)
    body = g.cylinder(r, h - 0.01, z0=0.005, sections=28)
    rims = [g.cylinder(r * 0.93, 0.005, sections=28), g.cylinder(r * 0.93, 0.005, z0=h - 0.005, sections=28)]
    band = g.cylinder(r * 1.005, h * 0.4, z0=h * 0.3, sections=28)
    band_col = "white" if color != "white" else "red"
    return Geometry([part(body, color, rng, 0.25), part(band, band_col, rng)] + [part(m, "silver", rng, 0.2) for m in rims],
                    collision=[g.hull(body, *rims)], colors=(color, band_col, "silver"))


@category("jar", colors=("clear",), density=900, material="glass", shapes=("cylindrical", "with a lid"),
          uses=("something to store jam or pickles", "a container"), fact="is closed with a screw-top lid",
          mass_range=(0.1, 0.8), **CONT)
def jar(rng, color):
    r = rng.uniform(0.03, 0.045)
    h = rng.uniform(0.07, 0.13)
    body = g.cylinder(r, h, sections=28)
    lid_col = str(rng.choice(["gold", "silver", "red", "white", "black"]))
    lid = g.cylinder(r * 0.92, 0.015, z0=h, sections=28)
    content = g.cylinder(r * 0.92, h * rng.uniform(0.5, 0.9), z0=0.004, sections=20)
    fill = str(rng.choice(["red", "orange", "dark red", "green", "brown", "yellow"]))
    return Geometry([part(body, color, rng, 0.05), part(content, fill, rng), part(lid, lid_col, rng, 0.3)],
                    collision=[g.hull(body), g.hull(lid)], colors=(fill, lid_col, color))


@category("milk_carton", colors=("white", "blue", "red"), density=700, material="paper", shapes=("rectangular", "tall"),
          uses=("something that holds milk", "something to pour from"), fact="must be kept in the fridge",
          names=("milk carton", "carton"), mass_range=(0.03, 1.1), **CONT)
def milk_carton(rng, color):
    w = rng.uniform(0.06, 0.075)
    h = rng.uniform(0.14, 0.2)
    body = g.box((w, w, h))
    roof = g.moved(g.hull(g.box((w, w, 0.001)), g.box((w, 0.004, 0.001), z0=w * 0.45)), (0, 0, h))
    return Geometry([part(body, color, rng, 0.6), part(roof, "white", rng, 0.6)])


@category("ketchup_bottle", colors=("red",), density=1000, material="plastic", shapes=("cylindrical", "squeezable"),
          uses=("something to squeeze onto fries",), fact="is made from tomatoes", names=("ketchup bottle", "ketchup"),
          mass_range=(0.05, 0.7), **CONT)
@category("spray_bottle", colors=("white", "blue", "green", "yellow", "clear"), density=800, material="plastic",
          shapes=("cylindrical", "with a trigger"), uses=("something to spray cleaner with",), fact="is used for cleaning windows",
          names=("spray bottle",), mass_range=(0.05, 0.7), **CONT)
def squeeze_bottle(rng, color):
    r = rng.uniform(0.026, 0.035)
    h = rng.uniform(0.15, 0.2)
    neck_r, neck_h, sh = r * 0.5, h * 0.1, 0.75
    body = g.revolve(_bottle_profile(r, h, neck_r, sh, neck_h), 20)
    cap = g.cylinder(neck_r * 1.2, 0.025, z0=h - 0.005, sections=12)
    cap_col = "white" if color != "white" else "blue"
    return Geometry([part(body, color, rng, 0.3), part(cap, cap_col, rng)],
                    collision=_bottle_collision(r, h, neck_r, sh, neck_h) + [g.hull(cap)], colors=(color, cap_col))
