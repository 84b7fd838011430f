"""--policy-latency: the arm holds its previous joint target for the policy's latency before each
chunk; a fixed latency and the same latency measured give the same records."""

import numpy as np
import pytest

from realm_ms.eval.latency import hold_steps, latency_summary, parse_latency
from realm_ms.eval.policies.roboarena_server import RoboArenaServer


def test_the_rounding_rule():
    assert [hold_steps("0.3", 0), hold_steps("measured", 0.3), hold_steps("measured", 0.366)] == [5, 5, 5]  # 4.5 .. 5.49 steps
    assert hold_steps("measured", 0.367) == 6 and hold_steps("0.25", 9.0) == 4 and hold_steps("0.2", 0) == 3
    assert hold_steps("0", 1.0) == 0 and hold_steps("measured", 0.0) == 0 and hold_steps("measured", 0.033) == 0


@pytest.mark.parametrize("text, want", [("0", "0"), ("-0", "0"), ("0.0", "0"), ("0.30", "0.3"), ("measured", "measured"), (" Measured ", "measured"), (0.25, "0.25")])
def test_settings(text, want):
    assert parse_latency(text) == want


@pytest.mark.parametrize("text, match", [("-0.1", "must be >= 0"), ("nan", "finite"), ("fast", "expected a single number"),
                                         ("120", "more than 60 s"), ("inf", "finite")])
def test_bad_settings(text, match):
    with pytest.raises(ValueError, match=match):
        parse_latency(text)


def test_summary_per_server():
    recs = [dict(status="ok", policy_latency="measured", latency_s={"a:1": [0.1, 0.2, 0.3]}),
            dict(status="ok", policy_latency="measured", latency_s={"a:1": [0.4], "b:2": [1.0]})]
    s = latency_summary(recs)
    assert s["settings"] == ["measured"] and s["servers"]["a:1"] == dict(requests=4, median_s=0.25, p95_s=0.385)
    assert s["servers"]["b:2"]["requests"] == 1


class _Reach:
    """Reaches for a joint-0 goal from the joints it is shown: what it answers depends on how stale
    its observation is. ``sleep``: seconds of "inference"."""

    def __init__(self, sleep: float = 0.0):
        self.sleep = sleep

    def infer(self, obs):
        import time

        time.sleep(self.sleep)
        q = np.asarray(obs["observation/joint_position"], np.float64)
        steps = np.arange(1, 9)[:, None]
        target = np.tile(q, (8, 1))
        target[:, 0] = q[0] + np.clip(0.8 - q[0], -0.05, 0.05) * steps[:, 0]
        return np.concatenate([target, np.zeros((8, 1))], axis=1)


def _run(tmp_path, name, sleep, latency):
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS
    from realm_ms.eval.records import read_records

    with RoboArenaServer(_Reach(sleep), dict(needs_wrist_camera=False, n_external_cameras=0)) as srv:
        proto = PRESETS["realm"].with_overrides(episodes=1, seed=0, max_steps=30, replan_every=8)
        code = evaluate(f"roboarena:{srv.address}", ["REALM-PickApple-v1"], ["Default"], proto, tmp_path / name, workers=1, backend="cpu",
                        camera_size=(64, 36), quality=True, progress=False, quiet=True, policy_latency=latency)
        requests = srv.requests
    assert code == 0
    (rec,) = read_records(tmp_path / name / "records.jsonl")
    return rec, requests


def _same(rec):
    return {k: v for k, v in rec.items() if k not in ("wall_s", "latency_s", "policy_latency", "fingerprint", "policy")}


def test_a_fixed_latency_and_the_same_latency_measured_give_the_same_records(tmp_path):
    fixed, n_fixed = _run(tmp_path, "fixed", 0.0, "0.3")
    measured, n_measured = _run(tmp_path, "measured", 0.3, "measured")
    none, n_none = _run(tmp_path, "none", 0.0, "0")
    assert fixed["policy_latency"] == "0.3" and measured["policy_latency"] == "measured"
    (lat,) = measured["latency_s"].values()
    assert all(0.3 <= x < 0.3 + 1 / 15 for x in lat), lat  # the tolerance of the rounding rule: up to 66 ms of overhead
    assert _same(fixed) == _same(measured) and n_fixed == n_measured == 3  # 30 steps = 5 held + 8, twice, then 4 of 5 held
    # time stopping during inference is another robot: more chunks fit in the episode and the arm moves further
    assert n_none == 4 and none["quality"]["joint_path_length"] > fixed["quality"]["joint_path_length"] * 1.2
    # another latency is another run: the same --out refuses it instead of mixing records
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS

    with RoboArenaServer(_Reach(0.0), dict(needs_wrist_camera=False, n_external_cameras=0)) as srv:
        proto = PRESETS["realm"].with_overrides(episodes=1, seed=0, max_steps=30, replan_every=8)
        with pytest.raises(ValueError, match="policy_latency 0.3 vs 0.25"):
            evaluate(f"roboarena:{srv.address}", ["REALM-PickApple-v1"], ["Default"], proto, tmp_path / "fixed", workers=1, backend="cpu",
                     camera_size=(64, 36), progress=False, quiet=True, policy_latency="0.25")


def test_the_hold_tracks_the_previous_target_in_velocity_space():
    """joint_velocity: during the hold the arm settles on the last target the velocity asked for; it
    does not keep moving at the last velocity."""
    import gymnasium as gym

    import realm_ms  # noqa: F401
    from realm_ms.agents.droid_action_spaces import joint_velocity_to_delta
    from realm_ms.tasks.episode import Episode, EpisodeEngine

    env = gym.make("REALM-PickApple-v1", obs_mode="state", action_space="joint_velocity", gripper_action_space="position")
    engine = EpisodeEngine(env)
    engine.reset({0: Episode(seed=0, max_steps=100)})
    u = env.unwrapped
    v = np.zeros((8, 8), np.float32)
    v[:, 0] = 0.5
    step = joint_velocity_to_delta(np.full(7, 0.5))[0]  # rad per step at v = 0.5
    engine.run(7, {0: v[:7]})
    target = u.agent.droid_state()[0, 0].item() + step  # the last step's target: from the state before it
    engine.run(1, {0: v[:1]})
    q_moving = u.agent.droid_state()[0, 0].item()
    engine.run(1, {0: np.zeros((1, 8), np.float32)}, delays={0: 12})
    q_after = u.agent.droid_state()[0, 0].item()
    # settled on that target (the arm lags it while moving), not 12 steps of velocity further
    assert abs(q_after - target) < 0.1 * step and q_moving < target - 0.3 * step, (q_moving, q_after, target)
    assert engine.episodes[0].steps == 8 + 12 + 1
    env.close()


def test_realm_eval_with_two_workers_and_the_installed_report(tmp_path, capsys):
    """The path a user types: ``realm eval --policy roboarena:... --policy-latency 0.3 --workers 2``,
    then ``realm eval report``: records, metrics and the report's header state the latency."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    from realm_ms.cli import main

    realm = str(Path(sys.executable).parent / "realm")
    # the eval runs in-process (the installed `realm eval --workers 2` is test_installed_cli's); its two
    # worker processes still carry the hold to the process backend, camera-less (nothing to render:
    # images over the process backend are test_e2e's); the report goes through the installed script
    with RoboArenaServer(_Reach(0.0), dict(needs_wrist_camera=False, n_external_cameras=0)) as srv:
        assert main(["eval", "--policy", f"roboarena:{srv.address}", "--policy-latency", "0.3", "--tasks", "REALM-PickApple-v1",
                     "--perturbations", "Default", "--episodes", "2", "--max-steps", "12", "--workers", "2", "--backend", "cpu",
                     "--no-progress", "--no-quality", "--out", str(tmp_path / "run")]) == 0
        assert len(srv.resets) == 2 and srv.requests == 2 * 1  # 12 steps = 5 held + 8 (cut at 12): one request each
    recs = [json.loads(x) for x in (tmp_path / "run" / "records.jsonl").read_text().splitlines()]
    assert all(x["policy_latency"] == "0.3" and x["steps"] == 12 and list(x["latency_s"]) == [srv.address] for x in recs)
    m = json.loads((tmp_path / "run" / "metrics.json").read_text())["policy_latency"]
    assert m["settings"] == ["0.3"] and m["servers"][srv.address]["requests"] == 2
    r = subprocess.run([realm, "eval", "report", str(tmp_path / "run"), "--out", str(tmp_path / "r.html")], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    html = (tmp_path / "r.html").read_text()
    assert "holds its previous target 5 control steps before each chunk" in html and f"{srv.address} median" in html
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:  # an argparse error (the installed script's exit 2 on one: tests/bad_inputs)
        main(["eval", "--policy", "zero", "--policy-latency", "-1", "--out", str(tmp_path / "x")])
    assert e.value.code == 2 and "argument --policy-latency: must be >= 0" in capsys.readouterr().err.strip().splitlines()[-1]
