"""Shared drawer motion for open_drawer / close_drawer: grasp the top drawer's bar handle top-down
(fingers straddling the bar along the pull axis), pull it out (or push it in) along the cabinet's
axis, release, retreat; retried while the drawer is short of its goal."""

import math

import numpy as np

from realm_ms.expert.primitives import DEFAULT_YAW, approach, close, descend, hold, move, release


def _handle(ctx, cab):
    h = ctx.to_base(cab.handle_pos())
    _, r = ctx.obj_pose(cab)
    axis = r[:, 0]  # cabinet +x: into the cabinet; drawers open along -x
    yaw = math.atan2(axis[1], axis[0])
    yaw = min((yaw + k * math.pi for k in (-2, -1, 0, 1, 2)), key=lambda y: abs(y - DEFAULT_YAW))
    return h, axis, yaw


def move_drawer(ctx, opening: bool, tries: int = 3):
    cab = ctx.env.main
    travel = cab.geom.travel
    goal = (lambda: float(cab.openness()[ctx.i]) > 0.97) if opening else (lambda: float(cab.openness()[ctx.i]) < 0.03)
    for attempt in range(tries):
        h, axis, yaw = _handle(ctx, cab)
        yield from approach(ctx, h, yaw, clearance=0.08)
        yield from descend(ctx, h + np.array([0, 0, 0.002]))
        yield from close(ctx, None, max_steps=12)
        # pull out (-axis) or push in (+axis) by the remaining travel, plus a margin
        op = float(cab.openness()[ctx.i])
        dist = (1.0 - op) * travel + 0.02 if opening else op * travel + 0.02
        d = -axis if opening else axis
        yield from move(ctx, ctx.cmd.p + d * dist, speed=0.08, tol=0.01, settle=15)
        yield from release(ctx)
        yield from move(ctx, ctx.cmd.p + np.array([0, 0, 0.08]) - d * 0.02, speed=0.1, settle=5)
        if goal():
            break
        ctx.log.append(f"drawer attempt {attempt}: openness {float(cab.openness()[ctx.i]):.2f}")
    yield from hold(ctx, 20)

