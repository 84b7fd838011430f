"""Torque-saturated bursts: found from a logged torque or rebuilt from the law, left out of the score."""

import dataclasses

import numpy as np
import pytest

from realm_ms.sysid import saturation
from realm_ms.sysid.replay import SegmentSet
from realm_ms.sysid.timeseries import Trajectory

HOME = np.array([0.0, -0.63, 0.0, -2.5, 0.0, 1.9, 0.0])


def _log(duration=6.0, hz=1000.0, tau=None):
    t = np.arange(int(duration * hz) + 1) / hz
    q = HOME + 0.2 * np.sin(0.7 * t)[:, None]
    return Trajectory("a", t, q, q + 0.001, qd=0.14 * np.cos(0.7 * t)[:, None] * np.ones(7), tau=tau)


def test_a_logged_torque_at_its_limit_leaves_out_the_burst_around_it():
    tau = np.zeros((6001, 7))
    tau[3000:3010, 5] = 12.0  # joint 6 at its 12 N·m limit for 10 ms at t = 3 s
    tau[1000, 1] = 0.97 * 87.0  # within 3 %: not at the limit
    tr = _log(tau=tau)
    sat = saturation.saturated(tr)
    assert sat.sum() == 10 and sat[3000:3010].all()
    keep = saturation.unsaturated(tr)
    out = ~keep
    assert out[np.abs(tr.t - 3.0) < saturation.PAD_S - 1e-6].all()  # the excursion before and after
    assert keep[tr.t < 3.0 - saturation.PAD_S - 1e-3].all() and keep[tr.t > 3.009 + saturation.PAD_S + 1e-3].all()


def test_the_law_torque_is_rebuilt_from_state_and_command_like_an_independent_law():
    pytest.importorskip("mujoco")
    from realm_ms.sysid.excite import ExciteConfig, excite
    from realm_ms.sysid.reference_native import NativeReference

    c = excite(1, seed=3, config=ExciteConfig(duration_s=2.0, control_hz=15.0))[0]
    ticks = int(round((len(c) - 1) / 15 * 1000))
    k = np.minimum((np.arange(ticks) / 1000 * 15 + 1e-9).astype(int), len(c) - 1)
    q, qd, tau = NativeReference().rollout_torque(c[0], c[k])
    t = np.arange(ticks + 1) / 1000
    cmd = c[np.minimum(k.tolist() + [k[-1]], len(c) - 1)]
    tr = Trajectory("m", t[:-1], q[:-1], cmd[:-1], qd=qd[:-1])
    rebuilt = saturation.law_torque(tr)
    lim = 0.98 * np.asarray(saturation.NOMINAL_LIMITS)
    free = (np.abs(tau[:-1]) < lim).all(1)
    # MuJoCo's law (mj_jac, qfrc_bias) against realm-ms's model terms: the same torque wherever unclipped
    assert np.abs(rebuilt[free] - tau[:-1][free]).max() < 0.05
    # without a logged velocity the +-5 ms central difference of 0.1 mrad-noisy q still finds no burst
    noisy = dataclasses.replace(tr, q=tr.q + np.random.default_rng(0).normal(0, 1e-4, tr.q.shape), qd=None)
    assert saturation.saturated(noisy).sum() <= (~free).sum() + 5


def test_segments_simulate_through_a_burst_but_do_not_score_it():
    tau = np.zeros((6001, 7))
    tau[3000:3100, 0] = -87.0
    tr = _log(tau=tau)
    ss = SegmentSet.build([tr], 120.0, length_s=100.0, burn_in_s=1.0)
    scored = ss.sample_idx[0][ss.mask[0]]
    t_scored = tr.t[scored]
    assert not np.any((t_scored > 3.0 - saturation.PAD_S + 1e-3) & (t_scored < 3.099 + saturation.PAD_S - 1e-3))
    assert ss.saturated_fraction == pytest.approx(0.5 / 5.0, abs=0.01)  # 0.5 s of the 5 s scored window
    assert ss.steps >= int(5.0 * 120)  # the simulation still runs the whole window
    every = SegmentSet.build([tr], 120.0, length_s=100.0, burn_in_s=1.0, score_saturated=True)
    assert every.saturated_fraction == 0.0 and every.mask[0].sum() == ss.mask[0].sum() + round(0.5 * 5000 / 5)


def test_a_log_saturated_throughout_is_scored_rather_than_dropped():
    tr = _log(tau=np.full((6001, 7), 87.0))
    ss = SegmentSet.build([tr], 120.0, length_s=100.0, burn_in_s=1.0)
    assert ss.mask.any() and ss.saturated_fraction == 0.0
