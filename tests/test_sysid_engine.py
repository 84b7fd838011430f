"""Evaluator: chunking and worker processes give the same numbers as one in-process simulator."""

import numpy as np
import pytest

from realm_ms.agents.effects import make_effect
from realm_ms.sysid.engine import Evaluator
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
