"""REALM tasks as ManiSkill envs; importing this package registers every ``REALM-*`` env id."""

from realm_ms.tasks import pick_apple  # noqa: F401
from realm_ms.tasks.spec import TASKS, SceneObject, TaskSpec, register_task  # noqa: F401
