"""The in-memory frame cache behind ``python -m realm_ms.lerobot.train``: the same samples LeRobot's own
PyAV decoder gives, its tolerance, its fallback, and LeRobot's training script running on it."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

pytest.importorskip("lerobot")
from lerobot.datasets.dataset_reader import DatasetReader  # noqa: E402
from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: E402
from lerobot.datasets.video_utils import FrameTimestampError, decode_video_frames_pyav  # noqa: E402

from realm_ms.lerobot import frame_cache  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
CAMS = ("observation.images.a", "observation.images.b")


@pytest.fixture(scope="module")
def dataset_root(tmp_path_factory) -> Path:
    """Three episodes of two moving-pattern cameras, written by LeRobot's own writer (AV1 video)."""
    root = tmp_path_factory.mktemp("frames") / "ds"
    feats = {"observation.state": {"dtype": "float32", "shape": (2,), "names": None},
             "action": {"dtype": "float32", "shape": (2,), "names": None}}
    feats |= {c: {"dtype": "video", "shape": (24, 32, 3), "names": ["height", "width", "channels"]} for c in CAMS}
    ds = LeRobotDataset.create(repo_id="local/frames", fps=15, features=feats, root=root, use_videos=True)
    rng = np.random.default_rng(0)
    for ep, length in enumerate((12, 7, 20)):
        for i in range(length):
            frame = {"observation.state": np.float32([ep, i]), "action": np.float32([i, -i]), "task": "t"}
            for k, c in enumerate(CAMS):  # a bright block that moves, on noise: each frame distinct
                img = rng.integers(0, 60, (24, 32, 3), dtype=np.uint8)
                img[4:12, (i * 3 + 5 * k) % 24:(i * 3 + 5 * k) % 24 + 8] = 250
                frame[c] = img
            ds.add_frame(frame)
        ds.save_episode()
    ds.finalize()
    return root


def load(root, **kw):
    return LeRobotDataset("local/frames", root=root, video_backend="pyav", **kw)


@pytest.fixture
def cached_reader():
    """DatasetReader routed through the cache for one test, LeRobot's method restored after it."""
    original = DatasetReader._query_videos
    frame_cache._lerobot_query_videos = original
    DatasetReader._query_videos = frame_cache.query_videos
    yield
    DatasetReader._query_videos = original
    frame_cache._lerobot_query_videos = None
    frame_cache.clear()


def test_whole_file_decode_equals_lerobot_decoder(dataset_root):
    ds = load(dataset_root)
    files = frame_cache.video_files(ds)
    assert files and all(p.exists() for p in files)
    for path in files:
        stamps, frames = frame_cache.decode_file(path)
        assert frames.dtype == torch.uint8 and frames.shape[1:] == (3, 24, 32)
        theirs = decode_video_frames_pyav(path, stamps.tolist(), 1e-4, return_uint8=True)
        assert torch.equal(frames, theirs)


def test_samples_identical_with_and_without_cache(dataset_root, cached_reader):
    # a past frame and an action chunk: the query shapes lerobot-train asks for
    delta = {c: [-1 / 15, 0.0] for c in CAMS} | {"action": [i / 15 for i in range(5)]}
    plain = load(dataset_root, delta_timestamps=delta)
    DatasetReader._query_videos = frame_cache._lerobot_query_videos
    want = [plain[i] for i in range(len(plain))]
    DatasetReader._query_videos = frame_cache.query_videos
    ds = load(dataset_root, delta_timestamps=delta)
    held = frame_cache.preload(ds)
    assert held == 39 * len(CAMS) * 3 * 24 * 32  # every frame of every camera, once
    got = [ds[i] for i in range(len(ds))]
    for a, b in zip(want, got):
        for c in CAMS:
            assert b[c].shape == (2, 3, 24, 32) and b[c].dtype == torch.float32
        for k, v in a.items():
            if isinstance(v, torch.Tensor):
                assert torch.equal(v, b[k]), k


def test_over_budget_leaves_decoding_to_lerobot(dataset_root, cached_reader):
    ds = load(dataset_root)
    assert frame_cache.preload(ds, budget=1000) == 0 and not frame_cache._FRAMES
    assert torch.equal(ds[5][CAMS[0]], load(dataset_root)[5][CAMS[0]])


def test_tolerance_and_nearest_frame(dataset_root):
    path = frame_cache.video_files(load(dataset_root))[0]
    frame_cache.preload(load(dataset_root))
    try:
        stamps, frames = frame_cache._FRAMES[str(path)]
        t = float(stamps[3])
        got = frame_cache.frames_at(path, [t + 0.01, t - 0.01], 0.02, return_uint8=True)
        assert torch.equal(got, frames[[3, 3]])
        mid = (float(stamps[3]) + float(stamps[4])) / 2  # a tie goes to the earlier frame, as LeRobot's argmin
        assert torch.equal(frame_cache.frames_at(path, [mid], 0.1, return_uint8=True), frames[[3]])
        with pytest.raises(FrameTimestampError, match="no frame within"):
            frame_cache.frames_at(path, [t + 0.03], 0.02)
    finally:
        frame_cache.clear()


def test_lerobot_train_runs_on_cache_with_forked_loader_workers(dataset_root, tmp_path):
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "realm_ms.lerobot.train", "--policy.type=act", "--policy.pretrained_backbone_weights=null",
           "--policy.dim_model=16", "--policy.n_heads=2", "--policy.dim_feedforward=32", "--policy.n_encoder_layers=1",
           "--policy.n_decoder_layers=1", "--policy.n_vae_encoder_layers=1", "--policy.chunk_size=3",
           "--policy.n_action_steps=3", "--policy.device=cpu", "--policy.push_to_hub=false", "--dataset.repo_id=local/frames",
           f"--dataset.root={dataset_root}", "--dataset.video_backend=pyav", "--steps=3", "--batch_size=4", "--num_workers=2",
           "--save_freq=3", "--log_freq=1", f"--output_dir={out}", "--wandb.enable=false"]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600,
                       env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    log = p.stdout + p.stderr
    assert "frame cache: 0.2 MiB of decoded frames in memory" in log  # 39 frames x 2 cameras x 24 x 32 x 3
    ckpt = out / "checkpoints" / "000003" / "pretrained_model"
    assert (ckpt / "model.safetensors").exists()
    assert json.loads((ckpt / "train_config.json").read_text())["dataloader_multiprocessing_context"] == "fork"
