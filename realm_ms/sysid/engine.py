"""Evaluate many candidate models on many segments: chunking, worker processes, GPU dispatch.

``Evaluator.simulate(segset, effects, C)`` runs C candidate models (each effect's ``theta`` has C
rows, or 1 row shared by all) on every segment of ``segset`` and returns the simulated positions
at the data samples, candidate-major (C*N, L, 7). Large batches are cut into chunks of at most
``max_envs`` arms; with ``workers > 1`` the chunks go to persistent worker processes, each with its
own PhysX scene (spawned once, reused for every call). With ``device="cuda"`` one GPU scene runs the
whole batch (``gpu.py``). Equal arms are simulated once per batch, and arms simulated before come
from a bounded cache (``RolloutCache``).
"""

from __future__ import annotations

import hashlib
import os
from collections import OrderedDict
from typing import Any

import numpy as np

from realm_ms.agents.effects import Effect, make_effect
from realm_ms.sysid.replay import Scores, SegmentSet, score
from realm_ms.sysid.simulator import SimConfig

EffectSpec = tuple[str, dict[str, Any], np.ndarray]  # (name, config, theta (E, n))

_WORKER_SIM = None


def _spec(fx: Effect, theta: np.ndarray) -> EffectSpec:
    return (fx.name, fx.config_dict(), theta)


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
    from realm_ms.sysid.closed_loop import bind

    q0, qd0, cmd, specs, closed = args
    return _WORKER_SIM.rollout(q0, qd0, bind(closed, cmd), _effects_from_specs(specs), steps=cmd.shape[1])


def _theta_rows(fx: Effect, rows) -> np.ndarray:
    """The effect's parameters on arms ``rows`` (a theta of one row is shared by all arms)."""
    th = fx.theta.cpu().numpy()
    return th[rows] if th.shape[0] > 1 else th


def arm_keys(q0: np.ndarray, qd0: np.ndarray, cmd: np.ndarray, effects: list[Effect]) -> list[bytes]:
    """One digest per arm of everything its simulation depends on: start, commands, and the name,
    configuration and parameters of each effect that is not at its off-values on that arm. An effect
    at its off-values does nothing, so the other candidates of a screening batch do not make equal
    arms (every candidate's unperturbed probe, the baseline) look different."""
    per_effect = []
    for fx in sorted(effects, key=lambda f: f.name):
        per_effect.append(((fx.name + repr(fx.config_dict())).encode(), fx.theta.cpu().numpy(), fx.on_rows().cpu().numpy()))
    keys = []
    for i in range(q0.shape[0]):
        h = hashlib.blake2b(digest_size=16)
        for a in (q0[i], qd0[i], cmd[i]):
            h.update(np.ascontiguousarray(a).tobytes())
        for tag, th, on in per_effect:
            r = min(i, th.shape[0] - 1)
            if on[r]:
                h.update(tag)
                h.update(th[r].tobytes())
        keys.append(h.digest())
    return keys


class RolloutCache:
    """Simulated arms by ``arm_keys``, least recently used out first, at most ``max_bytes``: a fit
    re-simulates what the diagnosis or its own last step already ran (the nominal model, the best
    candidate, the centre of every probe batch)."""

    def __init__(self, max_bytes: float = 256e6):
        self.max_bytes = max_bytes
        self._rows: OrderedDict[bytes, np.ndarray] = OrderedDict()
        self._bytes = 0
        self.hits = self.misses = 0

    def get(self, key: bytes) -> np.ndarray | None:
        row = self._rows.get(key)
        if row is not None:
            self._rows.move_to_end(key)
        return row

    def put(self, key: bytes, row: np.ndarray) -> None:
        if key in self._rows or row.nbytes > self.max_bytes:
            return
        self._rows[key] = row = np.array(row)  # a copy: a view would keep its whole batch alive
        self._bytes += row.nbytes
        while self._bytes > self.max_bytes:
            self._bytes -= self._rows.popitem(last=False)[1].nbytes


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


#: ms one more arm adds to a rollout per physics step on one core, as ``Effect.step_cost`` counts
#: an effect's (bench/sysid_effect_cost.py measures both)
ARM_STEP_COST = 0.15


def plan_chunks(on: np.ndarray, step_cost: np.ndarray, n_chunks: int, max_envs: int,
                lengths: np.ndarray | None = None) -> list[np.ndarray]:
    """Arm indices of each chunk of a batch, at most ``max_envs`` arms per chunk.

    ``on`` (E, F) says which of the batch's F effects is on at each arm; ``step_cost`` (F, 2) what
    each costs per physics step in a chunk where it is on at all, and per arm it is on
    (``Effect.step_cost``); every arm adds ``ARM_STEP_COST``. Two plans are costed and the one
    whose dearest chunk costs least is kept: ``n_chunks`` contiguous equal chunks (all a batch whose
    arms run the same effects can have: a fit's population, a baseline), or arms with the same
    effects kept together and those groups spread over the chunks dearest first, each to the chunk
    it leaves cheapest, so that a screening batch's costly friction laws land on different workers.
    ``lengths``: the arms' physics steps, longest first; the contiguous chunks then hold equal
    shares of the arm-steps rather than of the arms (a chunk runs as long as its longest arm)."""
    e_count = on.shape[0]
    step_cost = np.asarray(step_cost, float).reshape(-1, 2)
    bounds = np.linspace(0, e_count, n_chunks + 1).astype(int)
    if lengths is not None and n_chunks > 1:
        # arms longest first: cut where each chunk holds an equal share of the arm-steps
        cum = np.cumsum(lengths)
        by_steps = np.r_[0, np.searchsorted(cum, cum[-1] * np.arange(1, n_chunks) / n_chunks) + 1, e_count]
        if (np.diff(by_steps) <= max_envs).all():
            bounds = np.maximum.accumulate(np.minimum(by_steps, e_count))
    contiguous = [np.arange(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
    sig = np.unique(on, axis=0, return_inverse=True)[1].reshape(-1)
    if n_chunks == 1 or sig.max(initial=0) == 0:
        return contiguous

    def cost(arms_on: np.ndarray, arms: int) -> float:  # arms_on: (F,) arms each effect is on
        used = arms_on > 0
        return float(step_cost[used, 0].sum() + step_cost[:, 1] @ arms_on) + ARM_STEP_COST * arms

    pieces = []
    for g in np.unique(sig):
        rows = np.flatnonzero(sig == g)
        pieces += [(on[rows[0]] * len(r), r) for r in np.array_split(rows, -(-len(rows) // max_envs))]
    pieces.sort(key=lambda p: -cost(p[0], len(p[1])))
    load = [(np.zeros(on.shape[1]), 0, []) for _ in range(n_chunks)]  # (arms each effect is on, arms, pieces)
    for arms_on, rows in pieces:
        room = [c for c in range(len(load)) if load[c][1] + len(rows) <= max_envs]
        if not room:  # the pieces do not pack into n_chunks: one more chunk, never one over max_envs
            load.append((np.zeros(on.shape[1]), 0, []))
            room = [len(load) - 1]
        c = min(room, key=lambda c: cost(load[c][0] + arms_on, load[c][1] + len(rows)))
        load[c] = (load[c][0] + arms_on, load[c][1] + len(rows), load[c][2] + [rows])
    grouped = [np.sort(np.concatenate(members)) for _, _, members in load if members]

    def dearest(chunks: list[np.ndarray]) -> float:
        return max(cost(on[rows].sum(axis=0), len(rows)) for rows in chunks)

    return grouped if dearest(grouped) < dearest(contiguous) else contiguous


class Evaluator:
    def __init__(self, config: SimConfig | None = None, workers: int = 1, device: str | None = None,
                 max_envs: int = 1200):
        self.config = config or SimConfig()
        self.workers = max(1, int(workers))
        self.device = device or "cpu"
        self.max_envs = max_envs
        self._sim = None
        self._pool = None
        self.cache = RolloutCache()
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

    def _pool_get(self) -> list:
        """One single-process executor per worker: chunk k of every batch goes to worker k % workers.
        A replay arm keeps a trace of what it simulated before (an arm reset after a build-time
        effect replays ~1e-6 rad off a fresh one), so a shared pool, which hands a chunk to whichever
        worker is free, made a run's results depend on timing; pinned, a run repeats bit for bit."""
        if self._pool is None:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            ctx = mp.get_context("spawn")
            self._pool = [ProcessPoolExecutor(1, mp_context=ctx, initializer=_worker_init, initargs=(self.config,))
                          for _ in range(self.workers)]
        return self._pool

    def close(self) -> None:
        if self._pool is not None:
            for pool in self._pool:
                pool.shutdown(cancel_futures=True)
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------ core
    def rollout(self, q0, qd0, cmd, effects: list[Effect], closed=None, lengths=None) -> np.ndarray:
        """Batched rollout (E arms) -> (E, S + 1, 7); effects' theta has E rows or 1. Each distinct
        arm (``arm_keys``) is simulated once, and not at all when the cache holds it.
        ``closed``: closed-loop DROID commands (``closed_loop.ClosedLoopCommand``), E rows.
        ``lengths``: (E,) physics steps each arm needs (None: all S); the steps after them hold
        the arm's last simulated state."""
        keys = arm_keys(q0, qd0, cmd, effects)
        if closed is not None:
            keys = [k + closed.key(i) for i, k in enumerate(keys)]
        rows = {k: self.cache.get(k) for k in keys}
        todo = list(dict.fromkeys(k for k in keys if rows[k] is None))
        self.cache.hits += len(keys) - len(todo)
        self.cache.misses += len(todo)
        if todo:
            first_of: dict[bytes, int] = {}
            for i, k in enumerate(keys):
                first_of.setdefault(k, i)
            first = np.array([first_of[k] for k in todo])
            sub = _effects_from_specs([_spec(fx, _theta_rows(fx, first)) for fx in effects])
            sub_closed = None if closed is None else closed.rows(first)
            sub_len = None if lengths is None else np.asarray(lengths)[first]
            for k, row in zip(todo, self._simulate(q0[first], qd0[first], cmd[first], sub, sub_closed, sub_len)):
                rows[k] = row
                self.cache.put(k, row)
        return np.stack([rows[k] for k in keys])

    def _simulate(self, q0, qd0, cmd, effects: list[Effect], closed=None, lengths=None) -> np.ndarray:
        """The rollout itself: chunked / in worker processes as configured, or on the GPU. With
        ``lengths``, arms are chunked longest first and each chunk runs only as many steps as its
        longest arm needs (a batch of segments runs as long as its longest one; the padding of the
        shorter ones is most of a chunk of short ones)."""
        e_count = q0.shape[0]
        if self.device.startswith("cuda"):
            if closed is not None:
                from realm_ms.validate import InputError

                raise InputError("--command closed_loop replays on the CPU (its IK runs per arm between physics "
                                 "steps); add --device cpu")
            return self.sim.rollout(q0, qd0, cmd, effects)
        n_chunks = max(1, -(-e_count // self.max_envs))
        if self.workers > 1 and e_count >= 8:
            n_chunks = max(n_chunks, self.workers)
        on = np.stack([np.broadcast_to(fx.on_rows().cpu().numpy(), (e_count,)) for fx in effects], 1) \
            if effects else np.zeros((e_count, 0), bool)
        steps = cmd.shape[1]
        lengths = np.full(e_count, steps) if lengths is None else np.clip(np.asarray(lengths), 1, steps)
        order = np.argsort(-lengths, kind="stable")
        chunks = [order[rows] for rows in plan_chunks(on[order], np.array([fx.step_cost for fx in effects]), n_chunks,
                                                      self.max_envs, lengths[order])]
        tasks = []
        for rows in chunks:
            # an effect at its off-values on every arm of a chunk replays as if absent (the effects'
            # contract): a chunk of several leaves it out rather than pay its hooks at every step
            specs = [_spec(fx, _theta_rows(fx, rows)) for fx, o in zip(effects, on.T) if len(chunks) == 1 or o[rows].any()]
            n = int(lengths[rows].max())
            tasks.append((q0[rows], qd0[rows], cmd[rows, :n], specs, None if closed is None else closed.rows(rows)))
        if self.workers > 1 and len(tasks) > 1:
            pools = self._pool_get()
            parts = [f.result() for f in [pools[k % len(pools)].submit(_worker_run, t) for k, t in enumerate(tasks)]]
        else:
            from realm_ms.sysid.closed_loop import bind

            parts = [self.sim.rollout(q, v, bind(cl, c), _effects_from_specs(s), steps=c.shape[1]) for q, v, c, s, cl in tasks]
        out = np.empty((e_count, steps + 1, 7), parts[0].dtype)
        for rows, part in zip(chunks, parts):
            out[rows, :part.shape[1]] = part
            out[rows, part.shape[1]:] = part[:, -1:]
        return out

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
            e = make_effect(fx.name, None, fx.config_dict())
            e.set_theta(rows)
            expanded.append(e)
        closed = None if segset.closed is None else segset.closed.rows(idx)
        hist = self.rollout(segset.q0[idx], segset.qd0[idx], segset.cmd[idx], expanded, closed, segset.lengths[idx])
        return segset.sample(hist, idx)

    def evaluate(self, segset: SegmentSet, effects: list[Effect], n_candidates: int = 1) -> Scores:
        return score(segset, self.simulate(segset, effects, n_candidates), n_candidates)
