"""Table heights: a scene parameter in DROID's range; the option moves the table top, the floor and
what spawns on the table together, with the robot base (and the cameras, given in its frame) fixed."""

from __future__ import annotations

import pytest
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401
from realm_ms.tasks.scenes import SCENES, TABLE_HEIGHT_RANGE, get_scene  # noqa: E402


def _static_boxes(env):
    """(half size, centre) of every collision box of the static scene of sub-env 0."""
    import sapien

    actor = next(a for name, a in env.unwrapped.scene.actors.items() if name.startswith("scene_static"))
    body = actor._objs[0].find_component_by_type(sapien.physx.PhysxRigidStaticComponent)
    return [(tuple(float(v) for v in s.half_size), s.local_pose.p) for s in body.collision_shapes if hasattr(s, "half_size")]


def test_every_scene_has_a_droid_table_level_with_the_robot_base():
    for name in SCENES:
        s = get_scene(name)
        assert TABLE_HEIGHT_RANGE[0] <= s.table_height <= TABLE_HEIGHT_RANGE[1], name
        # default geometry relative to the robot: the base level with the table top, as before
        assert s.base_above_table == 0.0 and s.table_top_z == 0.0 and s.robot_base_z == 0.0, name
        assert s.floor_z == pytest.approx(-s.table_height) and s.robot_stand_height == pytest.approx(s.table_height)


def test_scene_options_parse_and_fail_clearly():
    s = get_scene("studio?table_height=0.74&base_above_table=0.05")
    assert (s.table_height, s.base_above_table) == (0.74, 0.05)
    assert s.table_top_z == pytest.approx(-0.05) and s.floor_z == pytest.approx(-0.79)
    assert get_scene("studio") .table_height == 0.76  # the registered scene is unchanged
    with pytest.raises(ValueError, match="no option 'tabel_height'.*table_height"):
        get_scene("studio?tabel_height=0.7")
    with pytest.raises(ValueError, match="table_height=.*expected a float"):
        get_scene("studio?table_height=high")
    with pytest.raises(ValueError, match="not a table"):
        get_scene("studio?table_height=2.5")


@pytest.mark.parametrize("scene", ["studio", "dining_room"])
def test_table_height_moves_the_floor_not_the_task(scene):
    """``table_height`` is floor -> table top: the floor moves, the table top stays at the base."""
    env = gym.make("REALM-PickApple-v1", obs_mode="state", scene=f"{scene}?table_height=0.72")
    try:
        env.reset(seed=0)
        s = env.unwrapped.scene_def
        boxes = _static_boxes(env)
        floor = [c for h, c in boxes if h[0] == 4.0]
        assert len(floor) == 1 and float(floor[0][2]) + 0.01 == pytest.approx(-0.72, abs=1e-5)
        top = [c for h, c in boxes if h == pytest.approx(s.table_half_size)]
        assert len(top) == 1 and float(top[0][2]) + s.table_half_size[2] == pytest.approx(0.0, abs=1e-5)
    finally:
        env.close()


def test_base_above_table_moves_table_top_and_spawns_together():
    """The table 5 cm below the robot base: its top, every spawned object (resting on it after
    settling) and the fixtures move down together; the robot base stays at the origin."""
    d = 0.05
    rests = {}
    for opt in ("", f"?base_above_table={d}"):
        env = gym.make("REALM-PickSpoon-v1", obs_mode="state", scene=f"living_room{opt}")
        try:
            env.reset(seed=3)
            u = env.unwrapped
            assert float(u.agent.robot.pose.p[0, 2]) == pytest.approx(0.0, abs=1e-6)
            top = [c for h, c in _static_boxes(env) if h == pytest.approx(u.scene_def.table_half_size)]
            assert float(top[0][2]) + u.scene_def.table_half_size[2] == pytest.approx(-d if opt else 0.0, abs=1e-5)
            hold = torch.cat([u.agent.arm_qpos, torch.zeros(1, 1)], 1)
            for _ in range(15):
                env.step(hold)
            rests[opt] = {k: o.pose.p[0].clone() for k, o in u.objects.items()}
        finally:
            env.close()
    low, base = rests[f"?base_above_table={d}"], rests[""]
    for k in base:
        # same layout (the option changes no draw), everything resting d lower: on the lowered top
        assert low[k][:2] == pytest.approx(base[k][:2], abs=2e-3), k
        assert float(low[k][2] - base[k][2]) == pytest.approx(-d, abs=3e-3), k
