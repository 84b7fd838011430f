"""Reading and writing measured data.

Two input formats (see ``docs/sysid.md``):

* **npz directory**: one ``.npz`` per trajectory with ``t`` (T,) s, ``q`` (T,7) rad, ``q_cmd`` (T,7) rad
  (held from ``t[i]`` until ``t[i+1]``), optional ``qd``, ``tau``, ``gripper``, ``gripper_cmd`` and
  scalar ``control_hz``. ``synth`` writes this format.
* **LeRobot v3.0 dataset** (DROID convention): ``meta/info.json`` + ``data/chunk-*/file-*.parquet`` with
  ``observation.state`` = 7 joint positions + gripper, ``action`` = 7 joint-position targets + gripper,
  ``timestamp``, ``episode_index``; optional velocity/effort features (any feature whose name contains
  ``velocit`` / ``effort`` with 7 or 8 entries). Each episode is one trajectory. The parquet files
  are read directly (no video decoding).

A DATA directory holding ``train/`` and ``heldout/`` subdirectories (what ``synth`` writes) is
split that way; otherwise commands split it by trajectory (``timeseries.split``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from realm_ms.sysid.timeseries import DataError, Trajectory, validate

NPZ_REQUIRED = ("t", "q", "q_cmd")
NPZ_OPTIONAL = ("qd", "tau", "gripper", "gripper_cmd", "control_hz")


def joint_limits() -> np.ndarray:
    from realm_ms.agents.arm_model import ArmModel
    from realm_ms.sysid.urdf import BASE_LINK, TIP_LINK, source_urdf_path

    return ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK).q_limits


def read_npz(path: Path) -> Trajectory:
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except Exception as e:  # noqa: BLE001 - any unreadable file is a user error
        raise DataError(f"{path}: cannot read as .npz ({type(e).__name__}: {e})") from None
    missing = [k for k in NPZ_REQUIRED if k not in data]
    if missing:
        raise DataError(f"{path}: missing key(s) {missing}; an .npz trajectory needs t (T,), q (T,7), q_cmd (T,7)")
    hz = data.get("control_hz")
    return Trajectory(
        path.stem, data["t"], data["q"], data["q_cmd"], data.get("qd"), data.get("tau"),
        data.get("gripper"), data.get("gripper_cmd"), float(hz) if hz is not None else None,
    )


def write_npz(path: Path, traj: Trajectory) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"t": traj.t, "q": traj.q, "q_cmd": traj.q_cmd}
    for k in ("qd", "tau", "gripper", "gripper_cmd"):
        v = getattr(traj, k)
        if v is not None:
            arrays[k] = v
    if traj.control_hz is not None:
        arrays["control_hz"] = np.float64(traj.control_hz)
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, **arrays)
    tmp.replace(path)


def _lerobot_feature(info: dict, words: tuple[str, ...]) -> str | None:
    for name, feat in info.get("features", {}).items():
        if any(w in name for w in words) and feat.get("dtype") in ("float32", "float64") and feat.get("shape", [0])[0] in (7, 8):
            return name
    return None


def read_lerobot(root: Path) -> list[Trajectory]:
    info_path = root / "meta" / "info.json"
    info = json.loads(info_path.read_text())
    version = str(info.get("codebase_version", "?"))
    if not version.startswith("v3"):
        raise DataError(f"{root}: LeRobot dataset version {version}; only v3.0 is supported (convert with lerobot's v2.1->v3.0 script)")
    feats = info.get("features", {})
    for key in ("observation.state", "action"):
        if key not in feats:
            raise DataError(f"{root}: LeRobot dataset lacks `{key}`; DROID convention: observation.state = 7 joint positions + gripper, action = 7 joint targets + gripper")
        if feats[key].get("shape", [0])[0] not in (7, 8):
            raise DataError(f"{root}: `{key}` has shape {feats[key].get('shape')}; expected 7 joints (+ gripper)")
    files = sorted((root / "data").glob("chunk-*/*.parquet"))
    if not files:
        raise DataError(f"{root}: no parquet files under data/chunk-*/")
    import pandas as pd

    df = pd.concat([pd.read_parquet(f) for f in files], ignore_index=True)
    vel, eff = _lerobot_feature(info, ("velocit",)), _lerobot_feature(info, ("effort", "torque"))
    fps = float(info.get("fps", 15))
    trajs = []
    for ep, g in df.groupby("episode_index", sort=True):
        g = g.sort_values("frame_index") if "frame_index" in g else g
        state = np.stack(g["observation.state"].to_numpy())
        action = np.stack(g["action"].to_numpy())
        t = g["timestamp"].to_numpy(dtype=np.float64) if "timestamp" in g else np.arange(len(g)) / fps
        trajs.append(Trajectory(
            f"episode_{int(ep):06d}", t, state[:, :7], action[:, :7],
            np.stack(g[vel].to_numpy())[:, :7] if vel else None,
            np.stack(g[eff].to_numpy())[:, :7] if eff else None,
            state[:, 7] if state.shape[1] > 7 else None, action[:, 7] if action.shape[1] > 7 else None, fps,
        ))
    return trajs


def load_dir(path: str | Path, limits: np.ndarray | None = None) -> list[Trajectory]:
    """All trajectories in an npz directory or a LeRobot v3.0 dataset, validated."""
    root = Path(path)
    if not root.exists():
        raise DataError(f"{root}: no such file or directory")
    limits = joint_limits() if limits is None else limits
    if root.is_file() and root.suffix == ".npz":
        raw = [read_npz(root)]
    elif (root / "meta" / "info.json").exists():
        raw = read_lerobot(root)
    elif root.is_dir():
        files = sorted(root.glob("*.npz"))
        if not files:
            sub = [d.name for d in root.iterdir() if d.is_dir()]
            raise DataError(f"{root}: no .npz trajectories and no LeRobot dataset (meta/info.json) here" + (f"; subdirectories: {sub}" if sub else ""))
        raw = [read_npz(f) for f in files]
    else:
        raise DataError(f"{root}: expected a directory of .npz files or a LeRobot v3.0 dataset")
    return [validate(tr, limits, f"{root.name}/{tr.name}") for tr in raw]


def load_split(data: str | Path, heldout: str | Path | None = None, seed: int = 0,
               heldout_fraction: float = 0.3) -> tuple[list[Trajectory], list[Trajectory]]:
    """(train, held-out): ``--heldout DIR`` if given, ``DATA/train`` + ``DATA/heldout`` if present,
    else a seeded split by trajectory of DATA."""
    from realm_ms.sysid.timeseries import split

    root = Path(data)
    limits = joint_limits()
    if heldout is not None:
        return load_dir(root, limits), load_dir(heldout, limits)
    if (root / "train").is_dir() and (root / "heldout").is_dir():
        return load_dir(root / "train", limits), load_dir(root / "heldout", limits)
    return split(load_dir(root, limits), heldout_fraction, seed)
