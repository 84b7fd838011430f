"""DROID recordings in: per-step dumps (npz / json / csv), raw ``trajectory.h5`` and LeRobot
columns, normalised into one :class:`DroidLog`, then turned into a workbench
:class:`~realm_ms.sysid.timeseries.Trajectory` by one of the command modes.

DROID logs the same step's command in several action spaces at once (``action_dict`` in RLDS,
``action/*`` in ``trajectory.h5``, ``action.*`` in the LeRobot port); the joint-position target
is the one DROID's robot actually tracked. Names are matched after stripping the containers
DROID and its ports use, so ``observation/robot_state/joint_positions`` (h5),
``observation.state.joint_position`` (LeRobot), ``observation.joint_position`` (RLDS-JSON) and
``q`` (the workbench) are all the measured joints, and ``action/cartesian_position``,
``action_dict.cartesian_position``, ``action.cartesian_position`` and ``cartesian_position_cmd``
all the commanded flange pose.

Command modes (``--command MODE[:SPACE]``):

* ``logged``: the logged joint target (``q_cmd`` / ``joint_position`` command) as it is;
* ``rebuild``: q_target[t] = convert(cmd[t], q_measured[t]) with ``droid_action_spaces``, as
  DROID's robot did from its measured state. Assumes our IK makes the real IK's choices (its
  null-space pull, its damping): exact for the joint spaces, within the IK's agreement for the
  Cartesian ones;
* ``closed_loop``: the command stays in its own space and is converted at every control step
  from the *simulated* state inside the replay (``closed_loop.py``), so a simulated arm that lags
  gets the corrections the real one got, and drift compounds as on the robot. ``q_cmd`` is then
  the rebuilt target, used only to place segments;
* ``auto`` (default): ``logged`` when a joint target is logged, else ``rebuild``.

SPACE picks the logged space to rebuild / replay from; by default the first logged one of
``joint_velocity`` (exact), ``cartesian_velocity``, ``cartesian_position``.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from realm_ms.agents.droid_action_spaces import ACTION_SPACES
from realm_ms.errors import InputError
from realm_ms.sysid.timeseries import DataError, Trajectory

COMMAND_MODES = ("auto", "logged", "rebuild", "closed_loop")
#: the logged space a command is rebuilt from when several are there (joint velocity needs no IK)
REBUILD_ORDER = ("joint_velocity", "cartesian_velocity", "cartesian_position")
ARM_DIM = {"joint_position": 7, "joint_velocity": 7, "cartesian_position": 6, "cartesian_velocity": 6}
DROID_HZ = 15.0

# measured signals: canonical name -> accepted leaf names (after the containers are stripped)
MEASURED = {
    "q": ("q", "joint_position", "joint_positions"),
    "gripper": ("gripper", "gripper_position"),
    "qd": ("qd", "joint_velocity", "joint_velocities"),
}
TIME_KEYS = ("t", "timestamp", "time")
# containers around measured and commanded names in DROID's formats and ports
OBS_PREFIXES = ("observation/robot_state/", "observation.state.", "observation/", "observation.", "robot_state/")
CMD_PREFIXES = ("action_dict/", "action_dict.", "action/", "action.")
COMMAND_HELP = ("a command: q_cmd (joint targets) or one of DROID's action spaces "
                f"({', '.join(ACTION_SPACES)}) as <space>_cmd, action.<space>, action_dict.<space> or action/<space>")


@dataclass(frozen=True)
class ReadOptions:
    """How DROID-style logs become joint-target trajectories (``--command MODE[:SPACE]``)."""

    command: str = "auto"
    action_space: str | None = None

    @classmethod
    def parse(cls, text: str | None) -> "ReadOptions":
        if not text:
            return cls()
        mode, _, space = str(text).partition(":")
        mode = mode.replace("-", "_")
        if mode not in COMMAND_MODES:
            raise DataError(f"--command {text!r}: unknown mode {mode!r}; use one of {', '.join(COMMAND_MODES)} "
                            "(optionally MODE:SPACE, e.g. rebuild:cartesian_position)")
        if space and space not in ACTION_SPACES:
            raise DataError(f"--command {text!r}: unknown action space {space!r}; known: {', '.join(ACTION_SPACES)}")
        return cls(mode, space or None)


@dataclass
class DroidLog:
    """One episode as DROID logs it: measured joints, commands in any of its action spaces."""

    name: str
    t: np.ndarray
    q: np.ndarray
    commands: dict[str, np.ndarray]  # action space -> (T, 7) joint / (T, 6) Cartesian
    gripper: np.ndarray | None = None
    gripper_cmd: dict[str, np.ndarray] = field(default_factory=dict)  # "position" / "velocity" -> (T,)
    qd: np.ndarray | None = None
    control_hz: float | None = None
    meta: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------- flat key/value form
def _leaf(key: str, prefixes: tuple[str, ...]) -> str | None:
    for p in prefixes:
        if key.startswith(p):
            return key[len(p):]
    return None


def from_columns(cols: dict[str, np.ndarray], name: str, where: str, control_hz: float | None = None) -> DroidLog:
    """A DROID log from flat columns (nested names joined by ``/`` or ``.``), whatever format held them."""
    meas: dict[str, np.ndarray] = {}
    commands: dict[str, np.ndarray] = {}
    grip_cmd: dict[str, np.ndarray] = {}
    t = None
    for key, val in cols.items():
        if key.startswith(("action/robot_state/", "action/target_")):  # DROID h5: state at action time, not a command
            continue
        leaf = _leaf(key, CMD_PREFIXES)
        if leaf is None and key.endswith("_cmd"):
            leaf = key[:-4]
        if leaf is not None:
            if leaf in ("q", "joint_target"):
                leaf = "joint_position"
            if leaf in ACTION_SPACES:
                commands[leaf] = val
            elif leaf in ("gripper", "gripper_position"):
                grip_cmd["position"] = val
            elif leaf == "gripper_velocity":
                grip_cmd["velocity"] = val
            continue
        if key in ("action", "observation.state"):  # LeRobot's joint vectors: handled by the LeRobot reader
            continue
        obs = _leaf(key, OBS_PREFIXES) or key
        for canon, names in MEASURED.items():
            if obs in names and canon not in meas:
                meas[canon] = val
        if key in TIME_KEYS and t is None:
            t = val
    if "control_hz" in cols:
        try:
            control_hz = float(np.asarray(cols["control_hz"]).reshape(-1)[0])
        except (TypeError, ValueError, IndexError):
            raise DataError(f"{where}: control_hz must be a number of Hz, got {cols['control_hz']!r}") from None
    if "q" not in meas:
        raise DataError(f"{where}: no measured joint positions; a DROID log needs q (or joint_position, "
                        "observation.joint_position, observation/robot_state/joint_positions), (T, 7) rad")
    n = len(np.asarray(meas["q"]))
    if not commands:
        raise DataError(f"{where}: no command; a DROID log needs {COMMAND_HELP}")
    if t is None:
        if control_hz is None:
            raise DataError(f"{where}: no timestamps; add t (T,) in s, or control_hz (DROID: 15) to time the "
                            "steps as t = step / control_hz")
        t = np.arange(n) / control_hz
    for space, a in commands.items():
        a = np.asarray(a, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != ARM_DIM[space]:
            raise DataError(f"{where}: command `{space}` has shape {a.shape}; expected (T, {ARM_DIM[space]})")
        if len(a) != n:
            raise DataError(f"{where}: command `{space}` has {len(a)} steps but q has {n}; one row per step")
        commands[space] = a
    grip = meas.get("gripper")
    grip = None if grip is None else np.asarray(grip, dtype=np.float64).reshape(n, -1)[:, 0]
    grip_cmd = {k: np.asarray(v, dtype=np.float64).reshape(n, -1)[:, 0] for k, v in grip_cmd.items()}
    return DroidLog(name, np.asarray(t, dtype=np.float64).reshape(-1), np.asarray(meas["q"], dtype=np.float64),
                    commands, grip, grip_cmd, meas.get("qd"), control_hz, {"file": where})


def is_droid_columns(keys) -> bool:
    """Whether columns hold a DROID-style command (any action space) rather than the workbench's q_cmd."""
    for k in keys:
        leaf = _leaf(k, CMD_PREFIXES) or (k[:-4] if k.endswith("_cmd") else None)
        if leaf in ACTION_SPACES:
            return True
    return False


def _flatten(obj, prefix: str, out: dict) -> None:
    if isinstance(obj, dict):
        for k, v in obj.items():
            _flatten(v, f"{prefix}{k}.", out)
    else:
        out[prefix[:-1]] = obj


def read_json(path: Path) -> dict[str, np.ndarray]:
    """Columns of a JSON dump: an object of columns, a list of per-step objects, or ``{"steps": [...]}``;
    nested objects are joined with ``.`` (``{"action_dict": {"cartesian_position": ...}}``)."""
    try:
        doc = json.loads(path.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise DataError(f"{path}: not valid JSON ({type(e).__name__}); write the steps as a JSON list of objects "
                        "or an object of columns") from None
    if isinstance(doc, dict) and isinstance(doc.get("steps"), list):
        doc = doc["steps"]
    rows: dict[str, list] = {}
    if isinstance(doc, list):
        if not doc or not all(isinstance(s, dict) for s in doc):
            raise DataError(f"{path}: a JSON list must hold one object per step")
        for s in doc:
            flat: dict = {}
            _flatten(s, "", flat)
            for k, v in flat.items():
                rows.setdefault(k, []).append(v)
        flat = rows
    elif isinstance(doc, dict):
        flat = {}
        _flatten(doc, "", flat)
    else:
        raise DataError(f"{path}: expected a JSON object of columns or a list of per-step objects")
    out = {}
    for k, v in flat.items():
        try:
            a = np.asarray(v, dtype=np.float64)
        except (TypeError, ValueError):
            continue  # text (instructions, ids): not a signal
        out[k] = a
    return out


_CSV_INDEX = re.compile(r"^(.*?)(?:[_.\[])(\d+)\]?$")


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """Columns of a CSV dump; vector signals as numbered columns (``q_0..q_6`` / ``q1..q7`` /
    ``action.cartesian_position[0]`` ...), joined in index order."""
    import pandas as pd

    try:
        df = pd.read_csv(path, float_precision="round_trip")  # pandas' default parser is off by an ulp
    except Exception as e:  # noqa: BLE001 - pandas raises many types for malformed files
        raise DataError(f"{path}: not a readable CSV file ({type(e).__name__}); one header row, one row per step") from None
    groups: dict[str, list[tuple[int, str]]] = {}
    out: dict[str, np.ndarray] = {}
    for col in df.columns:
        if df[col].dtype.kind not in "fiu":
            continue
        m = _CSV_INDEX.match(str(col))
        if m:
            groups.setdefault(m.group(1), []).append((int(m.group(2)), col))
        else:
            out[str(col)] = df[col].to_numpy(np.float64)
    for name, members in groups.items():
        members.sort()
        if len(members) == 1:  # a lone numbered column is a scalar signal of its own name
            out[str(members[0][1])] = df[members[0][1]].to_numpy(np.float64)
        else:
            out[name] = np.stack([df[c].to_numpy(np.float64) for _, c in members], 1)
    return out


def on_grid(t: np.ndarray, hz: float, resolution: float) -> np.ndarray:
    """``t``, or the exact grid ``i / hz`` when every stamp is within ``resolution`` (what the format
    stores time to) of it: a steady clock then reads back to the same times from a format that
    stores time coarsely (LeRobot's float32 timestamps, DROID's integer-ms ``trajectory.h5``) as
    from the others, and replays the same; a jittery clock keeps its own stamps."""
    t = np.asarray(t, dtype=np.float64)
    grid = np.arange(len(t)) / hz
    return grid if np.all(np.abs(t - grid) <= resolution) else t


def read_h5(path: Path) -> dict[str, np.ndarray]:
    """Columns of DROID's raw ``trajectory.h5`` (``TrajectoryWriter``): every dataset by its path;
    the step time from ``observation/timestamp/control/step_start`` (ms) when it is there."""
    try:
        import h5py
    except ImportError:  # pragma: no cover - depends on the install
        raise DataError(f"{path}: reading DROID's trajectory.h5 needs h5py (pip install h5py)") from None
    out: dict[str, np.ndarray] = {}
    try:
        with h5py.File(path, "r") as f:
            def visit(name, obj):
                if isinstance(obj, h5py.Dataset) and obj.dtype.kind in "fiub":
                    out[name] = np.asarray(obj[()], dtype=np.float64)
            f.visititems(visit)
    except OSError as e:
        raise DataError(f"{path}: not a readable HDF5 file ({' '.join(str(e).split())})") from None
    for key, scale in (("observation/timestamp/control/step_start", 1e-3),
                       ("observation/timestamp/robot_state/robot_timestamp_seconds", 1.0)):
        if key in out:
            t = (out[key] - out[key][0]) * scale  # from the first step, then scaled: epoch ms x 1e-3 rounds to 0.2 us
            if key.endswith("seconds") and "observation/timestamp/robot_state/robot_timestamp_nanos" in out:
                ns = out["observation/timestamp/robot_state/robot_timestamp_nanos"]
                t = t + 1e-9 * (ns - ns[0])
            out["t"] = on_grid(t, DROID_HZ, 5e-4)  # a steady 15 Hz clock stored to the ms
            break
    else:
        out.setdefault("control_hz", np.float64(DROID_HZ))  # DROID steps at 15 Hz
    return out


def read_file(path: Path) -> DroidLog:
    """One per-step dump (``.npz``, ``.json``, ``.csv``, ``.h5``) as a DROID log."""
    suffix = path.suffix.lower()
    if suffix == ".npz":
        with np.load(path, allow_pickle=False) as z:
            cols = {k: z[k] for k in z.files}
    elif suffix == ".json":
        cols = read_json(path)
    elif suffix == ".csv":
        cols = read_csv(path)
    elif suffix in (".h5", ".hdf5"):
        cols = read_h5(path)
    else:
        raise DataError(f"{path}: unknown file type {suffix!r}; DROID logs are .npz, .json, .csv or trajectory.h5")
    name = path.parent.name if path.stem == "trajectory" else path.stem
    return from_columns(cols, name, str(path))


# ---------------------------------------------------------------------------- commands -> joint targets
def rebuild_targets(space: str, actions: np.ndarray, q: np.ndarray, g: np.ndarray | None, gripper_space: str = "position",
                    ik=None) -> np.ndarray:
    """(T, 7) joint targets: DROID's conversion of each step's arm command at the measured joints,
    clipped to the joint limits as the benchmark env clips a converted action."""
    from realm_ms.agents.droid_action_spaces import Q_LIMITS, make_action_space

    sp = make_action_space(space, gripper_space)
    g = np.zeros(len(q)) if g is None else g
    a = np.concatenate([actions, np.zeros((len(actions), 1))], 1)
    return np.clip(sp.to_joint_target(a, q, g, ik)[:, :7], Q_LIMITS[:, 0], Q_LIMITS[:, 1])


def _gripper_target(log: DroidLog) -> np.ndarray | None:
    if "position" in log.gripper_cmd:
        return np.clip(log.gripper_cmd["position"], 0.0, 1.0)
    if "velocity" in log.gripper_cmd and log.gripper is not None:
        from realm_ms.agents.droid_action_spaces import gripper_velocity_to_delta

        return np.clip(log.gripper + gripper_velocity_to_delta(log.gripper_cmd["velocity"]), 0.0, 1.0)
    return None


def to_trajectory(log: DroidLog, options: ReadOptions | None = None, ik=None) -> Trajectory:
    """The workbench trajectory of a DROID log under ``options`` (see the module docstring)."""
    opt = options or ReadOptions()
    where = log.meta.get("file", log.name)
    mode = opt.command
    has_target = "joint_position" in log.commands
    if mode == "auto":
        mode = "logged" if has_target and opt.action_space in (None, "joint_position") else "rebuild"
    meta = dict(log.meta, command_mode=mode)
    if mode == "logged":
        if not has_target:
            raise DataError(f"{where}: no logged joint target (q_cmd / action joint_position); it logs "
                            f"{', '.join(sorted(log.commands))}: use --command rebuild or --command closed_loop")
        q_cmd = log.commands["joint_position"]
        meta["command_space"] = "joint_position"
    else:
        space = opt.action_space or next((s for s in REBUILD_ORDER if s in log.commands), "joint_position")
        if space not in log.commands:
            raise DataError(f"{where}: no `{space}` command; it logs {', '.join(sorted(log.commands))}")
        if space == "joint_position":
            q_cmd = log.commands[space]
        else:
            q_cmd = rebuild_targets(space, log.commands[space], log.q, log.gripper, ik=ik)
        meta["command_space"] = space
        if mode == "closed_loop":
            meta["droid_command"] = {"space": space, "actions": log.commands[space]}
    return Trajectory(log.name, log.t, log.q, q_cmd, log.qd, None, log.gripper, _gripper_target(log),
                      log.control_hz, meta)


# ---------------------------------------------------------------------------- writers (synthetic DROID data)
FORMATS = ("npz", "json", "csv", "h5", "lerobot")


def write_log(out: Path, log: DroidLog, fmt: str) -> Path:
    """``log`` in one of DROID's formats under directory ``out``: ``NAME.npz`` / ``.json`` (RLDS-like
    steps) / ``.csv`` (numbered columns) / ``NAME/trajectory.h5`` (DROID's raw layout). LeRobot
    datasets hold many episodes: ``write_lerobot``."""
    out.mkdir(parents=True, exist_ok=True)
    grip = np.zeros(len(log.t)) if log.gripper is None else log.gripper
    gcmd = log.gripper_cmd.get("position", grip)
    if fmt == "npz":
        path = out / f"{log.name}.npz"
        np.savez(path, t=log.t, q=log.q, gripper=grip, gripper_cmd=gcmd,
                 **{f"{s}_cmd": a for s, a in log.commands.items()})
    elif fmt == "json":
        path = out / f"{log.name}.json"
        steps = [{"t": float(log.t[i]),
                  "observation": {"joint_position": log.q[i].tolist(), "gripper_position": float(grip[i])},
                  "action_dict": {**{s: a[i].tolist() for s, a in log.commands.items()}, "gripper_position": float(gcmd[i])}}
                 for i in range(len(log.t))]
        path.write_text(json.dumps({"steps": steps}))
    elif fmt == "csv":
        import pandas as pd

        path = out / f"{log.name}.csv"
        cols = {"t": log.t, **{f"q_{j}": log.q[:, j] for j in range(7)}, "gripper": grip, "gripper_cmd": gcmd}
        for s, a in log.commands.items():
            cols.update({f"action.{s}.{j}": a[:, j] for j in range(a.shape[1])})
        pd.DataFrame(cols).to_csv(path, index=False, float_format="%.17g")
    elif fmt == "h5":
        import h5py

        path = out / log.name / "trajectory.h5"
        path.parent.mkdir(parents=True, exist_ok=True)
        with h5py.File(path, "w") as f:
            f["observation/robot_state/joint_positions"] = log.q
            f["observation/robot_state/gripper_position"] = grip
            f["observation/timestamp/control/step_start"] = np.round(1e3 * log.t).astype(np.int64) + 1_700_000_000_000
            for s, a in log.commands.items():
                f[f"action/{s}"] = a
            f["action/gripper_position"] = gcmd
    else:
        raise InputError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}")
    return path


def write_lerobot(root: Path, logs: list[DroidLog], fps: float = DROID_HZ, layout: str = "droid") -> Path:
    """A LeRobot v3.0 dataset with the feature names of DROID's own LeRobot port (lerobot's
    ``port_droid``): ``observation.state`` (7 joints + gripper), ``observation.state.joint_position``,
    ``observation.state.gripper_position``, ``action.<space>`` per logged space,
    ``action.gripper_position``, and ``action`` (joint target + gripper) when the joint target is logged.
    ``layout="export"``: ``realm export``'s layout instead, ``observation.state`` and ``action`` only."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    spaces = list(logs[0].commands)
    vec = lambda n: {"dtype": "float32", "shape": (n,), "names": None}  # noqa: E731
    if layout == "export":
        if "joint_position" not in spaces:
            raise InputError("realm export's layout holds the joint target; the logs have none")
        feats = {"observation.state": vec(8), "action": vec(8)}
    else:
        feats = {"observation.state": vec(8), "observation.state.joint_position": vec(7),
                 "observation.state.gripper_position": vec(1), "action.gripper_position": vec(1),
                 **{f"action.{s}": vec(ARM_DIM[s]) for s in spaces}}
        if "joint_position" in spaces:
            feats["action"] = vec(8)
    ds = LeRobotDataset.create(repo_id="local/droid_synth", fps=int(round(fps)), features=feats, root=root, use_videos=False)
    for log in logs:
        grip = np.zeros(len(log.t)) if log.gripper is None else log.gripper
        gcmd = log.gripper_cmd.get("position", grip)
        for i in range(len(log.t)):
            f32 = lambda a: np.asarray(a, dtype=np.float32).reshape(-1)  # noqa: E731
            frame = {"observation.state": f32(np.r_[log.q[i], grip[i]]), "observation.state.joint_position": f32(log.q[i]),
                     "observation.state.gripper_position": f32(grip[i]), "action.gripper_position": f32(gcmd[i]),
                     **{f"action.{s}": f32(log.commands[s][i]) for s in spaces}}
            if "action" in feats:
                frame["action"] = f32(np.r_[log.commands["joint_position"][i], gcmd[i]])
            ds.add_frame({**{k: v for k, v in frame.items() if k in feats}, "task": "synthetic DROID"})
        ds.save_episode()
    ds.finalize()
    return root
