"""Which backend runs a plan: ``--backend NAME`` -> a backend (``choose_backend``), and the probe of
SAPIEN's GPU PhysX that ``auto`` / ``gpu`` / ``batched`` decide on (``gpu_physx_status``)."""

from __future__ import annotations

import sys

from realm_ms.eval.runner import RunConfig
from realm_ms.registry import Registry


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
    if workers <= 1:
        from realm_ms.eval.backends.inline import InlineBackend

        return InlineBackend(cfg, 1)
    from realm_ms.eval.backends.processes import ProcessBackend

    return ProcessBackend(cfg, workers)


def _gpu_backend(cfg: RunConfig, workers: int, gpu: bool):
    from realm_ms.eval.backends.batched import BatchedBackend

    return BatchedBackend(cfg, num_envs=workers, groups=1, sim_backend="physx_cuda")


def _batched_backend(cfg: RunConfig, workers: int, gpu: bool):
    """GPU simulation where it works; else the same runner on CPU physics, one sub-env per env."""
    from realm_ms.eval.backends.batched import BatchedBackend

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


__all__ = ["BACKENDS", "choose_backend", "gpu_physx_status", "gpu_physx_library"]
