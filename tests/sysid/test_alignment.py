"""The DROID alignment metrics and the closed-loop replay of Cartesian commands, on data our own
replay makes (an arm with a hidden command delay stands in for the real robot)."""

from __future__ import annotations

import numpy as np
import pytest

from realm_ms.sysid import alignment as al


def test_response_b_recovers_a_first_order_response():
    rng = np.random.default_rng(0)
    c = np.cumsum(rng.normal(0, 0.01, (200, 3)), 0)
    p = np.zeros_like(c)
    for t in range(199):
        p[t + 1] = p[t] + 0.2 * (c[t] - p[t])
    assert al.response_b(p, c) == pytest.approx(0.2, abs=1e-9)


def test_response_lag_finds_a_pure_delay():
    t = np.arange(300) / 15
    c = np.stack([np.sin(t), np.cos(0.7 * t), 0.1 * t], 1)
    p = np.concatenate([np.repeat(c[:1], 4, 0), c[:-4]])  # p[t] = c[t - 4]
    assert al.response_lag(p, c) == 4
    assert al.response_lag(c, c) == 0


def test_heldout_split_takes_a_third_of_every_lab():
    eps = [al.DroidEpisode(f"ep{i:03d}_{lab}", lab, np.zeros((5, 7)), np.zeros((5, 6)), np.zeros(5))
           for i, lab in enumerate(["A"] * 6 + ["B"] * 3 + ["C"] * 2)]
    held_in, held_out = al.heldout_split(eps)
    assert sorted(e.name for e in held_out) == ["ep002_A", "ep005_A", "ep008_B"]
    assert len(held_in) + len(held_out) == len(eps)


def _episodes(tmp_path, model):
    """Two episodes whose 'measured' joints are the closed-loop answer of ``model`` to smooth
    Cartesian commands around the DROID reset pose."""
    from realm_ms.agents.droid_action_spaces import DroidIK
    from realm_ms.agents.urdf import DROID_RESET_QPOS

    ik = DroidIK()
    p0 = ik.pose(np.array(DROID_RESET_QPOS)[None])[0]
    eps = []
    for k, amp in enumerate((0.06, 0.1)):
        t = np.arange(60) / 15
        cmd = np.repeat(p0[None], len(t), 0)
        cmd[:, 0] += amp * np.sin(1.5 * t)
        cmd[:, 2] += 0.5 * amp * (1 - np.cos(2.0 * t))
        ep = al.DroidEpisode(f"ep{k}_LAB", "LAB", np.repeat(np.array(DROID_RESET_QPOS)[None], len(t), 0), cmd, np.zeros(len(t)))
        eps.append(ep)
    for ep, q in zip(eps, al.replay_closed_loop(eps, model)):
        ep.q = q
        np.savez(tmp_path / f"{ep.name}.npz", t=np.arange(len(q)) / 15, q=q, cartesian_position_cmd=ep.cartesian_cmd,
                 gripper=ep.gripper)
    return eps


def test_closed_loop_replay_sees_a_hidden_delay(tmp_path):
    slow = {"effects": [{"name": "latency", "params": {"delay": 0.1}}]}
    _episodes(tmp_path, slow)
    eps, skipped = al.read_droid_episodes(tmp_path)
    assert [e.lab for e in eps] == ["LAB", "LAB"] and skipped == []
    nominal = al.align(eps, None)
    true = al.align(eps, slow, "slow")
    # the true model replays its own data; the nominal arm answers sooner and lands elsewhere
    assert true.overall.flange_mm < 0.05
    assert nominal.overall.flange_mm > 2.0
    assert nominal.overall.lag_sim < nominal.overall.lag_real
    assert nominal.overall.b_sim > 1.2 * nominal.overall.b_real
    assert true.overall.lag_sim == true.overall.lag_real
    assert "LAB" in nominal.table() and nominal.to_dict()["overall"]["episodes"] == 2
    # a grid over the delay picks the true one: the candidates run as rows of one batch
    found = dict((c["latency.delay"], r.overall) for c, r in al.align_grid(eps, None, {"latency.delay": [0.0, 0.05, 0.1]}))
    assert found[0.1].flange_mm < 0.05 < found[0.05].flange_mm < found[0.0].flange_mm
    assert found[0.0].flange_mm == pytest.approx(nominal.overall.flange_mm, rel=1e-3)


def test_a_bad_episode_is_set_aside_and_nothing_usable_is_one_clear_error(tmp_path):
    from realm_ms.sysid.timeseries import DataError, DataWarning

    t = np.arange(30) / 15
    home = np.array([0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8])
    np.savez(tmp_path / "ep0_LAB.npz", t=t, q=np.tile(home, (30, 1)), cartesian_position_cmd=np.zeros((30, 6)))
    np.savez(tmp_path / "short_LAB.npz", t=t[:10], q=np.tile(home, (10, 1)), cartesian_position_cmd=np.zeros((10, 6)))
    (tmp_path / "broken_LAB.npz").write_text("not an archive")
    with pytest.warns(DataWarning, match="left out") as seen:
        eps, skipped = al.read_droid_episodes(tmp_path)
    assert [e.name for e in eps] == ["ep0_LAB"] and len(skipped) == 2 == len(seen)
    assert "broken_LAB.npz" in skipped[0] and "not an .npz archive" in skipped[0]
    assert "short_LAB.npz" in skipped[1] and "only 10 samples" in skipped[1]
    (tmp_path / "ep0_LAB.npz").unlink()
    with pytest.raises(DataError, match="no usable episode; .*broken_LAB.npz.*short_LAB.npz"):
        al.read_droid_episodes(tmp_path)
    with pytest.raises(DataError, match="no such file or directory"):
        al.read_droid_episodes(tmp_path / "nope")


def test_one_lab_rule_and_a_split_that_an_unreadable_episode_does_not_move(tmp_path):
    import json

    (tmp_path / "index.json").write_text(json.dumps([{"file": "a_001.npz", "lab": "TRI"}]))
    labs = al.read_labs(tmp_path)
    assert al.lab_of("a_001", labs) == "TRI" and al.lab_of("droid100_007_RAIL", labs) == "RAIL"
    names = [f"ep{i}_A" for i in range(6)]
    every = {n: "A" for n in names}
    eps = [al.DroidEpisode(n, "A", np.zeros((5, 7)), np.zeros((5, 6)), np.zeros(5)) for n in names if n != "ep1_A"]
    _, out = al.heldout_split(eps, every)
    assert [e.name for e in out] == ["ep2_A", "ep5_A"]  # as with ep1_A read
    _, shifted = al.heldout_split(eps)
    assert [e.name for e in shifted] == ["ep3_A"]  # what counting only the read ones would hold out


def test_droid_ik_clips_its_nullspace_bias_to_the_joint_bounds():
    """dm_robotics' mapper clips the nullspace bias gain (ref - q) / dt to the joint bounds before
    its second hierarchy: with no Cartesian motion asked, the step is the nullspace direction n
    times n . clip(bias), inside the 0.2 rad bounds, and leaves the flange where it is."""
    from realm_ms.agents import droid_action_spaces as das

    ik = das.DroidIK()
    q = np.array([[0.3, -0.5, 0.2, -2.3, 0.1, 2.0, 0.9]])
    x = ik.cartesian_delta_to_joint_delta(np.zeros((1, 6)), q)[0]
    j = ik.jacobian(q)[0]
    n = np.linalg.svd(j)[2][-1]  # the one nullspace direction of a 7-joint arm
    lo, hi = ik.bounds(q[0])
    bias = das.NULLSPACE_GAIN * (das.NULLSPACE_REFERENCE - q[0]) * das.CONTROL_HZ
    assert np.abs(bias).max() > 0.5  # unclipped, far outside the 0.2 rad bounds
    s = np.clip(bias, lo, hi) @ n
    expected = s * n
    scale = min(1.0, *(hi[k] / expected[k] if expected[k] > 0 else lo[k] / expected[k] for k in range(7) if expected[k]))
    np.testing.assert_allclose(x, scale * expected, atol=1e-6)
    assert np.abs(j @ x).max() < 1e-6 and np.all(x >= lo - 1e-9) and np.all(x <= hi + 1e-9)
    legacy = das.DroidIK(clamp_bias=False).cartesian_delta_to_joint_delta(np.zeros((1, 6)), q)[0]
    assert np.abs(legacy - x).max() > 0.02  # the clip changes the step


def test_episodes_of_different_lengths_replay_in_their_own_batches(tmp_path, monkeypatch):
    """A short and a long episode go to separate batches (a batch runs as long as its longest
    episode); each replays as it does padded in one batch, and per-episode effect rows follow."""
    eps = _episodes(tmp_path, None)
    eps[0] = al.DroidEpisode("short_LAB", "LAB", eps[0].q[:20], eps[0].cartesian_cmd[:20], eps[0].gripper[:20])
    model = {"effects": [{"name": "latency", "params": {"delay": 0.05}}]}
    apart = al.replay_closed_loop(eps, model)
    monkeypatch.setattr(al, "BATCH_LENGTH_RATIO", 100.0)
    together = al.replay_closed_loop(eps, model)
    assert [len(x) for x in apart] == [20, 60]
    for a, b in zip(apart, together):
        np.testing.assert_allclose(a, b, atol=1e-5)
    found = dict((c["latency.delay"], r.overall) for c, r in al.align_grid(eps, None, {"latency.delay": [0.0, 0.05]}))
    assert found[0.05].flange_mm == pytest.approx(al.align(eps, model).overall.flange_mm, abs=1e-3)


def test_leave_one_lab_out_chooses_each_labs_candidate_on_the_other_labs():
    def ep(name, lab, mm):
        return al.EpisodeAlignment(name, lab, 10, mm, mm, [0.0] * 7, 4, 4, 0.2, 0.2)

    # candidate a suits labs A and B, candidate b suits lab C only
    a = al.tabulate([ep("a1", "A", 1.0), ep("b1", "B", 2.0), ep("c1", "C", 9.0)], "a", 0.0)
    b = al.tabulate([ep("a1", "A", 5.0), ep("b1", "B", 6.0), ep("c1", "C", 3.0)], "b", 0.0)
    rows = al.leave_one_lab_out([({"x": 1.0}, a), ({"x": 2.0}, b)])
    # leaving A out, B (2 vs 6) and C (9 vs 3) give medians 5.5 vs 4.5: b is chosen and A reads 5
    assert rows == [("A", {"x": 2.0}, 5.0), ("B", {"x": 2.0}, 6.0), ("C", {"x": 1.0}, 9.0)]
