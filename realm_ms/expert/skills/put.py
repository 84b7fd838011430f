"""put: pick the main object, carry it over the receptacle, lower it to just above the rim, release
(REACH -> GRASP -> LIFT_SLIGHT -> MOVE_CLOSE -> PLACE_INTO)."""

import numpy as np

from realm_ms.expert.primitives import carry, grasp, hold, lift, move, object_geometry, release


def place_on(ctx, obj, target, drop: float = 0.02, align_yaw=None, tries: int = 3):
    """Shared by put and stack: grasp ``obj``, carry it above ``target``'s top centre, lower it until
    its bottom is ``drop`` above the target's top, release and retreat."""
    for attempt in range(tries):
        ok = yield from grasp(ctx, obj)
        if not ok:
            ctx.log.append("place: no grasp")
        yield from lift(ctx, 0.0)
        tpos, tr = ctx.obj_pose(target)
        top = tpos[2] + float(object_geometry(ctx, target)[2][2])
        opos, _ = ctx.obj_pose(obj)
        hand = ctx.tcp()[2] - opos[2]  # TCP height above the object's bottom while held
        safe = max(top, 0.0) + hand + max(drop, 0.0) + 0.08
        yield from move(ctx, [ctx.cmd.p[0], ctx.cmd.p[1], safe], speed=0.15, tol=0.02, settle=5)
        centre = ctx.to_base(target.anchor_pos())
        # the object's centre (not the TCP) goes over the target's centre
        off = ctx.to_base(obj.anchor_pos())[:2] - ctx.tcp()[:2]
        goal_xy = centre[:2] - off
        yaw = ctx.cmd.yaw if align_yaw is None else align_yaw(ctx)
        yield from carry(ctx, [goal_xy[0], goal_xy[1], safe], yaw=yaw)
        off = ctx.to_base(obj.anchor_pos())[:2] - ctx.tcp()[:2]
        goal_xy = centre[:2] - off
        yield from move(ctx, [goal_xy[0], goal_xy[1], top + hand + drop], speed=0.08, tol=0.008, settle=20)
        yield from release(ctx, steps=10)
        yield from move(ctx, ctx.cmd.p + np.array([0, 0, 0.10]), speed=0.12, settle=5)
        yield from hold(ctx, 10)
        if bool(ctx.env.tracker.success[ctx.i]):
            return True
        ctx.log.append(f"place attempt {attempt} failed")
    return False


def put(ctx):
    yield from place_on(ctx, ctx.env.main, ctx.env.target, drop=0.02)
    yield from hold(ctx, 20)
