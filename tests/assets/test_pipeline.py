"""Processing stages on small fixtures, caching, failure isolation and resume."""

from __future__ import annotations

import importlib.util
import json
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from asset_pipeline.build import SourceUnavailable, build_catalog
from asset_pipeline.config import BuildConfig
from asset_pipeline.export import read_convex_obj
from asset_pipeline.process import process_item
from asset_pipeline.record import read_catalog
from asset_pipeline.sources.source import SourceItem
from asset_pipeline.stages.decompose import CoacdSettings, decompose
from asset_pipeline.stages.normalize import guess_units

_spec = importlib.util.spec_from_file_location("asset_meshes", Path(__file__).parent / "fixtures" / "meshes.py")
meshes = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(meshes)

FAST = BuildConfig(use_coacd=False, thumbnails=True, object_timeout_s=60)


@pytest.fixture(scope="module")
def user_folder(tmp_path_factory):
    """A user mesh folder laid out as <category>/<mesh>: two good meshes, two bad ones."""
    root = tmp_path_factory.mktemp("user_meshes")
    meshes.textured(root / "cube")
    (root / "mug").mkdir()
    meshes.huge_scale(root / "mug")
    (root / "bowl").mkdir()
    meshes.non_watertight(root / "bowl")
    (root / "junk").mkdir()
    meshes.broken(root / "junk")
    meshes.empty(root / "junk")
    return root


def _item(path: Path, category: str, **kw) -> SourceItem:
    return SourceItem(id=f"t/{path.stem}", source="test", licence="test", category=category, mesh=str(path), **kw)


def test_textured_mesh_keeps_texture_and_estimates_colour(tmp_path):
    p = meshes.textured(tmp_path / "src")
    o = process_item(_item(p, "cube"), tmp_path / "cat", FAST)
    assert o.status == "built", o.error
    r = o.record
    assert r["textured"] and r["real_mesh"]
    assert set(r["colors"]) & {"red", "dark red", "blue"}
    vis = trimesh.load(tmp_path / "cat" / r["visual"], force="scene")
    mats = [g.visual.material for g in vis.geometry.values()]
    assert any(getattr(m, "baseColorTexture", None) is not None for m in mats), "texture survives into the GLB"
    assert (tmp_path / "cat" / r["thumbnail"]).stat().st_size > 200


def test_huge_scale_mesh_is_rescaled_and_rests_at_origin(tmp_path):
    assert guess_units(100.0)[0] == "mm" and guess_units(8.0)[0] == "cm" and guess_units(0.2)[0] == "m"
    p = meshes.huge_scale(tmp_path)
    o = process_item(_item(p, "mug"), tmp_path / "cat", FAST)
    assert o.status == "built", o.error
    ext = np.array(o.record["extents"])
    assert 0.05 < ext.max() < 0.2, ext  # millimetres -> a mug-sized object
    hulls = read_convex_obj(tmp_path / "cat" / o.record["collision"])
    v = np.vstack([h.vertices for h in hulls])
    assert abs(v[:, 2].min()) < 1e-6 and np.allclose((v[:, :2].min(0) + v[:, :2].max(0)) / 2, 0, atol=1e-6)
    assert 0.05 < o.record["mass"] < 1.0


def test_non_watertight_mesh_gets_closed_volume_and_mass(tmp_path):
    p = meshes.non_watertight(tmp_path)
    o = process_item(_item(p, "bowl", known_scale=True), tmp_path / "cat", FAST)
    assert o.status == "built", o.error
    assert o.record["collision_volume"] > 0.5 * 0.1**3  # the open box is filled/hulled, not zero
    assert o.record["mass"] > 0


@pytest.mark.parametrize("maker", [meshes.broken, meshes.empty])
def test_broken_mesh_fails_cleanly(tmp_path, maker):
    o = process_item(_item(maker(tmp_path), "cube"), tmp_path / "cat", FAST)
    assert o.status == "failed" and o.error
    assert not (tmp_path / "cat" / "objects").exists() or not any((tmp_path / "cat" / "objects").iterdir())


def test_coacd_splits_concave_mesh_and_budget_falls_back(tmp_path):
    m = trimesh.load(meshes.concave(tmp_path), force="mesh")
    d = decompose(m, CoacdSettings(budget_s=60, mcts_iterations=20, preprocess_resolution=20), cache_dir=tmp_path / "c")
    assert d.method == "coacd" and len(d.hulls) >= 2
    assert sum(h.volume for h in d.hulls) < 0.9 * m.convex_hull.volume  # the notch is kept
    again = decompose(m, CoacdSettings(budget_s=60, mcts_iterations=20, preprocess_resolution=20), cache_dir=tmp_path / "c")
    assert again.cached and len(again.hulls) == len(d.hulls)
    tight = decompose(m, CoacdSettings(budget_s=0.001, mcts_iterations=21), cache_dir=None)
    assert tight.method == "hull-fallback:budget" and len(tight.hulls) == 1
    box = trimesh.creation.box(extents=(0.05, 0.05, 0.05))
    assert decompose(box, CoacdSettings()).method == "convex"  # convex inputs never reach CoACD


def test_build_isolates_failures_caches_and_resumes(tmp_path, user_folder):
    out = tmp_path / "cat"
    rep = build_catalog([str(user_folder), "procedural"], out, BuildConfig(use_coacd=False, procedural_variants=2, workers=1), progress=False,
                        limit_per_source=None)
    n_proc = 2 * len(__import__("asset_pipeline.procedural", fromlist=["REGISTRY"]).REGISTRY)
    assert rep.failed == 2 and rep.built == n_proc + 3
    fails = [json.loads(l) for l in (out / "failures.jsonl").read_text().splitlines()]
    assert sorted(f["id"] for f in fails) == ["user/junk/broken", "user/junk/empty"]
    recs = {r.id: r for r in read_catalog(out)}
    assert len(recs) == n_proc + 3 and recs["user/mug/mug_in_mm"].category == "mug"

    t0 = time.perf_counter()
    rep2 = build_catalog([str(user_folder), "procedural"], out, BuildConfig(use_coacd=False, procedural_variants=2), progress=False)
    assert rep2.built == 0 and rep2.cached == n_proc + 3 and rep2.failed == 2
    assert time.perf_counter() - t0 < 20  # unchanged sources: hashes only

    # Crash/resume: drop some finished objects; only those are rebuilt.
    import shutil

    gone = sorted((out / "objects").iterdir())[:3]
    for d in gone:
        shutil.rmtree(d)
    rep3 = build_catalog([str(user_folder), "procedural"], out, BuildConfig(use_coacd=False, procedural_variants=2), progress=False)
    assert rep3.built == 3 and rep3.cached == n_proc


def test_changed_source_file_is_rebuilt(tmp_path):
    src = tmp_path / "src" / "mug"
    src.mkdir(parents=True)
    p = meshes.huge_scale(src)
    out = tmp_path / "cat"
    assert build_catalog([str(tmp_path / "src")], out, FAST, progress=False).built == 1
    trimesh.creation.cylinder(radius=45.0, height=90.0).export(p)
    rep = build_catalog([str(tmp_path / "src")], out, FAST, progress=False)
    assert rep.built == 1 and rep.cached == 0


def test_parallel_workers_match_serial(tmp_path):
    cfg1 = BuildConfig(use_coacd=False, thumbnails=False, procedural_variants=1, workers=1)
    cfg2 = BuildConfig(use_coacd=False, thumbnails=False, procedural_variants=1, workers=2)
    # 16 objects: enough for both workers to take several (every object is built alike;
    # test_build_isolates_failures_caches_and_resumes builds the whole procedural set)
    r1 = build_catalog(["procedural"], tmp_path / "a", cfg1, progress=False, limit_per_source=16)
    r2 = build_catalog(["procedural"], tmp_path / "b", cfg2, progress=False, limit_per_source=16)
    assert r1.built == r2.built == 16
    a = {r.id: r.mass for r in read_catalog(tmp_path / "a")}
    b = {r.id: r.mass for r in read_catalog(tmp_path / "b")}
    assert a == b


def test_unknown_source_is_a_clear_error(tmp_path):
    with pytest.raises(SourceUnavailable, match="unknown source"):
        build_catalog(["nope"], tmp_path, FAST, progress=False)
