"""stack: place the main block on the target block, faces aligned, released from 5 mm
(REACH -> GRASP -> LIFT_SLIGHT -> MOVE_CLOSE -> PLACE_ONTO)."""

import math

from realm_ms.expert.primitives import hold, obj_yaw, wrap
from realm_ms.expert.skills.put import place_on


def stack(ctx):
    obj, target = ctx.env.main, ctx.env.target

    def align(c):
        # rotate the hand so that the held block's yaw matches the target's (mod 90 deg)
        d = wrap(obj_yaw(c.obj_pose(target)[1]) - obj_yaw(c.obj_pose(obj)[1]))
        d = (d + math.pi / 4) % (math.pi / 2) - math.pi / 4
        return c.cmd.yaw + d

    yield from place_on(ctx, obj, target, drop=0.006, align_yaw=align)
    yield from hold(ctx, 20)
