"""The light switch's mounting: where the scene config puts it (a wall panel or the table), where it
sits relative to that, and that it toggles physically and is pressed by the expert on either mount."""

from __future__ import annotations

import numpy as np
import pytest
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401
from realm_ms.tasks.scenes import get_scene  # noqa: E402


def _env(scene=None):
    kw = dict(scene=scene) if scene else {}
    return gym.make("REALM-PushSwitch-v1", obs_mode="state", **kw)


@pytest.fixture(scope="module", params=["kitchen", "kitchen?switch_mount=table"], ids=["wall", "table"])
def switch_env(request):
    env = _env(request.param)
    env.reset(seed=0)
    yield env
    env.close()


def _root_frame(sw):
    """(root position, root rotation) of sub-env 0, numpy."""
    from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix

    pose = sw.pose
    return pose.p[0].numpy().astype(float), quaternion_to_matrix(pose.q[:1])[0].numpy().astype(float)


def test_scene_config_chooses_the_mount():
    assert get_scene("kitchen").switch_mount == "wall"
    assert get_scene("office").switch_mount == "table"
    for scene, mount in (("kitchen", "wall"), ("office", "table"), ("pomaria?switch_mount=table", "table")):
        env = _env(scene)
        try:
            env.reset(seed=1)
            assert env.unwrapped.main.mount == mount, scene
        finally:
            env.close()


def test_bad_mount_is_a_clear_error():
    with pytest.raises(ValueError, match="switch_mount"):
        get_scene("kitchen?switch_mount=ceiling")


def test_switch_sits_where_the_mount_says(switch_env):
    """Pivot and press direction in the root frame: on a wall panel at the scene's height, the housing
    standing off the panel towards the robot; on the table, the housing on the table."""
    u = switch_env.unwrapped
    sw = u.main
    g = sw.geom
    p0, r = _root_frame(sw)
    pivot = r.T @ (sw.rocker.pose.p[0].numpy() - p0)  # the rocker link's origin is the pivot
    n = np.asarray(sw.press_direction_local())
    if sw.mount == "wall":
        h = u.scene_def.switch_height
        assert pivot == pytest.approx([-(sw.wall.standoff + 2 * g.base_half[2]), 0.0, h], abs=1e-4)
        assert n == pytest.approx([1.0, 0.0, 0.0], abs=1e-6)  # into the wall, away from the robot
        # the wall panel: its front face is the root's x = 0 plane, standing on the table top
        assert p0[2] == pytest.approx(u.scene_def.table_top_z, abs=1e-4)
        assert abs(r[2, 2] - 1.0) < 1e-5  # the root is upright: the panel is vertical
    else:
        assert pivot == pytest.approx([0.0, 0.0, 2 * g.base_half[2]], abs=1e-4)
        assert n == pytest.approx([0.0, 0.0, -1.0], abs=1e-6)
    # the press point lies on the raised end of the rocker, in front of (wall) / above (table) the pivot
    press = np.asarray(sw.press_point_local())
    assert float((press - pivot) @ -n) > g.pivot_height


def test_switch_toggles_physically_on_either_mount(switch_env):
    env = switch_env
    env.reset(seed=0)
    sw = env.unwrapped.main
    a = torch.cat([env.unwrapped.agent.arm_qpos, torch.zeros(1, 1)], 1)
    for _ in range(10):
        env.step(a)
    assert not bool(sw.toggled()[0]) and float(sw.angle()[0]) == pytest.approx(-sw.geom.tilt, abs=0.02)
    sw.art.set_qpos(torch.tensor([[-0.03]]))  # pressed not far enough: the detent returns it to off
    sw.art.set_qvel(torch.tensor([[1e-3]]))
    for _ in range(10):
        env.step(a)
    assert not bool(sw.toggled()[0]) and float(sw.angle()[0]) < -sw.geom.tilt + 0.02
    sw.art.set_qpos(torch.tensor([[0.03]]))  # past the centre: snaps over to on and stays
    sw.art.set_qvel(torch.tensor([[-1e-3]]))
    for _ in range(10):
        env.step(a)
    assert bool(sw.toggled()[0]) and float(sw.angle()[0]) > sw.geom.tilt - 0.02


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["kitchen", "kitchen?switch_mount=table"], ids=["wall", "table"])
def test_expert_presses_the_switch_on_either_mount(scene):
    from realm_ms.expert import run_episode

    env = _env(scene)
    try:
        for seed in (0, 1):
            res = run_episode(env, seed=seed)
            assert res["success"], (scene, seed, res["stalled_stage"], res["log"][-3:])
    finally:
        env.close()


def test_wall_switch_presses_its_top_end_for_either_goal():
    """"Turn off" (SB-VRB) starts the switch on with the goal off: on a wall it hangs upside down so the
    end to press is again the top one, and the detent still holds it at rest."""
    env = gym.make("REALM-PushSwitch-v1", obs_mode="state", perturbation="SB-VRB")
    try:
        env.reset(seed=0)
        sw = env.unwrapped.main
        assert sw.mount == "wall" and not sw.goal_on and sw.init_on
        p0, r = _root_frame(sw)
        pivot = r.T @ (sw.rocker.pose.p[0].numpy() - p0)
        assert sw.press_point_local()[2] > pivot[2] + 0.5 * sw.geom.rocker_half[0]
        a = torch.cat([env.unwrapped.agent.arm_qpos, torch.zeros(1, 1)], 1)
        for _ in range(10):
            env.step(a)
        assert not bool(sw.toggled()[0]) and float(sw.angle()[0]) == pytest.approx(sw.geom.tilt, abs=0.02)
    finally:
        env.close()
