"""pick: grasp the main object top-down and lift it well clear (REACH -> GRASP -> LIFT_LARGE)."""


from realm_ms.expert.primitives import grasp, hold, lift, release


def pick(ctx, lift_height: float = 0.16, tries: int = 3):
    obj = ctx.env.main
    for attempt in range(tries):
        z0 = ctx.obj_pose(obj)[0][2]
        ok = yield from grasp(ctx, obj)
        if not ok:
            ctx.log.append("pick: no grasp")
        yield from lift(ctx, lift_height)
        yield from hold(ctx, 5)
        if ctx.obj_pose(obj)[0][2] > z0 + 0.08 and ctx.grasped(obj.entity):
            break
        ctx.log.append(f"pick: lift attempt {attempt} dropped the object")
        yield from release(ctx)
    yield from hold(ctx, 25)
