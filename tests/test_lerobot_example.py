"""examples/train_eval_loop.py end to end in its ``--smoke`` variant: export -> lerobot-train (with
LeRobot's in-training eval on the ``realm`` env type) -> ``realm eval`` (Default + V-AUG) -> report."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _example():
    spec = importlib.util.spec_from_file_location("train_eval_loop", ROOT / "examples" / "train_eval_loop.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_train_eval_loop_smoke(tmp_path, capsys):
    out = tmp_path / "te"
    assert _example().main(["--smoke", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    report = out / "eval" / "report.html"
    assert f"report: {report.resolve()}" in printed and report.exists()
    ckpt = out / "train" / "checkpoints" / "last" / "pretrained_model"
    assert (ckpt / "model.safetensors").exists()
    cfg = json.loads((ckpt / "config.json").read_text())
    assert cfg["type"] == "act"
    assert set(cfg["input_features"]) == {"observation.state", "observation.images.exterior_1_left",
                                          "observation.images.exterior_2_left", "observation.images.wrist_left"}
    # LeRobot evaluated the checkpoint on the realm env type during training
    assert list((out / "train" / "eval").rglob("eval_episode_0.mp4"))
    records = [json.loads(line) for line in (out / "eval" / "records.jsonl").read_text().splitlines() if line.strip()]
    assert sorted(r["perturbation"] for r in records) == ["Default", "V-AUG"]
    assert all(r["status"] == "ok" and r["policy"].startswith("lerobot:") for r in records)
