"""Categories outside the DROID-like themes: the "unseen" pool for VSB-NOBJ and V-SC distractors."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

UNSEEN = dict(family="nondroid", theme="non_droid", seen=False, friction=0.6)
_X = (np.pi / 2, (0, 1, 0))


@category("rubber_duck", colors=("yellow",), density=300, material="rubber", shapes=("round", "duck-shaped"),
          uses=("a bath toy",), fact="floats in the bathtub", names=("rubber duck", "duck"), **UNSEEN)
def rubber_duck(rng, color):
    s = rng.uniform(0.8, 1.3)
    body = g.ellipsoid(0.04 * s, 0.03 * s, 0.025 * s)
    head = g.moved(g.ellipsoid(0.02 * s, 0.02 * s, 0.019 * s), (0.025 * s, 0, 0.035 * s))
    beak = g.moved(g.ellipsoid(0.012 * s, 0.008 * s, 0.004 * s), (0.045 * s, 0, 0.05 * s))
    return Geometry([part(body, color, rng, 0.4), part(head, color, rng, 0.4), part(beak, "orange", rng)], colors=(color, "orange"))


@category("chess_pawn", colors=("white", "black", "beige", "brown"), density=700, material="wood", shapes=("round", "small"),
          uses=("a game piece for chess",), fact="is the most numerous chess piece", names=("chess pawn", "pawn", "chess piece"), **UNSEEN)
def chess_pawn(rng, color):
    r = rng.uniform(0.012, 0.018)
    prof = [(0, 0), (r, 0), (r, r * 0.4), (r * 0.6, r * 0.6), (r * 0.35, r * 2.0), (r * 0.55, r * 2.1), (r * 0.3, r * 2.3)]
    base = g.revolve(prof + [(0, r * 2.3)], 20)
    head = g.moved(g.ellipsoid(r * 0.55, r * 0.55, r * 0.55), (0, 0, r * 2.2))
    return Geometry([part(base, color, rng, 0.3), part(head, color, rng, 0.3)], colors=(color,))


@category("traffic_cone", colors=("orange",), density=400, material="plastic", shapes=("conical", "pointed"),
          uses=("something to block a lane",), fact="warns drivers of road works", names=("traffic cone", "cone"), **UNSEEN)
def traffic_cone(rng, color):
    b = rng.uniform(0.06, 0.1)
    h = b * rng.uniform(1.3, 1.7)
    base = g.box((b, b, 0.006))
    cone = g.revolve([(0, 0.006), (b * 0.4, 0.006), (b * 0.08, h), (0, h)], 20)
    stripe = g.revolve([(0, h * 0.45), (b * 0.4 - (b * 0.32) * 0.45 + 0.001, h * 0.45), (b * 0.4 - (b * 0.32) * 0.65 + 0.001, h * 0.65), (0, h * 0.65)], 20)
    return Geometry([part(base, "black", rng), part(cone, color, rng), part(stripe, "white", rng)], collision=[g.hull(base), g.hull(cone)], colors=(color, "white", "black"))


@category("dumbbell", colors=("black", "grey", "blue", "red", "pink"), density=3000, material="metal", shapes=("symmetrical",),
          uses=("something to lift for exercise",), fact="builds arm muscles", mass_range=(0.3, 3.0), **UNSEEN)
def dumbbell(rng, color):
    r = rng.uniform(0.025, 0.04)
    L = rng.uniform(0.14, 0.2)
    bar = g.moved(g.cylinder(0.012, L, z0=-L / 2, sections=12), (0, 0, r), rot=_X)
    w = rng.uniform(0.025, 0.04)
    ends = [g.moved(g.cylinder(r, w, z0=-w / 2, sections=16), (x, 0, r), rot=_X) for x in (-L / 2 + w / 2, L / 2 - w / 2)]
    return Geometry([part(bar, "silver", rng, 0.3)] + [part(e, color, rng, 0.5) for e in ends], colors=(color, "silver"), lying=True)


@category("hourglass", colors=("brown", "gold", "black", "silver"), density=900, material="glass", shapes=("symmetrical",),
          uses=("something to measure time",), fact="is filled with sand", **UNSEEN)
def hourglass(rng, color):
    r = rng.uniform(0.03, 0.04)
    h = r * rng.uniform(2.5, 3.2)
    plates = [g.cylinder(r * 1.1, 0.008, z0=z, sections=20) for z in (0, h - 0.008)]
    glass = g.revolve([(0, 0.008), (r * 0.9, 0.008), (r * 0.12, h / 2), (r * 0.9, h - 0.008), (0, h - 0.008)], 20)
    sand = g.revolve([(0, 0.008), (r * 0.8, 0.008), (r * 0.3, h * 0.3), (0, h * 0.3)], 16)
    top, bottom = g.cylinder(r * 0.9, (h - 0.016) / 2, z0=0.008, sections=16), g.cylinder(r * 0.9, (h - 0.016) / 2, z0=h / 2, sections=16)
    return Geometry([part(p, color, rng) for p in plates] + [part(glass, "clear", rng, 0.05), part(sand, "beige", rng)],
                    collision=[g.hull(*plates[:1], top), g.hull(bottom, plates[1])], colors=(color, "clear", "beige"))


@category("trophy", colors=("gold", "silver"), density=1500, material="metal", shapes=("cup-shaped",),
          uses=("a prize for the winner",), fact="is awarded to champions", **UNSEEN)
def trophy(rng, color):
    b = rng.uniform(0.05, 0.08)
    base = g.box((b, b, b * 0.4))
    stem = g.cylinder(0.008, b * 0.8, z0=b * 0.4, sections=12)
    prof = np.array([[b * 0.15, b * 1.2], [b * 0.5, b * 1.5], [b * 0.55, b * 2.1]])
    cup = g.vessel(prof, 0.003, 24)
    return Geometry([part(base, "black", rng), part(stem, color, rng, 0.2), part(cup, color, rng, 0.2)],
                    collision=[g.hull(base), g.hull(stem)] + g.vessel_pieces(prof, 0.003, sectors=8, bands=1), colors=(color, "black"))


@category("hammer", colors=("brown", "black", "red", "yellow"), density=1500, material="metal", shapes=("long", "T-shaped"),
          uses=("something to drive nails with",), fact="is a carpenter's basic tool", mass_range=(0.1, 1.0), **UNSEEN)
def hammer(rng, color):
    L = rng.uniform(0.2, 0.3)
    handle = g.rounded_box((L, 0.025, 0.022), 0.007)
    head = g.moved(g.box((0.03, 0.1, 0.028)), (L / 2 - 0.015, 0, -0.003))
    return Geometry([part(handle, color, rng), part(head, "grey", rng, 0.3)], colors=(color, "grey"), lying=True)


@category("screwdriver", colors=("red", "yellow", "blue", "black", "green"), density=1300, material="metal", shapes=("long", "thin"),
          uses=("something to turn screws with",), fact="comes with flat or cross-shaped tips", mass_range=(0.03, 0.3), **UNSEEN)
def screwdriver(rng, color):
    hl, sl = rng.uniform(0.08, 0.11), rng.uniform(0.06, 0.12)
    handle = g.moved(g.rounded_box((hl, 0.028, 0.028), 0.008), (-hl / 2, 0, 0))
    shaft = g.moved(g.cylinder(0.003, sl, sections=8), (0, 0, 0.014), rot=_X)  # x in [0, sl]
    return Geometry([part(handle, color, rng, 0.4), part(shaft, "silver", rng, 0.2)], colors=(color, "silver"), lying=True)


@category("wrench", colors=("silver", "grey", "black"), density=7800, material="metal", shapes=("long", "flat"),
          uses=("something to tighten bolts with",), fact="is called a spanner in Britain", mass_range=(0.05, 0.6), **UNSEEN)
def wrench(rng, color):
    L = rng.uniform(0.15, 0.25)
    shaft = g.box((L, 0.018, 0.006))
    heads = [g.moved(g.cylinder(0.017, 0.007, sections=12), (x, 0, 0)) for x in (-L / 2, L / 2)]
    return Geometry([part(shaft, color, rng, 0.2)] + [part(h, color, rng, 0.2) for h in heads], colors=(color,), lying=True)


@category("candle", colors=("white", "red", "cream", "purple", "blue", "yellow"), density=900, material="wax", shapes=("cylindrical",),
          uses=("something to light",), fact="gives light as the wax burns", **UNSEEN)
def candle(rng, color):
    r = rng.uniform(0.012, 0.04)
    h = rng.uniform(0.05, 0.18)
    body = g.cylinder(r, h, sections=20)
    wick = g.cylinder(0.0015, 0.01, z0=h, sections=6)
    return Geometry([part(body, color, rng, 0.7), part(wick, "black", rng)], collision=[g.hull(body)], colors=(color,))


@category("light_bulb", colors=("white", "clear"), density=300, material="glass", shapes=("round", "pear-shaped"),
          uses=("something that gives light",), fact="was improved by Thomas Edison", names=("light bulb", "bulb"), **UNSEEN)
def light_bulb(rng, color):
    r = rng.uniform(0.028, 0.035)
    base = g.cylinder(r * 0.45, r * 0.9, sections=16)
    t = np.linspace(-np.pi / 2 + 0.5, np.pi / 2, 10)
    prof = [(0.0, r * 0.9)] + [(r * np.cos(a), r * 0.9 + r * 1.4 + r * np.sin(a)) for a in t]
    prof[1] = (r * 0.45, r * 0.9)
    prof.append((0.0, r * 3.3))
    bulb = g.revolve(prof, 20)
    return Geometry([part(base, "silver", rng, 0.2), part(bulb, color, rng, 0.05)], colors=(color, "silver"))


@category("tape_roll", colors=("white", "beige", "silver", "black", "blue"), density=900, material="plastic", shapes=("round", "ring"),
          uses=("something to stick things together",), fact="is sticky on one side", names=("roll of tape", "tape"), **UNSEEN)
def tape_roll(rng, color):
    R = rng.uniform(0.04, 0.055)
    w = rng.uniform(0.015, 0.05)
    prof = np.array([[R, 0.0], [R, w]])
    inner = R - rng.uniform(0.01, 0.02)
    ring = g.revolve([(inner, 0), (R, 0), (R, w), (inner, w), (inner, 0)], 28)
    return Geometry([part(ring, color, rng, 0.4)], collision=g.vessel_pieces(prof, R - inner, sectors=10, bands=1)[1:])


@category("flower_pot", colors=("orange", "brown", "white", "black", "green", "blue"), density=1500, material="ceramic",
          shapes=("conical", "hollow"), uses=("something to grow a plant in",), fact="has a drainage hole in the bottom", names=("flower pot", "pot"), **UNSEEN)
def flower_pot(rng, color):
    r = rng.uniform(0.04, 0.07)
    h = r * rng.uniform(1.0, 1.4)
    prof = np.array([[r * 0.7, 0.0], [r, h]])
    soil = g.cylinder(r * 0.85, h * 0.7, z0=0.005, sections=16)
    return Geometry([part(g.vessel(prof, 0.006, 24), color, rng), part(soil, "dark brown", rng, 1.0)],
                    collision=g.vessel_pieces(prof, 0.006, sectors=10, bands=2), colors=(color, "dark brown"))


@category("toy_car", colors=("red", "blue", "yellow", "green", "black", "white", "orange"), density=900, material="plastic",
          shapes=("boxy", "with wheels"), uses=("a toy to push around",), fact="is a small model of a real car", names=("toy car", "car"), **UNSEEN)
def toy_car(rng, color):
    L = rng.uniform(0.07, 0.13)
    W, H = L * 0.45, L * 0.22
    r = L * 0.11
    body = g.rounded_box((L, W, H), H * 0.2, z0=r)
    cabin = g.rounded_box((L * 0.5, W * 0.85, H * 0.8), H * 0.15, z0=r + H * 0.9)
    wheels = [g.moved(g.cylinder(r, W * 0.2, sections=12), (x, y, r), rot=(np.pi / 2, (1, 0, 0))) for x in (-L * 0.32, L * 0.32) for y in (-W * 0.4, W * 0.45)]
    for w in wheels:
        w.apply_translation((0, 0, -0.0))
    return Geometry([part(body, color, rng, 0.3), part(cabin, color, rng, 0.3)] + [part(w, "black", rng) for w in wheels], colors=(color, "black"))


@category("mushroom", colors=("red", "brown", "white", "beige"), density=600, material="organic", shapes=("round", "domed"),
          uses=("something to cook",), fact="is a fungus, not a plant", **UNSEEN)
def mushroom(rng, color):
    r = rng.uniform(0.02, 0.04)
    stem = g.cylinder(r * 0.35, r * 1.2, sections=12)
    t = np.linspace(0, np.pi / 2, 8)
    cap = g.revolve([(0, r * 1.1)] + [(r * np.cos(a), r * 1.1 + r * 0.8 * np.sin(a)) for a in t][:-1] + [(0, r * 1.9)], 20)
    return Geometry([part(stem, "cream", rng), part(cap, color, rng, 0.6)], colors=(color, "cream"))


@category("bell", colors=("gold", "silver"), density=3000, material="metal", shapes=("bell-shaped", "hollow"),
          uses=("something to ring",), fact="rings when struck", mass_range=(0.05, 0.8), **UNSEEN)
def bell(rng, color):
    r = rng.uniform(0.03, 0.05)
    h = r * rng.uniform(1.1, 1.4)
    prof = np.array([[r, 0.0], [r * 0.8, h * 0.3], [r * 0.55, h]])
    body = g.vessel(prof[::-1] * (1, -1) + (0, h), 0.003, 24)  # flipped: opening down
    handle = g.cylinder(0.007, 0.04, z0=h, sections=10)
    coll = [g.moved(p, (0, 0, 0)) for p in g.vessel_pieces(prof, 0.003, sectors=8, bands=1)[1:]] + [g.hull(handle)]
    return Geometry([part(body, color, rng, 0.2), part(handle, "black", rng)], collision=coll, colors=(color, "black"))


@category("spinning_top", colors=("red", "blue", "green", "yellow", "purple"), density=700, material="wood", shapes=("conical", "round"),
          uses=("a toy to spin",), fact="balances while it spins", names=("spinning top", "top"), **UNSEEN)
def spinning_top(rng, color):
    r = rng.uniform(0.025, 0.04)
    body = g.revolve([(0, 0), (r, r * 0.9), (r, r * 1.2), (0.005, r * 1.3), (0.005, r * 1.9), (0, r * 1.9)], 20)
    return Geometry([part(body, color, rng, 0.3)], collision=[g.hull(body)])


@category("padlock", colors=("gold", "silver", "black", "red", "blue"), density=4000, material="metal", shapes=("boxy", "with a shackle"),
          uses=("something to lock a gate with",), fact="opens with a key or a code", mass_range=(0.03, 0.6), **UNSEEN)
def padlock(rng, color):
    w = rng.uniform(0.035, 0.06)
    body = g.rounded_box((w, w * 0.4, w * 0.85), 0.004)
    path = g.arc(w * 0.3, 0, np.pi, 10, "xz", center=(0, 0, w * 0.85 + w * 0.05))
    shackle = g.tube(path, w * 0.05, sections=8)
    return Geometry([part(body, color, rng, 0.3), part(shackle, "silver", rng, 0.2)],
                    collision=[g.hull(body)] + g.tube_pieces(path, w * 0.05, step=3), colors=(color, "silver"))


@category("battery", colors=("black", "gold", "silver", "blue", "orange"), density=2500, material="metal", shapes=("cylindrical", "small"),
          uses=("something that powers a remote control",), fact="stores chemical energy", **UNSEEN)
def battery(rng, color):
    r = rng.choice([0.007, 0.0105, 0.0125])
    L = r * rng.uniform(4.5, 5.0)
    body = g.moved(g.cylinder(r, L, z0=-L / 2, sections=16), (0, 0, r), rot=_X)
    tip = g.moved(g.cylinder(r * 0.35, 0.0015, sections=8), (L / 2, 0, r), rot=_X)
    return Geometry([part(body, color, rng, 0.3), part(tip, "silver", rng)], collision=[g.hull(body)], colors=(color, "silver"), lying=True)


@category("toy_rocket", colors=("white", "red", "silver", "blue"), density=400, material="plastic", shapes=("pointed", "tall"),
          uses=("a toy spaceship",), fact="flies to space in stories", names=("toy rocket", "rocket"), **UNSEEN)
def toy_rocket(rng, color):
    r = rng.uniform(0.015, 0.025)
    h = r * rng.uniform(5, 7)
    body = g.revolve([(0, 0), (r, 0), (r, h * 0.75), (0, h), ], 16)
    fin = g.hull(g.moved(g.box((0.002, 0.002, h * 0.3)), (0, r * 0.9, 0)), g.moved(g.box((0.002, 0.002, 0.002)), (0, r * 1.8, 0)))
    fins = [g.moved(fin, rot=(a, (0, 0, 1))) for a in (0, 2.09, 4.19)]
    return Geometry([part(body, color, rng, 0.3)] + [part(f, "red" if color != "red" else "blue", rng) for f in fins])
