"""`realm eval` end to end on CPU: a tiny LeRobot policy (random init, saved and loaded by path) over
worker processes with shared-memory camera frames, an in-process openpi server, and the scripted
expert through the same path; records, metrics.json and the HTML report."""

import json

import pytest

from realm_ms.cli import main
from realm_ms.eval.policies.openpi_server import OpenPIServer, hold_infer

TASKS = ["REALM-PickApple-v1", "REALM-PushSwitch-v1"]


def _check_run(out, policy_prefix, n=4):
    recs = [json.loads(line) for line in (out / "records.jsonl").read_text().splitlines()]
    assert len(recs) == n and len({(r["task"], r["perturbation"], r["seed"]) for r in recs}) == n
    for r in recs:
        assert r["status"] == "ok" and r["policy"].startswith(policy_prefix)
        assert r["instruction"] and r["perturbation"] == "Default" and 0 < r["steps"] <= 12
        assert set(r["stages"]) and r["stalled_stage"] and "joint_path_length" in r["quality"]
    m = json.loads((out / "metrics.json").read_text())
    assert m["overall"]["episodes"] == n and set(m["per_task"]) == set(TASKS) and "Default" in m["per_perturbation"]
    assert sum(m["failure_stages"].values()) == pytest.approx(1.0)
    assert main(["eval", "report", str(out), "--out", str(out / "report.html")]) == 0
    html = (out / "report.html").read_text()
    assert "data:image/png;base64" in html and "REALM paper layout" in html
    assert (out / "report_files" / "heatmap_progression.png").stat().st_size > 1000
    assert (out / "report_files" / "table.md").read_text().startswith("| perturbation |")
    return recs


def test_lerobot_policy_over_worker_processes(tmp_path):
    from realm_ms.eval.policies.lerobot import make_tiny_policy

    ckpt = make_tiny_policy(tmp_path / "tiny_act")
    out = tmp_path / "run_lerobot"
    args = ["eval", "--policy", f"lerobot:{ckpt}", "--tasks", *TASKS, "--perturbations", "Default", "--episodes", "2", "--max-steps", "8",
            "--workers", "2", "--camera-size", "64x36", "--no-progress", "--out", str(out)]
    assert main(args) == 0
    recs = _check_run(out, "lerobot:")
    # the untrained net moves the arm (its actions are not the hold pose): the policy's actions drove the env
    assert max(r["quality"]["joint_path_length"] for r in recs) > 1e-3
    assert main(args) == 0  # the same command again: everything is done, nothing is rerun
    assert len((out / "records.jsonl").read_text().splitlines()) == 4


def test_openpi_server_in_process(tmp_path):
    out = tmp_path / "run_openpi"
    with OpenPIServer(hold_infer) as srv:
        assert main(["eval", "--policy", f"openpi:{srv.address}", "--tasks", *TASKS, "--perturbations", "Default", "--episodes", "2", "--max-steps", "12",
                     "--workers", "1", "--camera-size", "64x36", "--no-progress", "--out", str(out)]) == 0
        assert srv.requests == 4 * 2  # 12 steps re-planned every 8: two requests per episode
    _check_run(out, "openpi:")


def test_dead_openpi_server_fails_episodes_not_the_run(tmp_path, capsys):
    """Every episode is attempted and recorded as an error; the command then exits 1 (not 0) and says
    where the errors are; each error is shown live, as it happened."""
    out = tmp_path / "run_dead"
    capsys.readouterr()
    assert main(["eval", "--policy", "openpi:127.0.0.1:9", "--openpi-wait", "0.5", "--tasks", TASKS[1], "--perturbations", "Default", "--episodes", "2",
                 "--max-steps", "12", "--workers", "1", "--camera-size", "64x36", "--no-progress", "--out", str(out)]) == 1
    recs = [json.loads(line) for line in (out / "records.jsonl").read_text().splitlines()]
    assert len(recs) == 2 and all(r["status"] == "error" and "unreachable" in r["error"] for r in recs)
    assert json.loads((out / "metrics.json").read_text())["overall"]["episodes"] == 0
    err = capsys.readouterr().err
    assert "2 episode(s) ended in an error record" in err and str(out / "records.jsonl") in err
    assert f"error: {TASKS[1]} x Default seed 1234" in err and f"error: {TASKS[1]} x Default seed 1235" in err


def test_expert_through_eval_reaches_success(tmp_path):
    out = tmp_path / "run_expert"
    assert main(["eval", "--policy", "expert", "--tasks", "REALM-PushSwitch-v1", "--perturbations", "Default", "--episodes", "1", "--max-steps", "150",
                 "--workers", "1", "--no-progress", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["overall"]["success_rate"] == 1.0 and m["failure_stages"] == {"DONE": 1.0}
    assert m["time_to_stage"]["TOGGLED_ON"]["episodes"] == 1


def test_bad_flags_are_one_line_errors(tmp_path, capsys):
    assert main(["eval", "--policy", "nope", "--tasks", TASKS[0], "--out", str(tmp_path / "x")]) == 2
    assert main(["eval", "--policy", "zero", "--tasks", "REALM-Nope-v1", "--out", str(tmp_path / "x")]) == 2
    assert main(["eval", "--policy", "zero", "--tasks", TASKS[0], "--perturbations", "NOPE", "--out", str(tmp_path / "x")]) == 2
    assert main(["eval", "--policy", "lerobot:/does/not/exist", "--tasks", TASKS[0], "--out", str(tmp_path / "x")]) == 2
    assert main(["eval", "report", str(tmp_path / "empty")]) == 2
    from realm_ms.eval.backends.choose import gpu_physx_status

    if not gpu_physx_status()[0]:  # no SAPIEN GPU PhysX here: --backend gpu must say so in one line
        assert main(["eval", "--policy", "zero", "--tasks", TASKS[0], "--perturbations", "Default", "--backend", "gpu",
                     "--out", str(tmp_path / "g")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "known:" in err
    assert "--backend gpu: no CUDA device" in err or gpu_physx_status()[0]
