"""REALM tasks as ManiSkill envs; importing this package registers every ``REALM-*`` env id."""

import importlib

from realm_ms.task_index import TASK_MODULES
from realm_ms.tasks import articulated  # noqa: F401  (registers the "articulated/..." object builders)
from realm_ms.tasks.config import RealmEnvConfig, make_env  # noqa: F401
from realm_ms.tasks.env import RealmEnv, register_task  # noqa: F401
from realm_ms.tasks.skills import Skill  # noqa: F401
from realm_ms.tasks.task_spec import TASKS, SceneObject, TaskSpec  # noqa: F401

for _module in TASK_MODULES.values():  # each declares one TaskSpec and registers its env
    importlib.import_module(f"realm_ms.tasks.{_module}")
