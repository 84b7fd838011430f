"""The aligned DROID robot is a named robot model everywhere a robot model is accepted."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest
import torch

import realm_ms  # noqa: F401
from realm_ms.agents.robot_model import NAMED_MODELS, load_robot_model, named_model_path

ENV = "REALM-PickApple-v1"
REALM = Path(sys.executable).parent / "realm"  # the installed command, as a user types it


def test_the_named_model_ships_with_its_provenance_and_droids_credit():
    assert named_model_path("droid-aligned").is_file()
    m = load_robot_model("droid-aligned")
    assert "target_filter" in m.names and m.gains == "polymetis"
    prov = m.provenance
    assert "Khazatsky" in prov["credit"] and "CC-BY 4.0" in prov["credit"]
    for key in ("data", "command", "created", "realm_ms", "heldout"):
        assert prov.get(key), key
    # the command path is slower than the nominal robot's: a filter of tens of milliseconds
    assert 0.03 < m.effect("target_filter").values()["tau"] < 0.3
    # the real gripper strokes slower than the simulated one (docs/results.md, "Real DROID episodes")
    assert 0.4 < m.effect("gripper_response").values()["speed"] < 0.9


def test_an_unknown_name_lists_the_named_models(tmp_path):
    with pytest.raises(FileNotFoundError, match="droid-aligned"):
        load_robot_model("droid-alinged")


def test_gym_make_runs_the_named_model():
    env = gym.make(ENV, obs_mode="state", robot_model="droid-aligned")
    env.reset(seed=0)
    u = env.unwrapped
    assert u.config.robot_model == "droid-aligned"
    assert u.robot_model.gains == load_robot_model("droid-aligned").gains
    stages = [s.name for s in u.agent.arm_controller.driver.actuation.stages]
    assert "target_filter" in stages
    q0 = u.agent.arm_qpos[0].clone()
    q1 = q0 + torch.tensor([0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0])
    moved = []
    for _ in range(8):
        env.step(torch.cat([q1, torch.zeros(1)]))
        moved.append(float(u.agent.arm_qpos[0, 3] - q0[3]))
    # the delayed, filtered command: the first step barely moves, the arm gets there in the end
    assert moved[0] < 0.05 and moved[-1] > 0.08, moved
    assert u.config.to_dict()["robot_model"] == "droid-aligned"
    env.close()


def test_realm_eval_takes_a_named_robot_model_and_records_it(tmp_path):
    run = subprocess.run([str(REALM), "eval", "--policy", "zero", "--tasks", ENV,
                          "--perturbations", "Default", "--episodes", "1", "--max-steps", "3", "--workers", "1",
                          "--robot-model", "droid-aligned", "--no-progress", "--out", str(tmp_path / "run")],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    (rec,) = [json.loads(x) for x in (tmp_path / "run" / "records.jsonl").read_text().splitlines()]
    assert rec["robot_model"] == rec["config"]["robot_model"] == "droid-aligned"


def test_a_bad_robot_model_flag_is_one_line_and_exit_code_2(tmp_path, capsys):
    # the installed command for eval; export's flag goes through the same CLI code in this process
    # (the installed `realm export` is the bad-input corpus's `export-out-is-file`)
    from realm_ms.cli import main

    bad = ["--robot-model", "nope-model", "--out", str(tmp_path / "o")]
    run = subprocess.run([str(REALM), "eval", "--policy", "zero", "--tasks", ENV, "--episodes", "1", *bad],
                         capture_output=True, text=True, timeout=300)
    assert main(["export", "--tasks", ENV, "--episodes", "1", *bad]) == 2
    for code, err in ((run.returncode, run.stderr), (2, capsys.readouterr().err)):
        assert code == 2, err
        lines = [x for x in err.strip().splitlines() if x.strip()]
        assert len(lines) == 1 and "--robot-model nope-model" in lines[0] and "droid-aligned" in lines[0], err


def test_the_lerobot_env_type_passes_the_robot_model():
    pytest.importorskip("lerobot")
    from lerobot_env_realm import RealmEnvConfig

    cfg = RealmEnvConfig(task=ENV, robot_model="droid-aligned")
    assert cfg.gym_kwargs["robot_model"] == "droid-aligned"
    assert "robot_model" not in RealmEnvConfig(task=ENV).gym_kwargs
    assert set(NAMED_MODELS) == {"droid-aligned"}
