"""REALM tasks as ManiSkill envs; importing this package registers every ``REALM-*`` env id."""

from realm_ms.tasks import articulated  # noqa: F401  (registers the "articulated/..." object builders)
from realm_ms.tasks import (  # noqa: F401
    close_drawer,
    open_drawer,
    pick_apple,
    pick_spoon,
    pick_water_bottle,
    push_switch,
    put_banana_in_box,
    put_green_block_in_bowl,
    rotate_marker,
    rotate_mug,
    stack_cubes,
)
from realm_ms.tasks.config import RealmEnvConfig, make_env  # noqa: F401
from realm_ms.tasks.env import RealmEnv, register_task  # noqa: F401
from realm_ms.tasks.skills import Skill  # noqa: F401
from realm_ms.tasks.task_spec import TASKS, SceneObject, TaskSpec  # noqa: F401
