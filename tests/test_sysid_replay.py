"""Multiple-shooting segmentation and sampling."""

import numpy as np

from realm_ms.sysid.replay import SegmentSet, score
from realm_ms.sysid.timeseries import Trajectory

HOME = np.array([0.0, -0.63, 0.0, -2.5, 0.0, 1.9, 0.0])


def traj(duration=20.0, hz=15.0, name="a"):
    t = np.arange(int(duration * hz) + 1) / hz
    q = HOME + 0.2 * np.sin(0.7 * t)[:, None]
    return Trajectory(name, t, q, q + 0.01)


def test_every_sample_after_burn_in_is_scored_once():
    trs = [traj(), traj(12.0, 100.0, "b")]
    ss = SegmentSet.build(trs, 120.0, length_s=4.0, burn_in_s=1.0)
    for ti, tr in enumerate(trs):
        counts = np.zeros(len(tr.t), int)
        for i, s in enumerate(ss.segments):
            if s.traj == ti:
                idx = ss.sample_idx[i][ss.mask[i]]
                counts[idx] += 1
        assert np.all(counts[tr.t >= 1.0 + 1e-9] == 1)
        assert np.all(counts[tr.t < 1.0 - 1e-9] == 0)
    # segments start from the measured state, burn-in before the scored window
    for i, s in enumerate(ss.segments):
        np.testing.assert_array_equal(ss.q0[i], trs[s.traj].q[s.start])
        assert s.score_from > s.start


def test_command_hold_and_sampling():
    tr = traj(6.0)
    ss = SegmentSet.build([tr], 120.0, length_s=100.0, burn_in_s=1.0)
    # 8 physics steps per 15 Hz sample, the target held in between
    np.testing.assert_allclose(ss.cmd[0, :8], np.repeat(tr.q_cmd[:1], 8, 0), atol=1e-9)
    np.testing.assert_allclose(ss.cmd[0, 8], tr.q_cmd[1], atol=1e-9)
    hist = np.repeat(np.arange(ss.steps + 1, dtype=float)[None, :, None], 7, 2)  # q = step index
    sampled = ss.sample(hist)
    np.testing.assert_allclose(sampled[0, :10, 0], np.arange(10) * 8, atol=1e-9)
    sc = score(ss, np.repeat(ss.meas, 2, 0), 2)
    assert sc.mse.shape == (2,) and np.all(sc.mse == 0)
