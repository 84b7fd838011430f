"""Real meshes for task nouns: processed once, fitted to real sizes, procedural fallback when missing."""

import warnings

import numpy as np
import pytest

from realm_ms.assets import get_object_spec, task_object_spec
from realm_ms.assets import real_objects as ro
from realm_ms.assets.catalog import procedural_spec


@pytest.mark.parametrize("name", sorted(ro.REAL_OBJECTS))
def test_real_object_is_a_textured_mesh_at_real_size(name):
    spec = get_object_spec(ro.PREFIX + name)
    ref = procedural_spec(ro.REAL_OBJECTS[name].fallback)
    assert spec.id == ro.PREFIX + name and spec.record.real_mesh and spec.record.textured
    assert spec.visual_path.exists() and spec.collision_path.exists()
    assert spec.max_extent == pytest.approx(ref.max_extent, rel=1e-3)  # scaled to the real size
    assert spec.mass == pytest.approx(ref.mass) and spec.record.n_hulls >= 1
    assert spec.record.collision_volume > 0
    # the collision parts span the visual's size (the fitted files agree with the record)
    from asset_pipeline.export import read_convex_obj

    hulls = read_convex_obj(spec.collision_path)
    v = np.vstack([h.vertices for h in hulls])
    np.testing.assert_allclose(v.max(0) - v.min(0), spec.extents, atol=0.01)


def test_apple_is_apple_sized():
    apple = task_object_spec("apple")
    assert apple.id == "real/apple" and 0.07 <= apple.max_extent <= 0.08
    assert 0.1 < apple.mass < 0.25


def test_missing_package_file_falls_back_to_procedural(monkeypatch):
    broken = ro.RealObject("apple", "maniskill", "maniskill/no_such_mesh", "proc/apple/0?color=red&size=0.075", "-")
    monkeypatch.setitem(ro.REAL_OBJECTS, "apple", broken)
    ro._real_spec.cache_clear()
    try:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            spec = ro.real_object_spec("real/apple")
        assert spec.id.startswith("proc/apple/") and not spec.record.real_mesh
        assert any("procedural" in str(x.message) for x in w)
    finally:
        ro._real_spec.cache_clear()


def test_unknown_real_object_is_a_clear_error():
    with pytest.raises(KeyError, match="known"):
        get_object_spec("real/unicorn")
