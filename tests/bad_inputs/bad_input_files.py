"""Malformed input files for the bad-input corpus, generated into a temporary directory.

``make_all(root)`` writes every file the corpus refers to and returns nothing: cases name the
files by their path relative to ``root`` (``{root}/frames`` in an argv is replaced by the test).
Each file differs from a valid one in exactly one way, so the expected error names that way.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

HOME = np.array([0.0, -np.pi / 5, 0.0, -4 * np.pi / 5, 0.0, 3 * np.pi / 5, 0.0])


def trajectory(n: int = 45, rate: float = 15.0, seed: int = 0) -> dict[str, np.ndarray]:
    """A valid trajectory: ``n`` samples at ``rate`` Hz near the DROID home pose."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    q_cmd = HOME + 0.05 * np.sin(2 * np.pi * 0.3 * t[:, None] + rng.uniform(0, 6, 7))
    return {"t": t, "q": q_cmd + 1e-3, "q_cmd": q_cmd, "control_hz": np.float64(15.0)}


def npz_dir(root: Path, name: str, count: int = 3, **changes) -> Path:
    """``count`` trajectories in ``root/name``; ``changes`` replace (or, with None, drop) arrays of the first."""
    d = root / name
    d.mkdir(parents=True, exist_ok=True)
    for i in range(count):
        arrays = trajectory(seed=i)
        if i == 0:
            for k, v in changes.items():
                if v is None:
                    arrays.pop(k, None)
                else:
                    arrays[k] = v(arrays) if callable(v) else v
        np.savez(d / f"traj_{i:03d}.npz", **arrays)
    return d


def lerobot(root: Path, name: str, info=None, columns: dict | None = None, drop: tuple[str, ...] = (),
            corrupt: bool = False) -> Path:
    """A minimal LeRobot v3.0 dataset (2 episodes); ``info`` replaces meta/info.json (a dict is merged)."""
    d = root / name
    (d / "meta").mkdir(parents=True, exist_ok=True)
    base = {"codebase_version": "v3.0", "fps": 15,
            "features": {"observation.state": {"dtype": "float32", "shape": [8]},
                         "action": {"dtype": "float32", "shape": [8]},
                         "timestamp": {"dtype": "float32", "shape": [1]},
                         "episode_index": {"dtype": "int64", "shape": [1]}}}
    if isinstance(info, dict):
        for k, v in info.items():
            if k == "features":
                base["features"].update(v)
            else:
                base[k] = v
        text = json.dumps(base)
    elif info is None:
        text = json.dumps(base)
    else:
        text = info if isinstance(info, str) else json.dumps(info)
    (d / "meta" / "info.json").write_text(text)
    chunk = d / "data" / "chunk-000"
    chunk.mkdir(parents=True, exist_ok=True)
    path = chunk / "file-000.parquet"
    if corrupt:
        path.write_bytes(b"PAR1" + bytes(range(256)) * 4)
        return d
    import pandas as pd

    rows = []
    for ep in range(2):
        tr = trajectory(seed=ep)
        for i in range(len(tr["t"])):
            rows.append({"observation.state": np.r_[tr["q"][i], 0.0].astype(np.float32),
                         "action": np.r_[tr["q_cmd"][i], 0.0].astype(np.float32),
                         "timestamp": np.float32(tr["t"][i]), "frame_index": i, "episode_index": ep})
    df = pd.DataFrame(rows)
    for k, v in (columns or {}).items():
        df[k] = v
    df = df.drop(columns=list(drop))
    df.to_parquet(path)
    return d


def model(root: Path, name: str, text: str) -> Path:
    p = root / "models" / name
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p


def make_all(root: Path) -> None:
    root.mkdir(parents=True, exist_ok=True)
    n = 45
    npz_dir(root, "good")
    npz_dir(root, "one", count=1)
    synth = root / "synth_layout"
    npz_dir(synth, "train", count=2)
    npz_dir(synth, "heldout", count=1)
    npz_dir(root, "frames", t=lambda a: np.arange(n, dtype=float))
    npz_dir(root, "millis", t=lambda a: a["t"] * 1000.0)
    npz_dir(root, "gap", t=lambda a: np.where(np.arange(n) >= 20, a["t"] + 3600.0, a["t"]))
    npz_dir(root, "backwards", t=lambda a: np.r_[a["t"][:10], a["t"][9], a["t"][11:]])
    npz_dir(root, "ctrl_zero", control_hz=np.float64(0.0))
    npz_dir(root, "ctrl_neg", control_hz=np.float64(-15.0))
    npz_dir(root, "ctrl_nan", control_hz=np.float64(np.nan))
    npz_dir(root, "ctrl_vec", control_hz=np.array([15.0, 15.0, 15.0]))
    npz_dir(root, "ctrl_slow", control_hz=np.float64(60.0))
    npz_dir(root, "nan_gripper", gripper=lambda a: np.where(np.arange(n) == 7, np.nan, 0.0))
    npz_dir(root, "gripper_2d", gripper=np.zeros((n, 2)))
    npz_dir(root, "nan_q", q=lambda a: np.where(np.arange(n)[:, None] == 5, np.nan, a["q"]))
    npz_dir(root, "degrees", q=lambda a: np.degrees(a["q"]), q_cmd=lambda a: np.degrees(a["q_cmd"]))
    npz_dir(root, "q_six", q=lambda a: a["q"][:, :6])
    npz_dir(root, "q_short", q=lambda a: a["q"][:-3])
    npz_dir(root, "no_qcmd", q_cmd=None)
    npz_dir(root, "few_samples", t=lambda a: a["t"][:10], q=lambda a: a["q"][:10], q_cmd=lambda a: a["q_cmd"][:10])
    npz_dir(root, "beyond_limits", q_cmd=lambda a: a["q_cmd"] + np.array([0, 0, 0, 3.0, 0, 0, 0]))
    npz_dir(root, "t_scalar", t=np.float64(1.0))
    npz_dir(root, "t_text", t=np.array(["a"] * n))
    (root / "text_npz").mkdir()
    (root / "text_npz" / "traj.npz").write_text("t,q,q_cmd\n0,0,0\n")
    (root / "empty_npz").mkdir()
    (root / "empty_npz" / "traj.npz").write_bytes(b"")
    (root / "not_zip_npz").mkdir()
    (root / "not_zip_npz" / "traj.npz").write_bytes(bytes(range(200, 256)) * 8)
    np.save(root / "npy_as_npz.npy", np.zeros(3))
    (root / "npy_as_npz.npy").rename(root / "npy_as_npz.npz")
    (root / "no_data").mkdir()
    (root / "no_data" / "readme.txt").write_text("nothing here")
    (root / "a_file.txt").write_text("a plain file")

    lerobot(root, "lr_good")
    lerobot(root, "lr_list", info=[1, 2, 3])
    lerobot(root, "lr_empty", info={})
    (root / "lr_empty" / "meta" / "info.json").write_text("{}")
    lerobot(root, "lr_badjson", info="{not json")
    lerobot(root, "lr_v2", info={"codebase_version": "v2.1"})
    lerobot(root, "lr_shape_empty", info={"features": {"observation.state": {"dtype": "float32", "shape": []}}})
    lerobot(root, "lr_shape_6", info={"features": {"action": {"dtype": "float32", "shape": [6]}}})
    lerobot(root, "lr_features_list")
    (root / "lr_features_list" / "meta" / "info.json").write_text(
        json.dumps({"codebase_version": "v3.0", "fps": 15, "features": ["action"]}))
    lerobot(root, "lr_fps0", info={"fps": 0})
    lerobot(root, "lr_corrupt", corrupt=True)
    lerobot(root, "lr_no_episode", drop=("episode_index",))
    lerobot(root, "lr_no_timestamp", drop=("timestamp",))

    model(root, "physics_neg.yaml", "physics_hz: -120\n")
    model(root, "physics_zero.yaml", "physics_hz: 0\n")
    model(root, "physics_100.yaml", "physics_hz: 100\n")
    model(root, "physics_text.yaml", "physics_hz: fast\n")
    model(root, "physics_nan.yaml", "physics_hz: .nan\n")
    model(root, "effects_string.yaml", "effects: coulomb_friction\n")
    model(root, "effects_list_of_names.yaml", "effects: [coulomb_friction]\n")
    model(root, "effects_unknown.yaml", "effects: [{name: magic_friction}]\n")
    model(root, "effects_no_name.yaml", "effects: [{params: {fc: 0.1}}]\n")
    model(root, "param_bounds.yaml", "effects: [{name: coulomb_friction, params: {fc4: 99}}]\n")
    model(root, "param_unknown.yaml", "effects: [{name: coulomb_friction, params: {friction: 0.1}}]\n")
    model(root, "params_list.yaml", "effects: [{name: coulomb_friction, params: [0.1]}]\n")
    model(root, "config_unknown.yaml", "effects: [{name: coulomb_friction, config: {wobbly: true}}]\n")
    model(root, "bad_yaml.yaml", "effects: [unclosed\n")
    model(root, "top_list.yaml", "- coulomb_friction\n")
    model(root, "gains_unknown.yaml", "gains: stiff\n")
    model(root, "joint_physics_unknown.yaml", "joint_physics: sticky\n")
    model(root, "version_9.yaml", "realm_ms_robot_model: 9\n")
    model(root, "binary.yaml", "").write_bytes(bytes(range(128, 256)))
    (root / "out_dir").mkdir()
    (root / "diag_bad.json").write_text("{\"baseline\": 1")
    (root / "diag_other.json").write_text("{\"something\": 1}")
