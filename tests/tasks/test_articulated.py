"""The drawer cabinet and the light switch: openness observable, damped drawer, physical toggle."""

from __future__ import annotations

import pytest
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401


def _hold(env):
    u = env.unwrapped
    return torch.cat([u.agent.arm_qpos, torch.zeros(u.num_envs, 1)], 1)


@pytest.fixture(scope="module")
def switch_env():
    env = gym.make("REALM-PushSwitch-v1", obs_mode="state")
    yield env
    env.close()


@pytest.fixture(scope="module")
def drawer_env():
    env = gym.make("REALM-OpenDrawer-v1", obs_mode="state")
    yield env
    env.close()


def test_drawer_openness_and_damping(drawer_env):
    env = drawer_env
    env.reset(seed=0)
    cab = env.unwrapped.main
    assert cab.is_articulated and float(cab.openness()[0]) < 0.01
    q = cab.art.get_qpos().clone()
    q[:, -1] = 0.5 * cab.geom.travel
    cab.art.set_qpos(q)
    assert abs(float(cab.openness()[0]) - 0.5) < 1e-4
    # a push of 0.2 m/s decays quickly (heavily damped), the drawer stays where it is left
    cab.art.set_qvel(torch.tensor([[0.0, 0.0, 0.2]]))
    a = _hold(env)
    for _ in range(15):
        env.step(a)
    o = float(cab.openness()[0])
    assert 0.5 < o < 0.62
    assert abs(float(cab.art.get_qvel()[0, -1])) < 1e-3
    # handle moves with the drawer (anchor = handle), towards the robot when opening
    x_half = float(cab.anchor_pos()[0, 0])
    q[:, -1] = 0.0
    cab.art.set_qpos(q)
    assert float(cab.anchor_pos()[0, 0]) > x_half + 0.1


def test_close_drawer_starts_fully_open():
    env = gym.make("REALM-CloseDrawer-v1", obs_mode="state")
    try:
        env.reset(seed=0)
        assert float(env.unwrapped.main.openness()[0]) > 0.99
    finally:
        env.close()


def test_switch_toggles_physically(switch_env):
    env = switch_env
    env.reset(seed=0)
    sw = env.unwrapped.main
    a = _hold(env)
    for _ in range(10):
        env.step(a)
    assert not bool(sw.toggled()[0])  # stays off: the detent holds it at the off limit
    assert float(sw.angle()[0]) == pytest.approx(-sw.geom.tilt, abs=0.02)
    # pressed not far enough: springs back to off
    sw.art.set_qpos(torch.tensor([[-0.03]]))
    sw.art.set_qvel(torch.tensor([[1e-3]]))  # wakes the (sleeping) articulation up, as a touch would
    for _ in range(10):
        env.step(a)
    assert not bool(sw.toggled()[0]) and float(sw.angle()[0]) < -sw.geom.tilt + 0.02
    # pressed past the centre: snaps over to on and stays there
    sw.art.set_qpos(torch.tensor([[0.03]]))
    sw.art.set_qvel(torch.tensor([[-1e-3]]))
    for _ in range(10):
        env.step(a)
    assert bool(sw.toggled()[0]) and float(sw.angle()[0]) > sw.geom.tilt - 0.02
