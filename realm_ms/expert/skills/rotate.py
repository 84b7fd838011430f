"""rotate: grasp, lift 3 cm, turn the wrist by ~1.5 rad about the vertical, set down, release
(REACH -> GRASP -> ROTATED). Mugs are grasped by the rim opposite the handle."""

import math

import numpy as np

from realm_ms.expert.primitives import (DEFAULT_YAW, catch_up, grasp, hold, lift, move, obj_yaw, object_geometry, release,
                                        scaled_vertices)

TURN = 1.5  # rad (> 1.1 threshold)
CUPS = ("mug", "cup", "teacup", "coffee_cup")


def _rim_grasp(v: np.ndarray):
    """Rim point (local) for cup-like objects, from their (scaled) mesh vertices ``v``: the wall
    on the side away from the handle (local -x); the pads close radially."""
    top = v[:, 2].max()
    ring = v[v[:, 2] > top - 0.01]
    x_min = ring[:, 0].min()
    return np.array([x_min + 0.005, 0.0, top]), float(top)


def rotate(ctx, tries: int = 3):
    obj = ctx.env.main
    point = yaw = None
    asset, scale, _ = object_geometry(ctx, obj)
    verts = scaled_vertices(asset, scale) if asset.category in CUPS else None
    if verts is not None:
        local, top = _rim_grasp(verts)

        def point(c):
            pos, r = c.obj_pose(obj)
            w = pos + r @ local
            return np.array([w[0], w[1], pos[2] + top - 0.018])

        def yaw(c):
            th = obj_yaw(c.obj_pose(obj)[1])
            cands = [th + k * math.pi for k in (-2, -1, 0, 1, 2)]
            return min(cands, key=lambda y: abs(y - DEFAULT_YAW))

    for attempt in range(tries):
        yield from grasp(ctx, obj, point=point, yaw=yaw)
        yield from lift(ctx, 0.03)
        # turn away from the wrist limit: towards the default yaw side
        sign = 1.0 if ctx.cmd.yaw < DEFAULT_YAW + 0.3 else -1.0
        yield from move(ctx, ctx.cmd.p, yaw=ctx.cmd.yaw + sign * TURN, yaw_speed=1.5, settle=5)
        yield from catch_up(ctx)  # the turn done before setting down (velocity / Cartesian actions lag)
        yield from lift(ctx, -0.025)
        yield from release(ctx)
        yield from lift(ctx, 0.08)
        yield from hold(ctx, 5)
        if bool(ctx.env.tracker.success[ctx.i]):
            break
        ctx.log.append(f"rotate attempt {attempt} failed")
    yield from hold(ctx, 20)
