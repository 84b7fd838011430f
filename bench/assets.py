"""Asset pipeline throughput: objects/minute per core on a fixed mixed sample, and the extrapolated
time of the full default build (``realm assets build --all``).

    python bench/assets.py                # 1 worker, then 2 workers (speed-up)
    python bench/assets.py --workers 1    # one configuration only

The sample mixes every object kind of the default catalog: procedural objects, prebuilt-collision
objects (LIBERO boxes, pybullet random_urdfs), convex shapes (RGB objects) and CoACD objects (YCB,
robosuite). Per-kind mean times are multiplied by the kind's count in the full build.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from asset_pipeline.build import enumerate_items  # noqa: E402
from asset_pipeline.config import BuildConfig  # noqa: E402
from asset_pipeline.process import process_item  # noqa: E402
from asset_pipeline.sources import DEFAULT_SOURCES  # noqa: E402

# Fixed sample: every n-th item of each source (deterministic), capped per source. Costs differ far
# more between sources (CoACD scans vs prebuilt boxes vs generators) than within one.
SAMPLE = {"procedural": (89, 40), "ycb": (26, 3), "libero": (12, 4), "robosuite": (3, 2), "rgb_objects": (50, 6),
          "robocasa": (1, 1), "pybullet": (3, 3), "pybullet_random": (125, 8)}


def kind(item) -> str:
    return item.source


def run(items, workers: int, cfg: BuildConfig) -> tuple[float, dict[str, list[float]]]:
    out = Path(tempfile.mkdtemp(prefix="realm-bench-"))
    per_kind: dict[str, list[float]] = defaultdict(list)  # CPU seconds per object (contention-free)
    t0 = time.perf_counter()
    try:
        if workers == 1:
            outcomes = [process_item(it, out, cfg) for it in items]
        else:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            order = sorted(items, key=lambda i: i.procedural is not None)
            with ProcessPoolExecutor(workers, mp_context=mp.get_context("fork")) as ex:
                outcomes = list(ex.map(process_item, order, [str(out)] * len(order), [cfg] * len(order)))
            items = order
        wall = time.perf_counter() - t0
        for it, o in zip(items, outcomes):
            if o.status == "failed":
                print(f"  failed: {o.id}: {o.error}", file=sys.stderr)
            per_kind[kind(it)].append(o.cpu_seconds)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    return wall, per_kind


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    cfg = BuildConfig()
    full, skipped = enumerate_items(DEFAULT_SOURCES, cfg, strict=False)
    full_counts: dict[str, int] = defaultdict(int)
    for it in full:
        full_counts[kind(it)] += 1
    by_source: dict[str, list] = defaultdict(list)
    for it in full:
        by_source[it.source].append(it)
    sample = []
    for src, (step, cap) in SAMPLE.items():
        sample += by_source.get(src, [])[::step][:cap]
    results = {"sample_objects": len(sample), "full_objects": len(full), "full_by_kind": dict(full_counts), "skipped_sources": skipped, "runs": []}
    for w in args.workers:
        wall, per_kind = run(sample, w, cfg)
        mean = {k: sum(v) / len(v) for k, v in per_kind.items()}
        cpu_total = sum(sum(v) for v in per_kind.values())
        cpu_s = sum(full_counts[k] * mean.get(k, max(mean.values())) for k in full_counts)
        r = {"workers": w, "wall_s": round(wall, 1), "cpu_s": round(cpu_total, 1),
             "objects_per_min_wall": round(60 * len(sample) / wall, 1),
             "objects_per_min_per_core": round(60 * len(sample) / cpu_total, 1),
             "mean_cpu_s_by_kind": {k: round(v, 3) for k, v in mean.items()},
             "full_build_cpu_min": round(cpu_s / 60, 1),
             "full_build_estimate_min": round(cpu_s / w / 60, 1)}
        results["runs"].append(r)
        if not args.json:
            print(f"{w} worker(s): {len(sample)} objects in {wall:.1f} s wall, {cpu_total:.1f} s CPU = "
                  f"{r['objects_per_min_per_core']:.0f} obj/min per core ({r['objects_per_min_wall']:.0f} obj/min wall on this machine now); "
                  f"CPU s per object by kind {r['mean_cpu_s_by_kind']}; full default build ({len(full)} objects) = "
                  f"{r['full_build_cpu_min']:.0f} CPU-min ~ {r['full_build_estimate_min']:.0f} min on {w} idle core(s)")
    if len(results["runs"]) > 1:
        results["speedup"] = round(results["runs"][0]["wall_s"] / results["runs"][-1]["wall_s"], 2)
        if not args.json:
            print(f"speed-up {args.workers[0]} -> {args.workers[-1]} workers: {results['speedup']}x")
    if args.json:
        print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
