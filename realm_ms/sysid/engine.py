"""Evaluate many candidate models on many segments: chunking, worker processes, GPU dispatch.

``Evaluator.simulate(segset, effects, C)`` runs C candidate models (each effect's ``theta`` has C
rows, or 1 row shared by all) on every segment of ``segset`` and returns the simulated positions
at the data samples, candidate-major (C*N, L, 7). Large batches are cut into chunks of at most
``max_envs`` arms; with ``workers > 1`` the chunks go to persistent worker processes, each with its
own PhysX scene (spawned once, reused for every call). With ``device="cuda"`` one GPU scene runs the
whole batch (``gpu.py``).
"""

from __future__ import annotations

import os
from dataclasses import asdict
from typing import Any

import numpy as np

from realm_ms.agents.effects import Effect, make_effect
from realm_ms.sysid.replay import Scores, SegmentSet, score
from realm_ms.sysid.simulator import SimConfig

EffectSpec = tuple[str, dict[str, Any], np.ndarray]  # (name, config, theta (E, n))

_WORKER_SIM = None


def _spec(fx: Effect, theta: np.ndarray) -> EffectSpec:
    cfg = {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(fx.config).items()}
    return (fx.name, cfg, theta)


def _effects_from_specs(specs: list[EffectSpec]) -> list[Effect]:
    out = []
    for name, cfg, theta in specs:
        fx = make_effect(name, None, cfg)
        fx.set_theta(theta)
        out.append(fx)
    return out


def _worker_init(config: SimConfig) -> None:
    global _WORKER_SIM
    import torch

    torch.set_num_threads(1)
    from realm_ms.sysid.simulator import ReplaySimulator

    _WORKER_SIM = ReplaySimulator(config)


def _worker_run(args):
    q0, qd0, cmd, specs = args
    return _WORKER_SIM.rollout(q0, qd0, cmd, _effects_from_specs(specs))


def default_workers() -> int:
    """CPU worker processes when none are asked for: ``REALM_SYSID_WORKERS``, else min(2, cores)."""
    return int(os.environ.get("REALM_SYSID_WORKERS", min(2, os.cpu_count() or 1)))


def make_simulator(config: SimConfig | None = None, device: str | None = None):
    """CPU simulator (``simulator.py``), or the GPU one when ``device`` is ``cuda`` (``gpu.py``)."""
    if device and device.startswith("cuda"):
        from realm_ms.sysid.gpu import GpuReplaySimulator

        return GpuReplaySimulator(config)
    from realm_ms.sysid.simulator import ReplaySimulator

    return ReplaySimulator(config)


class Evaluator:
    def __init__(self, config: SimConfig | None = None, workers: int = 1, device: str | None = None,
                 max_envs: int = 1200):
        self.config = config or SimConfig()
        self.workers = max(1, int(workers))
        self.device = device or "cpu"
        self.max_envs = max_envs
        self._sim = None
        self._pool = None
        self.progress = False  # progress bars for large in-process rollouts

    @classmethod
    def auto(cls, config: SimConfig | None = None, workers: int | None = None, device: str | None = None) -> "Evaluator":
        """GPU when CUDA is available (and device not forced), else CPU with ``workers`` processes
        (default: ``REALM_SYSID_WORKERS`` or min(2, cpu count))."""
        if device is None:
            try:
                import torch

                device = "cuda" if torch.cuda.is_available() else "cpu"
            except ImportError:  # pragma: no cover
                device = "cpu"
        if workers is None:
            workers = default_workers()
        return cls(config, workers, device)

    @property
    def sim(self):
        if self._sim is None:
            self._sim = make_simulator(self.config, self.device)
            self._sim.show_progress = self.progress
        return self._sim

    def _pool_get(self):
        if self._pool is None:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            ctx = mp.get_context("spawn")
            self._pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_worker_init, initargs=(self.config,))
        return self._pool

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------ core
    def rollout(self, q0, qd0, cmd, effects: list[Effect]) -> np.ndarray:
        """Raw batched rollout (E arms), chunked / parallel as configured; effects' theta has E rows or 1."""
        e_count = q0.shape[0]
        if self.device.startswith("cuda"):
            return self.sim.rollout(q0, qd0, cmd, effects)
        n_chunks = max(1, -(-e_count // self.max_envs))
        if self.workers > 1 and e_count >= 8:
            n_chunks = max(n_chunks, self.workers)
        bounds = np.linspace(0, e_count, n_chunks + 1).astype(int)
        tasks = []
        for a, b in zip(bounds[:-1], bounds[1:]):
            specs = [_spec(fx, fx.theta.cpu().numpy()[a:b] if fx.theta.shape[0] > 1 else fx.theta.cpu().numpy()) for fx in effects]
            tasks.append((q0[a:b], qd0[a:b], cmd[a:b], specs))
        if self.workers > 1 and len(tasks) > 1:
            return np.concatenate(list(self._pool_get().map(_worker_run, tasks)), axis=0)
        return np.concatenate([self.sim.rollout(q, v, c, _effects_from_specs(s)) for q, v, c, s in tasks], axis=0)

    def simulate(self, segset: SegmentSet, effects: list[Effect], n_candidates: int = 1) -> np.ndarray:
        """(C*N, L, 7) simulated positions at the data samples, candidate-major."""
        n = segset.n
        idx = np.tile(np.arange(n), n_candidates)
        expanded = []
        for fx in effects:
            th = fx.theta.cpu().numpy()
            if th.shape[0] not in (1, n_candidates):
                raise ValueError(f"{fx.name}: theta has {th.shape[0]} rows, expected 1 or {n_candidates}")
            rows = np.repeat(th, n, axis=0) if th.shape[0] == n_candidates and n_candidates > 1 else th
            e = make_effect(fx.name, None, {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(fx.config).items()})
            e.set_theta(rows)
            expanded.append(e)
        hist = self.rollout(segset.q0[idx], segset.qd0[idx], segset.cmd[idx], expanded)
        return segset.sample(hist, idx)

    def evaluate(self, segset: SegmentSet, effects: list[Effect], n_candidates: int = 1) -> Scores:
        return score(segset, self.simulate(segset, effects, n_candidates), n_candidates)
