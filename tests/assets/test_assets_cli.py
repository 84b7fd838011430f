"""`realm assets build|stats` end to end (small procedural build), and the Ray backend."""

from __future__ import annotations

import json

import pytest

from asset_pipeline.record import read_catalog
from realm_ms.cli import main


def test_build_and_stats_cli(tmp_path, capsys, monkeypatch):
    out = tmp_path / "cat"
    rc = main(["assets", "build", "--source", "procedural", "--variants", "1", "--out", str(out), "--workers", "1", "--quiet", "--json"])
    assert rc == 0
    rep = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert rep["built"] == rep["total"] >= 40 and rep["failed"] == 0
    monkeypatch.setenv("REALM_ASSETS_DIR", str(out))  # stats without a path reads the default location
    assert main(["assets", "stats", "--json"]) == 0
    st = json.loads(capsys.readouterr().out)
    assert st["objects"] == rep["total"] and st["categories"] == rep["total"]
    assert st["unseen_objects"] > 0 and st["real_mesh_objects"] == 0
    assert set(st) >= {"objects", "categories", "real_mesh_objects", "unseen_objects", "by_category", "by_source"}
    assert (out / "contact_sheet.png").stat().st_size > 1000
    assert main(["assets", "stats", str(out)]) == 0
    assert "categories" in capsys.readouterr().out


def test_cli_user_errors(tmp_path, capsys):
    assert main(["assets", "build", "--out", str(tmp_path)]) == 2
    assert "--source" in capsys.readouterr().err
    assert main(["assets", "build", "--source", "no_such_source", "--out", str(tmp_path)]) == 2
    assert "unknown source" in capsys.readouterr().err
    assert main(["assets", "stats", str(tmp_path / "missing")]) == 2
    assert "no catalog" in capsys.readouterr().err


def test_ray_backend_matches_local(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray backend test needs `pip install ray`")
    from asset_pipeline.build import build_catalog
    from asset_pipeline.config import BuildConfig

    cfg = BuildConfig(use_coacd=False, thumbnails=False, procedural_variants=1, workers=2)
    try:
        rep = build_catalog(["procedural"], tmp_path / "ray", cfg, ray=True, progress=False, limit_per_source=12)
    finally:
        ray.shutdown()
    local = build_catalog(["procedural"], tmp_path / "local", cfg, progress=False, limit_per_source=12)
    assert rep.backend == "ray" and rep.built == local.built == 12 and rep.failed == 0
    a = {r.id: (r.mass, r.extents) for r in read_catalog(tmp_path / "ray")}
    b = {r.id: (r.mass, r.extents) for r in read_catalog(tmp_path / "local")}
    assert a == b
