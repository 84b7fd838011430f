"""Open-loop chunks capture camera images only where the policy looks: at the chunk's last step.

The images the policy receives must be exactly those of capturing every step; only the number of
captures may change (rendering dominates a step with cameras).
"""

import numpy as np
import pytest
from mani_skill.envs.sapien_env import BaseEnv

from realm_ms.eval.policies.policy import ObsRequest
from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.runner import RunConfig
from realm_ms.eval.slots import EpisodeRunner

TASK, CHUNK, CHUNKS = "REALM-PickApple-v1", 4, 3


@pytest.fixture
def captures(monkeypatch):
    calls = []
    original = BaseEnv._get_obs_sensor_data

    def counting(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(BaseEnv, "_get_obs_sensor_data", counting)
    return calls


def rollout(videos: str, tmp_path) -> list[dict]:
    cfg = RunConfig(policy="zero", max_steps=100, replan_every=CHUNK, videos=videos, videos_dir=str(tmp_path),
                    obs=ObsRequest(cameras=("exterior_1", "wrist"), width=64, height=36), quality=False)
    runner = EpisodeRunner(cfg)
    try:
        obs = [runner.start(EpisodeKey(TASK, "Default", 3))]
        rng = np.random.default_rng(0)
        home = obs[0]["state"][:7].astype(np.float32)
        for _ in range(CHUNKS):  # a moving arm, so that every captured frame differs
            chunk = np.concatenate([home + rng.uniform(-0.15, 0.15, (CHUNK, 7)).astype(np.float32), np.zeros((CHUNK, 1), np.float32)], 1)
            o, rec = runner.step(chunk)
            assert rec is None
            obs.append(o)
        return obs
    finally:
        runner.close()


def test_sparse_capture_gives_the_policy_the_same_images(tmp_path, captures):
    dense = rollout("all", tmp_path / "dense")  # every frame goes into a video: capture every step
    n_dense = len(captures)
    captures.clear()
    sparse = rollout("none", tmp_path / "sparse")
    n_sparse = len(captures)
    # the reset's captures are the same in both; each chunk then captures once instead of CHUNK times
    assert n_dense - n_sparse == CHUNKS * (CHUNK - 1), (n_dense, n_sparse)
    for d, s in zip(dense, sparse):
        np.testing.assert_array_equal(d["state"], s["state"])
        for cam in ("exterior_1", "wrist"):
            np.testing.assert_array_equal(d["images"][cam], s["images"][cam])
    assert not np.array_equal(dense[1]["images"]["wrist"], dense[2]["images"]["wrist"])  # the frames are live


def test_env_returns_the_last_capture_while_capture_is_off():
    import gymnasium as gym

    env = gym.make(TASK, obs_mode="rgb", camera_width=32, camera_height=18)
    try:
        obs, _ = env.reset(seed=0)
        u = env.unwrapped
        action = u.agent.droid_state()[:, :8].clone()
        u.capture_sensors = False
        held, *_ = env.step(action)
        assert held["sensor_data"] is obs["sensor_data"]  # no capture: the last one
        u.capture_sensors = True
        fresh, *_ = env.step(action)
        assert fresh["sensor_data"] is not obs["sensor_data"]
        u.capture_sensors = False
        env.reset(seed=1)  # a reset always captures, whatever the flag says
        after, *_ = env.step(action)
        assert after["sensor_data"] is not fresh["sensor_data"]
    finally:
        env.close()
