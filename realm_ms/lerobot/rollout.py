"""``realm export``'s episodes: one env (num_envs = 1), one policy, one dataset frame per control step.

``rollout_config`` describes the REALM env with the cameras the export stores (``tasks.make_env``
builds it; every exported episode stores the config); ``make_export_policy`` turns a policy spec
into an actor (``expert`` directly; env-side policies bound to the env) or, for any other spec of
``realm eval``'s policy registry (e.g. ``lerobot:DIR``), a ``ChunkedPolicy`` whose action chunks are
re-planned every ``replan_every`` steps as ``realm eval`` does; ``record_episode`` runs one episode
on the episode engine (``tasks.episode``) from a seed (optionally replaying recorded perturbation
draws) and hands every step to a callback. Frame t holds the observation *before* action t and the
progression / success *after* it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from realm_ms.lerobot.features import DEFAULT_SIZE, obs_to_numpy
from realm_ms.task_index import DEFAULT as DEFAULT_PERTURBATION


@dataclass
class EpisodeResult:
    steps: int
    progression: float  # best progression reached
    success: bool  # at the end of the episode
    instruction: str
    perturbation: dict | None  # the env's info["perturbation"] after reset (names + drawn params)


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


class ChunkedPolicy:
    """A ``realm eval`` policy (batched, action chunks) on one env: ``chunk(obs)`` -> (T, 8), of
    which the engine executes at most ``replan_every`` before asking again."""

    def __init__(self, policy, env, replan_every: int = 8):
        from realm_ms.eval.policies.policy import CAMERAS

        self.policy, self.env, self.replan_every = policy, env.unwrapped, int(replan_every)
        self.cameras = tuple(policy.obs_request().cameras) or CAMERAS

    def reset(self) -> None:
        self.policy.reset([0])

    def chunk(self, obs) -> np.ndarray:
        from realm_ms.eval.policies.policy import PolicyError, PolicyInput

        batch = PolicyInput(
            state=obs["agent"]["droid_state"][:1].detach().cpu().numpy().astype(np.float32),
            instructions=self.env.get_language_instruction()[:1],
            images={c: obs["sensor_data"][c]["rgb"][:1].detach().cpu().numpy() for c in self.cameras},
            slots=[0],
        )
        from realm_ms.eval.policies.replies import check_output

        # the same reply checks as `realm eval` (shape, numbers, finite, within the space's bounds);
        # export's envs act in joint_position
        actions, errors = check_output(self.policy.act(batch), 1, None, self.policy.name)
        if errors:
            raise PolicyError(errors[0])
        return actions[0][: self.replan_every]


def make_export_policy(spec: str, env, replan_every: int = 8):
    """For ``spec`` on ``env`` (after a reset): an actor (``act(obs) -> (1, 8)``, ``reset()``) or a
    ``ChunkedPolicy``."""
    if spec == "expert":
        from realm_ms.expert import make_expert

        return make_expert(env)
    from realm_ms.eval.policies import make_policy

    policy = make_policy(spec)
    if policy.env_side:
        return policy.bind_env_policy(env.unwrapped)
    return ChunkedPolicy(policy, env, replan_every)


def record_episode(env, policy, seed: int, on_frame: Callable[[dict, np.ndarray, float, bool, bool, str], None],
                   max_steps: int | None = None, perturbation_params=None) -> EpisodeResult:
    """Run one episode of ``policy`` from ``env.reset(seed=seed)``; ``on_frame(np_obs, action, progression, success, done, instruction)``.

    ``perturbation_params``: a recorded ``info["perturbation"]["params"]`` to replay instead of
    drawing. The episode ends on termination (success + tail), truncation (horizon /
    ``max_episode_steps``), ``max_steps``, or when a scripted policy has finished its script."""
    from realm_ms.tasks.episode import Episode, EpisodeEngine

    u = env.unwrapped
    chunked = isinstance(policy, ChunkedPolicy)
    ep = Episode(seed=int(seed), max_steps=max_steps or u.spec.max_episode_steps or u.task_spec.horizon)
    before: list[dict] = []  # the observation the step's action was chosen from, as numpy

    def frame(step) -> None:
        action = step.action.detach().cpu().numpy().reshape(-1, 8)[0]
        on_frame(before.pop(), action, ep.progression, ep.success, ep.done, ep.instruction)

    engine = EpisodeEngine(env, actor=None if chunked else policy, every_frame=True,
                           before_step=lambda obs: before.append(obs_to_numpy(obs)), after_step=frame)
    engine.reset({0: ep}, {"perturbation_params": perturbation_params} if perturbation_params is not None else {})
    if chunked:
        policy.reset()
    while not ep.done:
        if chunked:
            engine.run(policy.replan_every, {0: policy.chunk(engine.obs)})
        else:
            engine.run(ep.max_steps)
    return EpisodeResult(steps=ep.steps, progression=ep.best, success=ep.success, instruction=ep.instruction, perturbation=ep.perturbation)
