"""push: with the gripper closed, press the raised end of the light switch's rocker past its centre,
down on a table switch, horizontally into a wall switch (REACH -> TOUCH -> TOGGLED_ON)."""

import numpy as np

from realm_ms.expert.primitives import CLOSED, approach, hold, move, nearest_yaw


def push(ctx, tries: int = 3):
    sw = ctx.env.main
    for attempt in range(tries):
        pos, r = ctx.obj_pose(sw)
        press = pos + r @ np.asarray(sw.press_point_local(), float)
        into = r @ np.asarray(sw.press_direction_local(), float)  # down on a table switch, towards a wall switch's wall
        # closing axis across the rocker: both (closed) fingers press side by side on its raised end
        yaw = nearest_yaw([float(np.arctan2(r[1, 0], r[0, 0])) + np.pi / 2])
        yield from approach(ctx, press - 0.08 * into, yaw, clearance=0.0, grip_value=CLOSED)
        # pads end 4 mm below the TCP; go 2 cm past the raised end to press it through
        yield from move(ctx, press + (0.02 + 0.005 * attempt) * into, speed=0.05, tol=0.004, settle=15)
        yield from hold(ctx, 5)
        yield from move(ctx, press - 0.08 * into, speed=0.12, settle=5)
        if bool(sw.toggled()[ctx.i]):
            break
        ctx.log.append(f"push attempt {attempt} did not toggle")
    yield from hold(ctx, 20)
