"""The policy interface every evaluated policy implements.

A policy sees a *batch* of observations (one row per active episode slot) and returns a chunk of
``droid_joint_pos`` actions per row, shape (B, T, 8): 7 absolute joint targets (rad) + gripper in
[0, 1] (1 = closed). The runner executes the first ``replan_every`` actions of each chunk open-loop
(REALM: 8) and then asks again. Batching happens once per round in the main process, whatever the
number of simulation workers.

Privileged policies (the scripted expert) cannot run from observations: they set ``env_side`` and
are built inside the process that owns the env via ``bind_env_policy(env)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.rendering import CAMERA_UIDS as CAMERAS  # noqa: F401  (the env's camera uids, re-exported)


@dataclass
class ObsRequest:
    """What the env must render for a policy: cameras (subset of ``CAMERAS``) at width x height."""

    cameras: tuple[str, ...] = ()
    width: int = 320
    height: int = 180


@dataclass
class PolicyInput:
    """One round's batch. ``images[cam]`` (B, H, W, 3) uint8; ``state`` (B, 8) DROID state."""

    state: np.ndarray
    instructions: list[str]
    images: dict[str, np.ndarray] = field(default_factory=dict)
    slots: list[int] = field(default_factory=list)  # which episode slot each row belongs to

    def __len__(self) -> int:
        return len(self.state)


@dataclass
class PolicyOutput:
    """(B, T, 8) actions; ``errors[i]`` is a message when row i could not be served (that episode
    fails); ``latency_s[i]`` the wall time of row i's request and ``servers[i]`` who served it
    (server policies; otherwise the driver times ``act`` itself)."""

    actions: np.ndarray
    errors: list[str | None] | None = None
    latency_s: list[float] | None = None
    servers: list[str] | None = None


class PolicyError(RuntimeError):
    """The policy cannot serve an episode (e.g. its server stayed down); the episode is recorded as failed."""


class Policy:
    """Base class; subclasses set ``name`` and implement ``act`` (or ``bind_env_policy`` if env-side)."""

    name: str = "policy"
    env_side: bool = False  # privileged: runs next to the env instead of from observations
    chunk: int = 8  # native chunk length T

    def obs_request(self) -> ObsRequest:
        return ObsRequest()

    def reset(self, slots: list[int]) -> None:
        """New episodes start in ``slots`` (clear per-episode state such as action queues)."""

    def act(self, batch: PolicyInput) -> PolicyOutput:
        raise NotImplementedError

    def bind_env_policy(self, env):
        """Env-side policies: an object with ``reset()`` and ``act(obs) -> (num_envs, 8)``."""
        raise NotImplementedError(f"{self.name} is not an env-side policy")

    def spec(self) -> str:
        """A string that rebuilds this policy with ``make_policy`` (for workers and Ray shards)."""
        return self.name

    def close(self) -> None:
        pass
