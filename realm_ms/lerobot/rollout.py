"""The episode loop of ``realm export``: one env (num_envs = 1), one policy, one frame per control step.

``rollout_config`` describes the REALM env with the cameras the export stores (``tasks.make_env``
builds it; every exported episode stores the config); ``make_export_policy`` turns a
policy spec into a per-step actor (``expert`` directly; any other spec of ``realm eval``'s policy
registry, e.g. ``lerobot:DIR``, through its chunked interface, re-planning every ``replan_every``
steps as ``realm eval`` does); ``record_episode`` resets with a seed (and optionally replays recorded
perturbation draws), lets the policy act until the episode ends and hands every step to a callback.
Frame t holds the observation *before* action t and the progression / success *after* it.

This loop is deliberately separate from ``realm eval``'s runner, which executes action chunks
without exposing per-step observations and actions; both reset and step the same envs the same way.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from realm_ms.jsonable import jsonable
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
    """A ``realm eval`` policy (batched, action chunks) as a per-step actor on one env."""

    def __init__(self, policy, env, replan_every: int = 8):
        from realm_ms.eval.policies.policy import CAMERAS

        self.policy, self.env, self.replan_every = policy, env.unwrapped, int(replan_every)
        self.cameras = tuple(policy.obs_request().cameras) or CAMERAS
        self.queue: list[np.ndarray] = []

    def reset(self) -> None:
        self.queue = []
        self.policy.reset([0])

    def act(self, obs):
        from realm_ms.eval.policies.policy import PolicyError, PolicyInput

        if not self.queue:
            batch = PolicyInput(
                state=obs["agent"]["droid_state"][:1].detach().cpu().numpy().astype(np.float32),
                instructions=self.env.get_language_instruction()[:1],
                images={c: obs["sensor_data"][c]["rgb"][:1].detach().cpu().numpy() for c in self.cameras},
                slots=[0],
            )
            out = self.policy.act(batch)
            if out.errors and out.errors[0]:
                raise PolicyError(out.errors[0])
            self.queue = list(np.asarray(out.actions[0][: self.replan_every], dtype=np.float32))
        return self.queue.pop(0)[None]

    __call__ = act


def make_export_policy(spec: str, env, replan_every: int = 8):
    """A per-step actor for ``spec`` on ``env`` (after a reset): ``act(obs) -> (1, 8)``, ``reset()``."""
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
    options = {"perturbation_params": perturbation_params} if perturbation_params is not None else {}
    obs, info = env.reset(seed=int(seed), options=options)
    policy.reset()
    u = env.unwrapped
    instruction = u.get_language_instruction()[0]  # language perturbations change it per episode
    horizon = max_steps or u.spec.max_episode_steps or u.task_spec.horizon
    best, steps, success = 0.0, 0, False
    for steps in range(1, horizon + 1):
        np_obs = obs_to_numpy(obs)
        action = policy.act(obs)
        obs, _, term, trunc, info_s = env.step(action)
        progression = float(info_s["progression"][0])
        success = bool(info_s["success"][0])
        best = max(best, progression)
        script_over = bool(getattr(policy, "done", [False])[0])
        done = bool(term[0]) or bool(trunc[0]) or steps == horizon or script_over
        a = action.detach().cpu().numpy() if hasattr(action, "detach") else np.asarray(action)
        on_frame(np_obs, a.reshape(-1, 8)[0], progression, success, done, instruction)
        if done:
            break
    return EpisodeResult(steps=steps, progression=best, success=success,
                         instruction=instruction, perturbation=jsonable(info.get("perturbation")))
