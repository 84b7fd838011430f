"""The ``realm`` LeRobot env type: registration, feature contract with exports, and ``lerobot-eval``.

Runs LeRobot's own eval entry point in-process (``lerobot_eval.eval_main`` parsing a command line
with ``--env.discover_packages_path=lerobot_env_realm``) on a tiny randomly initialised ACT policy
for one short episode.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

W, H = 64, 48


def test_realm_env_type_registered_with_export_features():
    import lerobot_env_realm
    from lerobot.envs.configs import EnvConfig
    from lerobot.envs.factory import make_env_config
    from lerobot.envs.utils import env_to_policy_features

    from realm_ms.lerobot.features import dataset_features

    assert EnvConfig.get_choice_class("realm") is lerobot_env_realm.RealmEnvConfig
    cfg = make_env_config("realm", task="REALM-PickApple-v1", observation_width=W, observation_height=H)
    policy_feats = env_to_policy_features(cfg)
    ds = dataset_features(W, H)
    # every policy-facing key of an export (observation.* and action) is what the env provides
    wanted = {k for k in ds if k.startswith("observation.") or k == "action"}
    assert set(policy_feats) == wanted
    for k, ft in policy_feats.items():
        shape = ds[k]["shape"]
        assert tuple(ft.shape) == ((shape[2], shape[0], shape[1]) if len(shape) == 3 else tuple(shape))


def test_vector_env_observations_match_lerobot_preprocessing():
    from lerobot.envs.factory import make_env, make_env_config
    from lerobot.envs.utils import preprocess_observation

    import lerobot_env_realm  # noqa: F401

    cfg = make_env_config("realm", task="REALM-PushSwitch-v1", observation_width=W, observation_height=H, episode_length=3)
    envs = make_env(cfg, n_envs=1, use_async_envs=False)
    vec = envs["REALM-PushSwitch-v1"][0]
    try:
        obs, info = vec.reset(seed=[5])
        assert vec.observation_space["pixels"]["wrist_left"].shape == (1, H, W, 3)
        batch = preprocess_observation(obs)
        assert batch["observation.images.exterior_1_left"].shape == (1, 3, H, W)
        assert batch["observation.state"].shape == (1, 8)
        assert list(vec.call("task_description")) == ["push the light switch"]
        assert vec.call("_max_episode_steps")[0] == 3
        a = np.repeat(batch["observation.state"].numpy(), 1, 0)  # hold the current joints
        for _ in range(3):
            obs, reward, term, trunc, info = vec.step(a)
        assert bool(trunc[0]) and "is_success" in info
        assert vec.call("render")[0].shape == (H, 3 * W, 3)
    finally:
        vec.close()


def _tiny_act(path):
    import torch
    from lerobot.configs import FeatureType, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy
    from lerobot.policies.factory import make_pre_post_processors

    from realm_ms.lerobot.features import CAMERAS, image_key

    inputs = {"observation.state": PolicyFeature(FeatureType.STATE, (8,))}
    inputs |= {image_key(c): PolicyFeature(FeatureType.VISUAL, (3, H, W)) for c in CAMERAS}
    cfg = ACTConfig(
        input_features=inputs, output_features={"action": PolicyFeature(FeatureType.ACTION, (8,))},
        pretrained_backbone_weights=None, dim_model=16, n_heads=2, dim_feedforward=32, n_encoder_layers=1,
        n_decoder_layers=1, n_vae_encoder_layers=1, chunk_size=4, n_action_steps=4, device="cpu",
    )
    torch.manual_seed(0)
    ACTPolicy(cfg).save_pretrained(path)
    pre, post = make_pre_post_processors(cfg, dataset_stats=None)
    pre.save_pretrained(path)
    post.save_pretrained(path)


def test_lerobot_eval_runs_realm_env(tmp_path, monkeypatch):
    from lerobot.scripts import lerobot_eval

    pol = tmp_path / "policy"
    _tiny_act(pol)
    out = tmp_path / "eval"
    argv = [
        "lerobot-eval", "--env.discover_packages_path=lerobot_env_realm", "--env.type=realm",
        "--env.task=REALM-PickApple-v1", "--env.episode_length=6", f"--env.observation_width={W}",
        f"--env.observation_height={H}", f"--policy.path={pol}", "--policy.device=cpu",
        "--eval.n_episodes=1", "--eval.batch_size=1", f"--output_dir={out}",
    ]
    monkeypatch.setattr(sys, "argv", argv)
    lerobot_eval.eval_main()
    info = json.loads((out / "eval_info.json").read_text())
    assert info["overall"]["n_episodes"] == 1
    assert 0.0 <= info["overall"]["pc_success"] <= 100.0
    video = info["overall"]["video_paths"][0]
    assert video.endswith(".mp4") and (out / "videos").exists()


def test_unknown_task_is_a_clear_error():
    from lerobot.envs.factory import make_env, make_env_config

    import lerobot_env_realm  # noqa: F401

    with pytest.raises(ValueError, match="unknown REALM task"):
        make_env(make_env_config("realm", task="REALM-Nope-v1"), n_envs=1)


def test_success_reaches_lerobot_through_final_info():
    """The scripted expert driving the vector env: LeRobot's rollout reads success from final_info."""
    from lerobot.envs.factory import make_env, make_env_config

    import lerobot_env_realm  # noqa: F401
    from realm_ms.expert import make_expert

    cfg = make_env_config("realm", task="REALM-PushSwitch-v1", observation_width=32, observation_height=24, episode_length=150)
    vec = make_env(cfg, n_envs=1, use_async_envs=False)["REALM-PushSwitch-v1"][0]
    try:
        vec.reset(seed=[0])
        expert = make_expert(vec.envs[0]._env)
        for _ in range(150):
            _, _, term, trunc, info = vec.step(expert.act(None).cpu().numpy())
            if term[0] or trunc[0]:
                break
        assert bool(term[0]) and bool(info["final_info"]["is_success"][0])
    finally:
        vec.close()


def test_robot_model_reaches_the_env():
    """``--env.robot_model droid-aligned``: the env LeRobot builds runs the aligned robot, not the nominal one."""
    from lerobot.envs.factory import make_env, make_env_config

    import lerobot_env_realm  # noqa: F401
    from realm_ms.agents.robot_model import load_robot_model

    cfg = make_env_config("realm", task="REALM-PushSwitch-v1", observation_width=32, observation_height=24,
                          episode_length=5, robot_model="droid-aligned")
    vec = make_env(cfg, n_envs=1, use_async_envs=False)["REALM-PushSwitch-v1"][0]
    try:
        vec.reset(seed=[0])
        env = vec.envs[0]._env.unwrapped
        assert env.robot_model is not None
        assert env.robot_model.names == load_robot_model("droid-aligned").names
        assert env.config.robot_model == "droid-aligned"
    finally:
        vec.close()
