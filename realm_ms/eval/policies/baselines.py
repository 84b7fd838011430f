"""Observation-free baselines: ``zero`` (hold the current joints) and ``random`` (bounded random walk).

``zero`` is "zero motion", not the all-zeros joint vector (that would drive the arm to a singular
upright pose): it holds the current joints and gripper, so it measures what the scene does on its
own (and is the throughput bench's policy).

Both plan joint targets and emit them in the env's DROID action space (``action_space`` option,
``realm eval --action-space``): a chunk of targets becomes the actions that ask for each target from
the one before it (``DroidActionSpace.from_joint_target``), so under ``joint_velocity`` ``zero`` is
a zero velocity, never an absolute target read as a velocity.
"""

from __future__ import annotations

import numpy as np

from realm_ms.agents.droid_action_spaces import (DroidActionSpace, DroidIK, make_action_space, parse_action_space_flag,
                                                 space_of_keywords)
from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.policy import Policy, PolicyInput, PolicyOutput

# droid_joint_pos bounds (Panda joint limits + gripper [0, 1])
Q_LOW = np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973, 0.0], dtype=np.float32)
Q_HIGH = np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973, 1.0], dtype=np.float32)


def space_of(action_space: str | None) -> DroidActionSpace:
    """The DROID action space of ``SPACE[:GRIPPER]`` (None = joint_position); ValueError if unknown."""
    try:
        return space_of_keywords(parse_action_space_flag(action_space))
    except ValueError as e:
        raise ValueError(f"--action-space: {e}") from None


class BaselinePolicy(Policy):
    """Joint-target chunks (``targets``), emitted in ``space``."""

    def __init__(self, space: DroidActionSpace | None = None):
        self.space = space or make_action_space()
        self.ik = DroidIK() if self.space.action_space.startswith("cartesian") else None

    def targets(self, batch: PolicyInput) -> np.ndarray:
        raise NotImplementedError

    def act(self, batch: PolicyInput) -> PolicyOutput:
        t = np.clip(self.targets(batch), Q_LOW, Q_HIGH).astype(np.float64)  # (B, T, 8)
        if self.space == make_action_space():
            return PolicyOutput(t.astype(np.float32))
        # step k asks for target k from target k-1 (the controller tracks them; step 0 from the state)
        b, n = t.shape[:2]
        prev = np.concatenate([batch.state[:, None, :].astype(np.float64), t[:, :-1]], 1)
        a = self.space.from_joint_target(t.reshape(-1, 8), prev[..., :7].reshape(-1, 7), prev[..., 7].reshape(-1), self.ik)
        lo, hi = self.space.bounds()
        return PolicyOutput(np.clip(a.reshape(b, n, -1), lo, hi).astype(np.float32))


class ZeroPolicy(BaselinePolicy):
    name = "zero"

    def targets(self, batch: PolicyInput) -> np.ndarray:
        return np.repeat(batch.state[:, None, :], self.chunk, axis=1)


class RandomPolicy(BaselinePolicy):
    """Random walk of the joint targets (``step`` rad per control step), random gripper per chunk."""

    name = "random"

    def __init__(self, seed: int = 0, step: float = 0.05, space: DroidActionSpace | None = None):
        super().__init__(space)
        self.rng = np.random.default_rng(seed)
        self.step = step

    def targets(self, batch: PolicyInput) -> np.ndarray:
        b = len(batch)
        d = self.rng.uniform(-self.step, self.step, size=(b, self.chunk, 7)).cumsum(axis=1)
        q = batch.state[:, None, :7] + d
        g = np.repeat(self.rng.integers(0, 2, size=(b, 1, 1)), self.chunk, axis=1)
        return np.concatenate([q, g], -1)

    def spec(self) -> str:
        return "random"


POLICIES.register("zero", lambda arg, **kw: ZeroPolicy(space_of(kw.get("action_space"))))
POLICIES.register("random", lambda arg, **kw: RandomPolicy(seed=int(arg) if arg else int(kw.get("seed", 0)),
                                                           space=space_of(kw.get("action_space"))))
