"""close_drawer: push the open top drawer fully in by its handle
(REACH -> TOUCH_AND_MOVE_JOINT -> CLOSE_JOINT_SMALL -> CLOSE_JOINT_LARGE -> CLOSE_JOINT_FULL)."""

from realm_ms.expert.skills.drawer import move_drawer


def close_drawer(ctx):
    yield from move_drawer(ctx, opening=False)
