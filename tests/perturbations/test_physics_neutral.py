"""Perturbations that act only on what a policy sees or reads (images, cameras, lights, instruction)
leave the simulated world bit-identical: the privileged expert's trajectory under each equals
Default's with the same seed. This is why the expert bench's result for Default carries over to
them, and a regression here means a perturbation leaks into physics (REALM's compounding bugs)."""

from __future__ import annotations

import pytest
import torch

gym = pytest.importorskip("gymnasium")

import realm_ms  # noqa: E402,F401
from realm_ms.expert.core import make_expert  # noqa: E402

STEPS = 40
# perturbation -> a task it is checked on (cycling through skills: pick, push, drawer, rotate, stack)
NEUTRAL = {
    "V-AUG": "REALM-PickApple-v1",
    "V-VIEW": "REALM-OpenDrawer-v1",
    "V-LIGHT": "REALM-PushSwitch-v1",
    "S-PROP": "REALM-PutBananaInBox-v1",
    "S-LANG": "REALM-CloseDrawer-v1",
    "S-MO": "REALM-RotateMug-v1",
    "S-AFF": "REALM-StackCubes-v1",
    "S-INT": "REALM-PickWaterBottle-v1",
}


def trajectory(task: str, perturbation: str, seed: int) -> torch.Tensor:
    env = gym.make(task, obs_mode="state", perturbation=perturbation)
    try:
        obs, _ = env.reset(seed=seed)
        expert = make_expert(env.unwrapped)
        states = [obs.clone()]
        for _ in range(STEPS):
            obs, *_ = env.step(expert.act(obs))
            states.append(obs.clone())
        return torch.stack(states)
    finally:
        env.close()


@pytest.mark.parametrize("name", sorted(NEUTRAL))
def test_observation_side_perturbation_leaves_physics_identical(name):
    task, seed = NEUTRAL[name], 5
    a, b = trajectory(task, "Default", seed), trajectory(task, name, seed)
    diff = (a - b).abs().flatten(1).amax(1)
    assert torch.equal(a, b), f"{name} on {task}: state differs from Default from step {int(torch.nonzero(diff)[0])}, max {float(diff.max()):.3g}"
