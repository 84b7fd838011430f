"""Observation-free baselines: ``zero`` (hold the current joints) and ``random`` (bounded random walk).

``zero`` is "zero motion", not the all-zeros joint vector (that would drive the arm to a singular
upright pose): it repeats the current joint positions and gripper, so it measures what the scene
does on its own (and is the throughput bench's policy).
"""

from __future__ import annotations

import numpy as np

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.policy import Policy, PolicyInput, PolicyOutput

# droid_joint_pos bounds (Panda joint limits + gripper [0, 1])
Q_LOW = np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973, 0.0], dtype=np.float32)
Q_HIGH = np.array([2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973, 1.0], dtype=np.float32)


class ZeroPolicy(Policy):
    name = "zero"

    def act(self, batch: PolicyInput) -> PolicyOutput:
        a = np.repeat(batch.state[:, None, :].astype(np.float32), self.chunk, axis=1)
        return PolicyOutput(np.clip(a, Q_LOW, Q_HIGH))


class RandomPolicy(Policy):
    """Random walk of the joint targets (``step`` rad per control step), random gripper per chunk."""

    name = "random"

    def __init__(self, seed: int = 0, step: float = 0.05):
        self.rng = np.random.default_rng(seed)
        self.step = step

    def act(self, batch: PolicyInput) -> PolicyOutput:
        b = len(batch)
        d = self.rng.uniform(-self.step, self.step, size=(b, self.chunk, 7)).cumsum(axis=1)
        q = batch.state[:, None, :7] + d
        g = np.repeat(self.rng.integers(0, 2, size=(b, 1, 1)), self.chunk, axis=1).astype(np.float32)
        return PolicyOutput(np.clip(np.concatenate([q, g], -1).astype(np.float32), Q_LOW, Q_HIGH))

    def spec(self) -> str:
        return "random"


POLICIES.register("zero", lambda arg, **kw: ZeroPolicy())
POLICIES.register("random", lambda arg, **kw: RandomPolicy(seed=int(arg) if arg else int(kw.get("seed", 0))))
