"""The gripper channel: strokes, the fit of ``gripper_response`` from data our code makes, and the
effect in a REALM env (the simulated gripper the channel stands for)."""

from __future__ import annotations

import numpy as np
import pytest

from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.effect_spec import parse_effects
from realm_ms.sysid.gripper import SIM_SPEED, check_gripper, simulate, strokes, synth_gripper
from realm_ms.sysid.timeseries import Trajectory

HZ = 15.0


def gripper_trajs(values: dict, seed: int = 0, n: int = 3, seconds: float = 14.0, grasp: bool = True,
                  with_cmd: bool = True) -> list[Trajectory]:
    """Trajectories whose gripper answers full open/close requests under ``values``; with ``grasp`` the
    last one closes on an object at 0.7 (the fingers stop there)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * HZ)) / HZ
    out = []
    for i in range(n):
        g, cmd = synth_gripper(t, rng, values)
        if grasp and i == n - 1:
            g = np.minimum(g, 0.7)
        out.append(Trajectory(f"g{i}", t, np.zeros((len(t), 7)), np.zeros((len(t), 7)), gripper=g,
                              gripper_cmd=cmd if with_cmd else None))
    return out


def test_strokes_of_a_simulated_step():
    t = np.arange(40) / HZ
    cmd = np.r_[np.zeros(5), np.ones(20), np.zeros(15)]
    g = simulate(cmd[None], t, [0.0])[0]
    ss = strokes(g, t)
    assert [s.direction for s in ss] == ["close", "open"]
    assert ss[0].speed == pytest.approx(SIM_SPEED, rel=0.02)
    assert ss[0].begin == 0.0 and ss[0].end == pytest.approx(1.0)


def test_fit_recovers_a_hidden_slower_later_gripper():
    trajs = gripper_trajs({"speed": 0.6, "delay": 0.1})
    c = check_gripper(trajs)
    assert c.with_command and not c.matches and c.verdict == "real gripper slower and later"
    assert c.speed == pytest.approx(0.6, abs=0.03)
    assert c.delay == pytest.approx(0.1, abs=0.015)
    assert c.rmse_after < 0.2 * c.rmse_before
    assert 0.7 in [round(x, 1) for x in c.grasp_stops]  # the grasp's stop is seen, not fitted as slowness
    fx = c.effect()
    assert fx.values()["speed"] == pytest.approx(0.6, abs=0.03) and fx.values()["delay"] == pytest.approx(0.1, abs=0.015)
    # the fitted effect, as the model's, makes the simulated gripper match
    again = check_gripper(trajs, RobotModel([fx]))
    assert again.matches and again.speed == pytest.approx(1.0, abs=0.05)


def test_without_the_request_only_the_speed_is_seen():
    c = check_gripper(gripper_trajs({"speed": 0.6, "delay": 0.1}, with_cmd=False))
    assert not c.with_command and c.delay is None
    assert c.speed == pytest.approx(0.6, abs=0.04)
    assert "cannot be seen" in c.line() and c.verdict == "real gripper slower"
    assert "delay" not in c.effect().values() or c.effect().values()["delay"] == 0.0


@pytest.mark.parametrize("with_cmd", [True, False])
def test_nominal_gripper_matches(with_cmd):
    c = check_gripper(gripper_trajs({}, seed=1, with_cmd=with_cmd))
    assert c.matches and c.verdict == "matches"
    assert c.speed == pytest.approx(1.0, abs=0.05)
    assert c.to_json()["verdict"] == "matches"


def test_no_strokes_is_said():
    t = np.arange(60) / HZ
    c = check_gripper([Trajectory("still", t, np.zeros((60, 7)), np.zeros((60, 7)), gripper=np.zeros(60))])
    assert c.strokes == 0 and c.matches and "no strokes" in c.line()


def test_the_arm_never_sees_the_gripper_effect():
    from realm_ms.sysid import api
    from realm_ms.errors import InputError

    m = RobotModel(parse_effects("latency:delay=0.02,gripper_response:speed=0.6"))
    assert [s.name for s in m.actuation().stages] == ["latency"]
    assert m.gripper_law().speed == pytest.approx(0.6)
    assert RobotModel().gripper_law() is None
    with pytest.raises(InputError, match="acts on the gripper"):
        api.fit(([], []), add="gripper_response")
    with pytest.raises(InputError, match="acts on the gripper"):
        api.diagnose(([], []), candidates=("latency", "gripper_response"))


def test_synth_writes_a_gripper_channel_the_fit_recovers(tmp_path):
    from realm_ms.sysid import api
    from realm_ms.sysid.data_io import load_dir

    api.synth("gripper_response:speed=0.5,delay=0.15", tmp_path, seed=0, n_train=2, n_heldout=1, duration_s=8.0)
    trajs = load_dir(tmp_path / "train") + load_dir(tmp_path / "heldout")
    assert all(tr.gripper is not None and tr.gripper_cmd is not None for tr in trajs)
    c = check_gripper(trajs)
    assert c.speed == pytest.approx(0.5, abs=0.03) and c.delay == pytest.approx(0.15, abs=0.02)


# ---------------------------------------------------------------------------- in the env
def _env_run(model, cmd: np.ndarray) -> np.ndarray:
    """The gripper of a REALM env under ``model`` answering ``cmd``, the arm held still."""
    gym = pytest.importorskip("gymnasium")
    pytest.importorskip("mani_skill")
    import realm_ms  # noqa: F401

    env = gym.make("REALM-PickApple-v1", obs_mode="state", num_envs=1, robot_model=model)
    env.reset(seed=0)
    agent = env.unwrapped.agent
    q = agent.arm_qpos[0].cpu().numpy()
    g = [float(agent.gripper_position[0])]
    for c in cmd[:-1]:
        env.step(np.concatenate([q, [c]]).astype(np.float32))
        g.append(float(agent.gripper_position[0]))
    env.close()
    return np.array(g)


def test_env_gripper_is_the_law_and_the_effect_slows_it():
    t = np.arange(75) / HZ
    cmd = np.r_[np.zeros(5), np.ones(30), np.zeros(40)]
    nominal = _env_run(None, cmd)
    # the simulated gripper is the channel's law: its drive tracks the target within a physics step
    np.testing.assert_allclose(nominal, simulate(cmd[None], t, [0.0])[0], atol=0.03)
    slow = _env_run({"effects": [{"name": "gripper_response", "params": {"speed": 0.6, "delay": 0.1}}]}, cmd)
    s_nom, s_slow = strokes(nominal, t), strokes(slow, t)
    assert s_slow[0].speed == pytest.approx(0.6 * s_nom[0].speed, rel=0.05)
    assert s_slow[0].start - s_nom[0].start in (1, 2)  # 0.1 s later: 1.5 control steps
    # the channel reads the env's slowed gripper back
    tr = Trajectory("env", t, np.zeros((len(t), 7)), np.zeros((len(t), 7)), gripper=slow, gripper_cmd=cmd)
    c = check_gripper([tr])
    assert c.speed == pytest.approx(0.6, abs=0.04) and c.delay == pytest.approx(0.1, abs=0.02)


def test_law_partial_reset_keeps_the_other_envs_requests_in_flight():
    import torch

    from realm_ms.agents.effects.gripper_response import GripperLaw

    law, dt, v = GripperLaw(delay=0.1, speed=0.6), 1 / 120, 1.0
    law.reset(torch.zeros(3, 1))
    for _ in range(5):  # 42 ms of a 100 ms delay: nothing moves yet
        y = law.step(torch.ones(3, 1), dt, v)
    assert float(y.abs().max()) == 0.0
    law.reset(torch.zeros(3, 1), torch.tensor([False, True, False]))
    for _ in range(10):
        y = law.step(torch.ones(3, 1), dt, v)
    # envs 0 and 2 kept their request: moving for 3 steps at 0.6 v; env 1's arrives 100 ms after its reset
    np.testing.assert_allclose(y[:, 0].numpy(), [3 * 0.6 * v * dt, 0.0, 3 * 0.6 * v * dt], atol=1e-6)
