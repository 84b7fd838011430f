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
        np.savez(tmp_path / f"{ep.name}.npz", q=q, cartesian_position_cmd=ep.cartesian_cmd, gripper=ep.gripper)
    return eps


def test_closed_loop_replay_sees_a_hidden_delay(tmp_path):
    slow = {"effects": [{"name": "latency", "params": {"delay": 0.1}}]}
    _episodes(tmp_path, slow)
    eps = al.read_droid_episodes(tmp_path)
    assert [e.lab for e in eps] == ["LAB", "LAB"]
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
    found = dict((c["latency.delay"], r) for c, r in al.align_grid(eps, None, {"latency.delay": [0.0, 0.05, 0.1]}))
    assert found[0.1].flange_mm < 0.05 < found[0.05].flange_mm < found[0.0].flange_mm
    assert found[0.0].flange_mm == pytest.approx(nominal.overall.flange_mm, rel=1e-3)


def test_bad_episode_files_get_one_clear_error(tmp_path):
    from realm_ms.errors import UserError

    np.savez(tmp_path / "x_LAB.npz", q=np.zeros((10, 7)))
    with pytest.raises(UserError, match="missing cartesian_position_cmd"):
        al.read_droid_episodes(tmp_path)
    with pytest.raises(UserError, match="no such directory"):
        al.read_droid_episodes(tmp_path / "nope")
