"""One way to build an env: a ``realm eval`` record stores its env's ``RealmEnvConfig``, and
``make_env(RealmEnvConfig.from_dict(record["config"]))`` builds the same env, in which the episode
replays bit for bit."""

from __future__ import annotations

import json

import pytest

TASK, PERTURBATION, SEED, STEPS = "REALM-PickApple-v1", "VB-POSE", 3, 40


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS

    run = tmp_path_factory.mktemp("run")
    proto = PRESETS["quick"].with_overrides(episodes=1, max_steps=STEPS, seed=SEED)
    evaluate("expert", [TASK], [PERTURBATION], proto, run, workers=1, backend="cpu", progress=False, quiet=True)
    recs = [json.loads(line) for line in (run / "records.jsonl").read_text().splitlines()]
    assert len(recs) == 1 and recs[0]["status"] == "ok", recs
    return recs[0]


def test_record_holds_the_config_it_ran(record):
    from realm_ms.tasks.config import RealmEnvConfig

    cfg = RealmEnvConfig.from_dict(record["config"])
    assert (cfg.task, cfg.perturbation, cfg.horizon) == (TASK, PERTURBATION, STEPS)
    assert cfg.to_dict() == record["config"]  # JSON round trip is exact


def test_env_from_the_record_replays_the_episode_bit_for_bit(record):
    import numpy as np

    from realm_ms.eval.quality import TrajectoryQuality
    from realm_ms.expert.core import run_episode
    from realm_ms.tasks.config import RealmEnvConfig, make_env

    env = make_env(RealmEnvConfig.from_dict(record["config"]))
    try:
        quality = None

        def on_step(env, obs, info):
            quality.update()

        env.reset(seed=record["seed"])
        quality = TrajectoryQuality(env)
        res = run_episode(env, seed=record["seed"], max_steps=STEPS, on_step=on_step)
        assert env.unwrapped.perturbations.record()["params"] == record["perturbation_params"]["params"]
    finally:
        env.close()
    assert (res["steps"], res["success"]) == (record["steps"], record["success"])
    assert res["progression"] == pytest.approx(record["progression"], abs=1e-6)
    summary = json.loads(json.dumps(quality.summary()))
    for key, value in record["quality"].items():  # path lengths, jerk, contacts: the trajectory itself
        if isinstance(value, float):
            assert np.float64(summary[key]) == pytest.approx(value, rel=0, abs=1e-9), key
        else:
            assert summary[key] == value, key
