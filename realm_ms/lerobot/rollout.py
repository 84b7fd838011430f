"""The env of ``realm export`` episodes and of the LeRobot ``realm`` env: ``rollout_config``.

``rollout_config`` describes the REALM env with RGB cameras at the dataset's size (``tasks.make_env``
builds it; every exported episode stores the config). The episodes themselves run on ``realm
eval``'s driver (``lerobot.export``).
"""

from __future__ import annotations

from realm_ms.lerobot.features import DEFAULT_SIZE
from realm_ms.task_index import DEFAULT as DEFAULT_PERTURBATION


def rollout_config(task: str, width: int = DEFAULT_SIZE[0], height: int = DEFAULT_SIZE[1], max_steps: int | None = None,
                   shader: str = "default", perturbation: str | None = None, **env_kwargs):
    """The REALM env ``task`` with RGB cameras at ``width`` x ``height`` (batched torch, num_envs = 1),
    as a ``RealmEnvConfig`` plus the ManiSkill keywords it has no field for."""
    from realm_ms.tasks.config import RealmEnvConfig

    kw = dict(obs_mode="rgb", control_mode="droid_joint_pos", camera_width=width, camera_height=height, shader=shader,
              perturbation=None if perturbation in (None, DEFAULT_PERTURBATION) else perturbation)
    if max_steps:
        kw["max_episode_steps"] = int(max_steps)
    return RealmEnvConfig.from_gym_kwargs(task, kw | env_kwargs)
