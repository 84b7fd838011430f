"""`--ray-address local`: (task, perturbation) cells sharded over a local Ray; records stream back."""

import json

import pytest

from realm_ms.cli import main

ray = pytest.importorskip("ray", reason="ray is in the dev extra")


@pytest.mark.slow
def test_ray_local_shards_cells(tmp_path):
    out = tmp_path / "run_ray"
    try:
        assert main(["eval", "--policy", "zero", "--tasks", "REALM-PickApple-v1", "REALM-PushSwitch-v1", "--perturbations", "Default",
                     "--episodes", "2", "--max-steps", "8", "--ray-address", "local", "--no-progress", "--no-quality", "--out", str(out)]) == 0
    finally:
        ray.shutdown()
    recs = [json.loads(line) for line in (out / "records.jsonl").read_text().splitlines()]
    assert sorted((r["task"], r["seed"]) for r in recs) == [(t, s) for t in ("REALM-PickApple-v1", "REALM-PushSwitch-v1") for s in (1234, 1235)]
    assert all(r["status"] == "ok" and r["steps"] == 8 for r in recs)
    assert json.loads((out / "metrics.json").read_text())["overall"]["episodes"] == 4
