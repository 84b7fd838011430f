"""Decoded camera frames held in memory while `lerobot-train` runs.

LeRobot's PyAV path answers every sample by opening the camera's video file, seeking to a keyframe
and decoding forward, once per camera: on a training set of short, small-frame episodes that is most
of the data loader's work (``bench/train_loader.py`` measures it). :func:`preload` decodes each video
file of a dataset once, in the training process before the data loader forks its workers (they share
those pages), and :func:`query_videos` then answers LeRobot's timestamp queries from memory
(:func:`frames_at`): the same frames LeRobot's decoder returns, chosen by the same nearest-timestamp
rule and refused beyond the same tolerance. A dataset whose decoded frames would not fit
``budget_bytes`` stays with LeRobot's decoder, as do depth videos.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import torch

DEFAULT_BUDGET_GB = 8.0  # decoded uint8 frames held per training process; REALM_FRAME_CACHE_GB overrides

# video path -> (frame timestamps in s (N,) float64, frames (N, C, H, W) uint8)
_FRAMES: dict[str, tuple[torch.Tensor, torch.Tensor]] = {}


def decode_file(path: Path | str) -> tuple[torch.Tensor, torch.Tensor]:
    """Every frame of a video file: timestamps as LeRobot computes them (pts x time base) and RGB frames."""
    import av

    stamps, frames = [], []
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        for frame in container.decode(stream):
            if frame.pts is None:
                continue
            stamps.append(float(frame.pts * stream.time_base))
            frames.append(frame.to_ndarray(format="rgb24"))
    if not frames:
        raise ValueError(f"{path}: no video frames could be decoded")
    return torch.tensor(stamps, dtype=torch.float64), torch.from_numpy(np.stack(frames)).permute(0, 3, 1, 2).contiguous()


def rgb_keys(meta) -> list[str]:
    return [k for k in meta.video_keys if k not in getattr(meta, "depth_keys", ())]


def video_files(dataset) -> list[Path]:
    """The RGB video files behind a LeRobotDataset (each once, in episode order)."""
    meta = dataset.meta
    rgb = rgb_keys(meta)
    episodes = dataset.episodes if dataset.episodes is not None else range(meta.total_episodes)
    files = {dataset.root / meta.get_video_file_path(ep, key): None for ep in episodes for key in rgb}
    return list(files)


def budget_bytes() -> int:
    return int(float(os.environ.get("REALM_FRAME_CACHE_GB", DEFAULT_BUDGET_GB)) * 2**30)


def preload(dataset, budget: int | None = None, threads: int | None = None) -> int:
    """Decode the dataset's video files into memory; returns the bytes held. Nothing is decoded when the
    frames (estimated from the dataset's own frame count and image shapes) would pass ``budget``."""
    budget = budget_bytes() if budget is None else budget
    meta = dataset.meta
    keys = rgb_keys(meta)
    need = sum(meta.total_frames * int(np.prod(meta.features[k]["shape"])) for k in keys)
    if not keys or need > budget:
        return 0
    todo = [p for p in video_files(dataset) if str(p) not in _FRAMES]
    with ThreadPoolExecutor(max_workers=threads or min(len(todo), os.cpu_count() or 1) or 1) as pool:
        for path, decoded in zip(todo, pool.map(decode_file, todo)):  # PyAV decodes outside the GIL
            _FRAMES[str(path)] = decoded
    return sum(f.numel() for _, f in _FRAMES.values())


def clear() -> None:
    _FRAMES.clear()


def nearest(stamps: torch.Tensor, query: torch.Tensor) -> torch.Tensor:
    """Index of the frame nearest each query time; ties go to the earlier frame (LeRobot's argmin)."""
    right = torch.searchsorted(stamps, query).clamp(max=len(stamps) - 1)
    left = (right - 1).clamp(min=0)
    return torch.where((query - stamps[left]).abs() <= (stamps[right] - query).abs(), left, right)


def frames_at(video_path, timestamps, tolerance_s, return_uint8=False) -> torch.Tensor:
    """The preloaded frames nearest ``timestamps``, as LeRobot's decoder returns them (uint8, or float32
    in [0, 1]); FrameTimestampError beyond ``tolerance_s``."""
    stamps, frames = _FRAMES[str(video_path)]
    query = torch.tensor(timestamps, dtype=torch.float64)
    idx = nearest(stamps, query)
    off = (stamps[idx] - query).abs()
    if not (off < tolerance_s).all():
        from lerobot.datasets.video_utils import FrameTimestampError

        raise FrameTimestampError(f"{video_path}: query timestamps {query[off >= tolerance_s].tolist()} have no "
                                  f"frame within {tolerance_s} s (nearest {stamps[idx[off >= tolerance_s]].tolist()})")
    out = frames[idx]
    return out if return_uint8 else out.type(torch.float32) / 255


def query_videos(reader, query_timestamps: dict[str, list[float]], ep_idx: int) -> dict[str, torch.Tensor]:
    """``DatasetReader._query_videos`` from memory: the same shift by the episode's start in the file and
    the same squeeze; LeRobot's method (a thread per camera and sample) where a file is not held."""
    ep = reader._meta.episodes[ep_idx]
    out = {}
    for key, stamps in query_timestamps.items():
        path = str(reader.root / reader._meta.get_video_file_path(ep_idx, key))
        if path not in _FRAMES or key in reader._meta.depth_keys:
            return _lerobot_query_videos(reader, query_timestamps, ep_idx)
        start = ep[f"videos/{key}/from_timestamp"]
        out[key] = frames_at(path, [start + t for t in stamps], reader._tolerance_s,
                             return_uint8=reader._return_uint8).squeeze(0)
    return out


_lerobot_query_videos = None


def install(train_module) -> None:
    """Route LeRobot's dataset reader through :func:`query_videos` and have ``train_module``
    (``lerobot.scripts.lerobot_train``) preload the datasets it makes."""
    global _lerobot_query_videos
    from lerobot.datasets.dataset_reader import DatasetReader

    if _lerobot_query_videos is None:
        _lerobot_query_videos = DatasetReader._query_videos
        DatasetReader._query_videos = query_videos
    make = train_module.make_train_eval_datasets
    if getattr(make, "_preloads", False):
        return

    def make_and_preload(cfg):
        datasets = make(cfg)
        for ds in datasets:
            if ds is not None and hasattr(ds, "meta"):
                held = preload(ds)
                print(f"frame cache: {held / 2**20:.1f} MiB of decoded frames in memory" if held else
                      "frame cache: frames left to LeRobot's decoder (over REALM_FRAME_CACHE_GB or no video)", flush=True)
        return datasets

    make_and_preload._preloads = True
    train_module.make_train_eval_datasets = make_and_preload
