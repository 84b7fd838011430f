"""Runtime side: specs without a build, attribute sampling, ManiSkill actors, and a drop test."""

from __future__ import annotations

import os

import numpy as np
import pytest

import realm_ms.assets.catalog as catalog_mod
from asset_pipeline.export import read_convex_obj
from realm_ms.assets import (
    TASK_OBJECTS,
    ObjectQuery,
    build_actor,
    categories,
    describe,
    get_object_spec,
    load_catalog,
    make_cpu_scene,
    procedural_object_spec,
    sample_objects,
    task_object_spec,
)


@pytest.fixture(autouse=True, scope="module")
def isolated_dirs(tmp_path_factory):
    """Empty catalog dir (so the procedural catalog is used) and a private mesh cache."""
    old = {k: os.environ.get(k) for k in ("REALM_ASSETS_DIR", "REALM_ASSETS_CACHE")}
    os.environ["REALM_ASSETS_DIR"] = str(tmp_path_factory.mktemp("no_catalog"))
    os.environ["REALM_ASSETS_CACHE"] = str(tmp_path_factory.mktemp("mesh_cache"))
    catalog_mod._catalog_cache.clear()
    yield
    for k, v in old.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v
    catalog_mod._catalog_cache.clear()


def test_procedural_spec_without_build_is_cached_on_disk():
    s = get_object_spec("proc/apple/0")
    assert s.visual_path.exists() and s.collision_path.exists()
    assert str(s.root).startswith(os.environ["REALM_ASSETS_CACHE"])
    assert s.category == "apple" and s.noun == "apple" and 0.1 < s.mass < 0.4
    assert get_object_spec("proc/apple/0").visual_path == s.visual_path
    cube = procedural_object_spec("cube", 0, color="green", size=0.03)
    assert np.allclose(cube.extents, 0.03) and cube.record.colors[0] == "green"


def test_task_objects_resolve_with_requested_sizes():
    for noun in TASK_OBJECTS:
        assert task_object_spec(noun).collision_path.exists()
    assert abs(task_object_spec("marker").max_extent - 0.17) < 1e-6
    assert abs(task_object_spec("bowl").max_extent - 0.175) < 1e-3  # REALM's bowl, real mesh at its real size
    with pytest.raises(KeyError):
        task_object_spec("unicorn")


def test_sampling_by_attributes():
    rng = np.random.default_rng(0)
    cat = load_catalog()
    assert type(cat).__name__ == "ProceduralCatalog" and len(cat) >= 3500
    unseen = sample_objects(5, rng, seen=False, distinct_categories=True)
    assert len({s.category for s in unseen}) == 5 and all(not s.record.seen for s in unseen)
    red = sample_objects(4, rng, colors="red", exclude_categories=("apple",))
    assert all("red" in s.record.colors and s.category != "apple" for s in red)
    drink = sample_objects(3, rng, uses="drink")
    assert all(any("drink" in u for u in s.record.uses) for s in drink)
    assert describe(drink[0], "use") in drink[0].record.uses
    assert describe(red[0], "color").startswith("the red ")
    assert "mug" in categories(uses="drink") and "hammer" not in categories(seen=True)
    with pytest.raises(ValueError):
        sample_objects(1, rng, categories=("mug",), colors=("ultraviolet",))
    # Same seed, same draw.
    a = [s.id for s in sample_objects(6, np.random.default_rng(5), seen=True)]
    b = [s.id for s in sample_objects(6, np.random.default_rng(5), query=ObjectQuery(seen=True))]
    assert a == b


def test_build_actor_mass_scale_and_body_types():
    import sapien

    scene = make_cpu_scene()
    spec = get_object_spec("proc/mug/1")
    a = build_actor(scene, spec, "mug", pose=sapien.Pose(p=[0, 0, 0.0]))
    body = a._objs[0].find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
    assert len(body.collision_shapes) == spec.record.n_hulls > 5
    assert abs(body.mass - spec.mass) / spec.mass < 0.05
    big = build_actor(scene, spec, "mug2x", pose=sapien.Pose(p=[1, 0, 0]), scale=2.0)
    m2 = big._objs[0].find_component_by_type(sapien.physx.PhysxRigidDynamicComponent).mass
    assert abs(m2 / body.mass - 8.0) < 0.5  # density is kept: mass grows with volume
    heavy = build_actor(scene, spec, "mug_heavy", pose=sapien.Pose(p=[2, 0, 0]), mass=1.5, scale=(1.0, 1.2, 0.8))
    assert abs(heavy._objs[0].find_component_by_type(sapien.physx.PhysxRigidDynamicComponent).mass - 1.5) < 0.05
    st = build_actor(scene, "proc/tray/0", "tray", body_type="static", pose=sapien.Pose(p=[3, 0, 0]))
    assert st._objs[0].find_component_by_type(sapien.physx.PhysxRigidStaticComponent) is not None
    with pytest.raises(ValueError):
        build_actor(scene, spec, "bad", scale=0)


def _world_min_z(actor, hull_pts: np.ndarray) -> float:
    pose = actor._objs[0].pose
    R = pose.to_transformation_matrix()[:3, :3]
    return float((hull_pts @ R.T + pose.p)[:, 2].min())


def test_random_objects_dropped_on_table_come_to_rest(table_scene):
    """A random sample of catalog objects, dropped in random orientations onto a table top, settles:
    no explosion (stays near its drop point), no sinking (hull stays above the table), at rest."""
    import sapien
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(1)
    specs = sample_objects(12, rng, distinct_categories=True) + [task_object_spec("bowl"), task_object_spec("wineglass")]
    scene, top = table_scene, 0.80
    actors = []
    for i, s in enumerate(specs):
        q = Rotation.random(random_state=int(rng.integers(1 << 30))).as_quat()  # x, y, z, w
        p = [-3 + (i % 7) * 1.0, -1 + (i // 7) * 1.0, top + 0.05 + s.max_extent]
        a = build_actor(scene, s, f"obj{i}", pose=sapien.Pose(p=p, q=[q[3], q[0], q[1], q[2]]))
        pts = np.vstack([h.vertices for h in read_convex_obj(s.collision_path)])
        actors.append((s, a, np.array(p), pts))
    for _ in range(400):  # 4 s at 100 Hz
        scene.px.step()
    for s, a, p0, pts in actors:
        ent = a._objs[0]
        body = ent.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
        assert np.all(np.isfinite(ent.pose.p)), s.id
        assert np.linalg.norm(ent.pose.p[:2] - p0[:2]) < 0.6, f"{s.id} flew away"
        assert _world_min_z(a, pts) > top - 0.01, f"{s.id} sank into the table"
        assert np.linalg.norm(body.linear_velocity) < 0.05 or body.is_sleeping, f"{s.id} still moving"


def test_real_mesh_objects_dropped_on_table_come_to_rest(tmp_path):
    """Same drop test on built real-mesh objects: the user-folder fixtures and ManiSkill's meshes
    (a core dependency) always, plus a few objects from each optional package source that is
    installed (skipped silently when absent)."""
    import importlib.util
    from pathlib import Path

    import sapien

    from asset_pipeline.build import build_catalog
    from asset_pipeline.config import BuildConfig
    from asset_pipeline.stages.decompose import CoacdSettings
    from realm_ms.assets.catalog import BuiltCatalog

    spec_ = importlib.util.spec_from_file_location("asset_meshes", Path(__file__).parent / "fixtures" / "meshes.py")
    meshes = importlib.util.module_from_spec(spec_)
    spec_.loader.exec_module(meshes)
    user = tmp_path / "user"
    meshes.textured(user / "cube")
    (user / "mug").mkdir()
    meshes.huge_scale(user / "mug")
    (user / "toy").mkdir()
    meshes.concave(user / "toy")
    # a budget CoACD meets on a loaded machine too: a decomposition cut by its budget falls back to one
    # convex hull, and ManiSkill's bottle as one hull rolls on (what this test checks is settling, not the budget)
    cfg = BuildConfig(coacd=CoacdSettings(budget_s=120, mcts_iterations=20), thumbnails=False, stable_poses=False)
    rep = build_catalog([str(user), "maniskill", "libero", "rgb_objects", "pybullet", "ycb"], tmp_path / "cat", cfg, progress=False,
                        limit_per_source=2, strict=False)
    assert rep.failed == 0 and rep.built >= 3
    cat = BuiltCatalog(tmp_path / "cat")
    scene = make_cpu_scene(ground=False)
    t = scene.create_actor_builder()
    t.add_box_collision(half_size=[6, 6, 0.02])
    t.initial_pose = sapien.Pose(p=[0, 0, 0.78])
    t.build_static(name="table")
    actors = []
    for i, r in enumerate(cat.records):
        s = cat.get(r.id)
        p = [-5 + (i % 10) * 1.0, -1 + (i // 10) * 1.0, 0.85]
        a = build_actor(scene, s, f"r{i}", pose=sapien.Pose(p=p, q=[0.9238795, 0.3826834, 0, 0]))  # tilted 45 deg
        actors.append((s, a, np.array(p), np.vstack([h.vertices for h in read_convex_obj(s.collision_path)])))
    for _ in range(400):
        scene.px.step()
    for s, a, p0, pts in actors:
        ent = a._objs[0]
        body = ent.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
        assert np.linalg.norm(ent.pose.p[:2] - p0[:2]) < 0.6, f"{s.id} flew away"
        assert _world_min_z(a, pts) > 0.79, f"{s.id} sank into the table"
        assert np.linalg.norm(body.linear_velocity) < 0.05 or body.is_sleeping, f"{s.id} still moving"
