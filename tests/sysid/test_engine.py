"""Evaluator: chunking and worker processes give the same numbers as one in-process simulator."""

import numpy as np
import pytest

from realm_ms.agents.effects import make_effect
from realm_ms.sysid.engine import Evaluator, RolloutCache, arm_keys, plan_chunks
from realm_ms.sysid.excite import ExciteConfig, excite


def _batch(n=6, steps=120):
    cmds = excite(n, seed=4, config=ExciteConfig(duration_s=2.0))
    k = np.minimum((np.arange(steps) / 120 * 15).astype(int), len(cmds[0]) - 1)
    cmd = np.stack([c[k] for c in cmds])
    return cmd[:, 0].copy(), cmd


def test_chunking_is_transparent():
    q0, cmd = _batch()
    fx = make_effect("coulomb_friction")
    th = np.zeros((6, len(fx.params)))
    th[:, :7] = np.linspace(0, 0.5, 6)[:, None]
    fx.set_theta(th)
    one = Evaluator(workers=1, max_envs=100).rollout(q0, np.zeros_like(q0), cmd, [fx])
    chunked = Evaluator(workers=1, max_envs=4).rollout(q0, np.zeros_like(q0), cmd, [fx])
    np.testing.assert_allclose(one, chunked, atol=1e-6)


def test_arms_that_need_fewer_steps_are_trimmed_and_nothing_they_need_changes():
    """With ``lengths``, arms are chunked longest first and each chunk runs as long as its longest
    arm: the steps an arm needs are those of the full rollout, the rest holds its last state."""
    q0, cmd = _batch(n=6, steps=120)
    fx = make_effect("coulomb_friction", {"fc": 0.3})
    lengths = np.array([120, 40, 90, 40, 120, 60])
    ev = Evaluator(workers=1, max_envs=2)
    full = ev.rollout(q0, np.zeros_like(q0), cmd, [fx])
    ev.cache, before = RolloutCache(), ev.sim.profile.arm_steps
    trimmed = ev.rollout(q0, np.zeros_like(q0), cmd, [fx], lengths=lengths)
    assert trimmed.shape == full.shape and np.isfinite(trimmed).all()
    for i, n in enumerate(lengths):
        np.testing.assert_allclose(trimmed[i, :n + 1], full[i, :n + 1], atol=1e-6)
    # chunks of two, longest first (120, 120 | 90, 60 | 40, 40), each as long as its longest arm
    assert ev.sim.profile.arm_steps - before == 2 * 120 + 2 * 90 + 2 * 40
    np.testing.assert_array_equal(trimmed[5, 91:], np.repeat(trimmed[5, 90:91], 30, 0))  # held after its chunk


def test_contiguous_chunks_share_the_arm_steps_when_lengths_are_given():
    same = np.ones((6, 1), bool)
    lengths = np.array([300, 100, 100, 100, 100, 100])  # longest first
    chunks = plan_chunks(same, np.ones((1, 2)), 2, 100, lengths)
    assert [c.tolist() for c in chunks] == [[0, 1], [2, 3, 4, 5]]
    assert [c.tolist() for c in plan_chunks(same, np.ones((1, 2)), 2, 3, lengths)] == [[0, 1, 2], [3, 4, 5]]


def test_plan_spreads_costly_effects_over_chunks_and_keeps_each_group_whole():
    # a screening batch in candidate order: two costly laws first, then two cheap effects, then
    # arms with no effect; contiguous halves would put both costly laws in one chunk
    groups = [0] * 3 + [1] * 3 + [2] * 4 + [3] * 2 + [-1] * 2
    on = np.array([[g == f for f in range(4)] for g in groups])
    costs = np.array([[10.0, 0.1], [9.0, 0.1], [1.0, 0.0], [1.0, 0.0]])  # per step, per arm on
    chunks = plan_chunks(on, costs, n_chunks=2, max_envs=100)
    assert len(chunks) == 2
    assert sorted(np.concatenate(chunks).tolist()) == list(range(len(groups)))
    owner = {int(i): c for c, rows in enumerate(chunks) for i in rows}
    for g in set(groups):
        assert len({owner[i] for i, gi in enumerate(groups) if gi == g}) == 1  # a group is not cut
    assert owner[0] != owner[3]
    assert all(np.all(np.diff(rows) > 0) for rows in chunks)

    # no chunk over max_envs: the big group is cut, a chunk is added where the pieces do not pack,
    # and the plan still covers every arm once
    chunks = plan_chunks(on, costs, n_chunks=5, max_envs=3)
    assert max(map(len, chunks)) <= 3
    assert sorted(np.concatenate(chunks).tolist()) == list(range(len(groups)))

    # arms that all run the same effects: equal contiguous chunks, as before
    same = np.ones((10, 2), bool)
    assert [c.tolist() for c in plan_chunks(same, np.ones((2, 2)), 2, 100)] == [list(range(5)), list(range(5, 10))]
    assert [c.tolist() for c in plan_chunks(np.zeros((3, 0), bool), np.ones((0, 2)), 1, 100)] == [[0, 1, 2]]

    # an effect that costs per arm, on most of the batch: its group kept whole would be the dearest
    # chunk, so the equal contiguous halves are kept
    on = np.zeros((12, 2), bool)
    on[:10, 0] = on[10:, 1] = True
    chunks = plan_chunks(on, np.array([[0.0, 1.0], [0.1, 0.0]]), 2, 100)
    assert [c.tolist() for c in chunks] == [list(range(6)), list(range(6, 12))]


def test_a_mixed_batch_in_chunks_matches_one_chunk():
    # arms with Coulomb, arms with armature, arms with neither: chunked by effect, each chunk
    # leaving out the effect that is off on all its arms, the arms come back in their order
    q0, cmd = _batch(9)
    fric, arm = make_effect("coulomb_friction"), make_effect("armature")
    th_f = np.zeros((9, len(fric.params)))
    th_f[[0, 4, 8], :7] = 0.3
    th_a = np.zeros((9, len(arm.params)))
    th_a[[1, 2, 5], :] = 0.2
    fric.set_theta(th_f)
    arm.set_theta(th_a)
    one = Evaluator(workers=1, max_envs=100).rollout(q0, np.zeros_like(q0), cmd, [fric, arm])
    chunked = Evaluator(workers=1, max_envs=4).rollout(q0, np.zeros_like(q0), cmd, [fric, arm])
    np.testing.assert_allclose(one, chunked, atol=1e-5)  # float32 batches of other sizes round apart
    bare = Evaluator(workers=1).rollout(q0, np.zeros_like(q0), cmd, [])
    assert np.abs(chunked[[0, 1]] - bare[[0, 1]]).max(axis=(1, 2)).min() > 1e-4  # neither effect was dropped
    np.testing.assert_allclose(chunked[3], bare[3], atol=1e-5)


@pytest.mark.slow
def test_worker_processes_match_in_process():
    q0, cmd = _batch(8)
    fx = make_effect("armature")
    th = np.tile(np.linspace(0, 0.4, 8)[:, None], (1, 7))
    fx.set_theta(th)
    one = Evaluator(workers=1).rollout(q0, np.zeros_like(q0), cmd, [fx])
    with Evaluator(workers=2) as ev:
        two = ev.rollout(q0, np.zeros_like(q0), cmd, [fx])
    np.testing.assert_allclose(one, two, atol=1e-6)


@pytest.mark.slow
def test_worker_processes_repeat_a_run_bit_for_bit():
    """Chunk k of every batch goes to the same worker, so a run whose arms carry traces of earlier
    batches (a build-time effect, then a plain batch) repeats exactly on a fresh evaluator."""
    q0, cmd = _batch(8)

    def run() -> list[np.ndarray]:
        fx, fc = make_effect("armature"), make_effect("coulomb_friction")
        fx.set_theta(np.tile(np.linspace(0, 0.4, 8)[:, None], (1, 7)))
        fc.set_theta(np.tile(np.linspace(0, 0.3, 8)[:, None], (1, len(fc.params))))
        with Evaluator(workers=2) as ev:
            return [ev.rollout(q0, np.zeros_like(q0), cmd, [fx]), ev.rollout(q0, np.zeros_like(q0), cmd, [fc])]

    for a, b in zip(run(), run()):
        assert np.array_equal(a, b)


def test_equal_arms_are_simulated_once_and_then_come_from_the_cache():
    q0, cmd = _batch(3)
    fx = make_effect("coulomb_friction")
    th = np.zeros((3, len(fx.params)))
    th[:, :7] = np.array([0.0, 0.2, 0.4])[:, None]
    fx.set_theta(th)
    alone = Evaluator(workers=1).rollout(q0, np.zeros_like(q0), cmd, [fx])

    # arms 3-5 repeat arms 0-2; arm 6 repeats arm 1's start and commands with another friction; a
    # second effect at its off-values on every arm (another screening candidate) splits nothing
    idx = np.array([0, 1, 2, 0, 1, 2, 1])
    th7 = th[idx].copy()
    th7[6, :7] = 0.3
    fx7, idle = make_effect("coulomb_friction"), make_effect("viscous_damping")
    fx7.set_theta(th7)
    idle.set_theta(np.zeros((7, len(idle.params))))
    q7, cmd7 = q0[idx], cmd[idx]
    ev = Evaluator(workers=1)
    sim = ev.rollout(q7, np.zeros_like(q7), cmd7, [fx7, idle])
    assert (ev.cache.misses, ev.cache.hits) == (4, 3)
    assert sim.shape == (7, *alone.shape[1:])
    np.testing.assert_array_equal(sim[3:6], sim[:3])
    np.testing.assert_allclose(sim[:3], alone, atol=1e-6)
    assert np.abs(sim[6] - sim[1]).max() > 1e-4  # the other friction is its own arm

    # the frictionless arm again, without the idle effect: nothing left to simulate
    fx1 = make_effect("coulomb_friction")
    fx1.set_theta(th[:1])
    again = ev.rollout(q0[:1], np.zeros_like(q0[:1]), cmd[:1], [fx1])
    assert ev.cache.misses == 4
    np.testing.assert_array_equal(again[0], sim[0])
    # a cache too small for one arm keeps nothing, and the rollout still answers
    ev.cache = RolloutCache(max_bytes=1)
    np.testing.assert_allclose(ev.rollout(q0[:1], np.zeros_like(q0[:1]), cmd[:1], [fx1])[0], sim[0], atol=1e-6)
    assert ev.cache.misses == 1 and ev.cache.get(arm_keys(q0[:1], np.zeros_like(q0[:1]), cmd[:1], [fx1])[0]) is None


def test_a_verb_stops_its_replay_workers_before_it_returns(tmp_path, monkeypatch):
    """The verbs run their space `with`: the evaluator's worker processes are shut down when the verb
    returns, not left to the interpreter's exit (where a pool's wake-up pipe could already be closed:
    `OSError: [Errno 9] Bad file descriptor` after `realm sysid auto` had written its results)."""
    from realm_ms.sysid import api
    from realm_ms.sysid.synth import SynthConfig, synth

    synth("none", tmp_path, SynthConfig(n_train=1, n_heldout=1, duration_s=2.0), evaluator=Evaluator(workers=1))
    closed = []
    close = Evaluator.close
    monkeypatch.setattr(Evaluator, "close", lambda self: (closed.append(self), close(self)))
    api.compare(tmp_path / "train", workers=1, device="cpu")
    assert len(closed) == 1 and closed[0]._pool is None
