"""More of the bad-input corpus: run directories and resume, output paths, `realm validate`,
`realm export`, `realm eval report`, `realm perturbations sheet`, `realm assets build`, `gym.make`
keywords and scene names, effect settings in model files, policy specs.

``make_files(root)`` writes what these cases read, next to ``bad_input_files.make_all``'s files.
``{root}/run_ok`` is a real run (`realm eval`, the zero policy, 2 episodes of 2 steps); the other
run directories are copies of it changed in one way each: another command's records copied in,
a damaged ``run.json``, garbage lines in ``records.jsonl``, a file where a directory belongs.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from bad_input_cases import Case, cli

REALM = Path(sys.executable).parent / "realm"
TASK = "REALM-PushSwitch-v1"
# the command that made {root}/run_ok; the cases below rerun it with one change (``ev``)
EVAL_FLAGS = {"--policy": "zero", "--tasks": TASK, "--perturbations": "Default", "--episodes": "2", "--max-steps": "2",
              "--workers": "1", "--no-progress": None, "--no-quality": None}


def ev(out: str, **changes: str) -> str:
    """The run_ok command with ``--out out`` and flags changed or added (``max_steps="3"``), each given once."""
    flags = dict(EVAL_FLAGS)
    flags.update({"--" + k.replace("_", "-"): v for k, v in changes.items()})
    return "eval " + " ".join(k if v is None else f"{k} {v}" for k, v in flags.items()) + f" --out {out}"
CSV_HEADER = "policy,task,real,sim\n"


def _realm(argv: list[str], environ: dict | None = None, timeout: float = 150) -> subprocess.CompletedProcess:
    return subprocess.run([str(REALM), *argv], capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "PYTHONWARNINGS": "ignore", **(environ or {})})


def _realm_in_process(argv: list[str]) -> subprocess.CompletedProcess:
    """``main(argv)`` in this process, its output captured: for cases about a verb's behaviour, not
    the installed script (each verb keeps one case through ``_realm``; a fresh interpreter costs ~10 s)."""
    import contextlib
    import io

    from realm_ms.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as e:  # argparse rejects a flag
            code = e.code if isinstance(e.code, int) else 2
    return subprocess.CompletedProcess(argv, code, out.getvalue(), err.getvalue())


def _records(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_bytes().decode("utf-8").splitlines() if line.strip()]


def _write_records(path: Path, recs: list[dict], extra: bytes = b"") -> None:
    path.write_bytes(b"".join(json.dumps(r).encode() + b"\n" for r in recs) + extra)


def _copy_run(root: Path, name: str, drop: tuple[str, ...] = ()) -> Path:
    d = root / name
    shutil.copytree(root / "run_ok", d)
    for f in drop:
        (d / f).unlink()
    return d


def make_files(root: Path) -> None:
    r = _realm(ev(str(root / "run_ok")).split())
    assert r.returncode == 0, r.stderr[-2000:]
    ok = _records(root / "run_ok" / "records.jsonl")
    assert len(ok) == 2 and all("fingerprint" in x for x in ok)

    # another command's records, without a run.json to guard them
    _copy_run(root, "run_no_runjson", drop=("run.json",))
    # a third line whose fingerprint says --max-steps 3 (copied in from another run)
    d = _copy_run(root, "run_mixed", drop=("run.json",))
    other = dict(ok[1], seed=1236, fingerprint=dict(ok[1]["fingerprint"], max_steps=3), steps=3, max_steps=3)
    _write_records(d / "records.jsonl", ok + [other])
    # records of a realm-ms without fingerprints (or written by hand)
    d = _copy_run(root, "run_legacy", drop=("run.json",))
    _write_records(d / "records.jsonl", [{k: v for k, v in x.items() if k != "fingerprint"} for x in ok])
    d = _copy_run(root, "run_half_legacy")
    _write_records(d / "records.jsonl", ok + [{k: v for k, v in dict(ok[0], seed=1236).items() if k != "fingerprint"}])
    # a record of another robot copied in (export --from-eval: a dataset holds one robot)
    d = _copy_run(root, "run_two_robots", drop=("run.json",))
    aligned = dict(ok[1], robot_model="droid-aligned", config=dict(ok[1]["config"], robot_model="droid-aligned"))
    _write_records(d / "records.jsonl", [ok[0], aligned])
    # damaged run.json
    for name, data in (("run_json_corrupt", b'{"policy": "zero", '), ("run_json_list", b"[1, 2, 3]"),
                       ("run_json_binary", bytes(range(128, 256)))):
        d = _copy_run(root, name)
        (d / "run.json").write_bytes(data)
    d = _copy_run(root, "run_json_dir", drop=("run.json",))
    (d / "run.json").mkdir()
    d = _copy_run(root, "run_records_dir", drop=("records.jsonl",))
    (d / "records.jsonl").mkdir()
    d = _copy_run(root, "run_metrics_dir", drop=("metrics.json",))
    (d / "metrics.json").mkdir()
    # garbage lines among the two real records (lines 3-10), and a cut last line
    garbage = [b'{"foo": 1}', b"[1, 2, 3]", b'"just a string"', json.dumps(dict(ok[0], seed="abc")).encode(), b"\xff\xfe\xfa not utf-8",
               json.dumps(dict(ok[0], progression=1.5)).encode(), b'{"task": "T", "perturbation": "Default", "seed": 5, "status": "done"}',
               json.dumps(dict(ok[0], success="yes")).encode()]
    d = _copy_run(root, "run_garbage")
    _write_records(d / "records.jsonl", ok, b"\n".join(garbage) + b'\n{"task": "REALM-Push')
    d = _copy_run(root, "run_only_garbage", drop=("run.json",))
    (d / "records.jsonl").write_bytes(b"\n".join(garbage) + b"\n")
    d = _copy_run(root, "run_videos_file")
    (d / "videos").write_text("not a directory")
    (root / "run_empty").mkdir()
    (root / "rep_files").write_text("a file where the report's figures go")
    (root / "sh_REALM-PickApple-v1.png").mkdir()
    make_model_files(root)
    # a directory holding something else than a dataset (export --out)
    (root / "not_a_dataset").mkdir()
    (root / "not_a_dataset" / "notes.txt").write_text("mine")
    (root / "empty_source").mkdir()
    # paired CSVs for `realm validate`
    csvs = {
        "rate_above_1": "p1,A,1.5,0.3\np2,A,0.4,0.5\np3,A,0.2,0.1\n",
        "rate_negative": "p1,A,0.5,-0.2\np2,A,0.4,0.5\np3,A,0.2,0.1\n",
        "percent_no_flag": "p1,A,44,30\np2,A,52,61\np3,A,20,12\n",
        "percent_over_100": "p1,A,144,30\np2,A,52,61\np3,A,20,12\n",
        "percent_mixed": "p1,A,44,30\np2,A,0.52,0.61\np3,A,20,12\n",
        "percent_ok": "p1,A,44,30\np2,A,52,61\np3,A,20,12\n",
        "duplicate_conflict": "p1,A,0.4,0.3\np2,A,0.5,0.6\np1,A,0.9,0.8\n",
        "duplicate_same": "p1,A,0.4,0.3\np2,A,0.5,0.6\np1,A,0.4,0.3\n",
        "one_policy": "p1,A,0.4,0.3\np1,B,0.5,0.6\np2,B,0.2,0.1\np3,B,0.7,0.9\n",
        "two_policies": "p1,A,0.4,0.3\np2,A,0.5,0.6\n",
        "zero_variance": "p1,A,0.4,0.3\np2,A,0.5,0.3\np3,A,0.7,0.3\n",
        "nan_value": "p1,A,nan,0.3\np2,A,0.5,0.6\n",
        "empty_policy": ",A,0.4,0.3\np2,A,0.5,0.6\n",
    }
    for name, rows in csvs.items():
        (root / f"{name}.csv").write_text(CSV_HEADER + rows)
    (root / "bom.csv").write_bytes(b"\xef\xbb\xbf" + (CSV_HEADER + "p1,A,0.4,0.3\np2,A,0.5,0.6\np3,A,0.2,0.1\n").encode())
    (root / "not_utf8.csv").write_bytes(b"policy,task,real,sim\n\xff\xfe,A,0.1,0.2\n")


# ---------------------------------------------------------------------------- checks of accepted inputs
def _check_garbage_reported(res):
    code, err, metrics = res
    assert code == 0, err
    for n in range(3, 11):  # every garbage line is reported by its number
        assert f"records.jsonl:{n}:" in err, (n, err)
    assert "records.jsonl:11: no newline at the end" in err, err
    assert "not UTF-8" in err and "`seed` is 'abc'" in err and "`progression` is 1.5" in err
    assert metrics["overall"]["episodes"] == 2  # the two real records, nothing else counted


def _check_validate_undefined(res):
    code, out, data = res
    assert code == 0
    a = data["per_task"]["A"]
    assert a["pearson_r"] is None and a["mmrv"] is None and a["undefined"]["pearson_r"].startswith("1 policy")
    assert "undefined" in out.splitlines()[1]  # the table row of task A
    assert data["mean"]["pearson_r"] == data["per_task"]["B"]["pearson_r"] and data["mean"]["tasks"]["pearson_r"] == 1


def _check_validate_two(res):
    code, out, data = res
    assert code == 0 and data["per_task"]["A"]["pearson_r"] is None and data["per_task"]["A"]["mmrv"] is not None
    assert "2 policies, needs >= 3" in out


def _check_zero_variance(res):
    code, out, data = res
    assert code == 0 and data["per_task"]["A"]["pearson_r"] is None and "zero variance" in out


def _check_percent(res):
    code, out, data = res
    assert code == 0 and abs(data["per_task"]["A"]["rmsd"] - ((0.14**2 + 0.09**2 + 0.08**2) / 3) ** 0.5) < 1e-9


def _check_report(res):
    code, err, html = res
    assert code == 0, err
    assert "records.jsonl:3:" in err and "data:image/png;base64" in html


def _check_repo_default(cfg):
    assert cfg.repo_id == "realm/my_demos_v2", cfg.repo_id


def _check_scene(scene):
    assert scene.table_half_size == (0.4, 0.7, 0.02) and scene.table_height == 0.74


# ---------------------------------------------------------------------------- Python calls
def _eval_garbage(root):
    out = root / "run_garbage"
    r = _realm_in_process(ev(str(out)).split())
    return r.returncode, r.stderr, json.loads((out / "metrics.json").read_text())


def _validate(name, *flags, installed=False):
    def call(root):
        js = root / f"validate_{name}.json"
        r = (_realm if installed else _realm_in_process)(["validate", str(root / f"{name}.csv"), "--json", str(js), *flags])
        return r.returncode, r.stdout + r.stderr, json.loads(js.read_text()) if js.exists() else None

    return call


def _report_garbage(root):
    out = root / "reports" / "garbage.html"
    r = _realm_in_process(["eval", "report", str(root / "run_garbage"), "--out", str(out), "--videos", "none"])
    return r.returncode, r.stderr, out.read_text() if out.exists() else ""


def _export_config(**kw):
    def call(root):
        from realm_ms.lerobot.export import ExportConfig

        return ExportConfig(**{"tasks": [TASK], **{k: (v.format(root=root) if isinstance(v, str) else v) for k, v in kw.items()}})

    return call


def _scene(name):
    def call(root):
        from realm_ms.tasks.scenes import get_scene

        return get_scene(name)

    return call


def _make(**kw):
    def call(root):
        import gymnasium as gym

        import realm_ms  # noqa: F401

        env = gym.make(TASK, obs_mode="state", **kw)
        env.close()
        return env

    return call


def _model_setting(effect, **config):
    def call(root):
        from realm_ms.agents.robot_model import RobotModel

        return RobotModel.from_dict({"effects": [{"name": effect, "config": config}]}, "MODEL.yaml")

    return call


def _policy(spec, **options):
    def call(root):
        from realm_ms.eval.policies import make_policy

        return make_policy(spec, **options)

    return call


def _v_sc_small_catalog(root):
    """V-SC on a user catalog of 2 objects: the env says what is missing (not `only 2 objects ...`)."""
    import gymnasium as gym

    import realm_ms  # noqa: F401

    cat = root / "small_catalog"
    if not (cat / "catalog.jsonl").exists():
        r = _realm(["assets", "build", "--source", "procedural", "--variants", "1", "--limit", "2", "--no-coacd",
                    "--no-thumbnails", "--workers", "1", "--quiet", "--out", str(cat)])
        assert r.returncode == 0, r.stderr
    old = os.environ.get("REALM_ASSETS_DIR")
    os.environ["REALM_ASSETS_DIR"] = str(cat)
    try:
        env = gym.make(TASK, obs_mode="state", perturbation="V-SC")
        try:
            env.reset(seed=0)
        finally:
            env.close()
    finally:
        if old is None:
            os.environ.pop("REALM_ASSETS_DIR")
        else:
            os.environ["REALM_ASSETS_DIR"] = old


def _perturbations_list(root):
    from realm_ms.perturbations import all_perturbations

    r = _realm(["perturbations", "list"], environ={"COLUMNS": "100"})
    return r, [p.describe() for p in all_perturbations()]


def _check_list_wraps(res):
    r, rows = res
    assert r.returncode == 0 and max(map(len, r.stdout.splitlines())) <= 100, r.stdout
    words = r.stdout.split()
    for row in rows:  # every word of every "changes" and "ranges" text is printed: wrapped, not cut
        for w in f"{row['acts_on']} {row['ranges']}".split():
            assert w in words, (row["name"], w)


def _no_grpc() -> bool:
    import importlib.util

    return importlib.util.find_spec("grpc") is None


CASES: list[Case] = [
    # ------------------------------------------------------------------------ realm eval: numbers and specs
    cli("eval-seed-neg", ev("{root}/ev_seed", seed="-1"), r"argument --seed: must be >= 0, got -1"),
    cli("eval-seed-2-pow-40", ev("{root}/ev_seed", seed="1099511627776"), r"argument --seed: must be <= 4294967295"),
    cli("eval-seed-last-episode-overflows", ev("{root}/ev_seed", seed="4294967295"), r"--seed: seeds 4294967295\.\.4294967296 go past 2\*\*32 - 1"),
    cli("eval-seed-text", ev("{root}/ev_seed", seed="12ab"), r"argument --seed: expected an integer"),
    cli("eval-episodes-huge-no-hang", ev("{root}/ev_huge", episodes="1000000000"), r"--episodes 1000000000: at most 100000"),
    cli("eval-camera-size-three-parts", ev("{root}/ev_cam", camera_size="64x36x3"), r"--camera-size must be WxH"),
    cli("eval-openpi-wait-nan-no-hang", ev("{root}/ev_pi", policy="openpi:127.0.0.1:1", openpi_wait="nan"),
        r"argument --openpi-wait: must be a finite number", subprocess=True),
    cli("eval-openpi-wait-0", ev("{root}/ev_pi", policy="openpi:127.0.0.1:1", openpi_wait="0"), r"argument --openpi-wait: must be > 0 s"),
    cli("eval-openpi-wait-inf", ev("{root}/ev_pi", policy="openpi:127.0.0.1:1", openpi_wait="inf"), r"argument --openpi-wait: must be a finite"),
    cli("eval-openpi-port-99999", ev("{root}/ev_pi", policy="openpi:127.0.0.1:99999"), r"port: must be <= 65535, got 99999", subprocess=True),
    cli("eval-openpi-port-0", ev("{root}/ev_pi", policy="openpi:127.0.0.1:0"), r"port: must be >= 1, got 0"),
    cli("eval-openpi-no-address", ev("{root}/ev_pi", policy="openpi"), r"--policy openpi needs the server address"),
    cli("eval-lerobot-no-path", ev("{root}/ev_lr", policy="lerobot:"), r"--policy lerobot: needs a checkpoint", subprocess=True),
    cli("eval-lerobot-missing-dir", ev("{root}/ev_lr", policy="lerobot:/nonexistent/ckpt"), r"no such checkpoint directory /nonexistent/ckpt"),
    cli("eval-lerobot-is-file", ev("{root}/ev_lr", policy="lerobot:{root}/a_file.txt"), r"a_file\.txt is a file; give the checkpoint directory"),
    cli("eval-ray-address-no-port", ev("{root}/ev_ray", ray_address="ray://:5"), r"--ray-address ray://:5: expected ray://HOST:PORT"),
    cli("eval-ray-address-port-range", ev("{root}/ev_ray", ray_address="ray://10.0.0.1:70000"), r"port: must be <= 65535"),
    cli("eval-ray-client-missing", ev("{root}/ev_ray", ray_address="ray://127.0.0.1:10001"), r"Ray Client needs the `ray\[client\]` extra",
        marks=[pytest.mark.skipif(not _no_grpc(), reason="ray[client] is installed here")]),
    # ------------------------------------------------------------------------ realm eval: --out
    cli("eval-out-is-file", ev("{root}/a_file.txt"), r"--out: .*a_file\.txt exists and is a file; give a directory"),
    cli("eval-out-under-file", ev("{root}/a_file.txt/run"), r"--out: cannot create .*a_file\.txt/run: .*a_file\.txt is a file"),
    cli("eval-out-unwritable", ev("/sys/realm_run"), r"--out: cannot write /sys/realm_run: directory /sys is not writable"),
    cli("eval-out-run-json-is-dir", ev("{root}/run_json_dir"), r"--out: .*run_json_dir/run\.json is a directory; give a file path"),
    cli("eval-out-records-is-dir", ev("{root}/run_records_dir"), r"--out: .*run_records_dir/records\.jsonl is a directory", subprocess=True),
    cli("eval-out-metrics-is-dir", ev("{root}/run_metrics_dir"), r"--out: .*run_metrics_dir/metrics\.json is a directory"),
    cli("eval-out-videos-is-file", ev("{root}/run_videos_file", videos="all"), r"--out: .*run_videos_file/videos exists and is a file; give a directory"),
    # ------------------------------------------------------------------------ realm eval: resume contract
    cli("resume-other-max-steps-run-json", ev("{root}/run_ok", max_steps="3"),
        r"run_ok holds a run made differently \(max_steps 2 vs 3; theirs vs this command's\): use another --out", subprocess=True),
    cli("resume-other-policy-run-json", ev("{root}/run_ok", policy="random"),
        r"holds a run made differently \(policy zero vs random"),
    cli("resume-other-camera-size", ev("{root}/run_ok", camera_size="64x36"), r"holds a run made differently \(camera_size \[320,180\] vs \[64,36\]"),
    cli("resume-other-replan", ev("{root}/run_ok", replan_every="4"), r"holds a run made differently \(replan_every 8 vs 4"),
    cli("resume-records-without-run-json", ev("{root}/run_no_runjson", max_steps="3"),
        r"records\.jsonl: 2 of 2 record\(s\) were not made by this command \(line 1: max_steps 2 vs 3", subprocess=True),
    cli("resume-records-other-policy-without-run-json", ev("{root}/run_no_runjson", policy="random"),
        r"records\.jsonl: 2 of 2 record\(s\) were not made by this command \(line 1: policy zero vs random"),
    cli("resume-one-copied-record", ev("{root}/run_mixed"), r"records\.jsonl: 1 of 3 record\(s\) were not made by this command \(line 3: max_steps 3 vs 2"),
    cli("resume-records-without-fingerprint", ev("{root}/run_legacy"), r"line 1: no run fingerprint"),
    cli("resume-run-json-corrupt", ev("{root}/run_json_corrupt"), r"run_json_corrupt/run\.json: not valid JSON .*delete it to have this command rewrite it"),
    cli("resume-run-json-list", ev("{root}/run_json_list"), r"run\.json: expected a JSON object, got list"),
    cli("resume-run-json-binary", ev("{root}/run_json_binary"), r"run\.json: not UTF-8 text"),
    Case("resume-garbage-lines-reported-not-counted", call=_eval_garbage, check=_check_garbage_reported,
         accepted="lines that are not records are reported by line number, skipped, and never counted in metrics.json"),
    # ------------------------------------------------------------------------ realm eval report
    cli("report-reference-bogus", "eval report {root}/run_ok --reference bogus", r"--reference 'bogus': no paper numbers for it; known: pi0"),
    cli("report-out-is-dir", "eval report {root}/run_ok --out {root}/out_dir", r"--out: .*out_dir is a directory; give a file path"),
    cli("report-out-under-file", "eval report {root}/run_ok --out {root}/a_file.txt/r.html", r"--out: cannot create .*a_file\.txt is a file"),
    cli("report-files-dir-is-file", "eval report {root}/run_ok --out {root}/rep.html", r"--out \(its figures directory\): .*rep_files exists and is a file"),
    cli("report-run-missing", "eval report {root}/no_such_run", r"RUN .*no_such_run does not exist"),
    cli("report-run-is-file", "eval report {root}/a_file.txt", r"RUN .*a_file\.txt is a file"),
    cli("report-run-without-records", "eval report {root}/run_empty", r"run_empty has no records\.jsonl"),
    cli("report-only-garbage", "eval report {root}/run_only_garbage", r"records\.jsonl: no readable records \(.*records\.jsonl:1: `task` is missing"),
    cli("report-mixed-fingerprints", "eval report {root}/run_mixed", r"records\.jsonl: line 3 was made differently from line 1 \(max_steps 3 vs 2"),
    cli("report-records-without-fingerprint-mixed", "eval report {root}/run_half_legacy", r"line 3 was made differently .*one has no run fingerprint"),
    Case("report-garbage-lines-reported", call=_report_garbage, check=_check_report,
         accepted="a report over a run with garbage lines: written, the lines reported by number"),
    # ------------------------------------------------------------------------ realm validate
    cli("validate-rate-above-1", "validate {root}/rate_above_1.csv", r"rate_above_1\.csv:2: real = 1\.5 is outside \[0, 1\]"),
    cli("validate-rate-negative", "validate {root}/rate_negative.csv", r"rate_negative\.csv:2: sim = -0\.2 is outside \[0, 1\]"),
    cli("validate-percent-without-flag", "validate {root}/percent_no_flag.csv", r"real = 44 is outside \[0, 1\]; .*give --percent"),
    cli("validate-percent-over-100", "validate {root}/percent_over_100.csv --percent", r"real = 144 is outside \[0, 100\] \(--percent\)"),
    cli("validate-percent-mixed-fractions", "validate {root}/percent_mixed.csv --percent", r"fractions mixed with percentages \(line 3: 0\.52"),
    cli("validate-duplicate-conflicting", "validate {root}/duplicate_conflict.csv", r"duplicate_conflict\.csv:4: policy 'p1' on task 'A' is given again \(first on line 2\)"),
    cli("validate-duplicate-identical", "validate {root}/duplicate_same.csv", r"duplicate_same\.csv:4: policy 'p1' on task 'A' is given again"),
    cli("validate-nan", "validate {root}/nan_value.csv", r"nan_value\.csv:2: real must be finite"),
    cli("validate-empty-policy", "validate {root}/empty_policy.csv", r"empty_policy\.csv:2: empty policy or task name"),
    Case("validate-byte-order-mark", call=_validate("bom", installed=True), check=lambda res: res[0] == 0 or pytest.fail(res[1]),
         accepted="a spreadsheet's UTF-8 byte-order mark before the header is not part of the column name"),
    cli("validate-not-utf8", "validate {root}/not_utf8.csv", r"not_utf8\.csv: not a UTF-8 text"),
    cli("validate-csv-is-dir", "validate {root}/out_dir", r"out_dir is a directory, expected a CSV file"),
    cli("validate-json-is-dir", "validate {root}/percent_ok.csv --percent --json {root}/out_dir", r"--json: .*out_dir is a directory; give a file path"),
    cli("validate-json-under-file", "validate {root}/percent_ok.csv --percent --json {root}/a_file.txt/v.json", r"--json: cannot create .*a_file\.txt is a file"),
    Case("validate-one-policy-undefined", call=_validate("one_policy"), check=_check_validate_undefined,
         accepted="Pearson r and MMRV of a one-policy task are 'undefined' with the reason (not 1.0); the mean uses the other tasks"),
    Case("validate-two-policies-pearson-undefined", call=_validate("two_policies"), check=_check_validate_two,
         accepted="Pearson r needs >= 3 policies: undefined for 2; MMRV is defined"),
    Case("validate-zero-variance-undefined", call=_validate("zero_variance"), check=_check_zero_variance,
         accepted="Pearson r with every sim value equal: undefined (zero variance)"),
    Case("validate-percent-flag", call=_validate("percent_ok", "--percent"), check=_check_percent,
         accepted="--percent reads 0-100 values as rates / 100"),
    # ------------------------------------------------------------------------ realm export
    cli("export-episodes-huge", f"export --tasks {TASK} --episodes 1000000000 --out {{root}}/ex0", r"--episodes 1000000000: at most 100000"),
    cli("export-policy-unknown", f"export --tasks {TASK} --episodes 1 --policy nope --out {{root}}/ex_nope", r"unknown policy 'nope'; known: .*expert"),
    cli("export-policy-lerobot-missing", f"export --tasks {TASK} --episodes 1 --policy lerobot:/nonexistent/ckpt --out {{root}}/ex_nope",
        r"no such checkpoint directory /nonexistent/ckpt"),
    cli("export-episodes-0", f"export --tasks {TASK} --episodes 0 --out {{root}}/ex0", r"--episodes must be >= 1 \(got 0\)"),
    cli("export-max-steps-0", f"export --tasks {TASK} --episodes 1 --max-steps 0 --out {{root}}/ex0", r"--max-steps must be >= 1 \(got 0\)"),
    cli("export-max-steps-neg", f"export --tasks {TASK} --episodes 1 --max-steps -8 --out {{root}}/ex0", r"--max-steps must be >= 1"),
    cli("export-repo-id-bad", f"export --tasks {TASK} --episodes 1 --out {{root}}/ex0 --repo-id bad_id/with/../slashes!",
        r"--repo-id 'bad_id/with/\.\./slashes!' is not a Hub repo id"),
    cli("export-repo-id-no-owner", f"export --tasks {TASK} --episodes 1 --out {{root}}/ex0 --repo-id demos", r"--repo-id 'demos' is not a Hub repo id"),
    cli("export-out-is-file", f"export --tasks {TASK} --episodes 1 --out {{root}}/a_file.txt", r"--out: .*a_file\.txt exists and is a file", subprocess=True),
    cli("export-out-under-file", f"export --tasks {TASK} --episodes 1 --out {{root}}/a_file.txt/ds", r"--out: cannot create .*a_file\.txt is a file"),
    cli("export-out-unwritable", f"export --tasks {TASK} --episodes 1 --out /sys/realm_ds", r"--out: cannot write /sys/realm_ds"),
    cli("export-out-not-a-dataset", f"export --tasks {TASK} --episodes 1 --out {{root}}/not_a_dataset", r"not_a_dataset exists and is not a LeRobot dataset"),
    cli("export-seed-neg", f"export --tasks {TASK} --episodes 1 --seed -3 --out {{root}}/ex0", r"argument --seed: must be >= 0"),
    cli("export-seed-overflow", f"export --tasks {TASK} --episodes 3 --seed 4294967294 --out {{root}}/ex0", r"--seed: seeds 4294967294\.\.4294967296 go past"),
    cli("export-commit-every-0", f"export --tasks {TASK} --episodes 1 --commit-every 0 --out {{root}}/ex0", r"--commit-every must be >= 1 \(got 0\)"),
    cli("export-from-eval-missing", "export --from-eval {root}/no_such_run --out {root}/ex0", r"--from-eval: .*no_such_run.* does not exist"),
    cli("export-from-eval-with-episodes", "export --from-eval {root}/run_ok --episodes 2 --out {root}/ex0", r"--from-eval exports one episode per record.*drop --episodes"),
    cli("export-from-eval-only-garbage", "export --from-eval {root}/run_only_garbage --out {root}/ex0", r"no realm eval records found"),
    cli("export-from-eval-two-robots", "export --from-eval {root}/run_two_robots --out {root}/ex0",
        r"run_two_robots/records\.jsonl: its records ran 2 robot models \(nominal, droid-aligned\).*split records\.jsonl by robot_model"),
    cli("export-from-eval-robot-contradicts", "export --from-eval {root}/run_ok --robot-model droid-aligned --out {root}/ex0",
        r"--robot-model droid-aligned contradicts .*run_ok.*ran robot model nominal; drop --robot-model"),
    cli("export-tasks-all-and-more", f"export --tasks all {TASK} --episodes 1 --out {{root}}/ex0", r"--tasks all stands alone"),
    cli("export-unknown-task", "export --tasks REALM-Nope-v1 --episodes 1 --out {root}/ex0", r"unknown task\(s\) \['REALM-Nope-v1'\]"),
    Case("export-default-repo-id-from-odd-dir-name", call=_export_config(out="{root}/my demos!!v2"), check=_check_repo_default,
         accepted="the default repo id realm/<out dir name> is made a valid Hub id (realm/my_demos_v2)"),
    # ------------------------------------------------------------------------ realm perturbations sheet
    cli("sheet-out-is-dir", f"perturbations sheet --task {TASK} --out {{root}}/out_dir", r"--out: .*out_dir is a directory; give a file path"),
    cli("sheet-out-under-file", f"perturbations sheet --task {TASK} --out {{root}}/a_file.txt/s.png", r"--out: cannot create .*a_file\.txt is a file"),
    cli("sheet-out-not-an-image", f"perturbations sheet --task {TASK} --out {{root}}/sheet.txt", r"--out .*sheet\.txt: the sheet is an image"),
    cli("sheet-one-of-two-outputs-is-dir", f"perturbations sheet --task {TASK} --task REALM-PickApple-v1 --out {{root}}/sh.png",
        r"--out: .*sh_REALM-PickApple-v1\.png is a directory"),
    cli("sheet-seed-neg", f"perturbations sheet --task {TASK} --out {{root}}/s.png --seed -1", r"argument --seed: must be >= 0"),
    cli("sheet-width-0", f"perturbations sheet --task {TASK} --out {{root}}/s.png --width 0", r"argument --width: must be >= 16"),
    cli("sheet-height-huge", f"perturbations sheet --task {TASK} --out {{root}}/s.png --height 100000", r"argument --height: must be <= 4096"),
    cli("sheet-shader-bogus", f"perturbations sheet --task {TASK} --out {{root}}/s.png --shader bogus", r"argument --shader: invalid choice: 'bogus'"),
    Case("perturbations-list-wraps", call=_perturbations_list, check=_check_list_wraps,
         accepted="`realm perturbations list` wraps its changes and ranges columns to the terminal, never cuts them"),
    Case("v-sc-small-user-catalog", call=_v_sc_small_catalog, env=True,
         error=r"V-SC draws 3 object\(s\) of different categories .* catalog at .*small_catalog has \d+ in \d+ categor.*missing categories: .*realm assets build --source procedural"),
    # ------------------------------------------------------------------------ realm assets build
    cli("assets-build-empty-folder", "assets build --source {root}/empty_source --out {root}/cat_empty --quiet",
        r"no objects found in .*empty_source; nothing was built"),
    # ------------------------------------------------------------------------ gym.make keywords, scene names
    Case("env-unknown-keyword", call=_make(camera_widht=64), env=True,
         error=r"unknown gym\.make keyword\(s\) 'camera_widht' \(did you mean 'camera_width'\?\); REALM keywords: .*ManiSkill keywords: "),
    Case("env-scene-name-keyword", call=_make(scene_name="kitchen"), env=True,
         error=r"unknown gym\.make keyword\(s\) 'scene_name' \(did you mean 'scene'\?\)"),
    Case("env-num-envs-0", call=_make(num_envs=0), env=True, error=r"num_envs must be >= 1, got 0"),
    Case("env-num-envs-fraction", call=_make(num_envs=1.5), env=True, error=r"num_envs must be a whole number"),
    Case("env-scene-key-twice", call=_make(scene="kitchen?table_height=0.74&table_height=0.9"), env=True,
         error=r"option 'table_height' is given twice \('0\.74', '0\.9'\)"),
    Case("scene-tuple-text", call=_scene("kitchen?table_half_size=abc"), error=r"table_half_size='abc': expected 3 comma-separated numbers"),
    Case("scene-tuple-wrong-length", call=_scene("kitchen?table_half_size=0.4,0.7"), error=r"expected 3 comma-separated numbers"),
    Case("scene-half-size-neg", call=_scene("kitchen?table_half_size=-0.4,0.7,0.02"), error=r"half sizes must be > 0"),
    Case("scene-height-nan", call=_scene("kitchen?table_height=nan"), error=r"table_height='nan': expected a finite number"),
    Case("scene-height-text", call=_scene("kitchen?table_height=tall"), error=r"table_height='tall': expected a float"),
    Case("scene-seed-fraction", call=_scene("kitchen?seed=1.5"), error=r"seed='1\.5': expected an int"),
    Case("scene-no-value", call=_scene("kitchen?table_height"), error=r"malformed options 'table_height'"),
    Case("scene-nested-option", call=_scene("kitchen?lamps=1"), error=r"option 'lamps' cannot be set in a scene name"),
    Case("scene-tuple-accepted", call=_scene("kitchen?table_half_size=0.4,0.7,0.02&table_height=0.74"), check=_check_scene,
         accepted="a tuple option is comma-separated numbers; several keys combine"),
    # ------------------------------------------------------------------------ model files: effect settings
    Case("model-direction-velocity-0", call=_model_setting("coulomb_friction", direction_velocity=0),
         error=r"MODEL\.yaml: effects\[0\]\.config\.direction_velocity: must be > 0 rad/s"),
    Case("model-direction-velocity-neg", call=_model_setting("coulomb_friction", direction_velocity=-0.01),
         error=r"direction_velocity: must be > 0 rad/s"),
    Case("model-direction-velocity-text", call=_model_setting("coulomb_friction", direction_velocity="fast"),
         error=r"direction_velocity: expected a finite number"),
    Case("model-asymmetric-text", call=_model_setting("coulomb_friction", asymmetric="yes"), error=r"asymmetric: expected true or false"),
    Case("model-torque-width-zero", call=_model_setting("backlash", torque_width=[1, 1, 1, 1, 0.2, 0.2, 0]), error=r"torque_width: must be > 0 N·m"),
    Case("model-torque-width-short", call=_model_setting("backlash", torque_width=[1, 1]), error=r"torque_width: expected a list of 7 numbers"),
    Case("model-payload-offset-inf", call=_model_setting("payload", offset=[0, 0, float("inf")]), error=r"offset: expected finite numbers"),
    cli("model-file-direction-velocity-0", f"sysid compare {{root}}/good --model {{root}}/models/direction_velocity_0.yaml --device cpu --workers 1",
        r"direction_velocity_0\.yaml: effects\[0\]\.config\.direction_velocity: must be > 0 rad/s"),
    # ------------------------------------------------------------------------ repeated flags: an error, or they accumulate
    cli("eval-seed-twice", ev("{root}/ev_seed", seed="1") + " --seed 2", r"argument --seed: given twice \(1, then 2\); give it once"),
    cli("eval-policy-twice", ev("{root}/ev_twice") + " --policy random", r"argument --policy: given twice \('zero', then 'random'\)"),
    cli("eval-tasks-twice-accumulate", ev("{root}/ev_twice") + " --tasks REALM-Nope-v1", r"unknown task\(s\) REALM-Nope-v1"),
    cli("report-out-twice", "eval report {root}/run_ok --out {root}/a.html --out {root}/b.html", r"argument --out: given twice \('.*a\.html', then"),
    cli("validate-json-twice", "validate {root}/percent_ok.csv --json {root}/a.json --json {root}/b.json", r"argument --json: given twice"),
    cli("export-repo-id-twice", f"export --tasks {TASK} --episodes 1 --out {{root}}/ex0 --repo-id a/b --repo-id c/d", r"argument --repo-id: given twice"),
    cli("export-tasks-twice-accumulate", f"export --tasks {TASK} --tasks REALM-Nope-v1 --episodes 1 --out {{root}}/ex0",
        r"unknown task\(s\) \['REALM-Nope-v1'\]"),
    cli("sheet-seed-twice", f"perturbations sheet --task {TASK} --out {{root}}/s.png --seed 1 --seed 2", r"argument --seed: given twice"),
    cli("assets-out-twice", "assets build --source procedural --out {root}/c1 --out {root}/c2", r"argument --out: given twice"),
    cli("demo-out-twice", "demo --out {root}/d1 --out {root}/d2", r"argument --out: given twice"),
    cli("render-out-twice", "render sheet --out {root}/r1.png --out {root}/r2.png", r"argument --out: given twice"),
    cli("sysid-compare-json-twice", "sysid compare {root}/nope --json {root}/a.json --json {root}/b.json", r"argument --json: given twice"),
    # ------------------------------------------------------------------------ policy specs (Python API)
    Case("api-openpi-port-99999", call=_policy("openpi:127.0.0.1:99999"), error=r"port: must be <= 65535"),
    Case("api-openpi-wait-nan", call=_policy("openpi:127.0.0.1:1", openpi_wait_s=float("nan")), error=r"--openpi-wait: must be a finite"),
]


def make_model_files(root: Path) -> None:
    p = root / "models" / "direction_velocity_0.yaml"
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text("effects: [{name: coulomb_friction, config: {direction_velocity: 0}}]\n")
