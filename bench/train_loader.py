"""Training data-loader throughput: LeRobot's per-sample PyAV decoding against the in-memory frame cache
(``python -m realm_ms.lerobot.train``), samples/s through a DataLoader as ``lerobot-train`` builds it.

    .venv/bin/python bench/train_loader.py --root outputs/train_eval/dataset [--workers 2] [--batches 30]

Both rows read the same dataset with ACT's query (the current frame of every camera, a 20-step action
chunk), shuffled, ``--batch-size`` samples per batch, ``--workers`` forked loader processes (0: in
this process). The cache row includes its one-off preload, reported separately.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


def throughput(ds, batch_size: int, workers: int, batches: int) -> float:
    import torch

    loader = torch.utils.data.DataLoader(ds, batch_size=batch_size, shuffle=True, num_workers=workers,
                                         multiprocessing_context="fork" if workers else None,
                                         generator=torch.Generator().manual_seed(0))
    it = iter(loader)
    next(it)  # worker start-up and the first batch are not throughput
    t0 = time.perf_counter()
    for _ in range(batches):
        next(it)
    return batches * batch_size / (time.perf_counter() - t0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, required=True, help="a LeRobot dataset with video cameras (e.g. a realm export)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--batch-size", type=int, default=64)
    ap.add_argument("--batches", type=int, default=30)
    ap.add_argument("--chunk", type=int, default=20)
    a = ap.parse_args(argv)
    if not (a.root / "meta" / "info.json").exists():
        ap.error(f"--root {a.root}: no LeRobot dataset there (meta/info.json missing); make one with `realm export`")

    from lerobot.datasets.dataset_reader import DatasetReader
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.scripts import lerobot_train

    from realm_ms.lerobot import frame_cache

    def dataset():
        meta = LeRobotDataset(f"realm/{a.root.name}", root=a.root, video_backend="pyav").meta
        delta = {"action": [i / meta.fps for i in range(a.chunk)]}
        return LeRobotDataset(f"realm/{a.root.name}", root=a.root, video_backend="pyav", delta_timestamps=delta)

    base = throughput(dataset(), a.batch_size, a.workers, a.batches)
    frame_cache.install(lerobot_train)
    ds = dataset()
    t0 = time.perf_counter()
    held = frame_cache.preload(ds)
    preload_s = time.perf_counter() - t0
    cached = throughput(ds, a.batch_size, a.workers, a.batches)
    DatasetReader._query_videos = frame_cache._lerobot_query_videos
    print(f"dataset {a.root}: {ds.meta.total_episodes} episodes, {ds.meta.total_frames} frames, "
          f"{len(ds.meta.video_keys)} cameras; batch {a.batch_size}, {a.workers} loader workers, {a.batches} batches")
    print(f"LeRobot PyAV per sample : {base:8.1f} samples/s")
    print(f"frame cache             : {cached:8.1f} samples/s  ({cached / base:.2f}x; preload {preload_s:.1f} s, "
          f"{held / 2**20:.0f} MiB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
