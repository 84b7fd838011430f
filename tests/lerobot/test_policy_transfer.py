"""A checkpoint that `lerobot-train` wrote from a `realm export` reaches the env unchanged.

`make test` runs the fast check first: a LeRobot checkpoint whose network is made to emit the
demo's actions (normalised as its saved processors expect) replays the demo through `realm export
--policy lerobot:CKPT`, so the adapter's state and action layout, its post-processing and the
gripper convention are the export's. The overfit run below (`make test-slow`, ~6 min of CPU) adds
a checkpoint that `lerobot-train` really wrote:

One expert demonstration of PushSwitch (the expert closes the gripper at once, then reaches and
presses, so both the seven joints and the gripper move) is exported, a small ACT is overfit to it
with LeRobot's `lerobot-train` (run through `realm_ms.lerobot.train`, which decodes each video once:
600 steps of batch 8 end ~0.06 rad from the demo, half the check's margin), and the checkpoint is
run from the demo's seed:

- through `realm export --policy lerobot:CKPT` (the `lerobot:` policy of `realm eval`; the exports run
  in the test's process, the training in a child): the joint
  trajectory replays the demo's and the gripper closes as in the demo (a joint-order or gripper-
  convention error makes either fail);
- through LeRobot's own `lerobot-eval --env.type=realm`: same features as the export and the episode
  succeeds.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TASK, SEED, W, H = "REALM-PushSwitch-v1", 3, 32, 24


def _run(cmd: list[str]) -> None:
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    p = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    assert p.returncode == 0, f"{cmd[:3]} failed ({p.returncode}):\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"


def _export(out: Path, *extra: str, max_steps: int = 120) -> None:
    """`realm export` in this process (the recipe's test runs the installed script): the test
    worker's renderer and imports serve both exports."""
    from realm_ms.cli import main

    assert main(["export", "--tasks", TASK, "--episodes", "1", "--seed", str(SEED), "--width", str(W), "--height", str(H),
                 "--max-steps", str(max_steps), "--out", str(out), "--repo-id", f"realm/{out.name}", "--no-progress",
                 *extra]) == 0


def _episode(root: Path) -> tuple[np.ndarray, np.ndarray, dict]:
    import pandas as pd

    df = pd.concat(pd.read_parquet(f) for f in sorted((root / "data").rglob("*.parquet")))
    side = json.loads((root / "meta" / "realm_episodes.jsonl").read_text().splitlines()[0])
    return np.stack(df["observation.state"].values), np.stack(df["action"].values), side


@pytest.fixture(scope="module")
def demo(tmp_path_factory) -> Path:
    """One successful expert episode of PushSwitch, exported; it closes the gripper."""
    out = tmp_path_factory.mktemp("transfer") / "demo"
    _export(out, "--success-only")
    _, a_demo, side = _episode(out)
    assert side["success"] and a_demo[:, 7].max() > 0.5
    return out


def test_a_checkpoint_that_emits_the_demos_actions_replays_the_demo(demo, tmp_path, monkeypatch):
    import torch
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.policies.act.modeling_act import ACTPolicy
    from lerobot.policies.factory import make_pre_post_processors

    from realm_ms.eval.policies.lerobot import make_tiny_policy

    s_demo, a_demo, _ = _episode(demo)
    ckpt = make_tiny_policy(tmp_path / "ckpt", image_size=(H, W))
    # the saved post-processor is affine per dimension: action = mean + std * output
    _, post = make_pre_post_processors(PreTrainedConfig.from_pretrained(ckpt), pretrained_path=str(ckpt))
    mean, one = (post(torch.full((1, 8), float(v))).numpy()[0] for v in (0.0, 1.0))
    std = one - mean
    calls = []

    def emit_demo(self, obs):  # each call is the next chunk of the demo (replan_every = chunk = 8)
        t = 8 * len(calls)
        calls.append(obs["observation.state"].shape)
        idx = np.minimum(np.arange(t, t + 8), len(a_demo) - 1)
        return torch.from_numpy(((a_demo[idx] - mean) / std).astype(np.float32))[None]

    monkeypatch.setattr(ACTPolicy, "predict_action_chunk", emit_demo)
    monkeypatch.setattr(ACTPolicy, "reset", lambda self: calls.clear())
    replay = tmp_path / "replay"
    _export(replay, "--policy", f"lerobot:{ckpt}", max_steps=len(s_demo))
    s_rep, a_rep, side_rep = _episode(replay)
    assert calls and calls[0] == (1, 8) and side_rep["policy"] == f"lerobot:{ckpt}" and side_rep["success"]
    n = len(s_rep)
    assert n >= len(s_demo) - 5
    # the actions reach the env as the export stored them, and the arm and gripper follow the demo
    np.testing.assert_allclose(a_rep[:n], a_demo[:n], atol=1e-4)
    travel = np.abs(s_demo[:, :7] - s_demo[0, :7]).max()
    # float32 normalisation round-off (~1e-5 rad in the targets) grows to ~2 mrad through the press;
    # a joint-order or gripper-convention error puts a joint ~1 rad off
    assert travel > 0.3 and np.abs(s_rep[:, :8] - s_demo[:n, :8]).max() < 1e-2


@pytest.fixture(scope="module")
def overfit(demo):
    root = demo.parent
    run = root / "train"
    # realm_ms.lerobot.train is LeRobot's lerobot-train with each video decoded once (the recipe's trainer)
    _run([sys.executable, "-m", "realm_ms.lerobot.train", "--dataset.repo_id=realm/demo", f"--dataset.root={demo}",
          "--dataset.video_backend=pyav", "--policy.type=act", "--policy.device=cpu", "--policy.push_to_hub=false",
          "--policy.pretrained_backbone_weights=null", "--policy.dim_model=64", "--policy.n_heads=2",
          "--policy.dim_feedforward=128", "--policy.n_encoder_layers=1", "--policy.n_decoder_layers=1",
          "--policy.use_vae=false", "--policy.dropout=0", "--policy.chunk_size=8", "--policy.n_action_steps=8",
          "--policy.optimizer_lr=5e-4", "--policy.optimizer_lr_backbone=5e-4", "--steps=600", "--batch_size=8",
          "--num_workers=0", "--save_freq=600", "--log_freq=100", f"--output_dir={run}", "--wandb.enable=false"])
    return root, demo, run / "checkpoints" / "last" / "pretrained_model"


@pytest.mark.slow
def test_checkpoint_features_are_the_export_and_env_features(overfit):
    from lerobot.envs.factory import make_env_config
    from lerobot.envs.utils import env_to_policy_features

    import lerobot_env_realm  # noqa: F401

    _, demo, ckpt = overfit
    cfg = json.loads((ckpt / "config.json").read_text())
    trained = {k: tuple(v["shape"]) for k, v in {**cfg["input_features"], **cfg["output_features"]}.items()}
    env_side = env_to_policy_features(make_env_config("realm", task=TASK, observation_width=W, observation_height=H))
    assert trained == {k: tuple(f.shape) for k, f in env_side.items()}
    info = json.loads((demo / "meta" / "info.json").read_text())
    assert set(trained) <= set(info["features"])


@pytest.mark.slow
def test_overfit_policy_replays_the_demo_through_lerobot_policy(overfit):
    root, demo, ckpt = overfit
    s_demo = _episode(demo)[0]
    replay = root / "replay"
    _export(replay, "--policy", f"lerobot:{ckpt}", max_steps=len(s_demo))
    s_rep, _, side_rep = _episode(replay)
    assert side_rep["policy"] == f"lerobot:{ckpt}" and side_rep["success"]
    n = len(s_rep)  # the replay may end a step or two early: an episode stops on success
    assert n >= len(s_demo) - 5
    s_demo = s_demo[:n]
    travel = np.abs(s_demo[:, :7] - s_demo[0, :7]).max()
    err = np.abs(s_rep[:, :7] - s_demo[:, :7]).max(axis=0)
    # a wrong joint order would put the joints ~1 rad or more off
    assert travel > 0.3 and err.max() < 0.1 * travel, f"joint error {err.round(3)} vs demo travel {travel:.2f} rad"
    # gripper position in [0, 1], 1 = closed: it closes as the demo's does
    assert np.abs(s_rep[:, 7] - s_demo[:, 7]).max() < 0.15 and s_rep[-1, 7] > 0.8


@pytest.mark.slow
def test_lerobot_eval_runs_the_checkpoint_to_success(overfit, tmp_path, monkeypatch):
    from lerobot.scripts import lerobot_eval

    _, demo, ckpt = overfit
    steps = len(_episode(demo)[0])
    out = tmp_path / "eval"
    monkeypatch.setattr(sys, "argv", [
        "lerobot-eval", "--env.discover_packages_path=lerobot_env_realm", "--env.type=realm", f"--env.task={TASK}",
        f"--env.episode_length={steps + 20}", f"--env.observation_width={W}", f"--env.observation_height={H}",
        f"--policy.path={ckpt}", "--policy.device=cpu", "--eval.n_episodes=1", "--eval.batch_size=1",
        f"--seed={SEED}", f"--output_dir={out}"])
    lerobot_eval.eval_main()
    info = json.loads((out / "eval_info.json").read_text())
    assert info["overall"]["n_episodes"] == 1 and info["overall"]["pc_success"] == 100.0
