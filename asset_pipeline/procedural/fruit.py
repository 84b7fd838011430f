"""Fruit and vegetables: revolved or ellipsoidal bodies, convex by construction (one hull each)."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

FOOD = dict(family="fruit", theme="food", friction=0.8)


def _stem(rng, h_top: float, color: str = "brown"):
    s = g.cylinder(rng.uniform(0.0015, 0.0025), rng.uniform(0.008, 0.015), z0=h_top - 0.004, sections=6)
    return part(s, color, rng)


def _apple_profile(r: float, h: float) -> list[tuple[float, float]]:
    t = np.linspace(0, np.pi, 14)
    # Wider shoulders than base, with shallow dimples at both poles.
    rr = r * np.sin(t) * (1 + 0.08 * np.cos(t))
    zz = h / 2 * (1 - np.cos(t))
    prof = list(zip(rr, zz))
    prof[0] = (0.0, 0.06 * h)
    prof[-1] = (0.0, 0.92 * h)
    return prof


@category("apple", colors=("red", "green", "light green", "yellow", "dark red"), density=800, material="organic",
          shapes=("round",), uses=("something to eat", "a healthy snack"), fact="grows on trees in orchards",
          names=("apple",), **FOOD)
def apple(rng, color):
    r = rng.uniform(0.035, 0.045)
    h = r * rng.uniform(1.7, 2.0)
    body = g.revolve(_apple_profile(r, h), sections=24)
    return Geometry([part(body, color, rng, 0.4), _stem(rng, 0.92 * h)], collision=[g.hull(body)])


@category("half_apple", colors=("red", "green", "yellow"), density=800, material="organic",
          shapes=("half", "round", "flat"), uses=("something to eat",), fact="turns brown when the cut side meets air",
          names=("half apple", "apple half"), **FOOD)
def half_apple(rng, color):
    # Cut face down: a dome of the apple's upper half; the cream cut face is a thin disc underneath.
    r = rng.uniform(0.035, 0.045)
    t = np.linspace(0, np.pi / 2, 10)
    prof = [(0.0, 0.0)] + [(r * np.cos(a), r * 0.95 * np.sin(a) + 0.003) for a in t]
    prof[-1] = (0.0, r * 0.95 + 0.003)
    dome = g.revolve(prof, sections=24)
    face = g.cylinder(r * 0.97, 0.003, sections=24)
    return Geometry([part(dome, color, rng, 0.4), part(face, "cream", rng)], collision=[g.hull(dome, face)], colors=(color, "cream"))


@category("orange", colors=("orange",), density=850, material="organic", shapes=("round", "spherical"),
          uses=("something to eat", "something to peel", "a source of vitamin C"), fact="is a citrus fruit that grows in warm climates",
          **FOOD)
def orange(rng, color):
    r = rng.uniform(0.035, 0.045)
    body = g.ellipsoid(r, r, r * rng.uniform(0.9, 1.0), subdivisions=2)
    return Geometry([part(body, color, rng, 0.7)])


@category("lemon", colors=("yellow",), density=850, material="organic", shapes=("oval", "pointed"),
          uses=("something sour", "something to squeeze"), fact="is a sour citrus fruit", **FOOD)
@category("lime", colors=("green", "light green"), density=850, material="organic", shapes=("oval", "round"),
          uses=("something sour", "something to squeeze"), fact="is a small green citrus fruit", **FOOD)
def lemon(rng, color):
    # Lies on its side: long axis along x, with pointed tips.
    r = rng.uniform(0.025, 0.032)
    L = r * rng.uniform(1.3, 1.6)
    t = np.linspace(0, np.pi, 16)
    prof = [(r * np.sin(a) ** 1.2, L * (1 - np.cos(a))) for a in t]
    body = g.moved(g.revolve(prof, 20), rot=(np.pi / 2, (0, 1, 0)))
    return Geometry([part(body, color, rng, 0.6)], lying=True)


@category("banana", colors=("yellow",), density=900, material="organic", shapes=("curved", "long"),
          uses=("something to eat", "something to peel"), fact="grows in bunches on tropical plants", **FOOD)
def banana(rng, color):
    L = rng.uniform(0.17, 0.21)
    bend = rng.uniform(0.5, 0.8)  # radians of arc
    R = L / bend
    n = 14
    a = np.linspace(-bend / 2, bend / 2, n)
    path = np.stack([R * np.sin(a), np.zeros(n), R * (1 - np.cos(a))], 1)
    r0 = rng.uniform(0.016, 0.02)
    radii = r0 * np.clip(np.sin(np.linspace(0.15, np.pi - 0.15, n)) ** 0.5, 0.25, 1)
    body = g.tube(path, radii, sections=10)
    tip = g.cylinder(0.004, 0.012, sections=6)
    tip = g.moved(tip, path[-1] + (0.002, 0, -0.004), rot=(np.pi / 2 - 0.3, (0, 1, 0)))
    return Geometry([part(body, color, rng, 0.5), part(tip, "dark brown", rng)],
                    collision=g.tube_pieces(path, radii, step=3), colors=(color,), lying=True)


@category("pear", colors=("green", "light green", "yellow"), density=850, material="organic", shapes=("teardrop",),
          uses=("something to eat",), fact="ripens from the inside out", **FOOD)
def pear(rng, color):
    r = rng.uniform(0.032, 0.04)
    h = r * rng.uniform(2.6, 3.0)
    z = np.linspace(0, 1, 16)
    rad = r * (np.sin(np.pi * np.clip(z * 1.6, 0, 1)) * (z < 0.55) + (z >= 0.55) * (0.55 + 0.4 * np.cos((z - 0.55) / 0.45 * np.pi / 2)))
    rad[0], rad[-1] = 0.0, 0.0
    rad = np.maximum(rad, 0.0)
    prof = list(zip(rad, z * h))
    body = g.revolve(prof, 20)
    return Geometry([part(body, color, rng, 0.5), _stem(rng, h)], collision=[g.hull(body)])


@category("peach", colors=("orange", "pink"), density=850, material="organic", shapes=("round",),
          uses=("something to eat",), fact="has a fuzzy skin and a stone in the middle", **FOOD)
@category("tomato", colors=("red", "dark red", "orange"), density=900, material="organic", shapes=("round",),
          uses=("something to eat", "an ingredient for salad"), fact="is botanically a fruit", **FOOD)
@category("plum", colors=("purple", "dark red"), density=900, material="organic", shapes=("round", "oval"),
          uses=("something to eat",), fact="dries into a prune", **FOOD)
def roundfruit(rng, color):
    r = rng.uniform(0.025, 0.04)
    body = g.ellipsoid(r, r * rng.uniform(0.92, 1.0), r * rng.uniform(0.8, 0.95))
    return Geometry([part(body, color, rng, 0.45), _stem(rng, body.bounds[1, 2], "dark green")], collision=[g.hull(body)], colors=(color,))


@category("egg", colors=("white", "beige", "brown"), density=1000, material="organic", shapes=("oval",),
          uses=("something to cook", "something fragile"), fact="is laid by hens", **FOOD)
def egg(rng, color):
    r = rng.uniform(0.02, 0.023)
    t = np.linspace(0, np.pi, 14)
    prof = [(r * np.sin(a) * (1 - 0.12 * np.cos(a)), r * 1.3 * (1 - np.cos(a))) for a in t]
    body = g.moved(g.revolve(prof, 18), rot=(np.pi / 2, (0, 1, 0)))
    return Geometry([part(body, color, rng, 0.8)], lying=True)


@category("carrot", colors=("orange",), density=900, material="organic", shapes=("long", "conical", "pointed"),
          uses=("something to eat", "a vegetable for soup"), fact="is a root vegetable", **FOOD)
def carrot(rng, color):
    L = rng.uniform(0.13, 0.19)
    r = rng.uniform(0.012, 0.018)
    n = 10
    path = np.stack([np.linspace(-L / 2, L / 2, n), np.zeros(n), np.zeros(n)], 1)
    radii = r * np.linspace(1.0, 0.15, n)
    body = g.tube(path, radii, sections=10)
    leaves = g.moved(g.cylinder(0.006, 0.03, sections=6), (-L / 2 - 0.012, 0, 0), rot=(np.pi / 2, (0, 1, 0)))
    return Geometry([part(body, color, rng), part(leaves, "green", rng)], collision=[g.hull(body), g.hull(leaves)],
                    colors=(color, "green"), lying=True)


@category("potato", colors=("brown", "beige"), density=1050, material="organic", shapes=("oval", "lumpy"),
          uses=("something to cook",), fact="grows underground", **FOOD)
def potato(rng, color):
    body = g.ellipsoid(rng.uniform(0.035, 0.05), rng.uniform(0.025, 0.032), rng.uniform(0.02, 0.026), subdivisions=2)
    body.vertices *= 1 + rng.normal(0, 0.03, (len(body.vertices), 1))  # lumps
    return Geometry([part(body, color, rng, 0.9)])
