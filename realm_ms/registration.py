"""Every ``REALM-*`` gymnasium id, registered on ``import realm_ms`` whatever started the process.

Registering an id here costs only a gymnasium import: each id's entry point loads the task pack
(ManiSkill, torch, the task modules and the perturbations) the first time an env is made, then makes
it with ManiSkill's own ``make``. The spec mirrors what ManiSkill's ``register_env`` gives (horizon,
its time-limit wrapper, no env checker), and ``register_task`` swaps it for ManiSkill's own when the
task module loads, so the first env of a process is wrapped exactly like every later one.
"""

from __future__ import annotations

import importlib
from functools import partial

from realm_ms.task_index import HORIZON, TASK_MODULES


def load_task_pack() -> None:
    """Import what makes REALM envs work: the ``panda_droid`` agent, every task (ManiSkill's
    registration) and the perturbations (the envs' hook registry). Idempotent; seconds the first time."""
    importlib.import_module("realm_ms.agents")
    importlib.import_module("realm_ms.tasks")
    importlib.import_module("realm_ms.perturbations")


def _make(env_id: str, **kwargs):
    load_task_pack()
    from mani_skill.utils.registration import make

    return make(env_id, **kwargs)


def _make_vec(env_id: str, **kwargs):
    load_task_pack()
    from mani_skill.utils.registration import make_vec

    return make_vec(env_id, **kwargs)


def register_ids() -> None:
    """Register every id of ``TASK_MODULES`` with gymnasium (ids ManiSkill already holds are kept).
    Their entry points carry ``realm_placeholder = True``: ``register_task`` replaces them."""
    import gymnasium as gym
    from gymnasium.envs.registration import WrapperSpec

    for env_id in TASK_MODULES:
        if env_id in gym.registry:
            continue
        entry = partial(_make, env_id=env_id)
        entry.realm_placeholder = True
        gym.register(
            env_id, entry_point=entry, vector_entry_point=partial(_make_vec, env_id=env_id),
            max_episode_steps=HORIZON, disable_env_checker=True,
            additional_wrappers=(WrapperSpec("MSTimeLimit", "mani_skill.utils.registration:TimeLimitWrapper",
                                             dict(max_episode_steps=HORIZON)),),
        )
