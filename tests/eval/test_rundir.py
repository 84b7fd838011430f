"""The run directory contract: run.json and every record carry the run's fingerprint; a resume
refuses records made by another command (also without run.json); lines that are not records are
reported by line number and never counted. Plus `realm validate`'s undefined statistics."""

import json

import pytest

from realm_ms.cli import main
from realm_ms.eval.records import RecordWriter, read_records

TASK = "REALM-PushSwitch-v1"


def _eval(out, policy="zero", max_steps=2, episodes=2, seed=None):
    argv = ["eval", "--policy", policy, "--tasks", TASK, "--perturbations", "Default", "--episodes", str(episodes),
            "--max-steps", str(max_steps), "--workers", "1", "--no-progress", "--no-quality", "--out", str(out)]
    return main(argv + (["--seed", str(seed)] if seed is not None else []))


def _last_err(capsys) -> str:
    return [line for line in capsys.readouterr().err.splitlines() if line.strip()][-1]


@pytest.fixture(scope="module")
def run_ok(tmp_path_factory):
    out = tmp_path_factory.mktemp("rundir") / "run"
    assert _eval(out) == 0
    return out


def test_every_record_and_run_json_carry_the_fingerprint(run_ok):
    meta = json.loads((run_ok / "run.json").read_text())
    fp = meta["fingerprint"]
    assert fp["policy"] == "zero" and fp["max_steps"] == 2 and fp["replan_every"] == 8 and fp["camera_size"] == [320, 180]
    assert fp["action_space"] == "joint_position" and fp["code_version"].startswith("realm-ms ") and fp["protocol"] == "realm"
    recs = read_records(run_ok / "records.jsonl")
    assert len(recs) == 2 and all(r["fingerprint"] == fp for r in recs)


def test_resume_with_mismatched_records_refuses(run_ok, tmp_path, capsys):
    # records of a --max-steps 2 run, copied where there is no run.json: a --max-steps 3 resume refuses
    copy = tmp_path / "copy"
    copy.mkdir()
    before = (run_ok / "records.jsonl").read_bytes()
    (copy / "records.jsonl").write_bytes(before)
    capsys.readouterr()
    assert _eval(copy, max_steps=3) == 2
    last = _last_err(capsys)
    assert "records.jsonl: 2 of 2 record(s) were not made by this command (line 1: max_steps 2 vs 3" in last
    assert (copy / "records.jsonl").read_bytes() == before and not (copy / "run.json").exists()  # nothing written
    # with run.json there, it is the first guard
    assert _eval(run_ok, max_steps=3) == 2
    assert "holds a run made differently (max_steps 2 vs 3" in _last_err(capsys)
    # one record of another policy among this run's records: refused, by its line
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    other = tmp_path / "other"
    assert _eval(other, policy="random", episodes=1, seed=1236) == 0
    (mixed / "records.jsonl").write_bytes(before + (other / "records.jsonl").read_bytes())
    capsys.readouterr()
    assert _eval(mixed, episodes=3) == 2
    assert "1 of 3 record(s) were not made by this command (line 3: policy random vs zero" in _last_err(capsys)
    assert not (mixed / "metrics.json").exists()  # the foreign episode never reached the metrics


def test_garbage_line_is_reported_with_its_line_number(run_ok, tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    for f in ("run.json", "records.jsonl"):
        (run / f).write_bytes((run_ok / f).read_bytes())
    with open(run / "records.jsonl", "ab") as f:
        f.write(b'{"foo": 1}\n[1, 2, 3]\n\xff\xfe not utf-8\n{"task": "T", "perturbation": "Default", "seed": "abc"}\n')
    capsys.readouterr()
    assert _eval(run) == 0  # nothing to rerun: the two real episodes are done
    err = capsys.readouterr().err
    for n, why in ((3, "`task` is missing"), (4, "not a JSON object (a list)"), (5, "not UTF-8 text"), (6, "`seed` is 'abc'")):
        assert f"records.jsonl:{n}: {why}" in err, err
    assert json.loads((run / "metrics.json").read_text())["overall"]["episodes"] == 2  # never counted


def test_damaged_run_json_and_records_dir_are_one_line_errors(run_ok, tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "records.jsonl").write_bytes((run_ok / "records.jsonl").read_bytes())
    (run / "run.json").write_text('{"policy": ')
    assert _eval(run) == 2
    assert "run.json: not valid JSON" in _last_err(capsys)
    (run / "run.json").unlink()
    (run / "run.json").mkdir()
    assert _eval(run) == 2
    assert "run.json is a directory" in _last_err(capsys)


def test_read_records_reports_and_skips(tmp_path):
    path = tmp_path / "records.jsonl"
    good = dict(task="T", perturbation="Default", seed=0, status="ok", success=True, progression=1.0)
    path.write_bytes(json.dumps(good).encode() + b"\n" + b'{"task": "T", "perturbation": "Default", "seed": 1, "progression": 1.5, '
                     b'"success": false}\n' + json.dumps(dict(good, seed=2)).encode())  # last line: whole, without newline
    problems = []
    recs = read_records(path, problems)
    assert [r["seed"] for r in recs] == [0, 2]
    assert problems == [f"{path}:2: `progression` is 1.5; expected a number in [0, 1]"]
    RecordWriter(path).close()  # opening for append keeps a whole last line (adds its newline)
    assert path.read_bytes().endswith(b"}\n") and [r["seed"] for r in read_records(path)] == [0, 2]


def test_validate_one_policy_task_is_undefined(tmp_path, capsys):
    csv = tmp_path / "paired.csv"
    csv.write_text("policy,task,real,sim\np1,A,0.4,0.3\np1,B,0.5,0.6\np2,B,0.2,0.1\np3,B,0.7,0.9\n")
    js = tmp_path / "v.json"
    assert main(["validate", str(csv), "--json", str(js)]) == 0
    out = capsys.readouterr().out
    row_a = next(line for line in out.splitlines() if line.startswith("A "))
    assert "undefined" in row_a and "1.0000" not in row_a
    assert "A: pearson_r undefined (1 policy, needs >= 3)" in out
    res = json.loads(js.read_text())
    assert res["per_task"]["A"]["pearson_r"] is None and res["per_task"]["A"]["undefined"]["pearson_r"] == "1 policy, needs >= 3"
    assert res["mean"]["pearson_r"] == res["per_task"]["B"]["pearson_r"]  # the mean over the tasks where r is defined
