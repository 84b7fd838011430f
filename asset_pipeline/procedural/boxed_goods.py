"""Boxes, packaged food and flat items: box-like solids, some with a label band."""

from __future__ import annotations

import numpy as np

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

PACK = dict(family="packages", friction=0.7)


def _labelled_box(rng, e, color, label_col, rough=0.7):
    body = g.box(e)
    label = g.box((e[0] * 1.01, e[1] * 0.6, e[2] * 0.5), z0=e[2] * 0.25)
    return Geometry([part(body, color, rng, rough), part(label, label_col, rng, rough)], collision=[g.hull(body)],
                    colors=(color, label_col))


@category("box", colors=("brown", "beige", "white", "red", "blue", "green"), density=250, material="cardboard",
          shapes=("rectangular", "boxy"), uses=("something to put things in", "a container"), fact="is made from folded cardboard",
          theme="containers", names=("box", "cardboard box"), mass_range=(0.02, 1.2), **PACK)
def box(rng, color):
    e = np.sort(rng.uniform(0.06, 0.25, 3))[::-1]
    e[2] = min(e[2], rng.uniform(0.04, 0.15))
    return Geometry([part(g.box(e), color, rng, 0.8)])


@category("cereal_box", colors=("yellow", "red", "blue", "orange", "green", "white"), density=200, material="cardboard",
          shapes=("rectangular", "tall", "flat"), uses=("something that holds breakfast cereal",), fact="is eaten with milk for breakfast",
          theme="food", names=("cereal box", "box of cereal"), mass_range=(0.05, 0.8), **PACK)
@category("cracker_box", colors=("red", "orange", "yellow", "blue"), density=250, material="cardboard",
          shapes=("rectangular", "boxy"), uses=("something that holds crackers", "a snack"), fact="is baked until crisp",
          theme="food", names=("cracker box", "box of crackers"), mass_range=(0.05, 0.6), **PACK)
def cereal_box(rng, color):
    e = (rng.uniform(0.05, 0.07), rng.uniform(0.14, 0.2), rng.uniform(0.18, 0.28))
    if rng.random() < 0.5:
        e = (e[0], e[1], e[2] * 0.7)
    return _labelled_box(rng, e, color, str(rng.choice(["white", "yellow", "brown"])))


@category("chocolate_bar", colors=("brown", "dark brown", "purple", "red", "blue", "gold"), density=1200, material="paper",
          shapes=("rectangular", "flat"), uses=("something to eat", "a sweet snack"), fact="is made from cocoa beans",
          theme="food", names=("chocolate bar", "chocolate", "candy bar"), **PACK)
def chocolate_bar(rng, color):
    e = (rng.uniform(0.06, 0.085), rng.uniform(0.13, 0.17), rng.uniform(0.008, 0.014))
    return _labelled_box(rng, e, color, str(rng.choice(["white", "gold", "silver"])), 0.4)


@category("tea_bag", colors=("white", "beige"), density=300, material="paper", shapes=("square", "flat", "small"),
          uses=("something to make tea with",), fact="is steeped in hot water", theme="food", names=("tea bag", "teabag"), **PACK)
def tea_bag(rng, color):
    w = rng.uniform(0.05, 0.065)
    body = g.rounded_box((w, w * rng.uniform(0.9, 1.2), 0.006), 0.0025)
    tag = g.box((0.02, 0.025, 0.001))
    tag = g.moved(tag, (0, w * 0.7 + 0.02, 0))
    tag_col = str(rng.choice(["green", "yellow", "red", "orange"]))
    return Geometry([part(body, color, rng, 0.9), part(tag, tag_col, rng)], collision=[g.hull(body), g.hull(tag)],
                    colors=(color, tag_col), lying=True)


@category("bag_of_cookies", colors=("blue", "red", "yellow", "orange", "brown", "green"), density=300, material="plastic",
          shapes=("rectangular", "soft", "pillow"), uses=("something to eat", "a sweet snack"), fact="is best with a glass of milk",
          theme="food", names=("bag of cookies", "cookies", "cookie bag"), **PACK)
@category("bag_of_chips", colors=("yellow", "red", "green", "blue", "orange", "silver"), density=60, material="plastic",
          shapes=("pillow", "soft"), uses=("something to eat", "a salty snack"), fact="is made from thinly sliced potatoes",
          theme="food", names=("bag of chips", "chips", "crisps"), **PACK)
def snack_bag(rng, color):
    L, W, T = rng.uniform(0.14, 0.22), rng.uniform(0.1, 0.16), rng.uniform(0.03, 0.05)
    body = g.hull(g.box((W * 0.8, L * 0.9, T)), g.box((W, L, 0.004), z0=T / 2 - 0.002))
    seams = [g.moved(g.box((W, 0.012, 0.003)), (0, s * (L / 2 - 0.006), T / 2 - 0.0015)) for s in (-1, 1)]
    return Geometry([part(body, color, rng, 0.3)] + [part(m, "silver", rng, 0.3) for m in seams],
                    collision=[g.hull(body, *seams)], colors=(color, "silver"), lying=True)


@category("book", colors=("red", "blue", "green", "black", "yellow", "brown", "navy", "purple", "white"), density=700,
          material="paper", shapes=("rectangular", "flat"), uses=("something to read",), fact="is kept in a library",
          theme="stationery", family="packages", friction=0.7)
@category("notebook", colors=("red", "blue", "green", "black", "yellow", "pink", "orange"), density=650, material="paper",
          shapes=("rectangular", "flat", "thin"), uses=("something to write in",), fact="has lined pages for notes",
          theme="stationery", family="packages", friction=0.7)
def book(rng, color):
    W, L, T = rng.uniform(0.12, 0.17), rng.uniform(0.17, 0.24), rng.uniform(0.008, 0.035)
    cover = g.box((W, L, T))
    pages = g.box((W * 0.97, L * 0.98, T * 0.85), z0=T * 0.075)
    pages.apply_translation((0.004, 0, 0))
    return Geometry([part(cover, color, rng, 0.6), part(pages, "cream", rng)], collision=[g.hull(cover)], colors=(color, "cream"), lying=True)


@category("ticket", colors=("white", "yellow", "pink", "orange", "light blue"), density=700, material="paper",
          shapes=("rectangular", "flat", "thin"), uses=("something to get into a show", "proof of payment"),
          fact="is checked at the entrance", theme="stationery", family="packages", friction=0.7)
def ticket(rng, color):
    e = (rng.uniform(0.05, 0.07), rng.uniform(0.12, 0.16), 0.002)
    body = g.box(e)
    stripe = g.box((e[0] * 1.002, 0.012, e[2] * 1.1), z0=-e[2] * 0.05)
    stripe.apply_translation((0, e[1] * 0.3, 0))
    return Geometry([part(body, color, rng, 0.8), part(stripe, "black", rng)], collision=[g.hull(body)], colors=(color, "black"), lying=True)


@category("sponge", colors=("yellow", "green", "pink", "blue", "orange"), density=60, material="foam",
          shapes=("rectangular", "soft"), uses=("something to wash dishes with", "something to clean with"),
          fact="soaks up water", theme="kitchen_tools", family="packages", friction=1.0)
def sponge(rng, color):
    e = (rng.uniform(0.06, 0.075), rng.uniform(0.09, 0.11), rng.uniform(0.025, 0.04))
    body = g.box((e[0], e[1], e[2] * 0.7))
    scour = g.box((e[0], e[1], e[2] * 0.3), z0=e[2] * 0.7)
    return Geometry([part(body, color, rng, 1.0), part(scour, "dark green", rng, 1.0)], collision=[g.hull(body, scour)], colors=(color, "dark green"))


@category("soap_bar", colors=("white", "pink", "light green", "light blue", "cream", "yellow"), density=1050, material="soap",
          shapes=("oval", "flat", "rounded"), uses=("something to wash hands with",), fact="lathers with water",
          theme="hardware", family="packages", friction=0.4)
def soap_bar(rng, color):
    b = g.ellipsoid(rng.uniform(0.035, 0.045), rng.uniform(0.022, 0.03), rng.uniform(0.012, 0.016), subdivisions=2)
    b.vertices[:, 2] = np.clip(b.vertices[:, 2], b.vertices[:, 2].max() * 0.08, None)  # flat bottom
    return Geometry([part(b, color, rng, 0.4)])
