"""Every ``REALM-*`` gymnasium id, registered on ``import realm_ms`` whatever started the process.

Registering an id here costs only a gymnasium import: each id's entry point loads the task pack
(ManiSkill, torch, the task modules and the perturbations) the first time an env is made, then makes
it with ManiSkill's own ``make``. The spec mirrors what ManiSkill's ``register_env`` gives (horizon,
its time-limit wrapper, no env checker), and ``register_task`` swaps it for ManiSkill's own when the
task module loads, so the first env of a process is wrapped exactly like every later one.

``TASK_MODULES`` is the one list of tasks: ``realm_ms.tasks`` imports exactly these modules. The
constants here are shared by every layer and cost no import.
"""

from __future__ import annotations

import importlib
from functools import partial

# env id -> module under realm_ms.tasks that declares its TaskSpec (and calls register_task)
TASK_MODULES: dict[str, str] = {
    "REALM-PickApple-v1": "pick_apple",
    "REALM-PickSpoon-v1": "pick_spoon",
    "REALM-PickWaterBottle-v1": "pick_water_bottle",
    "REALM-PutGreenBlockInBowl-v1": "put_green_block_in_bowl",
    "REALM-PutBananaInBox-v1": "put_banana_in_box",
    "REALM-StackCubes-v1": "stack_cubes",
    "REALM-RotateMarker-v1": "rotate_marker",
    "REALM-RotateMug-v1": "rotate_mug",
    "REALM-OpenDrawer-v1": "open_drawer",
    "REALM-CloseDrawer-v1": "close_drawer",
    "REALM-PushSwitch-v1": "push_switch",
}
HORIZON = 800  # control steps, REALM's episode length (TaskSpec.horizon's default)
DEFAULT = "Default"  # the unperturbed setting (perturbation id 0): the one spelling every layer uses


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
    """Register every id of ``TASK_MODULES`` with gymnasium (ids ManiSkill already holds are kept)."""
    import gymnasium as gym
    from gymnasium.envs.registration import WrapperSpec

    for env_id in TASK_MODULES:
        if env_id in gym.registry:
            continue
        gym.register(
            env_id, entry_point=partial(_make, env_id=env_id), vector_entry_point=partial(_make_vec, env_id=env_id),
            max_episode_steps=HORIZON, disable_env_checker=True,
            additional_wrappers=(WrapperSpec("MSTimeLimit", "mani_skill.utils.registration:TimeLimitWrapper",
                                             dict(max_episode_steps=HORIZON)),),
        )


def unregister_placeholder(env_id: str, horizon: int) -> None:
    """Called by ``register_task`` before ManiSkill registers ``env_id``: drop this module's
    placeholder so ManiSkill's spec replaces it without an "Overriding environment" warning."""
    import gymnasium as gym

    spec = gym.registry.get(env_id)
    if spec is None or not isinstance(spec.entry_point, partial) or spec.entry_point.func is not _make:
        return
    if horizon != HORIZON:
        raise ValueError(f"{env_id}: horizon {horizon} differs from realm_ms.registration.HORIZON ({HORIZON}); "
                         "the id's first make would be cut at the wrong step: keep them equal")
    del gym.registry[env_id]
