"""GPU replay (physx_cuda, one env per candidate) agrees with the CPU replay. Needs CUDA."""

import numpy as np
import pytest
import torch

pytestmark = pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA")


def test_gpu_matches_cpu():
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.excite import ExciteConfig, excite
    from realm_ms.sysid.gpu import GpuReplaySimulator
    from realm_ms.sysid.simulator import ReplaySimulator

    cmds = excite(4, seed=6, config=ExciteConfig(duration_s=3.0))
    k = np.minimum((np.arange(300) / 120 * 15).astype(int), len(cmds[0]) - 1)
    cmd = np.stack([c[k] for c in cmds])
    q0 = cmd[:, 0].copy()
    effects = lambda: [make_effect("coulomb_friction", {"fc": 0.3}), make_effect("latency", {"delay": 0.01}),  # noqa: E731
                       make_effect("armature", {"ia": 0.1})]
    cpu = ReplaySimulator().rollout(q0, np.zeros_like(q0), cmd, effects())
    gpu = GpuReplaySimulator().rollout(q0, np.zeros_like(q0), cmd, effects())
    assert np.all(np.isfinite(gpu))
    # GPU PhysX is a different solver build: agreement to a fraction of a milliradian
    assert np.abs(cpu - gpu).max() < 2e-3, np.abs(cpu - gpu).max()
    per_candidate = make_effect("viscous_damping")
    per_candidate.set_theta(np.tile(np.linspace(0, 1, 4)[:, None], (1, 7)))
    out = GpuReplaySimulator().rollout(q0, np.zeros_like(q0), cmd, [per_candidate])
    ref = ReplaySimulator().rollout(q0, np.zeros_like(q0), cmd, [per_candidate])
    assert np.abs(out - ref).max() < 2e-3
