"""Evaluator: chunking and worker processes give the same numbers as one in-process simulator."""

import numpy as np
import pytest

from realm_ms.agents.effects import make_effect
from realm_ms.sysid.engine import Evaluator, RolloutCache, arm_keys
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
