"""LeRobot env plugin: the ``realm`` env type (REALM tasks of realm-ms) for ``lerobot-eval`` / ``lerobot-train``.

    lerobot-eval --env.type=realm --env.task=REALM-PickApple-v1 --policy.path=DIR \\
                 --env.discover_packages_path=lerobot_env_realm --eval.n_episodes=10

Importing this package registers ``RealmEnvConfig`` with LeRobot's ``EnvConfig`` registry. LeRobot
imports it by itself when a distribution named ``lerobot_env_realm`` is installed (its
third-party plugin discovery, ``register_third_party_plugins``), otherwise pass
``--env.discover_packages_path=lerobot_env_realm``. Features and feature map match the datasets
written by ``realm export`` (``realm_ms.lerobot.features``): a policy trained on an export is
evaluated here without renaming.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial

from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig

from realm_ms.lerobot.features import ACTION, CAMERAS, DEFAULT_SIZE, FPS, OBS_STATE, image_key

ENV_TYPE = "realm"


def _features_map() -> dict[str, str]:
    return {ACTION: ACTION, "agent_pos": OBS_STATE, **{f"pixels/{cam}": image_key(cam) for cam in CAMERAS}}


@EnvConfig.register_subclass(ENV_TYPE)
@dataclass
class RealmEnvConfig(EnvConfig):
    """A REALM task (``--env.task``: env id, or several comma-separated ids, one suite each)."""

    task: str | None = "REALM-PickApple-v1"
    fps: int = FPS
    episode_length: int | None = None  # control steps; default: the task horizon (800)
    observation_width: int = DEFAULT_SIZE[0]
    observation_height: int = DEFAULT_SIZE[1]
    shader: str = "default"  # default (raster) | rt | rt-med | rt-fast
    perturbation: str | None = None  # a REALM perturbation name (None: Default)
    robot_model: str | None = None  # a named robot model (droid-aligned) or a MODEL.yaml (None: the nominal robot)
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=_features_map)

    def __post_init__(self):
        h, w = self.observation_height, self.observation_width
        self.features = {
            ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(8,)),
            "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(8,)),
            **{f"pixels/{cam}": PolicyFeature(type=FeatureType.VISUAL, shape=(h, w, 3)) for cam in CAMERAS},
        }

    def tasks(self) -> list[str]:
        return [t.strip() for t in (self.task or "").split(",") if t.strip()]

    @property
    def gym_kwargs(self) -> dict:
        # RealmLeRobotEnv maps these onto realm_ms's RealmEnvConfig (eval.runner.cell_config)
        return dict(observation_width=self.observation_width, observation_height=self.observation_height,
                    episode_length=self.episode_length, shader=self.shader, perturbation=self.perturbation,
                    **({"robot_model": self.robot_model} if self.robot_model else {}))

    def create_envs(self, n_envs: int, use_async_envs: bool = False):
        """``{task id: {0: VectorEnv of n_envs RealmLeRobotEnv}}`` (async: one process per env)."""
        import gymnasium as gym

        import realm_ms  # noqa: F401
        from realm_ms.lerobot.gym_env import RealmLeRobotEnv
        from realm_ms.tasks import TASKS

        tasks = self.tasks()
        unknown = [t for t in tasks if t not in TASKS]
        if not tasks or unknown:
            raise ValueError(f"--env.task: unknown REALM task(s) {unknown or [self.task]}; available: {sorted(TASKS)}")
        use_async = use_async_envs and n_envs > 1
        out = {}
        for t in tasks:
            fns = [partial(RealmLeRobotEnv, task=t, **self.gym_kwargs) for _ in range(n_envs)]
            if use_async:
                vec = gym.vector.AsyncVectorEnv(fns, context="forkserver", autoreset_mode=gym.vector.AutoresetMode.SAME_STEP)
            else:
                vec = gym.vector.SyncVectorEnv(fns, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP)
            out[t] = {0: vec}
        return out
