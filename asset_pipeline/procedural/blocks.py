"""Blocks, cubes and dice: the stacking/pushing primitives of the REALM tasks."""

from __future__ import annotations

import numpy as np
import trimesh

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

TOY = dict(family="blocks", theme="toys", friction=0.7)
BRIGHT = ("red", "green", "blue", "yellow", "orange", "purple", "pink", "teal", "white", "black")


@category("cube", colors=("green", "yellow", "blue", "orange", "red", "purple", "white", "pink"), density=650,
          material="wood", shapes=("cube", "square", "boxy"), uses=("something to stack", "a building block"),
          fact="has six equal square faces", names=("cube", "block"), **TOY)
def cube(rng, color):
    s = rng.uniform(0.028, 0.05)
    return Geometry([part(g.box((s, s, s)), color, rng, 0.5)])


@category("dice", colors=("white", "red", "black", "green"), density=1200, material="plastic",
          shapes=("cube", "small"), uses=("something to roll", "something for board games"),
          fact="has opposite faces that add up to seven", names=("die", "dice"), **TOY)
def dice(rng, color):
    s = rng.uniform(0.016, 0.03)
    body = g.rounded_box((s, s, s), s * 0.12)
    pip_col = "white" if color in ("red", "black", "green") else "black"
    pips = []
    # Visual-only pips slightly proud of each face; opposite faces sum to seven.
    layouts = {1: [(0, 0)], 2: [(-1, -1), (1, 1)], 3: [(-1, -1), (0, 0), (1, 1)], 4: [(-1, -1), (-1, 1), (1, -1), (1, 1)],
               5: [(-1, -1), (-1, 1), (0, 0), (1, -1), (1, 1)], 6: [(-1, -1), (-1, 0), (-1, 1), (1, -1), (1, 0), (1, 1)]}
    faces = [((0, 0, 1), 1), ((0, 0, -1), 6), ((1, 0, 0), 2), ((-1, 0, 0), 5), ((0, 1, 0), 3), ((0, -1, 0), 4)]
    d = s * 0.25
    for normal, n in faces:
        nrm = np.array(normal, float)
        u = np.array([1.0, 0, 0]) if abs(nrm[0]) < 0.5 else np.array([0, 1.0, 0])
        v = np.cross(nrm, u)
        for a, b in layouts[n]:
            c = nrm * (s / 2 + 0.0003) + u * a * d + v * b * d + (0, 0, s / 2)
            pips.append(g.moved(g.ellipsoid(s * 0.07, s * 0.07, s * 0.07, subdivisions=1), c - (0, 0, s * 0.07)))
    return Geometry([part(body, color, rng, 0.3), part(trimesh.util.concatenate(pips), pip_col, rng)],
                    collision=[g.hull(body)], colors=(color, pip_col))


@category("toy_block", colors=BRIGHT, density=650, material="wood", shapes=("rectangular", "boxy"),
          uses=("something to stack", "something to build with"), fact="is a classic children's toy",
          names=("toy block", "block", "brick"), **TOY)
def toy_block(rng, color):
    e = np.sort(rng.uniform(0.02, 0.08, 3))[::-1]
    return Geometry([part(g.box((e[0], e[1], e[2])), color, rng, 0.5)])


@category("toy_cylinder", colors=BRIGHT, density=650, material="wood", shapes=("cylindrical", "round"),
          uses=("something to stack",), fact="rolls when laid on its side", names=("cylinder block", "cylinder"), **TOY)
def toy_cylinder(rng, color):
    return Geometry([part(g.cylinder(rng.uniform(0.012, 0.03), rng.uniform(0.025, 0.08)), color, rng, 0.5)])


@category("toy_prism", colors=BRIGHT, density=650, material="wood", shapes=("triangular", "prism"),
          uses=("something to stack", "a roof for a block tower"), fact="has two triangular faces",
          names=("triangular block", "prism"), **TOY)
def toy_prism(rng, color):
    w, L, h = rng.uniform(0.03, 0.06), rng.uniform(0.03, 0.08), rng.uniform(0.02, 0.05)
    pts = np.array([[x, y, z] for y in (-L / 2, L / 2) for (x, z) in ((-w / 2, 0), (w / 2, 0), (0, h))])
    return Geometry([part(trimesh.convex.convex_hull(pts), color, rng)])


@category("domino", colors=("white", "black", "beige"), density=900, material="plastic", shapes=("rectangular", "flat"),
          uses=("something to line up and topple",), fact="is marked with pips on one face", **TOY)
def domino(rng, color):
    e = (rng.uniform(0.02, 0.025), rng.uniform(0.04, 0.05), rng.uniform(0.007, 0.01))
    return Geometry([part(g.box(e), color, rng, 0.3)], lying=True)
