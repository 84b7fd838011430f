"""examples/train_eval_loop.py (`make train-eval-demo`) end to end in its ``--quick`` variant: expert
demos -> one dataset -> lerobot-train -> the perturbation table -> Default and the worst perturbation
-> fine-tune on expert demos under it -> re-evaluation -> reports and summary; then its stages resume
without redoing their work."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _example():
    spec = importlib.util.spec_from_file_location("train_eval_loop", ROOT / "examples" / "train_eval_loop.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses resolve their module by name
    spec.loader.exec_module(mod)
    return mod


def _records(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "records.jsonl").read_text().splitlines() if line.strip()]


def test_train_eval_loop_quick_runs_every_stage_and_resumes(tmp_path, capsys):
    ex = _example()
    out = tmp_path / "te"
    assert ex.main(["--quick", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"report: {(out / 'report.html').resolve()}" in printed and (out / "report.html").exists()
    ckpt = out / "train" / "checkpoints" / "last" / "pretrained_model"
    cfg = json.loads((ckpt / "config.json").read_text())
    assert cfg["type"] == "act" and set(cfg["input_features"]) == {
        "observation.state", "observation.images.exterior_1_left", "observation.images.exterior_2_left",
        "observation.images.wrist_left"}
    # the quick table is Default + V-AUG, so V-AUG is the perturbation fine-tuned on
    summary = json.loads((out / "summary.json").read_text())
    assert summary["worst_perturbation"] == "V-AUG"
    assert {(r["task"], r["perturbation"]) for r in summary["rows"]} == {("REALM-PickApple-v1", "Default"),
                                                                         ("REALM-PickApple-v1", "V-AUG")}
    assert all(r["base"][1] == 1 and r["finetuned"][1] == 1 for r in summary["rows"])
    assert set(summary["table"]["REALM-PickApple-v1"]) == {"Default", "V-AUG"}
    assert "fine-tuning delta" in printed and "V-AUG" in printed
    # checkpoint selection evaluated every checkpoint on validation seeds, never the reported ones
    assert [v["step"] for v in summary["validation"]["finetune"]] == [1, 2]
    assert len(summary["validation"]["train"]) == 1 and summary["validation"]["train"][0]["episodes"] == 1
    val_seeds = {r["seed"] for r in _records(out / "eval" / "val_finetune_000001")}
    assert val_seeds and min(val_seeds) >= 50_000 and {r["seed"] for r in _records(out / "eval" / "default")} == {0}
    # the fine-tuned policy started from the base checkpoint, on the original demos + demos under V-AUG
    ft = json.loads((out / "finetune" / "checkpoints" / "last" / "pretrained_model" / "train_config.json").read_text())
    assert Path(ft["policy"]["pretrained_path"]).resolve() == ckpt.resolve()
    assert json.loads((out / "dataset_V-AUG" / "meta" / "info.json").read_text())["total_episodes"] == 2
    for run, perts in (("default", {"Default"}), ("table", {"Default", "V-AUG"}), ("worst", {"V-AUG"}),
                       ("finetuned", {"Default", "V-AUG"})):
        recs = _records(out / "eval" / run)
        assert {r["perturbation"] for r in recs} == perts and all(r["status"] == "ok" for r in recs)
    # the fine-tuned policy evaluated is one of the fine-tuning checkpoints that validation compared
    (used,) = {r["policy"] for r in _records(out / "eval" / "finetuned")}
    assert used in {f"lerobot:{v['checkpoint']}" for v in summary["validation"]["finetune"]}
    curve = (out / "learning_curve.csv").read_text().splitlines()
    assert curve[0] == "run,step,loss,l1_loss" and {line.split(",")[0] for line in curve[1:]} == {"train", "finetune"}
    assert (out / "learning_curve.png").stat().st_size > 0

    # a rerun resumes: each stage finds its work done. The recipe's own skips (merge, train) are asked
    # directly and one `realm eval` stage is rerun, so that its arguments are checked to be those
    # its run directory was made with; `realm eval`'s and `realm export`'s own resume are tested in
    # tests/eval/test_resume.py and tests/lerobot/test_export.py (a whole second run cost ~100 s of CPU)
    r = ex.parse(["--quick", "--out", str(out)])
    info = out / "dataset" / "meta" / "info.json"
    made = info.stat().st_mtime_ns
    assert ex.merge([out / "demos" / "demos_PickApple"], out / "dataset", "realm/dataset") == out / "dataset"
    assert info.stat().st_mtime_ns == made  # not aggregated again
    assert ex.train(r, out / "dataset", out / "train", r.steps) == ckpt
    assert ex.train(r, out / "dataset_V-AUG", out / "finetune", r.finetune_steps, init=ckpt).exists()
    assert capsys.readouterr().out.count("exists") == 2  # both checkpoints kept, no lerobot-train started
    (evaluated,) = {rec["policy"] for rec in _records(out / "eval" / "default")}  # the checkpoint validation chose
    n = len(_records(out / "eval" / "default"))
    ex.evaluate(r, Path(evaluated.removeprefix("lerobot:")), out / "eval" / "default", ["Default"], r.eval_episodes)
    assert len(_records(out / "eval" / "default")) == n


def test_fine_tuning_skips_what_a_language_blind_policy_cannot_observe():
    ex = _example()
    assert not any(ex.observable(p, language=False) for p in ("S-LANG", "SB-NOUN", "S-LANG+SB-VRB"))
    assert all(ex.observable(p, language=False) for p in ("V-AUG", "VB-POSE", "VSB-NOBJ", "B-HOBJ", "S-LANG+V-AUG"))
    assert ex.observable("SB-NOUN", language=True)


def test_recipe_loads_data_in_the_trainer_on_cpu_and_in_loader_processes_on_a_gpu(monkeypatch):
    import torch

    ex = _example()
    monkeypatch.setattr(ex.os, "cpu_count", lambda: 16)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)  # the GPU machine's answer
    assert ex.parse([]).dataloader_workers() == 0
    gpu = ex.parse(["--device", "cuda", "--batch-size", "64"])
    assert (gpu.dataloader_workers(), gpu.batch_size) == (14, 64)
    assert ex.parse(["--device", "cuda", "--loader-workers", "3"]).dataloader_workers() == 3
    assert ex.parse(["--quick", "--loader-workers", "1"]).dataloader_workers() == 1


def test_recipe_camera_size_reaches_every_stage_and_bad_sizes_are_refused(capsys):
    import pytest

    ex = _example()
    r = ex.parse(["--camera-size", "128x96"])
    assert (r.width, r.height) == (128, 96) and (ex.parse([]).width, ex.parse([]).height) == (64, 48)
    for bad, why in (("128", "must be WxH"), ("wide", "must be WxH"), ("0x96", "must be in [8, 4096]")):
        with pytest.raises(SystemExit):
            ex.parse(["--camera-size", bad])
        assert why in capsys.readouterr().err


def test_recipe_demo_counts_are_one_per_task(capsys):
    import pytest

    ex = _example()
    assert ex.parse(["--demos", "70,45"]).demos == (70, 45) and ex.parse([]).demos == (60, 40)
    assert ex.parse(["--quick", "--demos", "2"]).demos == (2,)
    for bad, why in (("70", "one count >= 1 per task (PickApple, OpenDrawer)"), ("70,0", "got 70,0"),
                     ("a,b", "give whole numbers")):
        with pytest.raises(SystemExit):
            ex.parse(["--demos", bad])
        assert why in capsys.readouterr().err


def test_recipe_flags_are_checked_before_any_stage(tmp_path, capsys, monkeypatch):
    """`--steps -1` used to traceback, and `--device cuda` without a GPU failed in LeRobot's driver
    after the demo and training stages: each is one line at parse time, before anything runs."""
    import pytest
    import torch

    ex = _example()
    (tmp_path / "afile").write_text("x")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    for argv, why in ((["--steps", "-1"], "argument --steps: must be >= 1, got -1"),
                      (["--steps", "1.5"], "argument --steps: expected an integer"),
                      (["--batch-size", "0"], "argument --batch-size: must be >= 1"),
                      (["--workers", "0"], "argument --workers: must be >= 1"),
                      (["--threads", "0"], "argument --threads: must be >= 1"),
                      (["--loader-workers", "-1"], "argument --loader-workers: must be >= 0"),
                      (["--out", str(tmp_path / "afile")], "afile exists and is a file; give a directory"),
                      (["--out", str(tmp_path / "afile" / "sub")], "is a file"),
                      (["--device", "cuda"], "--device cuda: no CUDA GPU is available here"),
                      (["--device", "cuda:x"], "unknown device 'cuda:x'")):
        with pytest.raises(SystemExit) as e:
            ex.main(argv)
        err = capsys.readouterr()
        assert e.value.code == 2 and why in err.err.strip().splitlines()[-1], (argv, err.err)
        assert "===" not in err.out  # no stage started
    assert not (tmp_path / "afile").is_dir()
