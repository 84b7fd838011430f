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


def _integrate(cmd: np.ndarray) -> np.ndarray:
    """A stand-in 'simulation' that depends on each row's commands only: q after k steps = Σ targets."""
    return np.concatenate([np.zeros_like(cmd[:, :1]), np.cumsum(cmd, axis=1)], axis=1)


def test_stacked_sets_simulate_as_each_set_alone():
    """Train and held-out segments go to one rollout: the stack pads the shorter set (its last target
    held, its last sample time repeated) and ``split`` hands each set exactly what it would get alone."""
    a = SegmentSet.build([traj(6.0), traj(9.0, name="c")], 120.0, length_s=100.0, burn_in_s=1.0)
    b = SegmentSet.build([traj(4.0, 100.0, "b")], 120.0, length_s=100.0, burn_in_s=1.0)
    assert a.steps > b.steps and a.pos.shape[1] < b.pos.shape[1]  # each set is the longer one on one axis
    st = SegmentSet.stack([a, b])
    assert st.n == 3 and st.steps == a.steps and st.pos.shape[1] == b.pos.shape[1]
    assert [s.traj for s in st.segments] == [0, 1, 2] and st.trajs[2] is b.trajs[0]
    np.testing.assert_array_equal(st.cmd[2, b.steps:], np.repeat(b.cmd[0, -1:], a.steps - b.steps, 0))
    assert not st.mask[:2, a.pos.shape[1]:].any() and (st.sample_idx[:2, a.pos.shape[1]:] == -1).all()
    c = 2  # candidate-major tiling, as Evaluator.simulate does
    idx = np.tile(np.arange(st.n), c)
    got = SegmentSet.split([a, b], st.sample(_integrate(st.cmd[idx]), idx), c)
    for ss, sim in zip([a, b], got):
        own = np.tile(np.arange(ss.n), c)
        np.testing.assert_allclose(sim, ss.sample(_integrate(ss.cmd[own]), own), rtol=0, atol=1e-9)
        np.testing.assert_array_equal(score(ss, sim, c).mse, score(ss, ss.sample(_integrate(ss.cmd[own]), own), c).mse)
    assert SegmentSet.stack([a]) is a
