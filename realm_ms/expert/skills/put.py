"""put: pick the main object, carry it over the receptacle, lower it until it touches, release
(REACH -> GRASP -> LIFT_SLIGHT -> MOVE_CLOSE -> PLACE_INTO)."""

import numpy as np

from realm_ms.contacts import any_contact
from realm_ms.expert.primitives import (
    CONTROL_HZ,
    Target,
    carry,
    grasp,
    hold,
    lift,
    move,
    object_geometry,
    pad_below_tcp,
    release,
    scaled_vertices,
)

SET_DOWN_SPEED = 0.04  # m/s while lowering a held object into a receptacle until it touches
BLOCKED = 0.01  # m the real TCP may lag the command before the hand counts as blocked
HAND_CLEARANCE = 0.005  # m the pad bottoms stay above the receptacle under the open hand
OPEN_HAND_RADIUS = 0.07  # m, half the open 2F-85's span across its fingers, with a margin


def hand_floor(ctx, target) -> float:
    """Lowest the pad bottoms may go over ``target``'s centre (base-frame z): above every part of the
    receptacle within the open hand's reach, read from its collision mesh (a deep tray lets the hand
    in to its floor, a small curved bowl only to where its walls come within reach)."""
    asset, scale, ext = object_geometry(ctx, target)
    tpos, _ = ctx.obj_pose(target)
    v = scaled_vertices(asset, scale)
    if v is None:
        return tpos[2] + float(ext[2])
    near = np.hypot(v[:, 0], v[:, 1]) < OPEN_HAND_RADIUS
    return tpos[2] + float(v[near, 2].max(initial=0.0))


def set_down(ctx, obj, target, floor: float):
    """Lower the held ``obj`` until it touches ``target`` (or the hand does, or is blocked, or the TCP
    reaches ``floor``), so that it is set down rather than dropped: dropped from above the rim, a
    tall glass comes to rest tilted off-centre on a curved bowl floor, and a mug can tip a light bowl
    over. ``floor`` keeps the pads clear of the receptacle (``hand_floor``): pads lowered into a bowl
    beside an apple caught its wall as they opened and threw bowl and apple off the table."""
    step = SET_DOWN_SPEED / CONTROL_HZ
    # the object or the hand against the receptacle, in one walk over the contacts
    mover, receptacle = [*obj.touch_entities(), *ctx.env.agent.gripper_links], target.touch_entities()
    while ctx.cmd.p[2] - step > floor:
        if bool(any_contact(ctx.env.scene, mover, receptacle)[ctx.i]):
            return
        if ctx.cmd.p[2] < ctx.tcp()[2] - BLOCKED:
            return
        ctx.cmd = Target(ctx.cmd.p - np.array([0.0, 0.0, step]), ctx.cmd.yaw, ctx.cmd.grip)
        yield ctx.cmd


def place_on(ctx, obj, target, drop: float = 0.02, align_yaw=None, tries: int = 3, until_contact: bool = False):
    """Shared by put and stack: grasp ``obj``, carry it above ``target``'s top centre, lower it until
    its bottom is ``drop`` above the target's top (``until_contact``: on until it touches the target,
    never below the target's base), release and retreat."""
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
        if until_contact:
            # the object's bottom no lower than the target's base, the pads (lowest when closed) clear of it
            floor = max(tpos[2] + hand + 0.005, hand_floor(ctx, target) + HAND_CLEARANCE + pad_below_tcp(0.0))
            yield from set_down(ctx, obj, target, floor=floor)
        yield from release(ctx, steps=10)
        yield from move(ctx, ctx.cmd.p + np.array([0, 0, 0.10]), speed=0.12, settle=5)
        yield from hold(ctx, 10)
        if bool(ctx.env.tracker.success[ctx.i]):
            return True
        ctx.log.append(f"place attempt {attempt} failed")
    return False


def put(ctx):
    yield from place_on(ctx, ctx.env.main, ctx.env.target, drop=0.02, until_contact=True)
    yield from hold(ctx, 20)
