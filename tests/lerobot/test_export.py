"""`realm export`: a LeRobot v3.0 dataset written through LeRobot's API, read back by LeRobot, faithful.

Exports 2 expert episodes of 2 tasks (short episodes, small images), reads them with
``LeRobotDataset(repo_id, root=...)``, checks features / shapes / fps / frame counts, replays the
stored actions in a fresh env with the same seed and compares the states, and checks resume.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

TASKS = ["REALM-PickApple-v1", "REALM-PushSwitch-v1"]
W, H, STEPS, EPISODES = 64, 48, 12, 2


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    from realm_ms.lerobot.export import ExportConfig, export_dataset

    root = tmp_path_factory.mktemp("export") / "demos"
    cfg = ExportConfig(out=root, tasks=TASKS, episodes=EPISODES, seed=3, width=W, height=H, max_steps=STEPS, progress=False)
    summary = export_dataset(cfg)
    return cfg, summary


def _dataset(cfg):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    return LeRobotDataset(cfg.repo_id, root=cfg.out, video_backend="pyav")


def test_realm_sysid_reads_an_export_as_joint_targets(tmp_path):
    """What `realm export` writes is data the workbench takes (`realm sysid compare DATASET`): each
    episode a trajectory at 15 Hz whose measured joints and joint targets are the dataset's
    observation.state and action, the gripper beside them (the workbench needs 20 samples)."""
    from realm_ms.lerobot.export import ExportConfig, export_dataset
    from realm_ms.sysid.data_io import load_dir

    cfg = ExportConfig(out=tmp_path / "d", tasks=[TASKS[1]], seed=3, width=32, height=24, max_steps=24, progress=False)
    export_dataset(cfg)
    (tr,) = load_dir(cfg.out)
    data = _dataset(cfg).hf_dataset.with_format("numpy")
    state, action = np.stack(data["observation.state"]), np.stack(data["action"])
    assert len(tr.t) == len(state) == 24 and np.allclose(np.diff(tr.t), 1 / 15)
    np.testing.assert_allclose(tr.q, state[:, :7], atol=1e-6)
    np.testing.assert_allclose(tr.q_cmd, action[:, :7], atol=1e-6)
    np.testing.assert_allclose(tr.gripper, state[:, 7], atol=1e-6)
    assert np.abs(np.diff(tr.q_cmd, axis=0)).max() > 1e-3  # the expert moved: not a constant target


def test_dataset_reads_back_with_droid_features(exported):
    cfg, summary = exported
    assert summary["written"] == len(TASKS) * EPISODES
    ds = _dataset(cfg)
    assert ds.num_episodes == len(TASKS) * EPISODES
    assert ds.fps == 15
    assert ds.meta.robot_type == "panda_droid"
    info = json.loads((cfg.out / "meta" / "info.json").read_text())
    assert info["codebase_version"].startswith("v3")
    feats = ds.meta.features
    for cam in ("exterior_1_left", "exterior_2_left", "wrist_left"):
        key = f"observation.images.{cam}"
        assert feats[key]["dtype"] == "video" and tuple(feats[key]["shape"]) == (H, W, 3)
    assert tuple(feats["observation.state"]["shape"]) == (8,) and tuple(feats["action"]["shape"]) == (8,)
    assert {"progression", "success", "next.done"} <= set(feats)
    # frame counts: every episode has STEPS frames (expert scripts are longer than STEPS), the last one done
    lengths = [int(ep["length"]) for ep in ds.meta.episodes]
    assert lengths == [STEPS] * len(lengths) and ds.num_frames == sum(lengths)
    item = ds[STEPS - 1]
    assert item["observation.images.wrist_left"].shape == (3, H, W)
    assert 0.0 <= float(item["observation.images.wrist_left"].max()) <= 1.0
    assert bool(item["next.done"]) and not bool(ds[0]["next.done"])
    # the language instruction is the task; per-episode metadata in the sidecar
    assert set(ds.meta.tasks.index) == {"pick up the apple", "push the light switch"}
    from realm_ms.lerobot.export import read_sidecar

    side = read_sidecar(cfg.out)
    assert [(r["task"], r["seed"], r["episode_index"]) for r in side] == [
        (t, 3 + k, i) for i, (t, k) in enumerate((t, k) for t in TASKS for k in range(EPISODES))
    ]
    assert all(r["perturbation"] == "Default" and r["policy"] == "expert" and r["kept"] for r in side)
    card = (cfg.out / "README.md").read_text()
    assert "LeRobot" in card and "REALM-PushSwitch-v1" in card


def test_replaying_stored_actions_reproduces_stored_states(exported):
    """Same seed, stored actions -> the stored observation.state sequence (the export is faithful)."""
    import gymnasium as gym
    import torch

    import realm_ms  # noqa: F401

    cfg, _ = exported
    ds = _dataset(cfg)
    data = ds.hf_dataset.with_format("numpy")
    episode = np.asarray(data["episode_index"])
    state_all = np.stack(data["observation.state"])
    action_all = np.stack(data["action"])
    from realm_ms.lerobot.export import read_sidecar

    side = {r["episode_index"]: r for r in read_sidecar(cfg.out)}
    for ep in (0, EPISODES):  # the first episode of each task
        rec = side[ep]
        states, actions = state_all[episode == ep], action_all[episode == ep]
        assert np.abs(np.diff(actions[:, :7], axis=0)).max() > 1e-4  # the expert moved the arm
        env = gym.make(rec["task"], obs_mode="state_dict")  # a fresh env; no cameras needed for physics
        try:
            obs, _ = env.reset(seed=rec["seed"])
            for t in range(len(actions)):
                np.testing.assert_allclose(obs["agent"]["droid_state"][0].numpy(), states[t], atol=1e-5, err_msg=f"episode {ep} step {t}")
                obs, *_ = env.step(torch.as_tensor(actions[t])[None])
        finally:
            env.close()


def test_rerun_resumes_without_duplicates(exported):
    from realm_ms.lerobot.export import SIDECAR, ExportConfig, export_dataset, read_sidecar

    cfg, _ = exported

    # a kill during save_episode: the sidecar line was written, the episode never committed
    ghost = dict(read_sidecar(cfg.out)[-1], seed=99, episode_index=len(TASKS) * EPISODES)
    with open(cfg.out / SIDECAR, "a") as f:
        f.write(json.dumps(ghost) + "\n")
    again = export_dataset(ExportConfig(out=cfg.out, tasks=TASKS, episodes=EPISODES, seed=3, width=W, height=H, max_steps=STEPS, progress=False))
    assert again["written"] == 0 and again["already"] == len(TASKS) * EPISODES
    assert 99 not in {r["seed"] for r in read_sidecar(cfg.out)}
    assert _dataset(cfg).num_episodes == len(TASKS) * EPISODES


def test_bad_inputs_are_one_line_errors(exported, tmp_path):
    from realm_ms.cli import main

    cfg, _ = exported
    assert main(["export", "--tasks", "REALM-Nope-v1", "--episodes", "1", "--out", str(tmp_path / "x")]) == 2
    assert main(["export", "--tasks", TASKS[0], "--episodes", "1", "--workers", "0", "--out", str(tmp_path / "x")]) == 2
    assert main(["export", "--tasks", TASKS[0], "--perturbations", "V-NOPE", "--episodes", "1", "--out", str(tmp_path / "x")]) == 2
    # an existing dataset with another image size is refused, not silently mixed
    assert main(["export", "--tasks", TASKS[0], "--episodes", "1", "--out", str(cfg.out), "--width", "32", "--height", "32",
                 "--repo-id", cfg.repo_id]) == 2
    (tmp_path / "junk").mkdir()
    (tmp_path / "junk" / "file.txt").write_text("x")
    assert main(["export", "--tasks", TASKS[0], "--episodes", "1", "--out", str(tmp_path / "junk")]) == 2


def test_export_of_a_realm_eval_run_resimulates_its_records(tmp_path):
    """`realm export --from-eval RUN`: one dataset episode per record, same seed / steps / outcome."""
    from realm_ms.cli import main

    run, out = tmp_path / "run", tmp_path / "from_eval"
    assert main(["eval", "--policy", "expert", "--tasks", TASKS[1], "--perturbations", "Default", "--episodes", "2",
                 "--seed", "7", "--max-steps", "10", "--workers", "1", "--no-progress", "--no-quality", "--out", str(run)]) == 0
    records = [json.loads(line) for line in (run / "records.jsonl").read_text().splitlines() if line.strip()]
    assert main(["export", "--from-eval", str(run), "--out", str(out), "--width", str(W), "--height", str(H)]) == 0
    from realm_ms.lerobot.export import read_sidecar

    side = read_sidecar(out)
    assert sorted((r["seed"], r["steps"], r["success"]) for r in side) == sorted((r["seed"], r["steps"], r["success"]) for r in records)
    for rec in records:
        mine = next(r for r in side if r["seed"] == rec["seed"])
        assert abs(mine["progression"] - rec["progression"]) < 1e-6 and mine["policy"] == "expert"
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    ds = LeRobotDataset("realm/from_eval", root=out, video_backend="pyav")
    assert ds.num_episodes == len(records) and ds.num_frames == sum(r["steps"] for r in records)


@pytest.fixture(scope="module")
def aligned(tmp_path_factory):
    """`realm export --robot-model droid-aligned`: the `exported` fixture's first PushSwitch episode
    (seed 3, STEPS steps) on the aligned robot."""
    from realm_ms.cli import main

    out = tmp_path_factory.mktemp("aligned") / "aligned"
    assert main(["export", "--robot-model", "droid-aligned", "--tasks", TASKS[1], "--episodes", "1", "--seed", "3", "--max-steps", str(STEPS),
                 "--width", "32", "--height", "24", "--no-progress", "--out", str(out)]) == 0
    return out


def _states(root, repo_id):
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    data = LeRobotDataset(repo_id, root=root, video_backend="pyav").hf_dataset.with_format("numpy")
    return np.asarray(data["episode_index"]), np.stack(data["observation.state"])


def test_export_on_droid_aligned_records_the_robot_and_its_credit(aligned, exported, capsys):
    """`--robot-model droid-aligned`: the sidecar and the card name the robot, the card keeps DROID's
    credit under a CC-BY 4.0 licence, the states are not the nominal robot's, and a resume on
    another robot is refused."""
    from realm_ms.agents.robot_model import load_robot_model
    from realm_ms.cli import main
    from realm_ms.lerobot.export import read_sidecar

    (rec,) = read_sidecar(aligned)
    assert rec["robot_model"] == rec["config"]["robot_model"] == "droid-aligned"
    card = (aligned / "README.md").read_text()
    assert "Robot model: `droid-aligned`" in card and load_robot_model("droid-aligned").provenance["credit"] in card
    assert "license: cc-by-4.0" in card and "YCB object set" in card
    cfg, _ = exported
    nominal_card = (cfg.out / "README.md").read_text()
    assert "Robot model: `nominal`" in nominal_card and "Khazatsky" not in nominal_card and "license: cc-by-4.0" in nominal_card
    assert read_sidecar(cfg.out)[0]["robot_model"] == "nominal"
    mine = _states(aligned, "realm/aligned")[1]
    episode, states = _states(cfg.out, cfg.repo_id)
    nominal = states[episode == EPISODES]  # PushSwitch seed 3
    assert mine.shape == nominal.shape and np.abs(mine - nominal).max() > 1e-3  # the aligned robot lags its commands
    capsys.readouterr()
    assert main(["export", "--tasks", TASKS[1], "--episodes", "1", "--seed", "3", "--max-steps", str(STEPS), "--width", "32",
                 "--height", "24", "--no-progress", "--out", str(aligned)]) == 2
    assert "holds episodes of robot model droid-aligned, not nominal" in capsys.readouterr().err


def test_from_eval_re_simulates_on_the_runs_robot_model(aligned, tmp_path, capsys):
    """`realm export --from-eval RUN` of a droid-aligned run, without --robot-model: the episode runs on
    droid-aligned (the states of a `--robot-model droid-aligned` export); a --robot-model naming
    another robot is one line, exit 2; the same robot named by its file is no contradiction."""
    from realm_ms.agents.robot_model import load_robot_model, named_model_path
    from realm_ms.cli import main
    from realm_ms.lerobot.export import read_sidecar, same_robot

    run, out = tmp_path / "run", tmp_path / "from_eval"
    assert main(["eval", "--policy", "expert", "--tasks", TASKS[1], "--perturbations", "Default", "--episodes", "1", "--seed", "3",
                 "--max-steps", str(STEPS), "--robot-model", "droid-aligned", "--workers", "1", "--no-progress", "--no-quality",
                 "--out", str(run)]) == 0
    (ran,) = [json.loads(line) for line in (run / "records.jsonl").read_text().splitlines() if line.strip()]
    assert main(["export", "--from-eval", str(run), "--out", str(out), "--width", "32", "--height", "24", "--no-progress"]) == 0
    (rec,) = read_sidecar(out)
    assert rec["robot_model"] == rec["config"]["robot_model"] == ran["robot_model"] == "droid-aligned"
    assert (rec["steps"], rec["success"]) == (ran["steps"], ran["success"]) and abs(rec["progression"] - ran["progression"]) < 1e-6
    np.testing.assert_array_equal(_states(out, "realm/from_eval")[1], _states(aligned, "realm/aligned")[1])
    assert "Robot model: `droid-aligned`" in (out / "README.md").read_text()

    other = load_robot_model("droid-aligned")
    other.effect("target_filter").set_values({"tau": 0.05})
    other.save(tmp_path / "other.yaml")
    capsys.readouterr()
    assert main(["export", "--from-eval", str(run), "--robot-model", str(tmp_path / "other.yaml"), "--out", str(tmp_path / "x")]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "contradicts" in err[0] and "ran robot model droid-aligned" in err[0] and "drop --robot-model" in err[0]
    assert not (tmp_path / "x").exists()
    assert same_robot("droid-aligned", str(named_model_path("droid-aligned"))) and not same_robot(None, "droid-aligned")
    assert not same_robot("droid-aligned", str(tmp_path / "other.yaml"))


def test_binary_gripper_labels_keep_the_episode_and_binarise_the_grasp(tmp_path, capsys):
    """``--gripper-labels binary``: the same episode (states, joint targets) as the commands export,
    with action[7] = 1 exactly where the expert's gentle pinch commanded any closing (0.03 ... 0.3);
    a resume with the other convention is refused."""
    from realm_ms.cli import main
    from realm_ms.lerobot.export import ExportConfig, export_dataset, read_sidecar

    steps = 62  # seed 3: the expert starts closing on the apple at step 55 (0.03, 0.06, ...): 7 closing frames
    out = {}
    for labels in ("command", "binary"):
        cfg = ExportConfig(out=tmp_path / labels, tasks=[TASKS[0]], seed=3, width=32, height=24, max_steps=steps,
                           progress=False, gripper_labels=labels)
        export_dataset(cfg)
        data = _dataset(cfg).hf_dataset.with_format("numpy")
        out[labels] = (np.stack(data["observation.state"]), np.stack(data["action"]))
        assert read_sidecar(cfg.out)[0]["gripper_labels"] == labels
    (s_cmd, a_cmd), (s_bin, a_bin) = out["command"], out["binary"]
    np.testing.assert_array_equal(s_cmd, s_bin)
    np.testing.assert_array_equal(a_cmd[:, :7], a_bin[:, :7])
    closing = a_cmd[:, 7] > 0.01
    assert closing.any() and (a_cmd[closing, 7] < 0.5).all(), "the expert's gentle pinch was not in the episode"
    np.testing.assert_array_equal(a_bin[:, 7], closing.astype(np.float32))
    assert main(["export", "--tasks", TASKS[0], "--episodes", "1", "--seed", "3", "--width", "32", "--height", "24",
                 "--out", str(tmp_path / "binary"), "--repo-id", "realm/binary"]) == 2
    assert "--gripper-labels binary" in capsys.readouterr().err


def test_several_workers_write_the_episodes_one_worker_writes(exported, tmp_path):
    """`realm export --workers 2` runs on `realm eval`'s process backend: the frames come back with
    each record and land in the dataset as the in-process export writes them."""
    from realm_ms.cli import main
    from realm_ms.lerobot.export import read_sidecar

    cfg, _ = exported
    out = tmp_path / "two_workers"
    assert main(["export", "--tasks", TASKS[0], "--episodes", str(EPISODES), "--seed", "3", "--width", str(W), "--height", str(H),
                 "--max-steps", str(STEPS), "--workers", "2", "--no-progress", "--out", str(out), "--repo-id", cfg.repo_id]) == 0
    mine = sorted(read_sidecar(out), key=lambda r: r["seed"])
    theirs = sorted((r for r in read_sidecar(cfg.out) if r["task"] == TASKS[0]), key=lambda r: r["seed"])
    strip = ("episode_index",)  # the order two workers finish in is free
    assert [{k: v for k, v in r.items() if k not in strip} for r in mine] == [{k: v for k, v in r.items() if k not in strip} for r in theirs]
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    def by_seed(root, side):
        data = LeRobotDataset(cfg.repo_id, root=root, video_backend="pyav").hf_dataset.with_format("numpy")
        index = np.asarray(data["episode_index"])
        return {r["seed"]: (np.stack(data["observation.state"])[index == r["episode_index"]],
                            np.stack(data["action"])[index == r["episode_index"]]) for r in side}

    a, b = by_seed(out, mine), by_seed(cfg.out, theirs)
    for seed in a:
        np.testing.assert_array_equal(a[seed][0], b[seed][0])
        np.testing.assert_array_equal(a[seed][1], b[seed][1])


def test_a_bad_policy_reply_fails_its_episode_and_nothing_is_written(tmp_path, monkeypatch, capsys):
    """A reply `realm eval` would reject (NaN) fails the episode through the same checks; the export
    writes nothing for it, says so, and exits 1 (a rerun retries it)."""
    import realm_ms.eval.policies as policies
    from realm_ms.cli import main
    from realm_ms.eval.policies.policy import ObsRequest, PolicyOutput
    from realm_ms.lerobot.export import read_sidecar

    class NaNPolicy:
        name, env_side = "nan", False

        def spec(self):
            return "nan"

        def obs_request(self):
            return ObsRequest()

        def reset(self, slots):
            pass

        def act(self, batch):
            return PolicyOutput(np.full((len(batch.state), 4, 8), np.nan, np.float32))

        def close(self):
            pass

    monkeypatch.setattr(policies, "make_policy", lambda spec, **kw: NaNPolicy())
    out = tmp_path / "nan"
    assert main(["export", "--policy", "zero", "--tasks", TASKS[0], "--episodes", "1", "--width", "32", "--height", "24",
                 "--max-steps", "4", "--no-progress", "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert f"{TASKS[0]} Default seed 0: error:" in captured.out and "NaN" in captured.out
    assert "1 episode(s) ended in an error" in captured.err
    assert read_sidecar(out) == []


def test_plans_skip_tried_keys_and_replay_recorded_draws():
    """Export's plans are `realm eval` episode keys: tried (key, policy) pairs are skipped, a cell
    with its episodes gets none, and records of a run become keys grouped per policy with their draws."""
    from realm_ms.eval.protocol import EpisodeKey
    from realm_ms.lerobot.export import ExportConfig, plan, plan_from_records, validate_tasks

    assert validate_tasks(["REALM-PickApple-v1"], ["default", "0", "Default", "v-aug"]) == ["Default", "V-AUG"]

    cfg = ExportConfig(out="/tmp/unused_plan_out", tasks=["REALM-PickApple-v1", "REALM-PushSwitch-v1"], episodes=2, seed=5)
    done = [dict(task="REALM-PickApple-v1", perturbation="Default", seed=5, policy="expert", kept=True),
            dict(task="REALM-PickApple-v1", perturbation="Default", seed=6, policy="expert", kept=True),
            dict(task="REALM-PushSwitch-v1", perturbation="Default", seed=5, policy="expert", kept=False)]
    (p,) = plan(cfg, done)
    assert p.keys == [EpisodeKey("REALM-PushSwitch-v1", "Default", 6)]
    assert p.want == {("REALM-PickApple-v1", "Default"): 0, ("REALM-PushSwitch-v1", "Default"): 2}
    draws = [{"V-AUG": {"sigma": 0.5}}]
    records = [dict(task="B", perturbation="V-AUG", seed=1, policy="expert", perturbation_params={"params": draws}, max_steps=30),
               dict(task="A", perturbation="Default", seed=1, policy="zero", replan_every=4, max_steps=30),
               dict(task="A", perturbation="V-AUG", seed=2, policy="expert", status="error"),
               dict(task="A", perturbation="Default", seed=2, policy="expert", max_steps=30),
               dict(task="B", perturbation="V-AUG", seed=3, policy="expert", max_steps=30)]
    plans = plan_from_records(records, done=[dict(task="B", perturbation="V-AUG", seed=3, policy="expert", kept=True)], max_steps=9)
    assert [(q.policy, q.replan_every, q.max_steps) for q in plans] == [("expert", 8, 9), ("zero", 4, 9)]
    assert plans[0].keys == [EpisodeKey("B", "V-AUG", 1), EpisodeKey("A", "Default", 2)] and plans[0].want is None
    assert plans[0].replay == {EpisodeKey("B", "V-AUG", 1): draws} and plans[1].keys == [EpisodeKey("A", "Default", 1)]
    from realm_ms.eval.records import robot_model_of

    assert robot_model_of(records[0]) is None  # a record without an env config predates --robot-model: nominal
