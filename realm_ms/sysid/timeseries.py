"""Measured trajectories: the in-memory form, validation, and the seeded train/held-out split.

A :class:`Trajectory` is one continuous recording: timestamps ``t`` (T,) [s], measured joint
positions ``q`` (T, 7) [rad], commanded joint targets ``q_cmd`` (T, 7) [rad] held from ``t[i]``
until ``t[i+1]`` (absent in a torque log from another controller: torque space only), optional measured velocities ``qd`` (T, 7) [rad/s] and torques ``tau`` (T, 7)
[N·m]. File formats live in ``data_io.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.validate import InputError

MIN_SAMPLES = 20
MIN_DURATION_S = 1.0
#: measured joints past the model's limits by more than WARN rad warn, by more than ERROR rad are refused
MEASURED_LIMIT_WARN, MEASURED_LIMIT_ERROR = 0.05, 0.25
MIN_RATE_HZ = 5.0  # slower logs cannot resolve the 15 Hz commands; a median step of 1 is frame indices
MAX_GAP_S = 1.0  # a longer jump in `t` (and > GAP_FACTOR x the median step) is a gap in the recording
GAP_FACTOR = 20.0
# Torque space differentiates q twice and smooths over ~50 ms (torque/smoothing.py): at DROID's
# 15 Hz a window holds < 1 sample, q̈ is a difference of command steps, and the 7.5 Hz Nyquist
# limit lies inside the motion band the residual is split into (torque/spectrum.py, up to > 10 Hz)
MIN_TORQUE_RATE_HZ = 100.0
MIN_MOTION_RAD = 1e-3  # peak-to-peak motion of every joint below this in every trajectory: the arm did not move


class DataError(InputError):
    """The data cannot be used; the message says what is wrong and how to fix it."""


class DataWarning(UserWarning):
    """The data can be used but something in it will bias the result; the message says what."""


DROID_CONTROL_HZ = 15.0
GRID_DRIFT_WARN_S = 0.005  # accumulated logger/command drift that visibly shifts a 15 Hz replay


def command_grid_drift(t: np.ndarray, control_hz: float | None) -> str | None:
    """A sentence when the log's samples drift off the command grid, else None.

    The replay holds ``q_cmd[i]`` from ``t[i]`` to ``t[i+1]``, i.e. it assumes a command switch at
    every n-th logged sample. A logger whose period is close to, but not exactly, n command
    periods (a 67 ms logger under 15 Hz = 66.7 ms commands) shifts every switch a little more
    than the last: after 10 s the replayed commands are 50 ms late or early, which the workbench
    would otherwise "diagnose" as latency. Without ``control_hz`` a log within 5 % of 15 Hz is
    checked against DROID's 15 Hz."""
    if len(t) < 2:
        return None
    period = float(t[-1] - t[0]) / (len(t) - 1)  # the mean: drift is what accumulates
    assumed = control_hz is None
    if assumed:
        if abs(1.0 / period - DROID_CONTROL_HZ) > 0.05 * DROID_CONTROL_HZ:
            return None
        control_hz = DROID_CONTROL_HZ
    cmd = 1.0 / control_hz
    n = max(1, int(round(cmd / period)))
    if abs(cmd / period - n) > 0.25:  # not a whole number of samples per command: no grid to drift from
        return None
    per_cmd = n * period - cmd
    total = abs(per_cmd) * float(t[-1] - t[0]) / cmd
    if total < GRID_DRIFT_WARN_S:
        return None
    where = "assumed DROID " if assumed else ""
    return (f"logged every {1e3 * period:.2f} ms under {where}{control_hz:g} Hz commands ({1e3 * cmd:.2f} ms): the samples "
            f"drift {1e3 * per_cmd:+.3f} ms per command off the command grid, {1e3 * total:.0f} ms over the "
            f"{t[-1] - t[0]:.1f} s log; the replay holds q_cmd[i] from t[i] to t[i+1], so its commands are "
            "mistimed by up to that much (looks like latency). Log at the command times (or a whole multiple "
            "of the command rate), or resample q_cmd onto the true command times"
            + ("" if not assumed else "; set control_hz in the file if the commands are not 15 Hz"))


def check_torque_rate(traj: "Trajectory") -> None:
    """DataError for a torque log slower than ``MIN_TORQUE_RATE_HZ``, saying why."""
    rate = 1.0 / float(np.median(np.diff(traj.t)))
    if rate < MIN_TORQUE_RATE_HZ * (1 - 1e-6):  # time stamps in float: 100 Hz reads as 99.99999
        raise DataError(f"{traj.name}: logged at {rate:.3g} Hz; torque-space work needs >= {MIN_TORQUE_RATE_HZ:g} Hz "
                        f"(it differentiates q twice and smooths over 50 ms; at {rate:.3g} Hz the Nyquist limit is "
                        f"{rate / 2:.3g} Hz). Log torques faster, or use --space position (the replay of q_cmd, if the log has it)")


def check_identifiable(trajs: list["Trajectory"]) -> None:
    """DataError "nothing to identify" for data no verdict can come from: an arm that never moves
    (the space adds its own checks: ``Space.check_identifiable``)."""
    def ptp(a):
        return np.ptp(a, axis=0) if a is not None and len(a) else np.zeros(7)

    if not any(max(ptp(tr.q).max(), ptp(tr.q_cmd).max()) > MIN_MOTION_RAD for tr in trajs):
        raise DataError(f"nothing to identify: the arm never moves (every joint's q and q_cmd vary by < "
                        f"{1e3 * MIN_MOTION_RAD:g} mrad in all {len(trajs)} trajectories); record motion, e.g. the "
                        "commands of `realm sysid excite`")


@dataclass
class Trajectory:
    name: str
    t: np.ndarray
    q: np.ndarray
    q_cmd: np.ndarray | None  # None: a torque log (``tau``) from any controller, torque space only
    qd: np.ndarray | None = None
    tau: np.ndarray | None = None
    gripper: np.ndarray | None = None
    gripper_cmd: np.ndarray | None = None
    control_hz: float | None = None
    meta: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    @property
    def rate_hz(self) -> float:
        return float((len(self.t) - 1) / max(self.duration, 1e-9))

    def velocity(self) -> np.ndarray:
        """Measured velocity, or central finite differences of ``q`` when the log has none."""
        if self.qd is not None:
            return self.qd
        return np.gradient(self.q, self.t, axis=0)


def _check_array(name: str, where: str, a, shape_tail: tuple[int, ...], n: int | None) -> np.ndarray:
    try:
        a = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise DataError(f"{where}: `{name}` is not numeric") from None
    if a.ndim == 0:
        raise DataError(f"{where}: `{name}` is a single number, expected an array with one row per timestamp")
    if a.ndim != 1 + len(shape_tail) or a.shape[1:] != shape_tail:
        want = "(T,)" if not shape_tail else f"(T, {', '.join(map(str, shape_tail))})"
        raise DataError(f"{where}: `{name}` has shape {a.shape}, expected {want}")
    if n is not None and a.shape[0] != n:
        raise DataError(f"{where}: `{name}` has {a.shape[0]} samples but `t` has {n}; all arrays need one row per timestamp")
    bad = ~np.isfinite(a)
    if bad.any():
        i = int(np.argwhere(bad)[0][0])
        raise DataError(f"{where}: `{name}` contains NaN/inf (first at sample {i}); drop or interpolate those samples")
    return a


def validate(traj: Trajectory, q_limits: np.ndarray, where: str | None = None) -> Trajectory:
    """Check one trajectory; raise :class:`DataError` with a clear message, return it cleaned."""
    where = where or traj.name
    t = _check_array("t", where, traj.t, (), None)
    n = t.shape[0]
    if n < MIN_SAMPLES:
        raise DataError(f"{where}: only {n} samples; need at least {MIN_SAMPLES} (and {MIN_DURATION_S:g} s) per trajectory")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise DataError(f"{where}: time is not strictly increasing at sample {i + 1} (t = {t[i]:.6g} -> {t[i + 1]:.6g} s); sort or de-duplicate the samples")
    if t[-1] - t[0] < MIN_DURATION_S:
        raise DataError(f"{where}: lasts {t[-1] - t[0]:.3g} s; need at least {MIN_DURATION_S:g} s")
    med = float(np.median(dt))
    if med > 1.0 / MIN_RATE_HZ:
        if np.allclose(t, np.round(t)) and abs(med - 1.0) < 1e-9:
            raise DataError(f"{where}: `t` looks like frame indices (0, 1, 2, ...); it must be in seconds "
                            "(e.g. t = frame_index / fps)")
        raise DataError(f"{where}: median time step {med:.3g} s ({1 / med:.3g} Hz) is too slow (need >= "
                        f"{MIN_RATE_HZ:g} Hz); `t` must be in seconds (milliseconds or ns? frame indices?)")
    gap = dt > max(MAX_GAP_S, GAP_FACTOR * med)
    if gap.any():
        i = int(np.argmax(gap))
        raise DataError(f"{where}: `t` jumps by {dt[i]:.6g} s at sample {i + 1} (median step {med:.3g} s): a gap in "
                        "the recording; split it into separate trajectories")
    control_hz = None
    if traj.control_hz is not None:
        c = np.asarray(traj.control_hz)
        if c.size != 1:
            raise DataError(f"{where}: `control_hz` has shape {c.shape}; expected one number (Hz)")
        if c.dtype.kind not in "fiu":
            raise DataError(f"{where}: `control_hz` = {c.reshape(-1)[0]!r} is not a number; expected Hz (DROID: 15)")
        control_hz = float(c.reshape(-1)[0])
        if not np.isfinite(control_hz) or control_hz <= 0:
            raise DataError(f"{where}: `control_hz` = {control_hz:g}; expected a positive number of Hz (DROID: 15)")
        if 1.0 / med < 0.95 * control_hz:
            raise DataError(f"{where}: logged at {1 / med:.3g} Hz, below its control rate control_hz = {control_hz:g} Hz; "
                            "log at least once per command")
    drift = command_grid_drift(t, control_hz) if traj.q_cmd is not None else None
    if drift:
        import warnings

        warnings.warn(f"{where}: {drift}", DataWarning, stacklevel=2)
    q = _check_array("q", where, traj.q, (7,), n)
    q_cmd = None if traj.q_cmd is None else _check_array("q_cmd", where, traj.q_cmd, (7,), n)
    qd = None if traj.qd is None else _check_array("qd", where, traj.qd, (7,), n)
    tau = None if traj.tau is None else _check_array("tau", where, traj.tau, (7,), n)
    gripper = None if traj.gripper is None else _check_array("gripper", where, traj.gripper, (), n)
    gripper_cmd = None if traj.gripper_cmd is None else _check_array("gripper_cmd", where, traj.gripper_cmd, (), n)
    for name, a in (("q", q), ("q_cmd", q_cmd)):
        if a is not None and np.abs(a).max() > 2 * np.pi:
            raise DataError(f"{where}: `{name}` reaches {np.abs(a).max():.1f}; joint angles must be in radians (these look like degrees: multiply by pi/180)")
    lo, hi = q_limits[:, 0], q_limits[:, 1]
    tol = 1e-3
    out = np.zeros(1, bool) if q_cmd is None else (q_cmd < lo - tol) | (q_cmd > hi + tol)
    if out.any():
        i, j = (int(v) for v in np.argwhere(out)[0])
        raise DataError(
            f"{where}: commanded target of joint {j + 1} = {q_cmd[i, j]:.4f} rad at sample {i} is outside the joint limits "
            f"[{lo[j]:.4f}, {hi[j]:.4f}] rad; check the joint order (panda_joint1..7) and units"
        )
    # Real arms read a little past the URDF's limits (DROID logs reach 3.82 rad on joint 6 against
    # 3.7525): a warning, since the simulated arm stops at its limit there; far past them the joint
    # order or the units are wrong.
    excess = np.maximum(lo - q, q - hi)
    if (excess > MEASURED_LIMIT_ERROR).any():
        i, j = (int(v) for v in np.argwhere(excess > MEASURED_LIMIT_ERROR)[0])
        raise DataError(f"{where}: measured joint {j + 1} = {q[i, j]:.4f} rad at sample {i} is outside the joint limits "
                        f"[{lo[j]:.4f}, {hi[j]:.4f}] rad by more than {MEASURED_LIMIT_ERROR:g} rad; check the joint order "
                        "(panda_joint1..7) and units")
    if (excess > MEASURED_LIMIT_WARN).any():
        import warnings

        i, j = (int(v) for v in np.argwhere(excess > MEASURED_LIMIT_WARN)[0])
        share = float((excess > MEASURED_LIMIT_WARN).any(axis=1).mean())
        warnings.warn(f"{where}: measured joint {j + 1} = {q[i, j]:.4f} rad at sample {i} is past the model's joint limits "
                      f"[{lo[j]:.4f}, {hi[j]:.4f}] rad ({share:.0%} of the samples); the simulated arm stops at its limit there",
                      DataWarning, stacklevel=2)
    return Trajectory(traj.name, t - t[0], q, q_cmd, qd, tau, gripper, gripper_cmd, control_hz, dict(traj.meta))


#: a single log is cut into contiguous blocks of at least this long (a held-out block holds one 8 s
#: replay segment and its 1 s burn-in), at most MAX_BLOCKS of them
MIN_BLOCK_S = 10.0
MAX_BLOCKS = 10


def blocks(traj: Trajectory, n: int) -> list[Trajectory]:
    """``traj`` cut into ``n`` contiguous, disjoint blocks of equal duration, each named
    ``NAME[t0-t1s]`` and timed from 0."""
    edges = np.searchsorted(traj.t, np.linspace(traj.t[0], traj.t[-1], n + 1))
    edges[-1] = len(traj.t)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        cut = lambda x: None if x is None else x[a:b]  # noqa: E731
        out.append(Trajectory(f"{traj.name}[{traj.t[a]:.1f}-{traj.t[b - 1]:.1f}s]", traj.t[a:b] - traj.t[a], traj.q[a:b],
                              cut(traj.q_cmd), cut(traj.qd), cut(traj.tau), cut(traj.gripper), cut(traj.gripper_cmd),
                              traj.control_hz, dict(traj.meta, block_of=traj.name, block_start_s=float(traj.t[a]))))
    return out


def split(trajs: list[Trajectory], heldout_fraction: float = 0.3, seed: int = 0) -> tuple[list[Trajectory], list[Trajectory]]:
    """Seeded split *by trajectory*: a permutation with ``numpy.random.default_rng(seed)`` of the
    trajectories sorted by name; the first ``max(1, round(f * N))`` are held out. Needs N >= 2.

    A single log (a robot's one long recording) is first cut into contiguous time blocks of at least
    ``MIN_BLOCK_S`` (``blocks``), which are then split the same way: held-out blocks are whole
    stretches of time the fit never saw."""
    if len(trajs) == 1:
        n = min(MAX_BLOCKS, int(trajs[0].duration // MIN_BLOCK_S))
        if n < 2:
            raise DataError(f"{trajs[0].name}: one trajectory of {trajs[0].duration:.1f} s; a single log is cut into blocks "
                            f"of >= {MIN_BLOCK_S:g} s to hold one out, so it needs >= {2 * MIN_BLOCK_S:g} s. Record longer, "
                            "add trajectories or pass --heldout DIR")
        trajs = blocks(trajs[0], n)
    if len(trajs) < 2:
        raise DataError(
            f"need at least 2 trajectories to hold some out (got {len(trajs)}); record more or pass --heldout DIR"
        )
    order = sorted(range(len(trajs)), key=lambda i: trajs[i].name)
    perm = np.random.default_rng(seed).permutation(len(order))
    n_held = min(len(trajs) - 1, max(1, int(round(heldout_fraction * len(trajs)))))
    held_idx = {order[i] for i in perm[:n_held]}
    train = [trajs[i] for i in order if i not in held_idx]
    held = [trajs[i] for i in order if i in held_idx]
    return train, held
