"""Balls: spheres with a seam/stripe band for texture cues."""

from __future__ import annotations

from asset_pipeline.procedural import geometry as g
from asset_pipeline.procedural.object_model import Geometry, category, part

BALL = dict(family="balls", theme="sports", friction=0.8, shapes=("round", "spherical"))


def _ball(rng, color, r, band_col=None, sub=2):
    body = g.ellipsoid(r, r, r, subdivisions=sub)
    parts = [part(body, color, rng, 0.7)]
    if band_col:
        band = g.cylinder(r * 1.005, r * 0.12, z0=r * 0.94, sections=24)
        parts.append(part(band, band_col, rng))
    return Geometry(parts, collision=[g.hull(body)], colors=(color,) + ((band_col,) if band_col else ()))


@category("tennis_ball", colors=("yellow", "light green"), density=380, material="felt", uses=("something to hit with a racket",),
          fact="is used in a sport played at Wimbledon", names=("tennis ball", "ball"), **BALL)
def tennis_ball(rng, color):
    return _ball(rng, color, rng.uniform(0.032, 0.034), "white")


@category("baseball", colors=("white",), density=600, material="leather", uses=("something to throw and catch",),
          fact="has red stitching", names=("baseball", "ball"), **BALL)
def baseball(rng, color):
    return _ball(rng, color, rng.uniform(0.036, 0.038), "red")


@category("golf_ball", colors=("white", "yellow", "orange"), density=1100, material="plastic", uses=("something to hit with a golf club",),
          fact="has dimples that help it fly farther", names=("golf ball", "ball"), **BALL)
def golf_ball(rng, color):
    return _ball(rng, color, 0.0214, None)


@category("ping_pong_ball", colors=("white", "orange"), density=80, material="plastic", uses=("something to play table tennis with",),
          fact="is hollow and very light", names=("ping pong ball", "ball"), **BALL)
def ping_pong_ball(rng, color):
    return _ball(rng, color, 0.02, None)


@category("rubber_ball", colors=("red", "blue", "green", "yellow", "purple", "pink", "orange"), density=500, material="rubber",
          uses=("something to bounce", "something to throw"), fact="bounces when dropped", names=("ball", "rubber ball"), **BALL)
def rubber_ball(rng, color):
    return _ball(rng, color, rng.uniform(0.025, 0.045), str(rng.choice(["white", "yellow", "blue"])) if rng.random() < 0.5 else None)
