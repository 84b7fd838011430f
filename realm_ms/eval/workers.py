"""Execution backends for ``run_plan``: where the episode slots' envs live and step.

- ``InlineBackend``: slots in this process (one slot: the expert bench, the demo, Ray shards);
- ``ProcessBackend``: N worker processes, each an ``EpisodeRunner`` stepping CPU physics and
  rendering (on the GPU through Vulkan when there is one); observations come back through one
  shared-memory block per worker (only a small control message goes through the pipe), the policy is
  batched once per round in the main process. A worker that dies fails its episode and is replaced;
  a worker whose parent dies exits.
- ``BatchedBackend`` (``batched.py``): each sub-env of a ManiSkill env with ``num_envs = N`` is a
  slot; ManiSkill GPU simulation (``sim_backend="physx_cuda"``) where SAPIEN's GPU PhysX works
  (``gpu_physx_status()``), the same code on CPU physics with one sub-env per env otherwise.
- ``run_ray`` shards (task, perturbation) cells over a Ray cluster (``--ray-address``).

All backends share one protocol (``backend.Backend``): ``n_slots``, ``cell(slot)``, ``assign(free, queue)
-> {slot: key}``, ``start({slot: key}) -> {slot: obs}``, ``policy_input(ready, pending)``,
``step({slot: actions | None}, {slot: delay steps}) -> {slot: (obs, record)}``, ``abort({slot: msg}) -> {slot: record}``,
``close()``. ``choose_backend`` maps ``--backend`` onto them through ``BACKENDS``.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import sys
import traceback
from multiprocessing import shared_memory

import numpy as np

from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.backend import Backend
from realm_ms.eval.runner import RunConfig
from realm_ms.eval.slots import EpisodeRunner
from realm_ms.registry import Registry


class InlineBackend(Backend):
    def __init__(self, cfg: RunConfig, n_slots: int = 1):
        self.runners = [EpisodeRunner(cfg) for _ in range(n_slots)]
        self.n_slots = n_slots

    def cell(self, slot: int):
        return self.runners[slot].cell

    def start(self, starts: dict[int, EpisodeKey]) -> dict[int, dict]:
        return {s: self.runners[s].start(k) for s, k in starts.items()}

    def step(self, commands: dict, delays: dict | None = None) -> dict:
        return {s: self.runners[s].step(a, delay=(delays or {}).get(s, 0)) for s, a in commands.items()}

    def abort(self, aborts: dict[int, str]) -> dict:
        return {s: self.runners[s].abort(m) for s, m in aborts.items()}

    def close(self) -> None:
        for r in self.runners:
            r.close()


# ---------------------------------------------------------------------------------------- processes
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
        if "unsupported" in obs:
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
            return "record", _crash_record(key, self.cfg, f"worker process died (exit code {proc.exitcode})")
        if kind == "error":
            key = self.keys[i]
            self.conns[i].send(("close", None))
            self.procs[i].join(timeout=10)
            self._spawn(i)
            return "record", _crash_record(key, self.cfg, payload.strip().splitlines()[-1], payload)
        self.deaths[i] = 0
        if kind == "obs":
            if payload.get("unsupported"):
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
                out[s] = {"failed_record": payload}
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


def _crash_record(key: EpisodeKey | None, cfg: RunConfig, msg: str, tb: str | None = None) -> dict:
    rec = dict(task=key.task, perturbation=key.perturbation, seed=key.seed, policy=cfg.policy, status="error",
               error=msg, success=False, progression=0.0, steps=0) if key else dict(status="error", error=msg)
    if tb:
        rec["traceback"] = tb[-4000:]
    return rec


# ---------------------------------------------------------------------------------------- GPU / choice
def gpu_physx_library():
    """Where SAPIEN keeps its GPU PhysX library (``sapien.physx.enable_gpu`` downloads it there from GitHub on first use)."""
    import platform
    from pathlib import Path

    import sapien

    name = "PhysXGpu_64.dll" if platform.system() == "Windows" else "libPhysXGpu_64.so"
    return Path.home() / ".sapien" / "physx" / sapien.physx.version() / name


def gpu_physx_status() -> tuple[bool, str]:
    """(available, reason): SAPIEN GPU PhysX needs a CUDA device and SAPIEN's GPU PhysX library.

    A missing library is reported, not fetched: SAPIEN's own fetch has no timeout and would hang a
    machine without internet access."""
    try:
        import torch

        if not torch.cuda.is_available():
            return False, "no CUDA device is visible (torch.cuda.is_available() is False)"
        import sapien

        lib = gpu_physx_library()
        if not sapien.physx.is_gpu_enabled() and not lib.exists():
            return False, (f"SAPIEN's GPU PhysX library is not installed ({lib}); fetch it once on a machine with internet access: "
                           "python -c 'import sapien; sapien.physx.enable_gpu()'")
        sapien.physx.PhysxGpuSystem()
        return True, "SAPIEN GPU PhysX available"
    except Exception as e:  # noqa: BLE001  (SAPIEN raises plain RuntimeError/ImportError variants)
        return False, f"SAPIEN GPU PhysX unavailable: {type(e).__name__}: {e}"


def _cpu_backend(cfg: RunConfig, workers: int, gpu: bool):
    return InlineBackend(cfg, 1) if workers <= 1 else ProcessBackend(cfg, workers)


def _gpu_backend(cfg: RunConfig, workers: int, gpu: bool):
    from realm_ms.eval.batched import BatchedBackend

    return BatchedBackend(cfg, num_envs=workers, groups=1, sim_backend="physx_cuda")


def _batched_backend(cfg: RunConfig, workers: int, gpu: bool):
    """GPU simulation where it works; else the same runner on CPU physics, one sub-env per env."""
    from realm_ms.eval.batched import BatchedBackend

    if gpu:
        return _gpu_backend(cfg, workers, gpu)
    return BatchedBackend(cfg, num_envs=1, groups=workers, sim_backend="physx_cpu")


# --backend NAME -> factory(cfg, workers, gpu_physx_available); ``auto`` resolves to gpu or cpu
BACKENDS: Registry = Registry("backend")
BACKENDS.register("cpu", _cpu_backend)
BACKENDS.register("gpu", _gpu_backend)
BACKENDS.register("batched", _batched_backend)


def choose_backend(kind: str, cfg: RunConfig, workers: int):
    """``auto``: GPU simulation where SAPIEN's GPU PhysX works, else CPU worker processes; ``cpu``:
    worker processes (``workers`` <= 1 runs in-process); ``gpu``: one batched GPU env of ``workers``
    sub-envs, or a clear error; ``batched``: the batched runner on GPU physics where it works, else on
    CPU physics with ``workers`` single-sub-env envs in this process (the path the tests run)."""
    gpu, why = gpu_physx_status() if kind in ("auto", "gpu", "batched") else (False, "")
    if kind == "auto":
        kind = "gpu" if gpu else "cpu"
        if not gpu and not why.startswith("no CUDA device"):  # a GPU machine that could simulate on it: say why not
            print(f"realm eval: GPU simulation unavailable ({why}); using CPU worker processes", file=sys.stderr)
    if kind == "gpu" and not gpu:
        raise RuntimeError(f"--backend gpu: {why}; use --backend cpu (N worker processes) instead")
    if kind not in BACKENDS:
        raise RuntimeError(f"unknown backend {kind!r}; known: auto, {', '.join(BACKENDS)}")
    return BACKENDS[kind](cfg, workers, gpu)


# ---------------------------------------------------------------------------------------- Ray
def run_ray(keys: list[EpisodeKey], policy_spec: str, policy_options: dict, cfg: RunConfig, address: str, on_record, progress_bar: bool = True) -> int:
    """Shard (task, perturbation) cells over Ray (``address``: ``local``, ``auto`` or ``ray://...``);
    each cell runs in-process in one Ray task with its own policy; records stream back as cells end."""
    import ray
    from tqdm import tqdm

    if not ray.is_initialized():
        ray.init(address=None if address == "local" else address, include_dashboard=False, log_to_driver=False,
                 num_cpus=os.cpu_count() if address == "local" else None)

    @ray.remote(num_cpus=1)
    def run_cell(cell_keys, spec, options, run_cfg):
        from realm_ms.eval.policies import make_policy
        from realm_ms.eval.runner import run_plan

        recs: list = []
        policy = make_policy(spec, **options)
        backend = InlineBackend(run_cfg, 1)
        try:
            run_plan(cell_keys, policy, backend, recs.append, progress_bar=False, replan_every=run_cfg.replan_every,
                     policy_latency=run_cfg.policy_latency, env_kwargs=run_cfg.env_kwargs)
        finally:
            backend.close()
            policy.close()
        return recs

    cells: dict = {}
    for k in keys:
        cells.setdefault(k.cell(), []).append(k)
    refs = [run_cell.remote(v, policy_spec, policy_options, cfg) for v in cells.values()]
    n = 0
    with tqdm(total=len(keys), desc="episodes (ray)", unit="ep", disable=not progress_bar) as bar:
        while refs:
            done, refs = ray.wait(refs, num_returns=1)
            for rec in ray.get(done[0]):
                on_record(rec)
                n += 1
                bar.update(1)
    return n
