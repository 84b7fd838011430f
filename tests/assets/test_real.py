"""Real meshes for task nouns: shipped as package data, fitted to real sizes, procedural fallback when missing."""

import json
import warnings

import numpy as np
import pytest
import trimesh

from asset_pipeline.export import read_convex_obj
from realm_ms.assets import get_object_spec, task_object_spec
from realm_ms.assets import real_objects as ro
from realm_ms.assets.catalog import procedural_spec

TEXTURED = {"apple", "bowl", "mug", "box"}  # the sources with a texture; the others are painted


@pytest.mark.parametrize("name", sorted(ro.REAL_OBJECTS))
def test_real_object_is_shipped_at_real_size_with_its_counterparts_physics(name):
    spec = get_object_spec(ro.PREFIX + name)
    ref = procedural_spec(ro.REAL_OBJECTS[name].fallback)
    assert spec.id == ro.PREFIX + name and spec.record.real_mesh
    assert spec.root == ro.SHIPPED_DIR / name  # package data: nothing built at run time
    assert spec.max_extent == pytest.approx(ref.max_extent, rel=1e-3)
    assert spec.mass == pytest.approx(ref.mass) and spec.record.friction == ref.record.friction
    assert spec.category == ref.category  # the expert and the rubrics key on the category
    hulls = read_convex_obj(spec.collision_path)
    assert len(hulls) == spec.record.n_hulls >= 1 and spec.record.collision_volume > 0
    # convex parts (up to the 6-decimal OBJ rounding), lean: SAPIEN cooks each part's hull
    assert all(len(h.vertices) <= 100 and h.volume == pytest.approx(h.convex_hull.volume, rel=0.02) for h in hulls)
    v = np.vstack([h.vertices for h in hulls])
    # the collision parts span the recorded size, origin at the bottom centre (the catalog convention)
    np.testing.assert_allclose(np.ptp(v, axis=0), spec.extents, atol=0.01)
    assert abs(v[:, 2].min()) < 2e-3 and np.all(np.abs((v.max(0) + v.min(0))[:2] / 2) < 0.01)
    # the visual sits on the collision parts (same frame, same scale)
    vis = trimesh.load(spec.visual_path, force="scene")
    np.testing.assert_allclose(vis.extents, spec.extents, atol=0.012)


@pytest.mark.parametrize("name", sorted(ro.REAL_OBJECTS))
def test_textured_where_the_source_is_else_the_counterparts_colour(name):
    spec = get_object_spec(ro.PREFIX + name)
    geoms = list(trimesh.load(spec.visual_path, force="scene").geometry.values())
    textures = [getattr(g.visual.material, "baseColorTexture", None) for g in geoms if hasattr(g.visual, "material")]
    textures = [t for t in textures if t is not None]
    assert spec.record.textured == (name in TEXTURED) == bool(textures)
    assert all(16 <= max(t.size) <= ro.MAX_TEXTURE_PX for t in textures)  # a real image, downscaled
    if name not in TEXTURED:
        ref = procedural_spec(ro.REAL_OBJECTS[name].fallback)
        assert spec.record.colors == ref.record.colors
        from asset_pipeline.procedural.colors import PALETTE

        rgb = np.asarray(PALETTE[ref.record.colors[0]]) * 255
        for g in geoms:  # a glTF material colour: SAPIEN ignores vertex/face colours
            assert np.abs(np.asarray(g.visual.material.baseColorFactor[:3], float) - rgb).max() <= 1.0


def test_task_nouns_use_the_real_meshes():
    for noun, name in [("apple", "apple"), ("bowl", "bowl"), ("banana", "banana"), ("mug", "mug"), ("teaspoon", "spoon"),
                       ("water bottle", "water_bottle"), ("marker", "marker"), ("box", "box")]:
        assert task_object_spec(noun).id == ro.PREFIX + name
    apple = task_object_spec("apple")
    assert 0.07 <= apple.max_extent <= 0.08 and 0.1 < apple.mass < 0.25


def test_mug_handle_points_to_plus_x():
    """The expert grasps a mug's rim opposite the handle, which it expects on local +x."""
    v = np.vstack([h.vertices for h in read_convex_obj(task_object_spec("mug").collision_path)])
    rim = v[:, 2].max()
    handle_side = v[v[:, 0] > 0.8 * v[:, 0].max()]
    other_side = v[v[:, 0] < 0.8 * v[:, 0].min()]
    assert handle_side[:, 2].max() < rim - 0.01  # the handle is below the rim
    assert other_side[:, 2].min() < handle_side[:, 2].min() - 0.01  # and off the table; the body's wall is not


def test_shipped_data_is_small_and_attributed():
    files = [p for p in ro.SHIPPED_DIR.rglob("*") if p.is_file()]
    assert sum(p.stat().st_size for p in files) < 3 * 2**20
    credits = (ro.SHIPPED_DIR / "ATTRIBUTION.txt").read_text()
    for o in ro.REAL_OBJECTS.values():
        assert f"{o.name}: {o.credit}" in credits and o.licence in credits
        assert "turbosquid" not in (o.item + o.credit).lower()  # no redistribution licence


def test_build_reproduces_the_shipped_folder(tmp_path):
    """The maintainer build (here: the apple, from the always-installed mani-skill wheel) writes what is shipped."""
    folder = ro.build(ro.REAL_OBJECTS["apple"], tmp_path / "out", work=tmp_path / "work")
    built = json.loads((folder / "record.json").read_text())
    shipped = json.loads((ro.SHIPPED_DIR / "apple" / "record.json").read_text())
    for key in ("id", "n_hulls", "category", "textured", "licence", "source_path"):
        assert built[key] == shipped[key]
    np.testing.assert_allclose(built["extents"], shipped["extents"], rtol=1e-4)


def test_missing_shipped_folder_falls_back_to_procedural(monkeypatch, tmp_path):
    monkeypatch.setattr(ro, "SHIPPED_DIR", tmp_path)
    ro._real_spec.cache_clear()
    try:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            spec = ro.real_object_spec("real/mug")
        assert spec.id.startswith("proc/mug/") and not spec.record.real_mesh
        assert any("procedural" in str(x.message) and "rebuild" not in str(x.message) for x in w)
    finally:
        ro._real_spec.cache_clear()


def test_stale_shipped_size_falls_back_and_says_how_to_rebuild(monkeypatch):
    stale = ro.RealObject("marker", "ycb", "ycb/040_large_marker", "proc/marker/0?color=black&size=0.12", "CC-BY-4.0", "-")
    monkeypatch.setitem(ro.REAL_OBJECTS, "marker", stale)
    ro._real_spec.cache_clear()
    try:
        with pytest.warns(RuntimeWarning, match="rebuild: python -m realm_ms.assets.real_objects marker"):
            spec = ro.real_object_spec("real/marker")
        assert spec.id.startswith("proc/marker/") and spec.max_extent == pytest.approx(0.12)
    finally:
        ro._real_spec.cache_clear()


def test_unknown_real_object_is_a_clear_error():
    with pytest.raises(KeyError, match="known"):
        get_object_spec("real/unicorn")


def test_real_objects_placed_as_tasks_place_them_stay_put(table_scene):
    """Tasks set objects down upright, 2 mm above the table (origin = bottom centre): each real mesh
    must then rest there, neither tipping over, rolling away nor sinking."""
    import sapien

    from realm_ms.assets import build_actor

    scene, top = table_scene, 0.80
    placed = []
    for i, name in enumerate(sorted(ro.REAL_OBJECTS)):
        spec = get_object_spec(ro.PREFIX + name)
        p = np.array([-2.0 + 0.6 * i, 0.0, top + 0.002])
        placed.append((name, build_actor(scene, spec, name, pose=sapien.Pose(p=p)), p))
    for _ in range(200):  # 2 s at 100 Hz
        scene.px.step()
    for name, actor, p0 in placed:
        pose = actor._objs[0].pose
        up = pose.to_transformation_matrix()[:3, 2]
        assert up[2] > 0.98, f"{name} tipped over"
        assert np.linalg.norm(pose.p[:2] - p0[:2]) < 0.01, f"{name} moved {np.linalg.norm(pose.p[:2] - p0[:2]):.3f} m"
        assert -0.003 < pose.p[2] - top < 0.003, f"{name} rests at {pose.p[2] - top:+.4f} m"
