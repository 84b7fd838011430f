"""Reading and writing measured data.

Input formats (see ``docs/sysid.md``); DROID's own recordings (per-step dumps in any action space,
raw ``trajectory.h5``, the LeRobot port's ``action.*`` features) are normalised by
``droid_formats.py``:

* **npz directory**: one ``.npz`` per trajectory with ``t`` (T,) s, ``q`` (T,7) rad, ``q_cmd`` (T,7) rad
  (held from ``t[i]`` until ``t[i+1]``), optional ``qd``, ``tau``, ``gripper``, ``gripper_cmd`` and
  scalar ``control_hz``. ``synth`` writes this format.
* **LeRobot v3.0 dataset** (DROID convention): ``meta/info.json`` + ``data/chunk-*/file-*.parquet`` with
  ``observation.state`` = 7 joint positions + gripper, ``action`` = 7 joint-position targets + gripper,
  ``timestamp``, ``episode_index``; optional velocity/effort features (any feature whose name contains
  ``velocit`` / ``effort`` with 7 or 8 entries). Each episode is one trajectory. The parquet files
  are read directly (no video decoding).

A DATA directory holding ``train/`` and ``heldout/`` subdirectories (what ``synth`` writes) is
split that way (``compare``, which does not split, reads both); otherwise commands split it by
trajectory (``timeseries.split``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from realm_ms import atomic
from realm_ms.sysid.timeseries import DataError, Trajectory, validate

NPZ_REQUIRED = ("t", "q")  # + q_cmd (position space) or tau (torque space)


def joint_limits() -> np.ndarray:
    from realm_ms.agents.arm_model import ArmModel
    from realm_ms.sysid.locked_urdf import BASE_LINK, TIP_LINK, source_urdf_path

    return ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK).q_limits


def read_npz(path: Path) -> Trajectory:
    try:
        with open(path, "rb") as f:
            magic = f.read(4)
    except OSError as e:
        raise DataError(f"{path}: cannot open ({e.strerror})") from None
    if magic[:2] != b"PK":  # every numpy.savez archive is a zip file
        kind = "empty" if not magic else "a text file" if _is_text(path) else "not a zip archive"
        raise DataError(f"{path}: not an .npz archive ({kind}); write trajectories with numpy.savez(path, t=..., q=..., q_cmd=...)")
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except Exception as e:  # noqa: BLE001 - any unreadable file is a user error
        raise DataError(f"{path}: cannot read as .npz ({type(e).__name__}: {' '.join(str(e).split())})") from None
    missing = [k for k in NPZ_REQUIRED if k not in data]
    if "q_cmd" not in data and "tau" not in data:
        missing.append("q_cmd")
    if missing:
        raise DataError(f"{path}: missing key(s) {missing}; an .npz trajectory needs t (T,), q (T,7) and q_cmd (T,7) "
                        "(commanded targets), or tau (T,7) (measured joint torque, for torque-space work)")
    return Trajectory(
        path.stem, data["t"], data["q"], data.get("q_cmd"), data.get("qd"), data.get("tau"),
        data.get("gripper"), data.get("gripper_cmd"), data.get("control_hz"),
        meta={"file": str(path), **({"lab": str(data["lab"])} if "lab" in data else {})},
    )


def _is_text(path: Path) -> bool:
    with open(path, "rb") as f:
        head = f.read(512)
    try:
        head.decode("utf-8")
        return True
    except UnicodeDecodeError:
        return False


def write_npz(path: Path, traj: Trajectory) -> None:
    arrays = {"t": traj.t, "q": traj.q}
    for k in ("q_cmd", "qd", "tau", "gripper", "gripper_cmd"):
        v = getattr(traj, k)
        if v is not None:
            arrays[k] = v
    if traj.control_hz is not None:
        arrays["control_hz"] = np.float64(traj.control_hz)
    if traj.meta.get("lab"):
        arrays["lab"] = np.str_(traj.meta["lab"])
    atomic.write_npz(path, **arrays)


def _shape(feat) -> list:
    shape = feat.get("shape") if isinstance(feat, dict) else None
    return list(shape) if isinstance(shape, (list, tuple)) else []


def _lerobot_feature(info: dict, words: tuple[str, ...]) -> str | None:
    for name, feat in info.get("features", {}).items():
        if (any(w in name for w in words) and not name.startswith("action") and isinstance(feat, dict) and feat.get("dtype") in ("float32", "float64")
                and _shape(feat)[:1] in ([7], [8])):
            return name
    return None


def _read_info(root: Path) -> dict:
    info_path = root / "meta" / "info.json"
    try:
        info = json.loads(info_path.read_text())
    except UnicodeDecodeError:
        raise DataError(f"{info_path}: not a text (JSON) file") from None
    except json.JSONDecodeError as e:
        raise DataError(f"{info_path}: not valid JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(info, dict) or not info:
        raise DataError(f"{info_path}: expected a JSON object with codebase_version, fps and features, "
                        f"got {'an empty object' if isinstance(info, dict) else type(info).__name__}")
    if not isinstance(info.get("features"), dict):
        raise DataError(f"{info_path}: `features` must be an object mapping feature names to {{dtype, shape}}")
    return info


def read_lerobot(root: Path, options=None) -> list[Trajectory]:
    """Every episode of a LeRobot v3.0 dataset; DROID's port's ``action.<space>`` features are read
    too and the command chosen by ``options`` (``droid_formats.ReadOptions``)."""
    from realm_ms.sysid.droid_formats import ARM_DIM, from_columns, on_grid, to_trajectory

    info = _read_info(root)
    info_path = root / "meta" / "info.json"
    version = str(info.get("codebase_version", "?"))
    if not version.startswith("v3"):
        raise DataError(f"{root}: LeRobot dataset version {version}; only v3.0 is supported (convert with lerobot's v2.1->v3.0 script)")
    feats = info["features"]
    # a torque log (an effort/torque feature, no joint-position `action`) is worked on in torque space
    torque_log = "action" not in feats and _lerobot_feature(info, ("effort", "torque")) is not None
    # DROID's LeRobot port logs the command in every action space: action.joint_position, ...
    spaces = [f"action.{s}" for s in ARM_DIM if f"action.{s}" in feats]
    grips = [f"action.gripper_{k}" for k in ("position", "velocity") if f"action.gripper_{k}" in feats]
    need_action = not torque_log and not spaces
    for key in ("observation.state",) + (("action",) if need_action else ()):
        if key not in feats:
            raise DataError(f"{root}: LeRobot dataset lacks `{key}`; DROID convention: observation.state = 7 joint positions + gripper, action = 7 joint targets + gripper")
        if _shape(feats[key])[:1] not in ([7], [8]) or len(_shape(feats[key])) != 1:
            raise DataError(f"{info_path}: features.{key}.shape is {_shape(feats[key]) if isinstance(feats[key], dict) else feats[key]!r}; "
                            "expected [7] (joints) or [8] (joints + gripper)")
    try:
        fps = float(info.get("fps", 15))
    except (TypeError, ValueError):
        fps = float("nan")
    if not np.isfinite(fps) or fps <= 0:
        raise DataError(f"{info_path}: fps = {info.get('fps')!r}; expected a positive number of frames per second")
    files = sorted((root / "data").glob("chunk-*/*.parquet"))
    if not files:
        raise DataError(f"{root}: no parquet files under data/chunk-*/")
    import pandas as pd

    frames = []
    for f in files:
        try:
            frames.append(pd.read_parquet(f))
        except Exception as e:  # noqa: BLE001 - pyarrow raises many types for damaged files
            raise DataError(f"{f}: not a readable parquet file ({type(e).__name__}); the file is damaged or truncated") from None
    df = pd.concat(frames, ignore_index=True)
    for col in ("episode_index", "observation.state") + (("action",) if need_action else ()) + tuple(spaces):
        if col not in df.columns:
            raise DataError(f"{files[0].parent}: the parquet files have no `{col}` column (columns: {', '.join(map(str, df.columns))})")
    vel, eff = _lerobot_feature(info, ("velocit",)), _lerobot_feature(info, ("effort", "torque"))
    trajs = []
    for ep, g in df.groupby("episode_index", sort=True):
        g = g.sort_values("frame_index") if "frame_index" in g else g
        where = f"{root.name}/episode {ep}"
        state = _stack(g, "observation.state", where)
        # LeRobot keeps a frame's timestamp within 1e-4 s of frame_index / fps, in float32
        t = on_grid(g["timestamp"].to_numpy(dtype=np.float64), fps, 1e-4) if "timestamp" in g else np.arange(len(g)) / fps
        qd = _stack(g, vel, where)[:, :7] if vel and vel in g else None
        tau = _stack(g, eff, where)[:, :7] if eff and eff in g else None
        if torque_log:
            trajs.append(Trajectory(f"episode_{int(ep):06d}", t, state[:, :7], None, qd, tau,
                                    state[:, 7] if state.shape[1] > 7 else None, None, None))
            continue
        cols = {"t": t, "q": state[:, :7], "control_hz": np.float64(fps)}
        if state.shape[1] > 7:
            cols["gripper"] = state[:, 7]
        if "action" in g:  # a joint target (+ gripper): realm export and DROID's port alike
            action = _stack(g, "action", where)
            cols["q_cmd"] = action[:, :7]
            if action.shape[1] > 7:
                cols["gripper_cmd"] = action[:, 7]
        for col in spaces + grips:
            cols[col] = _vectors(g, col, where)
        tr = to_trajectory(from_columns(cols, f"episode_{int(ep):06d}", where), options)
        tr.qd, tr.tau = qd, tau
        trajs.append(tr)
    return trajs


def _vectors(g, col: str, where: str) -> np.ndarray:
    try:
        a = np.stack([np.atleast_1d(v) for v in g[col].to_numpy()]).astype(np.float64)
    except (TypeError, ValueError):
        raise DataError(f"{where}: column `{col}` does not hold equal-length numeric vectors") from None
    return a[:, 0] if a.shape[1] == 1 else a


def _stack(g, col: str, where: str) -> np.ndarray:
    try:
        a = np.stack(g[col].to_numpy()).astype(np.float64)
    except (TypeError, ValueError):
        raise DataError(f"{where}: column `{col}` does not hold equal-length numeric vectors") from None
    if a.ndim != 2 or a.shape[1] < 7:
        raise DataError(f"{where}: column `{col}` has rows of shape {a.shape[1:]}; expected 7 joints (+ gripper)")
    return a


#: per-step dump files a DATA directory may hold (besides the workbench's npz); DROID's raw
#: recordings sit one episode per folder as ``<episode>/trajectory.h5``
DUMP_SUFFIXES = (".npz", ".json", ".csv", ".h5", ".hdf5")


def read_trajectory_file(path: Path, options=None) -> Trajectory:
    """One file: the workbench's npz (``q_cmd`` or ``tau``) or a DROID per-step dump (any action space)."""
    from realm_ms.sysid import droid_formats

    if path.suffix == ".npz":
        tr = read_npz_any(path)
        if tr is not None:
            return tr
    return droid_formats.to_trajectory(droid_formats.read_file(path), options)


def read_npz_any(path: Path) -> Trajectory | None:
    """The workbench npz, or None when the archive logs a command in one of DROID's action spaces."""
    from realm_ms.sysid.droid_formats import is_droid_columns

    try:
        with np.load(path, allow_pickle=False) as z:
            droid = is_droid_columns(z.files)
    except Exception:  # noqa: BLE001 - read_npz names what is wrong with the file
        droid = False
    return None if droid else read_npz(path)


#: metadata that sits beside trajectories (synth's record, an episode index), never a trajectory
SIDE_FILES = ("synth.json", "index.json")


def _files(root: Path) -> list[Path]:
    """The trajectory files of a directory: one format, the first of ``DUMP_SUFFIXES`` present
    (a directory of npz trajectories may hold a JSON index beside them), else DROID's raw tree
    ``[success/]DATE/EPISODE/trajectory.h5``."""
    files = [f for f in sorted(root.iterdir()) if f.is_file() and f.suffix.lower() in DUMP_SUFFIXES
             and f.name not in SIDE_FILES and ".tmp." not in f.name]
    for suffix in DUMP_SUFFIXES:
        same = [f for f in files if f.suffix.lower() == suffix]
        if same:
            return same
    return sorted(root.rglob("trajectory.h5"))


def load_dir(path: str | Path, limits: np.ndarray | None = None, options=None) -> list[Trajectory]:
    """All trajectories in DATA, validated: a directory of trajectory files (npz / json / csv / h5, see
    ``droid_formats``), one such file, a LeRobot v3.0 dataset, or DROID's raw episode folders
    (``trajectory.h5`` at any depth: ``[success/]DATE/EPISODE/``). ``options``: ``droid_formats.ReadOptions`` (the command mode).
    DROID recordings (``load_each``): an episode that fails to read or validate is set aside with a
    warning; the workbench's own npz files: the first bad one is an error."""
    return load_each(path, options, limits)[0]


def load_each(path: str | Path, options=None, limits: np.ndarray | None = None) -> tuple[list[Trajectory], list[str]]:
    """``load_dir`` with the episodes it set aside: (trajectories, one line per episode left out).
    In DROID recordings (any file a DROID log, or a LeRobot dataset of DROID's action spaces) one
    bad episode should not hide the others: each is left out with a ``DataWarning`` saying which
    and why; DataError only when nothing usable is left. Elsewhere the first bad file is the error."""
    root = Path(path)
    if not root.exists():
        raise DataError(f"{root}: no such file or directory")
    limits = joint_limits() if limits is None else limits
    if root.is_file() and root.suffix.lower() in DUMP_SUFFIXES:
        files, raw = [root], None
    elif root.is_file():
        raise DataError(f"{root}: expected a directory of .npz files (or .json, .csv, trajectory.h5 DROID logs), one "
                        "such file or a LeRobot v3.0 dataset directory")
    elif (root / "meta" / "info.json").exists():
        files, raw = [], read_lerobot(root, options)
    elif (root / "train").is_dir() and (root / "heldout").is_dir() and not any(root.glob("*.npz")):
        # the layout `synth` writes: all of it (commands that split use load_split)
        a, b = load_each(root / "train", options, limits), load_each(root / "heldout", options, limits)
        return a[0] + b[0], a[1] + b[1]
    else:
        files, raw = _files(root), None
        if not files:
            sub = [d.name for d in root.iterdir() if d.is_dir()]
            raise DataError(f"{root}: no .npz trajectories (nor .json, .csv, trajectory.h5) and no LeRobot dataset "
                            "(meta/info.json) here" + (f"; subdirectories: {sub}" if sub else ""))
    trajs, failed = [], []
    for f in files:
        try:
            trajs.append(read_trajectory_file(f, options))
        except DataError as e:
            failed.append(e)
    out = []
    for tr in raw if raw is not None else trajs:
        try:
            out.append(validate(tr, limits, tr.meta.get("file") or f"{root.name}/{tr.name}"))
        except DataError as e:
            failed.append(e)
    _tag_labs(out, root)
    if not failed:
        return out, []
    read = raw if raw is not None else trajs
    droid = any("command_mode" in tr.meta for tr in read) or any(f.suffix.lower() != ".npz" for f in files)
    if not droid or (not out and len(failed) == 1):  # a single bad log: its own message is the clearest
        raise failed[0]
    skipped = [" ".join(str(e).split()) for e in failed]
    if not out:
        raise DataError(f"{root}: no usable episode; " + "; ".join(skipped[:3])
                        + (f" (and {len(skipped) - 3} more)" if len(skipped) > 3 else ""))
    import warnings

    from realm_ms.sysid.timeseries import DataWarning

    for line in skipped:
        warnings.warn(f"left out: {line}", DataWarning, stacklevel=2)
    return out, skipped


def read_labs(root: Path) -> dict[str, str]:
    """Episode name (file stem) -> lab from ``index.json`` (``[{file, lab}, ...]``) in ``root`` or its
    parent; {} when there is none."""
    root = root if root.is_dir() else root.parent
    for index in (root / "index.json", root.parent / "index.json"):
        if index.is_file():
            try:
                return {Path(e["file"]).stem: str(e.get("lab", "?")) for e in json.loads(index.read_text())}
            except (ValueError, KeyError, TypeError):
                raise DataError(f"{index}: expected a JSON list of {{file, lab}} entries") from None
    return {}


def _tag_labs(trajs: list[Trajectory], root: Path) -> None:
    """``meta["lab"]`` from an ``index.json`` beside the files (``read_labs``), where the
    file names none of its own: the per-lab rows of the flange figures."""
    labs = read_labs(root)
    for tr in trajs:
        if tr.name in labs:
            tr.meta.setdefault("lab", labs[tr.name])


def load_split(data: str | Path, heldout: str | Path | None = None, seed: int = 0,
               heldout_fraction: float = 0.3, options=None) -> tuple[list[Trajectory], list[Trajectory]]:
    """(train, held-out): ``--heldout DIR`` if given, ``DATA/train`` + ``DATA/heldout`` if present,
    else a seeded split by trajectory of DATA."""
    from realm_ms.sysid.timeseries import split

    root = Path(data)
    limits = joint_limits()
    if heldout is not None:
        return load_dir(root, limits, options), load_dir(heldout, limits, options)
    if (root / "train").is_dir() and (root / "heldout").is_dir():
        return load_dir(root / "train", limits, options), load_dir(root / "heldout", limits, options)
    return split(load_dir(root, limits, options), heldout_fraction, seed)
