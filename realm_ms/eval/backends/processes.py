"""The process backend: N worker processes, each an ``EpisodeRunner`` stepping CPU physics and
rendering (on the GPU through Vulkan when there is one); the policy is batched once per round in
the main process. A worker that dies fails its episode and is replaced; a worker whose parent dies
exits.

Wire format: a worker writes each observation's arrays (``state``, ``img/<camera>``) into one
shared-memory block it owns, at 64-byte aligned offsets (``_layout``: name, shape, dtype, offset);
the pipe carries only ``(kind, new_block, payload)``: ``new_block`` = (block name, layout) when the
layout changed (the main process re-attaches), ``payload`` the small rest of the observation, an
``Unsupported`` signal, a finished record, or a worker's traceback.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import traceback
from multiprocessing import shared_memory

import numpy as np

from realm_ms.eval.backends.base import Backend, Failed, Unsupported
from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.runner import RunConfig, error_record
from realm_ms.eval.slots import EpisodeRunner


def _flat(obs: dict) -> dict[str, np.ndarray]:
    out = {"state": obs["state"]}
    for cam, img in obs.get("images", {}).items():
        out[f"img/{cam}"] = img
    return out


def _layout(arrays: dict[str, np.ndarray]) -> list[tuple]:
    out, off = [], 0
    for k, a in arrays.items():
        out.append((k, tuple(a.shape), a.dtype.str, off))
        off += (a.nbytes + 63) // 64 * 64
    return out


def _worker_main(conn, cfg: RunConfig, parent_pid: int) -> None:
    """Worker loop: commands from the pipe, observations into shared memory."""
    os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
    import torch

    torch.set_num_threads(1)
    runner = EpisodeRunner(cfg)
    shm, layout = None, None

    def send_obs(obs: dict) -> None:
        nonlocal shm, layout
        if isinstance(obs, Unsupported):
            conn.send(("obs", None, obs))
            return
        arrays = _flat(obs)
        lay = _layout(arrays)
        new = None
        if lay != layout:
            if shm is not None:
                shm.close()
                shm.unlink()
            size = max(64, sum((np.prod(s, dtype=np.int64) * np.dtype(d).itemsize + 63) // 64 * 64 for _, s, d, _ in lay))
            shm = shared_memory.SharedMemory(create=True, size=int(size))
            layout = lay
            new = (shm.name, lay)
        for (k, shape, dtype, off), a in zip(layout, arrays.values()):
            np.ndarray(shape, dtype=dtype, buffer=shm.buf, offset=off)[...] = a
        conn.send(("obs", new, {"instruction": obs["instruction"], "steps": obs["steps"]}))

    try:
        while True:
            if not conn.poll(5.0):
                if os.getppid() != parent_pid:  # orphaned: the driver was killed
                    break
                continue
            cmd, arg = conn.recv()
            try:
                if cmd == "start":
                    send_obs(runner.start(arg))
                elif cmd == "step":
                    actions, delay = arg
                    obs, rec = runner.step(actions, delay=delay)
                    if rec is not None:
                        conn.send(("record", None, rec))
                    else:
                        send_obs(obs)
                elif cmd == "abort":
                    conn.send(("record", None, runner.abort(arg)))
                elif cmd == "close":
                    break
            except Exception:
                conn.send(("error", None, traceback.format_exc()))
    except (EOFError, KeyboardInterrupt, BrokenPipeError):
        pass
    finally:
        runner.close()
        if shm is not None:
            shm.close()
            shm.unlink()


class ProcessBackend(Backend):
    """N worker processes (spawned: SAPIEN and torch are not fork-safe)."""

    def __init__(self, cfg: RunConfig, n_workers: int):
        self.cfg = cfg
        self.n_slots = n_workers
        self.ctx = mp.get_context("spawn")
        self.procs: list = [None] * n_workers
        self.conns: list = [None] * n_workers
        self.views: list[dict | None] = [None] * n_workers
        self.shms: list = [None] * n_workers
        self.cells: list = [None] * n_workers
        self.keys: list = [None] * n_workers
        self.deaths = [0] * n_workers
        for i in range(n_workers):
            self._spawn(i)

    def _spawn(self, i: int) -> None:
        parent, child = self.ctx.Pipe()
        env = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        old = {k: os.environ.get(k) for k in env}
        os.environ.update(env)  # inherited by the spawned interpreter
        try:
            p = self.ctx.Process(target=_worker_main, args=(child, self.cfg, os.getpid()), daemon=True)
            p.start()
        finally:
            for k, v in old.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        child.close()
        self.procs[i], self.conns[i] = p, parent
        self.views[i], self.shms[i], self.cells[i] = None, None, None

    def cell(self, slot: int):
        return self.cells[slot]

    def _attach(self, i: int, name: str, layout: list) -> None:
        if self.shms[i] is not None:
            self.shms[i].close()
        # the worker owns (and unlinks) the block; spawned workers share our resource tracker, which
        # also cleans it up if a worker is killed
        shm = shared_memory.SharedMemory(name=name)
        self.shms[i] = shm
        self.views[i] = {k: np.ndarray(shape, dtype=dtype, buffer=shm.buf, offset=off) for k, shape, dtype, off in layout}

    def _obs(self, i: int, meta: dict) -> dict:
        v = self.views[i]
        images = {k[4:]: v[k] for k in v if k.startswith("img/")}
        return {"state": v["state"].copy(), "images": images, "instruction": meta["instruction"], "steps": meta["steps"]}

    def _recv(self, i: int):
        """(kind, payload) from worker i; a dead worker yields an error record and is replaced."""
        try:
            kind, new, payload = self.conns[i].recv()
        except (EOFError, ConnectionResetError, BrokenPipeError):
            key, proc = self.keys[i], self.procs[i]
            proc.join(timeout=5)
            self.deaths[i] += 1
            if self.deaths[i] >= 3:  # dies before doing anything: a start-up problem, not an episode's
                raise RuntimeError(f"eval worker {i} died {self.deaths[i]} times in a row (exit code {proc.exitcode}); "
                                   "run with --workers 1 to see the error") from None
            self._spawn(i)
            return "record", error_record(self.cfg, key, f"worker process died (exit code {proc.exitcode})")
        if kind == "error":
            key = self.keys[i]
            self.conns[i].send(("close", None))
            self.procs[i].join(timeout=10)
            self._spawn(i)
            return "record", error_record(self.cfg, key, payload.strip().splitlines()[-1], payload)
        self.deaths[i] = 0
        if kind == "obs":
            if isinstance(payload, Unsupported):
                return "obs", payload
            if new is not None:
                self._attach(i, *new)
            return "obs", self._obs(i, payload)
        return kind, payload

    def start(self, starts: dict[int, EpisodeKey]) -> dict[int, dict]:
        for s, k in starts.items():
            self.keys[s] = k
            self.conns[s].send(("start", k))
        out = {}
        for s, k in starts.items():
            kind, payload = self._recv(s)
            if kind == "record":  # the reset itself failed: report it as the episode's result
                out[s] = Failed(payload)
            else:
                out[s] = payload
                self.cells[s] = k.cell()
        return out

    def step(self, commands: dict, delays: dict | None = None) -> dict:
        for s, a in commands.items():
            self.conns[s].send(("step", (a, (delays or {}).get(s, 0))))
        out = {}
        for s in commands:
            kind, payload = self._recv(s)
            out[s] = (None, payload) if kind == "record" else (payload, None)
        return out

    def abort(self, aborts: dict[int, str]) -> dict:
        for s, m in aborts.items():
            self.conns[s].send(("abort", m))
        return {s: self._recv(s)[1] for s in aborts}

    def close(self) -> None:
        for i, c in enumerate(self.conns):
            try:
                c.send(("close", None))
            except Exception:
                pass
        for p in self.procs:
            if p is not None:
                p.join(timeout=15)
                if p.is_alive():
                    p.terminate()
        for shm in self.shms:
            if shm is not None:
                shm.close()


__all__ = ["ProcessBackend"]
