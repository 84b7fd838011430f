"""Unseen (non-DROID) categories, second set: curios, instruments, gadgets, nature objects and odd
tools that do not occur in DROID-like scenes, for the VSB-NOBJ / V-SC pool. Same pattern as
:mod:`asset_pipeline.procedural.nondroid`: every visual part is convex (or has explicit convex
collision pieces), the first colour word is the requested colour, semantics are fixed per category.
"""

from __future__ import annotations

import numpy as np
import trimesh

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

UNSEEN = dict(family="nondroid", theme="non_droid", seen=False, friction=0.6)
_X = (np.pi / 2, (0, 1, 0))  # cylinder axis z -> x
_Y = (np.pi / 2, (1, 0, 0))  # cylinder axis z -> y


def _lying_cyl(r: float, length: float, sections: int = 16, x0: float = 0.0, z: float | None = None):
    """Cylinder along x, centred at x0, resting on z = 0 (or with its axis at height ``z``)."""
    return g.moved(g.cylinder(r, length, z0=-length / 2, sections=sections), (x0, 0, r if z is None else z), rot=_X)


@category("snow_globe", colors=("black", "brown", "gold", "white", "red"), density=1800, material="glass", shapes=("round", "spherical"),
          uses=("a souvenir to shake",), fact="shows falling snow when shaken", names=("snow globe", "globe"), **UNSEEN)
def snow_globe(rng, color):
    r = rng.uniform(0.035, 0.055)
    base = g.cylinder(r * 0.9, r * 0.6, sections=20)
    ball = g.ellipsoid(r, r, r, z0=r * 0.45)
    return Geometry([part(base, color, rng, 0.4), part(ball, "clear", rng, 0.05)], colors=(color, "clear"))


@category("desk_globe", colors=("blue", "light blue", "beige", "navy"), density=300, material="plastic", shapes=("round", "spherical"),
          uses=("something to find countries on",), fact="is a model of the Earth", names=("globe", "desk globe"), **UNSEEN)
def desk_globe(rng, color):
    r = rng.uniform(0.05, 0.08)
    base = g.cylinder(r * 0.7, 0.01, sections=20)
    stem = g.cylinder(0.005, r * 0.5, z0=0.01, sections=8)
    ball = g.ellipsoid(r, r, r, z0=0.01 + r * 0.45)
    return Geometry([part(base, "black", rng), part(stem, "gold", rng, 0.2), part(ball, color, rng, 0.5)], colors=(color, "black"))


@category("binoculars", colors=("black", "dark green", "grey", "navy"), density=700, material="plastic", shapes=("double-barrelled",),
          uses=("something to see far away with",), fact="magnifies distant birds", **UNSEEN)
def binoculars(rng, color):
    r, L = rng.uniform(0.02, 0.028), rng.uniform(0.1, 0.14)
    barrels = [_lying_cyl(r, L, x0=0, z=r) for _ in range(2)]
    barrels = [g.moved(b, (0, y, 0)) for b, y in zip(barrels, (-r * 1.15, r * 1.15))]
    bridge = g.box((L * 0.35, r * 1.6, r * 0.6), z0=r * 1.2)
    return Geometry([part(b, color, rng, 0.6) for b in barrels] + [part(bridge, color, rng, 0.6)], colors=(color,), lying=True)


@category("harmonica", colors=("silver", "gold", "black", "red"), density=2000, material="metal", shapes=("rectangular", "flat"),
          uses=("something to play music on",), fact="is played by breathing in and out", **UNSEEN)
def harmonica(rng, color):
    L = rng.uniform(0.09, 0.11)
    body = g.rounded_box((L, 0.026, 0.02), 0.003)
    comb = g.box((L * 0.98, 0.027, 0.008), z0=0.006)
    return Geometry([part(body, color, rng, 0.2), part(comb, "black", rng)], collision=[g.hull(body, comb)], colors=(color, "black"), lying=True)


@category("whistle", colors=("silver", "red", "blue", "orange", "black", "yellow"), density=900, material="metal", shapes=("small", "cylindrical"),
          uses=("something to blow to make a loud sound",), fact="is used by referees", **UNSEEN)
def whistle(rng, color):
    r = rng.uniform(0.01, 0.014)
    body = _lying_cyl(r, r * 2.0, x0=0)
    mouth = g.box((r * 3, r * 1.2, r * 0.9), z0=r * 0.9)
    mouth = g.moved(mouth, (r * 2.3, 0, 0))
    return Geometry([part(body, color, rng, 0.2), part(mouth, color, rng, 0.2)], colors=(color,), lying=True)


@category("compass", colors=("gold", "silver", "black", "red"), density=1500, material="metal", shapes=("round", "flat"),
          uses=("something to find north with",), fact="has a magnetised needle", names=("compass",), **UNSEEN)
def compass(rng, color):
    r = rng.uniform(0.025, 0.04)
    case = g.cylinder(r, r * 0.35, sections=24)
    face = g.cylinder(r * 0.85, 0.001, z0=r * 0.35, sections=24)
    needle = g.box((r * 1.4, r * 0.12, 0.001), z0=r * 0.35 + 0.001)
    return Geometry([part(case, color, rng, 0.2), part(face, "white", rng), part(needle, "red", rng)],
                    collision=[g.hull(case, face)], colors=(color, "white", "red"))


@category("magnifying_glass", colors=("black", "brown", "silver", "red"), density=900, material="glass", shapes=("round", "long"),
          uses=("something to make small print bigger",), fact="is a detective's famous tool", names=("magnifying glass", "magnifier"), **UNSEEN)
def magnifying_glass(rng, color):
    r = rng.uniform(0.03, 0.045)
    t = 0.008
    rim = g.cylinder(r, t, sections=24)
    lens = g.cylinder(r * 0.85, t + 0.0005, sections=24)
    hl = rng.uniform(0.08, 0.11)
    handle = g.moved(g.rounded_box((hl, 0.016, 0.014), 0.005), (r + hl / 2 - 0.003, 0, 0))
    return Geometry([part(rim, color, rng), part(lens, "clear", rng, 0.05), part(handle, color, rng)],
                    collision=[g.hull(rim, lens), g.hull(handle)], colors=(color, "clear"), lying=True)


@category("yo_yo", colors=("red", "blue", "green", "yellow", "purple", "black", "orange"), density=800, material="plastic",
          shapes=("round", "disc-shaped"), uses=("a toy on a string",), fact="climbs back up its string", names=("yo-yo", "yoyo"), **UNSEEN)
def yo_yo(rng, color):
    r = rng.uniform(0.025, 0.032)
    w = r * 0.55
    halves = [g.moved(g.cylinder(r, w * 0.45, z0=-w * 0.45 / 2, sections=24), (0, y, r), rot=_Y) for y in (-w * 0.3, w * 0.3)]
    return Geometry([part(h, color, rng, 0.3) for h in halves], collision=[g.hull(*halves)], colors=(color,))


@category("lantern", colors=("black", "red", "green", "gold", "silver"), density=500, material="metal", shapes=("cylindrical", "with a handle"),
          uses=("something that gives light outdoors",), fact="was used before electric lights", **UNSEEN)
def lantern(rng, color):
    r = rng.uniform(0.04, 0.06)
    h = r * rng.uniform(2.2, 2.8)
    base = g.cylinder(r, h * 0.12, sections=16)
    glass = g.cylinder(r * 0.8, h * 0.6, z0=h * 0.12, sections=16)
    top = g.revolve([(0, h * 0.72), (r, h * 0.72), (r * 0.3, h * 0.9), (0, h * 0.9)], 16)
    path = g.arc(r * 0.6, 0, np.pi, 10, "xz", center=(0, 0, h * 0.9))
    handle = g.tube(path, 0.003, sections=6)
    return Geometry([part(base, color, rng), part(glass, "clear", rng, 0.05), part(top, color, rng), part(handle, color, rng)],
                    collision=[g.hull(base, glass), g.hull(top)] + g.tube_pieces(path, 0.003, step=3), colors=(color, "clear"))


@category("alarm_clock", colors=("red", "black", "white", "blue", "silver", "pink"), density=500, material="metal", shapes=("round", "with bells"),
          uses=("something that wakes you up",), fact="rings at a set time", names=("alarm clock", "clock"), **UNSEEN)
def alarm_clock(rng, color):
    r = rng.uniform(0.04, 0.055)
    d = r * 0.7
    feet = [g.moved(g.cylinder(0.005, r * 0.25, sections=8), (x, 0, 0)) for x in (-r * 0.55, r * 0.55)]
    z = r * 0.25 + r
    body = g.moved(g.cylinder(r, d, z0=-d / 2, sections=24), (0, 0, z), rot=_Y)
    face = g.moved(g.cylinder(r * 0.85, 0.001, z0=d / 2, sections=24), (0, 0, z), rot=(-np.pi / 2, (1, 0, 0)))
    bells = [g.moved(g.ellipsoid(r * 0.35, r * 0.35, r * 0.25), (x, 0, z + r * 0.8)) for x in (-r * 0.55, r * 0.55)]
    return Geometry([part(body, color, rng, 0.3), part(face, "white", rng)] + [part(b, "silver", rng, 0.2) for b in bells] +
                    [part(f, "black", rng) for f in feet], collision=[g.hull(body, face)] + [g.hull(b) for b in bells] + [g.hull(f) for f in feet],
                    colors=(color, "white", "silver"))


@category("piggy_bank", colors=("pink", "white", "gold", "blue", "purple"), density=600, material="ceramic", shapes=("round", "pig-shaped"),
          uses=("something to save coins in",), fact="is broken open when it is full", names=("piggy bank", "pig"), **UNSEEN)
def piggy_bank(rng, color):
    s = rng.uniform(0.7, 1.2)
    L, W, H = 0.09 * s, 0.065 * s, 0.06 * s
    leg_h = 0.015 * s
    body = g.ellipsoid(L / 2, W / 2, H / 2, z0=leg_h * 0.6)
    legs = [g.cylinder(0.008 * s, leg_h, sections=10) for _ in range(4)]
    legs = [g.moved(lg, (x, y, 0)) for lg, (x, y) in zip(legs, [(-L * 0.25, -W * 0.22), (-L * 0.25, W * 0.22), (L * 0.25, -W * 0.22), (L * 0.25, W * 0.22)])]
    snout = g.moved(_lying_cyl(0.012 * s, 0.014 * s, x0=0, z=0), (L / 2 + 0.004 * s, 0, leg_h * 0.6 + H / 2))
    return Geometry([part(body, color, rng, 0.3), part(snout, color, rng, 0.3)] + [part(lg, color, rng, 0.3) for lg in legs], colors=(color,))


@category("cactus", colors=("green", "dark green"), density=700, material="organic", shapes=("tall", "spiky"),
          uses=("a houseplant that needs little water",), fact="stores water in its stem", **UNSEEN)
def cactus(rng, color):
    r = rng.uniform(0.03, 0.045)
    pot = g.revolve([(0, 0), (r * 0.8, 0), (r, r * 1.1), (0, r * 1.1)], 16)
    h = r * rng.uniform(2.0, 3.0)
    stem = g.ellipsoid(r * 0.55, r * 0.55, h / 2, z0=r * 1.0)
    arm = g.moved(g.ellipsoid(r * 0.22, r * 0.22, r * 0.5), (r * 0.6, 0, r * 1.0 + h * 0.35))
    pot_col = str(rng.choice(["orange", "brown", "white"]))
    return Geometry([part(pot, pot_col, rng), part(stem, color, rng, 0.7), part(arm, color, rng, 0.7)], colors=(color, pot_col))


@category("metronome", colors=("brown", "black", "dark brown", "red"), density=600, material="wood", shapes=("pyramid-shaped", "pointed"),
          uses=("something that keeps time for musicians",), fact="ticks at a steady beat", **UNSEEN)
def metronome(rng, color):
    b = rng.uniform(0.06, 0.09)
    h = b * rng.uniform(1.8, 2.3)
    body = g.hull(g.box((b, b * 0.8, 0.001)), g.box((b * 0.3, b * 0.3, 0.001), z0=h - 0.001))
    arm = g.moved(g.box((0.003, 0.003, h * 0.7)), (0, -b * 0.35, h * 0.2))
    return Geometry([part(body, color, rng, 0.4), part(arm, "silver", rng, 0.2)], colors=(color, "silver"))


@category("stopwatch", colors=("silver", "black", "red", "blue", "yellow"), density=1200, material="metal", shapes=("round", "flat"),
          uses=("something to time a race with",), fact="measures time to a hundredth of a second", **UNSEEN)
def stopwatch(rng, color):
    r = rng.uniform(0.025, 0.035)
    case = g.cylinder(r, r * 0.45, sections=24)
    face = g.cylinder(r * 0.85, 0.001, z0=r * 0.45, sections=24)
    crown = g.moved(_lying_cyl(r * 0.15, r * 0.4, z=0), (r * 1.1, 0, r * 0.22))
    return Geometry([part(case, color, rng, 0.2), part(face, "white", rng), part(crown, "silver", rng, 0.2)],
                    collision=[g.hull(case, face), g.hull(crown)], colors=(color, "white"))


@category("dreidel", colors=("blue", "silver", "gold", "red", "white"), density=700, material="wood", shapes=("four-sided", "pointed"),
          uses=("a spinning game piece",), fact="is spun during Hanukkah", **UNSEEN)
def dreidel(rng, color):
    a = rng.uniform(0.022, 0.032)
    tip = g.hull(g.box((a, a, 0.001), z0=a * 0.6), g.box((0.002, 0.002, 0.001)))
    body = g.box((a, a, a), z0=a * 0.6)
    stem = g.cylinder(a * 0.12, a * 0.6, z0=a * 1.6, sections=10)
    return Geometry([part(tip, color, rng, 0.3), part(body, color, rng, 0.3), part(stem, color, rng, 0.3)], colors=(color,))


@category("chess_rook", colors=("white", "black", "beige", "brown"), density=700, material="wood", shapes=("cylindrical", "castle-shaped"),
          uses=("a game piece for chess",), fact="moves in straight lines", names=("chess rook", "rook", "castle", "chess piece"), **UNSEEN)
def chess_rook(rng, color):
    r = rng.uniform(0.013, 0.018)
    base = g.revolve([(0, 0), (r * 1.2, 0), (r * 1.2, r * 0.4), (r * 0.8, r * 0.7), (r * 0.8, r * 2.2), (0, r * 2.2)], 20)
    top = g.cylinder(r * 1.0, r * 0.6, z0=r * 2.2, sections=20)
    return Geometry([part(base, color, rng, 0.3), part(top, color, rng, 0.3)], colors=(color,))


@category("game_controller", colors=("black", "white", "grey", "blue", "red"), density=500, material="plastic", shapes=("curved", "with buttons"),
          uses=("something to play video games with",), fact="vibrates in your hands", names=("game controller", "gamepad", "controller"), **UNSEEN)
def game_controller(rng, color):
    s = rng.uniform(0.9, 1.15)
    body = g.rounded_box((0.1 * s, 0.05 * s, 0.025 * s), 0.008 * s)
    grips = [g.moved(g.ellipsoid(0.02 * s, 0.03 * s, 0.0125 * s), (x, -0.025 * s, 0)) for x in (-0.035 * s, 0.035 * s)]
    sticks = [g.cylinder(0.006 * s, 0.006 * s, z0=0.025 * s, sections=10) for _ in range(2)]
    sticks = [g.moved(st, (x, 0, 0)) for st, x in zip(sticks, (-0.02 * s, 0.02 * s))]
    return Geometry([part(body, color, rng, 0.5)] + [part(gr, color, rng, 0.5) for gr in grips] + [part(st, "black" if color != "black" else "grey", rng) for st in sticks],
                    colors=(color,), lying=True)


@category("computer_mouse", colors=("black", "white", "grey", "silver"), density=400, material="plastic", shapes=("oval", "domed"),
          uses=("something to move the cursor with",), fact="was invented in the 1960s", names=("computer mouse", "mouse"), **UNSEEN)
def computer_mouse(rng, color):
    L = rng.uniform(0.1, 0.12)
    base = g.rounded_box((L, L * 0.55, 0.01), 0.004)
    dome = g.ellipsoid(L / 2, L * 0.27, L * 0.3, z0=-L * 0.3 + 0.008)
    top = dome.vertices[dome.vertices[:, 2] >= 0.008]  # upper half of the ellipsoid
    shell = trimesh.convex.convex_hull(np.vstack([top, base.vertices]))
    return Geometry([part(shell, color, rng, 0.4)], colors=(color,), lying=True)


@category("usb_stick", colors=("black", "blue", "red", "silver", "white"), density=1000, material="plastic", shapes=("small", "rectangular"),
          uses=("something to store files on",), fact="plugs into a computer port", names=("USB stick", "memory stick", "flash drive"), **UNSEEN)
def usb_stick(rng, color):
    L = rng.uniform(0.04, 0.06)
    body = g.rounded_box((L, 0.018, 0.008), 0.002)
    plug = g.moved(g.box((0.012, 0.012, 0.0045), z0=0.0018), (L / 2 + 0.006, 0, 0))
    return Geometry([part(body, color, rng, 0.4), part(plug, "silver", rng, 0.2)], colors=(color, "silver"), lying=True)


@category("key", colors=("silver", "gold"), density=8500, material="metal", shapes=("small", "flat", "long"),
          uses=("something to open a lock with",), fact="has a unique pattern of teeth", mass_range=(0.003, 0.05), **UNSEEN)
def key(rng, color):
    r = rng.uniform(0.01, 0.014)
    bow = g.cylinder(r, 0.0025, sections=16)
    L = rng.uniform(0.035, 0.05)
    blade = g.moved(g.box((L, r * 0.6, 0.0025)), (r + L / 2 - 0.002, 0, 0))
    teeth = g.moved(g.box((L * 0.5, r * 0.4, 0.0025)), (r + L * 0.6, -r * 0.45, 0))
    return Geometry([part(bow, color, rng, 0.2), part(blade, color, rng, 0.2), part(teeth, color, rng, 0.2)], colors=(color,), lying=True)


@category("horseshoe", colors=("silver", "grey", "gold", "dark brown"), density=7800, material="metal", shapes=("U-shaped", "flat"),
          uses=("a shoe for a horse", "a lucky charm"), fact="is said to bring good luck", mass_range=(0.05, 1.0), **UNSEEN)
def horseshoe(rng, color):
    R = rng.uniform(0.045, 0.065)
    t = R * 0.18
    path = g.arc(R, -0.25 * np.pi, 1.25 * np.pi, 16, "xy", center=(0, 0, t))
    shoe = g.tube(path, t, sections=8)
    return Geometry([part(shoe, color, rng, 0.3)], collision=g.tube_pieces(path, t, step=2), colors=(color,), lying=True)


@category("bowling_pin", colors=("white",), density=900, material="wood", shapes=("tall", "bottle-shaped"),
          uses=("something to knock down with a ball",), fact="ten of them stand in a triangle", names=("bowling pin", "skittle"), **UNSEEN)
def bowling_pin(rng, color):
    r = rng.uniform(0.025, 0.035)
    prof = [(0, 0), (r * 0.6, 0), (r, r * 1.5), (r, r * 2.5), (r * 0.45, r * 4.2), (r * 0.5, r * 5.0), (r * 0.35, r * 5.6), (0, r * 5.7)]
    pin = g.revolve(prof, 20)
    lower = g.revolve(prof[:4] + [(0, r * 2.5)], 20)
    upper = g.revolve([(0, r * 2.5), (r, r * 2.5), (r * 0.45, r * 4.2), (0, r * 4.2)], 20)
    head = g.revolve([(0, r * 4.2), (r * 0.45, r * 4.2), (r * 0.5, r * 5.0), (r * 0.35, r * 5.6), (0, r * 5.7)], 20)
    stripe = g.cylinder(r * 0.47, r * 0.25, z0=r * 4.3, sections=20)
    return Geometry([part(pin, color, rng, 0.3), part(stripe, "red", rng, 0.3)], collision=[g.hull(lower), g.hull(upper), g.hull(head)],
                    colors=(color, "red"))


@category("shuttlecock", colors=("white", "yellow"), density=150, material="feathers", shapes=("conical", "light"),
          uses=("something to hit in badminton",), fact="flies cork first", names=("shuttlecock", "birdie"), **UNSEEN)
def shuttlecock(rng, color):
    r = rng.uniform(0.012, 0.014)
    cork = g.ellipsoid(r, r, r)
    skirt = g.revolve([(0, r), (r, r), (r * 2.6, r * 5.5), (0, r * 5.5)], 20)
    return Geometry([part(skirt, color, rng, 0.8), part(cork, "white" if color != "white" else "cream", rng, 0.8)], colors=(color,))


@category("maraca", colors=("red", "yellow", "green", "orange", "blue", "brown"), density=300, material="wood", shapes=("round", "with a handle"),
          uses=("something to shake to make music",), fact="is filled with beads or seeds", **UNSEEN)
def maraca(rng, color):
    r = rng.uniform(0.03, 0.04)
    hl = r * rng.uniform(2.0, 2.6)
    head = g.ellipsoid(r * 1.2, r, r, z0=0)
    head = g.moved(head, (hl, 0, 0))
    handle = _lying_cyl(r * 0.25, hl * 1.1, x0=hl * 0.45, z=r)
    return Geometry([part(head, color, rng, 0.5), part(handle, "brown", rng, 0.5)], colors=(color, "brown"), lying=True)


@category("toy_drum", colors=("red", "blue", "yellow", "green", "white"), density=250, material="wood", shapes=("cylindrical", "round"),
          uses=("a toy to bang on",), fact="sounds when its skin is struck", names=("toy drum", "drum"), **UNSEEN)
def toy_drum(rng, color):
    r = rng.uniform(0.05, 0.08)
    h = r * rng.uniform(0.6, 0.9)
    shell = g.cylinder(r, h, sections=24)
    heads = [g.cylinder(r * 1.03, h * 0.08, z0=z, sections=24) for z in (0, h * 0.92)]
    return Geometry([part(shell, color, rng, 0.5)] + [part(hd, "white" if color != "white" else "cream", rng, 0.7) for hd in heads],
                    collision=[g.hull(shell, *heads)], colors=(color, "white" if color != "white" else "cream"))


@category("gemstone", colors=("red", "blue", "green", "purple", "clear", "pink", "teal"), density=2600, material="stone", shapes=("faceted", "small"),
          uses=("something to put in a ring",), fact="is cut to sparkle", names=("gemstone", "gem", "crystal"), **UNSEEN)
def gemstone(rng, color):
    r = rng.uniform(0.012, 0.025)
    n = int(rng.integers(6, 10))
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    crown = np.stack([r * np.cos(a), r * np.sin(a), np.full(n, r * 0.8)], 1)
    table = np.stack([r * 0.55 * np.cos(a + 0.3), r * 0.55 * np.sin(a + 0.3), np.full(n, r * 1.15)], 1)
    gem = trimesh.convex.convex_hull(np.vstack([[[0.0, 0.0, 0.0]], crown, table]))
    return Geometry([part(gem, color, rng, 0.05)], colors=(color,))


@category("acorn", colors=("brown", "light green", "beige"), density=800, material="organic", shapes=("oval", "small"),
          uses=("food for squirrels",), fact="grows into an oak tree", **UNSEEN)
def acorn(rng, color):
    r = rng.uniform(0.008, 0.013)
    nut = g.ellipsoid(r, r, r * 1.4)
    cap = g.moved(g.ellipsoid(r * 1.15, r * 1.15, r * 0.6), (0, 0, r * 2.0))
    stem = g.cylinder(r * 0.15, r * 0.5, z0=r * 2.5, sections=6)
    return Geometry([part(nut, color, rng, 0.4), part(cap, "dark brown", rng, 0.9), part(stem, "dark brown", rng)], colors=(color, "dark brown"))


@category("pine_cone", colors=("brown", "dark brown"), density=300, material="organic", shapes=("conical", "scaly"),
          uses=("a decoration for the autumn table",), fact="holds the seeds of a pine tree", names=("pine cone", "cone"), **UNSEEN)
def pine_cone(rng, color):
    r = rng.uniform(0.02, 0.035)
    h = r * rng.uniform(2.2, 3.0)
    body = g.revolve([(0, 0), (r * 0.5, r * 0.1), (r, h * 0.35), (r * 0.8, h * 0.75), (0, h)], 12)
    core = g.revolve([(0, 0), (r * 0.5, r * 0.1), (r, h * 0.35), (0, h * 0.35)], 12)
    top = g.revolve([(0, h * 0.35), (r, h * 0.35), (r * 0.8, h * 0.75), (0, h)], 12)
    return Geometry([part(body, color, rng, 0.9)], collision=[g.hull(core), g.hull(top)], colors=(color,), lying=bool(rng.random() < 0.5))


@category("starfish", colors=("orange", "red", "pink", "purple", "yellow"), density=1000, material="organic", shapes=("star-shaped", "flat"),
          uses=("a souvenir from the beach",), fact="can regrow a lost arm", **UNSEEN)
def starfish(rng, color):
    R = rng.uniform(0.04, 0.07)
    t = R * 0.18
    arm = g.hull(g.cylinder(R * 0.22, t, sections=10), g.moved(g.cylinder(R * 0.05, t * 0.6, sections=8), (R, 0, 0)))
    arms = [g.moved(arm, rot=(k * 2 * np.pi / 5, (0, 0, 1))) for k in range(5)]
    return Geometry([part(a, color, rng, 0.8) for a in arms], colors=(color,), lying=True)


@category("birdhouse", colors=("brown", "red", "blue", "white", "green", "yellow"), density=350, material="wood", shapes=("house-shaped", "boxy"),
          uses=("a home for small birds",), fact="is hung on a tree", names=("birdhouse", "bird house"), **UNSEEN)
def birdhouse(rng, color):
    w = rng.uniform(0.08, 0.12)
    h = w * rng.uniform(1.0, 1.3)
    body = g.box((w, w, h))
    roof = g.hull(g.box((w * 1.2, w * 1.2, 0.001), z0=h), g.box((w * 1.2, 0.004, 0.001), z0=h + w * 0.45))
    hole = g.moved(_lying_cyl(w * 0.12, 0.002, z=h * 0.6), (w / 2 + 0.001, 0, 0))
    roof_col = "dark brown" if color != "dark brown" else "red"
    return Geometry([part(body, color, rng, 0.7), part(roof, roof_col, rng, 0.7), part(hole, "black", rng)],
                    collision=[g.hull(body), g.hull(roof)], colors=(color, roof_col))


@category("toothbrush", colors=("blue", "green", "pink", "white", "purple", "red"), density=900, material="plastic", shapes=("long", "thin"),
          uses=("something to brush teeth with",), fact="should be replaced every three months", **UNSEEN)
def toothbrush(rng, color):
    L = rng.uniform(0.17, 0.19)
    handle = g.rounded_box((L, 0.012, 0.009), 0.004)
    bristles = g.moved(g.box((0.025, 0.01, 0.01), z0=0.008), (L / 2 - 0.018, 0, 0))
    return Geometry([part(handle, color, rng, 0.3), part(bristles, "white", rng, 0.9)], colors=(color, "white"), lying=True)


@category("hairbrush", colors=("black", "brown", "pink", "purple", "blue"), density=500, material="plastic", shapes=("long", "flat", "with a handle"),
          uses=("something to brush hair with",), fact="detangles long hair", **UNSEEN)
def hairbrush(rng, color):
    s = rng.uniform(0.9, 1.15)
    head = g.rounded_box((0.09 * s, 0.06 * s, 0.02 * s), 0.008 * s)
    handle = g.moved(g.rounded_box((0.11 * s, 0.025 * s, 0.015 * s), 0.006 * s), (0.095 * s, 0, 0.002 * s))
    pad = g.moved(g.box((0.08 * s, 0.05 * s, 0.008 * s)), (0, 0, 0.019 * s))
    return Geometry([part(head, color, rng), part(handle, color, rng), part(pad, "black" if color != "black" else "grey", rng, 0.9)],
                    colors=(color,), lying=True)


@category("bicycle_bell", colors=("silver", "red", "blue", "gold", "black"), density=2000, material="metal", shapes=("round", "domed"),
          uses=("something to ring on a bicycle",), fact="warns people on the path", names=("bicycle bell", "bike bell", "bell"), **UNSEEN)
def bicycle_bell(rng, color):
    r = rng.uniform(0.025, 0.033)
    base = g.cylinder(r * 0.6, r * 0.3, sections=16)
    t = np.linspace(0, np.pi / 2, 8)
    dome = g.revolve([(0, r * 0.3)] + [(r * np.cos(a), r * 0.3 + r * 0.7 * np.sin(a)) for a in t][:-1] + [(0, r)], 20)
    lever = g.moved(g.box((r * 0.8, r * 0.2, r * 0.15)), (r * 0.9, 0, r * 0.1))
    return Geometry([part(base, "black", rng), part(dome, color, rng, 0.2), part(lever, "black", rng)], colors=(color, "black"))


@category("robot_toy", colors=("silver", "grey", "blue", "red", "white"), density=500, material="plastic", shapes=("boxy", "humanoid"),
          uses=("a toy to play with",), fact="looks like a robot from the movies", names=("toy robot", "robot"), **UNSEEN)
def robot_toy(rng, color):
    s = rng.uniform(0.8, 1.3)
    legs = [g.moved(g.box((0.012 * s, 0.014 * s, 0.03 * s)), (0, y * s, 0)) for y in (-0.01, 0.01)]
    body = g.box((0.03 * s, 0.04 * s, 0.04 * s), z0=0.03 * s)
    head = g.box((0.024 * s, 0.026 * s, 0.022 * s), z0=0.07 * s)
    arms = [g.moved(g.box((0.01 * s, 0.008 * s, 0.035 * s), z0=0.032 * s), (0, y * s, 0)) for y in (-0.025, 0.025)]
    eye_col = "red" if color != "red" else "yellow"
    eyes = [g.moved(g.box((0.002 * s, 0.005 * s, 0.005 * s), z0=0.082 * s), (0.0125 * s, y * s, 0)) for y in (-0.006, 0.006)]
    return Geometry([part(body, color, rng, 0.3), part(head, color, rng, 0.3)] + [part(x, color, rng, 0.3) for x in legs + arms] +
                    [part(e, eye_col, rng) for e in eyes], colors=(color, eye_col))
