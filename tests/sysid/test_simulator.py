"""Replay simulator: same controller contract as the benchmark, exact replay of its own data,
multiple shooting at any logging rate."""

import numpy as np
import pytest

from realm_ms.sysid.engine import Evaluator
from realm_ms.sysid.fit import compare
from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.simulator import ReplaySimulator, SimConfig
from realm_ms.sysid.synth import SynthConfig, synth


@pytest.fixture(scope="module")
def ev():
    return Evaluator(workers=1, device="cpu")


def test_joint_contract_matches_the_benchmark(ev):
    sim = ev.sim
    sim._ensure(1)
    drv = sim._driver(1, __import__("realm_ms.agents.actuation", fromlist=["ActuationModel"]).ActuationModel())
    for i, j in enumerate(sim.arms[0].get_active_joints()):
        assert j.stiffness == 0.0
        assert j.damping == pytest.approx(float(drv.drive_damping[i]), rel=1e-5)
        assert j.friction == 0.0
    assert sim.dt == pytest.approx(1 / 120)
    assert len(sim.arms[0].get_links()) == 8  # gripper locked and lumped into link 7


@pytest.mark.parametrize("rate", [15.0, 100.0])
def test_truth_model_replays_noise_free_data_exactly(tmp_path, ev, rate):
    """Data synthesised with a hidden effect, replayed with that same effect, gives ~zero error:
    the replay (segments, command hold, sampling at the data timestamps) is consistent."""
    # 3 s logs (a replay costs per second of log; compare's 8 s segments hold each log whole at 5 s
    # too): the truth replays at ~3e-7 rad, the nominal model 3e4x above (seeds 3, 4)
    synth("latency:delay=0.015,viscous_damping:b=0.3", tmp_path, SynthConfig(seed=3, noise_rad=0.0, rate_hz=rate,
          n_train=2, n_heldout=1, duration_s=3.0), evaluator=ev)
    from realm_ms.sysid.data_io import load_dir

    data = load_dir(tmp_path / "train") + load_dir(tmp_path / "heldout")
    truth = RobotModel.load(tmp_path / "truth.yaml")
    c_true = compare(data, truth, evaluator=ev)
    c_nom = compare(data, RobotModel(), evaluator=ev)
    assert c_true.rmse < 2e-5
    assert c_nom.rmse > 50 * c_true.rmse
    assert len(c_true.per_joint_rmse) == 7


def test_sleeping_spare_arms_do_not_change_results(ev):
    from realm_ms.sysid.excite import ExciteConfig, excite

    cmds = excite(4, seed=5, config=ExciteConfig(duration_s=2.0))
    k = np.minimum((np.arange(200) / 120 * 15).astype(int), len(cmds[0]) - 1)
    cmd = np.stack([c[k] for c in cmds])
    q0 = cmd[:, 0].copy()
    a = ev.sim.rollout(q0, np.zeros_like(q0), cmd, [])
    big = ev.sim.rollout(np.repeat(q0, 3, 0), np.zeros((12, 7)), np.repeat(cmd, 3, 0), [])
    b = ev.sim.rollout(q0[:2], np.zeros((2, 7)), cmd[:2], [])
    np.testing.assert_allclose(a[:2], b, atol=1e-6)
    np.testing.assert_allclose(big[::3], a, atol=1e-6)


def test_the_cpu_replay_driver_takes_the_configured_model_rate():
    from realm_ms.agents.actuation import ActuationModel

    for rate in ("physics", "control"):
        sim = ReplaySimulator(SimConfig(model_rate=rate))
        assert sim._driver(1, ActuationModel()).config.model_rate == rate
    assert ReplaySimulator(SimConfig())._driver(1, ActuationModel()).config.model_rate == "path"  # the benchmark's
