"""Export's chunked policies: a reply is checked as ``realm eval`` checks it (shape, numbers, finite,
bounds) and a bad one fails the episode with the policy's name, never reaches the dataset."""

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from realm_ms.eval.policies.policy import ObsRequest, PolicyError, PolicyOutput
from realm_ms.lerobot.rollout import ChunkedPolicy

HOME = [0.0, -0.63, 0.0, -2.5, 0.0, 1.9, 0.0, 0.0]


class Fixed:
    name = "fixed"

    def __init__(self, actions):
        self.actions = actions

    def obs_request(self):
        return ObsRequest(cameras=("wrist",))

    def act(self, batch):
        assert batch.state.shape == (1, 8) and set(batch.images) == {"wrist"}
        return PolicyOutput(actions=self.actions)


def _chunk(actions, replan_every=8):
    env = SimpleNamespace(get_language_instruction=lambda: ["pick the apple"])
    env.unwrapped = env
    obs = {"agent": {"droid_state": torch.zeros(1, 8)}, "sensor_data": {"wrist": {"rgb": torch.zeros(1, 4, 4, 3)}}}
    return ChunkedPolicy(Fixed(actions), env, replan_every).chunk(obs)


def test_a_good_chunk_is_cut_to_replan_every():
    chunk = _chunk(np.tile(np.array(HOME, np.float32), (1, 10, 1)), replan_every=4)
    assert chunk.shape == (4, 8) and chunk.dtype == np.float32
    assert np.allclose(chunk[0], HOME)


@pytest.mark.parametrize("actions, why", [
    (np.full((1, 3, 8), np.nan), "NaN"),
    (np.zeros((1, 0, 8)), "empty action chunk"),
    (np.zeros((1, 3, 7)), r"shape \(1, 3, 7\)"),
    (np.array([[["a"] * 8]]), "shape"),
    (np.tile(np.array(HOME) + [0, 0, 0, 0, 0, 0, 50.0, 0], (1, 2, 1)), "fixed"),
])
def test_a_bad_reply_fails_the_episode_naming_the_policy(actions, why):
    with pytest.raises(PolicyError, match=why) as e:
        _chunk(actions)
    assert "fixed" in str(e.value)
