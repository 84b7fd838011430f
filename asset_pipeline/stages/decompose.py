"""Convex decomposition: CoACD under a wall-clock budget, with a convex-hull fallback.

CoACD runs in a child process (forkserver) so a slow or crashing decomposition can be killed at the
budget without losing the worker. Results are cached by (geometry, settings) hash, so re-running a
build after metadata-only changes never repeats a decomposition.
"""

from __future__ import annotations

import hashlib
import multiprocessing as mp
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import trimesh

from asset_pipeline.export import read_convex_obj, write_convex_obj


@dataclass(frozen=True)
class CoacdSettings:
    """Lighter than CoACD defaults (threshold 0.05, 150 MCTS iterations): 4-30 s instead of 50-200 s
    per household mesh on one core, with grasp-relevant concavities (mug handles, bowls) kept."""

    threshold: float = 0.08
    max_convex_hull: int = 24
    preprocess_resolution: int = 30
    resolution: int = 1000
    mcts_nodes: int = 15
    mcts_iterations: int = 60
    mcts_max_depth: int = 2
    budget_s: float = 60.0
    max_faces: int = 20_000  # larger inputs are decimated by CoACD's manifold preprocessing anyway
    seed: int = 0

    def key(self) -> str:
        d = asdict(self)
        d.pop("budget_s")
        return hashlib.sha1(repr(sorted(d.items())).encode()).hexdigest()[:10]


@dataclass
class Decomposition:
    hulls: list[trimesh.Trimesh]
    method: str  # prebuilt | convex | coacd | hull-fallback:<why>
    seconds: float
    cached: bool = False


CONVEX_RATIO = 0.95  # volume / hull volume above which a closed mesh is treated as convex


def _child(vertices: np.ndarray, faces: np.ndarray, s: CoacdSettings, out: str) -> None:
    import coacd

    coacd.set_log_level("error")
    parts = coacd.run_coacd(
        coacd.Mesh(vertices, faces), threshold=s.threshold, max_convex_hull=s.max_convex_hull,
        preprocess_resolution=s.preprocess_resolution, resolution=s.resolution, mcts_nodes=s.mcts_nodes,
        mcts_iterations=s.mcts_iterations, mcts_max_depth=s.mcts_max_depth, seed=s.seed,
    )
    write_convex_obj([trimesh.Trimesh(v, f, process=False) for v, f in parts], Path(out))


def mesh_key(mesh: trimesh.Trimesh) -> str:
    h = hashlib.sha1(np.round(np.asarray(mesh.vertices), 6).tobytes())
    h.update(np.asarray(mesh.faces, np.int64).tobytes())
    return h.hexdigest()[:16]


def clean_hulls(hulls: list[trimesh.Trimesh]) -> list[trimesh.Trimesh]:
    """Re-hull each part (guarantees convexity) and drop slivers PhysX cannot cook."""
    out = []
    for h in hulls:
        if len(h.vertices) < 4:
            continue
        try:
            c = trimesh.convex.convex_hull(h.vertices)
        except Exception:  # coplanar points
            continue
        if c.volume > 1e-10:
            out.append(c)
    return out


def decompose(mesh: trimesh.Trimesh, settings: CoacdSettings, cache_dir: Path | None = None, use_coacd: bool = True) -> Decomposition:
    t0 = time.perf_counter()
    hull = trimesh.convex.convex_hull(mesh.vertices)
    if mesh.is_watertight and abs(mesh.volume) >= CONVEX_RATIO * hull.volume:
        return Decomposition([hull], "convex", time.perf_counter() - t0)
    if not use_coacd:
        return Decomposition([hull], "hull-fallback:disabled", time.perf_counter() - t0)
    cache_file = None
    if cache_dir is not None:
        cache_file = Path(cache_dir) / f"{mesh_key(mesh)}-{settings.key()}.obj"
        if cache_file.exists():
            return Decomposition(clean_hulls(read_convex_obj(cache_file)), "coacd", time.perf_counter() - t0, cached=True)
    src = mesh
    if len(src.faces) > settings.max_faces:  # keep the child's input small: largest faces carry the shape
        keep = np.argsort(-src.area_faces)[: settings.max_faces]
        src = trimesh.Trimesh(src.vertices, src.faces[keep], process=True)
    out = Path(cache_file) if cache_file is not None else Path(f"/tmp/coacd-{mesh_key(mesh)}-{settings.key()}.obj")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(f".tmp{mp.current_process().pid}.obj")
    # forkserver, not fork: a process that has started OpenMP/torch thread pools (any env, any
    # policy) deadlocks a plainly forked child inside CoACD, which then looks like a budget timeout
    ctx = mp.get_context("forkserver")
    p = ctx.Process(target=_child, args=(np.asarray(src.vertices, np.float64), np.asarray(src.faces, np.int32), settings, str(tmp)))
    p.start()
    p.join(settings.budget_s)
    if p.is_alive():
        p.kill()
        p.join()
        return Decomposition([hull], "hull-fallback:budget", time.perf_counter() - t0)
    if p.exitcode != 0 or not tmp.exists():
        return Decomposition([hull], f"hull-fallback:error{p.exitcode}", time.perf_counter() - t0)
    tmp.replace(out)
    hulls = clean_hulls(read_convex_obj(out))
    if cache_file is None:
        out.unlink(missing_ok=True)
    if not hulls:
        return Decomposition([hull], "hull-fallback:empty", time.perf_counter() - t0)
    return Decomposition(hulls, "coacd", time.perf_counter() - t0)
