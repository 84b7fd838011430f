"""open_drawer: pull the top drawer fully out by its handle
(REACH -> TOUCH_AND_MOVE_JOINT -> OPEN_JOINT_SMALL -> OPEN_JOINT_LARGE -> OPEN_JOINT_FULL)."""

from realm_ms.expert.skills.drawer import move_drawer


def open_drawer(ctx):
    yield from move_drawer(ctx, opening=True)
