"""Catalog build orchestration: enumerate sources, skip cached objects, run the rest in parallel
(local processes or Ray tasks), write ``catalog.jsonl`` and ``failures.jsonl``.

Robustness: each object is written atomically to ``objects/<id>/`` with its content hash, so a
crashed or interrupted build resumes where it stopped and an unchanged re-run only reads hashes.
"""

from __future__ import annotations

import json
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path

from asset_pipeline.config import BuildConfig
from asset_pipeline.process import Outcome, process_item
from asset_pipeline.record import CATALOG_FILE, FAILURES_FILE
from asset_pipeline.sources import DEFAULT_SOURCES, SOURCES, SourceItem
from realm_ms.atomic import write_text


class SourceUnavailable(Exception):
    pass


@dataclass
class BuildReport:
    out: str
    total: int = 0
    built: int = 0
    cached: int = 0
    failed: int = 0
    seconds: float = 0.0
    workers: int = 1
    backend: str = "local"
    skipped_sources: dict[str, str] = field(default_factory=dict)
    decomposition: dict[str, int] = field(default_factory=dict)
    build_seconds: float = 0.0  # summed per-object wall time of the objects built in this run
    build_cpu_seconds: float = 0.0  # summed per-object CPU time (incl. CoACD children)

    @property
    def objects_per_minute(self) -> float:
        return 60.0 * self.built / self.seconds if self.seconds > 0 else 0.0


def resolve_source(spec: str, cfg: BuildConfig) -> Iterator[SourceItem]:
    """``procedural`` | ``ycb`` | ... | ``folder:PATH`` | ``PATH`` (a folder of meshes) | ``NAME=PATH`` (a source's files at PATH)."""
    if spec.startswith("folder:") or (spec not in SOURCES and "=" not in spec and Path(spec).is_dir()):
        root = Path(spec.split(":", 1)[1] if spec.startswith("folder:") else spec)
        if not root.is_dir():
            raise SourceUnavailable(f"folder {root} does not exist")
        return SOURCES["folder"].items(root)
    name, _, path = spec.partition("=")
    if name not in SOURCES or name == "folder":
        known = ", ".join(n for n in SOURCES if n != "folder")
        raise SourceUnavailable(f"unknown source {spec!r}; known: {known}, or a folder path")
    src = SOURCES[name]
    root = Path(path) if path else src.locate()
    if root is None or not Path(root).exists():
        raise SourceUnavailable(f"source {name!r} not installed (pip install {src.package}, or pass {name}=PATH)")
    if name == "procedural":
        return src.items(root, variants=cfg.procedural_variants)
    return src.items(root)


def _origin(item: SourceItem) -> str:
    """What an item is made from: the same origin twice (a source listed twice) is one object."""
    return repr(item.procedural) if item.procedural is not None else str(item.mesh)


def _unique_id(item: SourceItem, items: dict[str, SourceItem]) -> str | None:
    """``item.id``, or for a *different* object whose name maps to a taken id (``a b.obj`` and
    ``a_b.obj`` both slug to ``a_b``) the id with a short hash of its file path; None for a duplicate."""
    first = items.get(item.id)
    if first is None:
        return item.id
    if _origin(first) == _origin(item):
        return None
    import hashlib

    return f"{item.id}-{hashlib.sha1(_origin(item).encode()).hexdigest()[:6]}"


def enumerate_items(sources: Iterable[str], cfg: BuildConfig, limit_per_source: int | None = None, strict: bool = True) -> tuple[list[SourceItem], dict[str, str]]:
    items: dict[str, SourceItem] = {}
    skipped: dict[str, str] = {}
    for spec in sources:
        try:
            it = resolve_source(spec, cfg)
            for i, item in enumerate(it):
                if limit_per_source is not None and i >= limit_per_source:
                    break
                oid = _unique_id(item, items)
                if oid is not None:
                    item.id = oid
                    items[oid] = item
        except SourceUnavailable as e:
            if strict:
                raise
            skipped[spec] = str(e)
    return list(items.values()), skipped


# --- executors ------------------------------------------------------------------------------------------


def _run_local(items: list[SourceItem], out: Path, cfg: BuildConfig) -> Iterator[Outcome]:
    if cfg.workers <= 1:
        for it in items:
            yield process_item(it, out, cfg)
        return
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    # Real meshes first: they are the long tasks, so the pool ends with short procedural ones.
    order = sorted(items, key=lambda i: i.procedural is not None)
    with ProcessPoolExecutor(max_workers=cfg.workers, mp_context=mp.get_context("fork")) as ex:
        futs = [ex.submit(process_item, it, str(out), cfg) for it in order]
        for f in as_completed(futs):
            yield f.result()


def _run_ray(items: list[SourceItem], out: Path, cfg: BuildConfig, address: str | None) -> Iterator[Outcome]:
    try:
        import ray
    except ImportError:
        raise SourceUnavailable("--ray needs the `ray` package (pip install 'realm-ms[ray]')") from None
    if not ray.is_initialized():
        if address:
            ray.init(address=address, ignore_reinit_error=True, log_to_driver=False)
        else:
            ray.init(num_cpus=max(cfg.workers, 1), include_dashboard=False, ignore_reinit_error=True, log_to_driver=False)
    remote = ray.remote(num_cpus=1, max_retries=1)(process_item)
    # The output folder must be shared storage on a multi-node cluster (workers write objects there).
    pending = []
    window = max(4 * max(cfg.workers, 1), 32)  # bounded in-flight tasks: memory stays flat
    queue = sorted(items, key=lambda i: i.procedural is not None)
    qi = 0
    while qi < len(queue) or pending:
        while qi < len(queue) and len(pending) < window:
            pending.append(remote.remote(queue[qi], str(out), cfg))
            qi += 1
        done, pending = ray.wait(pending, num_returns=1)
        for ref in done:
            yield ray.get(ref)


def _progress(total: int, enabled: bool):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="obj", dynamic_ncols=True, file=sys.stderr, smoothing=0.05)


def build_catalog(
    sources: Iterable[str],
    out: str | Path,
    cfg: BuildConfig | None = None,
    *,
    ray: bool = False,
    ray_address: str | None = None,
    limit_per_source: int | None = None,
    strict: bool = True,
    progress: bool = True,
    on_outcome: Callable[[Outcome], None] | None = None,
) -> BuildReport:
    cfg = cfg or BuildConfig()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    items, skipped = enumerate_items(sources, cfg, limit_per_source, strict)
    rep = BuildReport(out=str(out), total=len(items), workers=cfg.workers, backend="ray" if ray else "local", skipped_sources=skipped)
    (out / "build.json").write_text(json.dumps({"sources": list(sources), "config": asdict(cfg), "items": len(items), "started": time.time()}, indent=1))
    t0 = time.perf_counter()
    records: dict[str, dict] = {}
    failures: list[dict] = []
    dec: Counter[str] = Counter()
    bar = _progress(len(items), progress)
    runner = _run_ray(items, out, cfg, ray_address) if ray else _run_local(items, out, cfg)
    log = open(out / "progress.jsonl", "a")
    try:
        for o in runner:
            if o.status == "failed":
                rep.failed += 1
                failures.append({"id": o.id, "error": o.error, "seconds": round(o.seconds, 2)})
            else:
                rep.built += o.status == "built"
                rep.cached += o.status == "cached"
                if o.status == "built":
                    rep.build_seconds += o.seconds
                    rep.build_cpu_seconds += o.cpu_seconds
                records[o.id] = o.record  # type: ignore[assignment]
                dec[(o.decomposition or "?").split(":")[0]] += 1
            log.write(json.dumps({"id": o.id, "status": o.status, "s": round(o.seconds, 3)}) + "\n")
            if on_outcome:
                on_outcome(o)
            if bar is not None:
                bar.update(1)
                bar.set_postfix(built=rep.built, cached=rep.cached, failed=rep.failed, refresh=False)
    finally:
        log.close()
        if bar is not None:
            bar.close()
        _write_catalog(out, records, {f["id"] for f in failures}, failures)
    rep.seconds = time.perf_counter() - t0
    rep.decomposition = dict(dec)
    return rep


def _write_catalog(out: Path, records: dict[str, dict], failed: set[str], failures: list[dict]) -> None:
    """Merge this run's records into the catalog (other sources' entries are kept); atomic rewrite."""
    merged: dict[str, dict] = {}
    cat = out / CATALOG_FILE
    if cat.exists():
        for line in cat.read_text().splitlines():
            if line.strip():
                d = json.loads(line)
                if (out / d["collision"]).exists():
                    merged[d["id"]] = d
    for oid in failed:
        merged.pop(oid, None)
    for oid, d in records.items():
        d = {k: v for k, v in d.items() if not k.startswith("_")}
        merged[oid] = d
    write_text(cat, "".join(json.dumps(merged[oid], separators=(",", ":")) + "\n" for oid in sorted(merged)))
    with open(out / FAILURES_FILE, "w") as f:
        for d in sorted(failures, key=lambda d: d["id"]):
            f.write(json.dumps(d) + "\n")


def default_sources() -> list[str]:
    return list(DEFAULT_SOURCES)
