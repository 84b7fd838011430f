"""Multiple shooting: cut trajectories into segments, simulate (segment x candidate) batches,
sample at the data timestamps, score.

Segmentation: scored windows of ``length_s`` (default 8 s) tile each trajectory after an initial
``burn_in_s`` (1 s);
the simulation of a window starts ``burn_in_s`` earlier from the measured state (q and q̇, q̇ from
finite differences when the log has none), so the error of the initial state has decayed before
scoring starts, every sample after the first ``burn_in_s`` of a trajectory is scored exactly once,
and stateful effects (delay lines, rate limiters) have filled up. Segment starts snap to the
quietest sample within ``snap_s`` before (best velocity estimate). Why 8 s and not 2: under dry
friction the stick position depends on the history, so every restart from a noisy measured state
(q̇ from 15 Hz finite differences) leaves a persistent error of up to Fc/Kp (~mrad); with 2.5 s
segments the *true* model replays a Coulomb data set at 1.6x the sensor noise, with 8 s at 1.05x.
The weakly damped null-space modes of the Cartesian impedance also need ~1 s of burn-in to decay.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from realm_ms.errors import InputError
from realm_ms.sysid.timeseries import Trajectory


def held_commands(t: np.ndarray, q_cmd: np.ndarray, n_steps: int, dt: float) -> np.ndarray:
    """Target per physics step k: the time average over [k dt, (k+1) dt) of the zero-order-hold
    command (q_cmd[i] held from t[i] until t[i+1], ``t`` relative to the simulation start). When
    the log's command switches fall between physics steps (100-500 Hz logs with a 120 Hz sim),
    the switch step gets the blend -- command timing at sub-step resolution, so the replay does
    not depend on how the physics grid falls on the log. At 15 Hz / 120 Hz the grid is aligned and
    this is exactly the held value."""
    t = np.asarray(t, dtype=float)
    widths = np.diff(t)
    cum = np.concatenate([np.zeros((1, q_cmd.shape[1])), np.cumsum(widths[:, None] * q_cmd[:-1], axis=0)])

    def integral(tau: np.ndarray) -> np.ndarray:
        j = np.clip(np.searchsorted(t, tau, side="right") - 1, 0, len(t) - 1)
        return cum[j] + (tau - t[j])[:, None] * q_cmd[j]

    edges = np.arange(n_steps + 1) * dt
    vals = integral(edges)
    return (vals[1:] - vals[:-1]) / dt


def _quietness(tr: Trajectory) -> np.ndarray:
    """Per sample: how far from quasi-static the arm is (|q̇| and |q̈| summed over joints, scaled),
    plus how much the target moves; low = a good place to start a segment from measurements."""
    v = tr.velocity()
    a = np.gradient(v, tr.t, axis=0) if len(tr.t) > 2 else np.zeros_like(v)
    dc = np.abs(np.gradient(tr.q_cmd, tr.t, axis=0))
    return np.abs(v).sum(1) / 0.1 + np.abs(a).sum(1) / 1.0 + dc.sum(1) / 0.1


@dataclass(frozen=True)
class Segment:
    traj: int
    start: int  # first sample simulated (initial state)
    stop: int  # one past the last sample simulated
    score_from: int  # first scored sample


@dataclass
class SegmentSet:
    trajs: list[Trajectory]
    segments: list[Segment]
    dt: float
    q0: np.ndarray  # (N, 7)
    qd0: np.ndarray  # (N, 7)
    cmd: np.ndarray  # (N, S, 7) target per physics step
    pos: np.ndarray  # (N, L) sample times in physics steps (float)
    meas: np.ndarray  # (N, L, 7) measured q at the samples
    mask: np.ndarray  # (N, L) bool, scored samples
    sample_idx: np.ndarray  # (N, L) sample index into the trajectory (-1 = padding)
    saturated_fraction: float = 0.0  # share of the scorable samples left out as torque-saturated (``saturation.py``)
    closed: object | None = None  # ``closed_loop.ClosedLoopCommand`` per segment (``--command closed_loop``)
    interaction_fraction: float = 0.0  # share of the scorable samples left out as grasps/stalls (``interaction.py``)

    @property
    def n(self) -> int:
        return len(self.segments)

    @property
    def steps(self) -> int:
        return self.cmd.shape[1]

    @property
    def lengths(self) -> np.ndarray:
        """(N,) physics steps each segment needs (its last sample's), at most ``steps``: the rest of
        a row is padding that holds the last target, simulated only to keep the batch rectangular."""
        return np.minimum(np.ceil(self.pos.max(axis=1) - 1e-9).astype(np.int64) + 1, self.steps)

    @classmethod
    def build(cls, trajs: list[Trajectory], physics_hz: float = 120.0, length_s: float = 5.0,
              burn_in_s: float = 1.0, snap_s: float = 0.6, gains: str = "polymetis",
              score_saturated: bool = False, score_interaction: bool = False) -> "SegmentSet":
        """``score_saturated=False``: samples in torque-saturated bursts (``saturation.py``) are
        simulated but not scored; ``score_interaction=False``: nor are grasps and stalls against
        the scene (``interaction.py``; each trajectory's share lands in ``meta["interaction"]``)."""
        from realm_ms.sysid.interaction import free_motion
        from realm_ms.sysid.saturation import unsaturated
        from realm_ms.validate import check_non_negative, check_positive

        # a zero, negative or NaN length would never advance the window loop below
        dt = 1.0 / check_positive(physics_hz, "physics_hz", "Hz")
        length_s = check_positive(length_s, "segment length (--segment)", "s")
        burn_in_s = check_non_negative(burn_in_s, "burn-in", "s")
        snap_s = check_non_negative(snap_s, "snap window", "s")
        segs: list[Segment] = []
        for ti, tr in enumerate(trajs):
            t = tr.t
            quiet = _quietness(tr)
            win = t[0] + burn_in_s
            end = t[-1]
            starts = []
            while win < end - 1e-9:
                starts.append(win)
                win += length_s
            if len(starts) > 1 and end - starts[-1] < 0.5 * length_s:
                starts.pop()  # merge a short tail into the previous window
            for k, ws in enumerate(starts):
                we = starts[k + 1] if k + 1 < len(starts) else math.inf
                start = int(np.searchsorted(t, ws - burn_in_s - 1e-9, side="left"))
                # snap the initial state to the quietest sample up to ``snap_s`` earlier: the
                # velocity estimate is best there, and dry friction keeps no memory of it
                lo = int(np.searchsorted(t, t[start] - snap_s - 1e-9, side="left"))
                if start > 0:
                    start = lo + int(np.argmin(quiet[lo:start + 1]))
                start = max(0, min(start, len(t) - 2))
                score_from = int(np.searchsorted(t, ws - 1e-9, side="left"))
                stop = int(np.searchsorted(t, we - 1e-9, side="left")) if math.isfinite(we) else len(t)
                if stop - score_from >= 1 and stop - start >= 2:
                    segs.append(Segment(ti, start, stop, score_from))
        if not segs:
            raise InputError("no segment to simulate: trajectories shorter than the burn-in")
        n = len(segs)
        steps = [int(math.ceil((trajs[s.traj].t[s.stop - 1] - trajs[s.traj].t[s.start]) / dt - 1e-6)) for s in segs]
        n_steps = max(1, max(steps))
        n_samp = max(s.stop - s.start for s in segs)
        q0, qd0 = np.zeros((n, 7)), np.zeros((n, 7))
        cmd = np.zeros((n, n_steps, 7))
        pos = np.zeros((n, n_samp))
        meas = np.zeros((n, n_samp, 7))
        mask = np.zeros((n, n_samp), dtype=bool)
        sample_idx = -np.ones((n, n_samp), dtype=np.int64)
        vel = [tr.velocity() for tr in trajs]
        keep = [None if score_saturated else unsaturated(tr, gains) for tr in trajs]
        free = [None if score_interaction else free_motion(tr) for tr in trajs]
        unsat = np.ones((n, n_samp), dtype=bool)
        loose = np.ones((n, n_samp), dtype=bool)
        for i, s in enumerate(segs):
            tr = trajs[s.traj]
            tt = tr.t[s.start:s.stop] - tr.t[s.start]
            q0[i], qd0[i] = tr.q[s.start], vel[s.traj][s.start]
            cmd[i] = held_commands(tt, tr.q_cmd[s.start:s.stop], n_steps, dt)
            m = s.stop - s.start
            pos[i, :m] = np.minimum(tt / dt, n_steps)
            pos[i, m:] = pos[i, m - 1]
            meas[i, :m] = tr.q[s.start:s.stop]
            mask[i, s.score_from - s.start:m] = True
            if keep[s.traj] is not None:
                unsat[i, :m] = keep[s.traj][s.start:s.stop]
            if free[s.traj] is not None:
                loose[i, :m] = free[s.traj][s.start:s.stop]
            sample_idx[i, :m] = np.arange(s.start, s.stop)
        left_out = 0.0
        if (mask & unsat).any():  # a log saturated throughout is scored whole rather than not at all
            left_out = 1.0 - (mask & unsat).sum() / mask.sum()
            mask &= unsat
        in_contact = 0.0
        if (mask & loose).any():  # likewise a log in contact throughout
            in_contact = 1.0 - (mask & loose).sum() / mask.sum()
            mask &= loose
        from realm_ms.sysid.closed_loop import from_segments

        return cls(trajs, segs, dt, q0, qd0, cmd, pos, meas, mask, sample_idx, float(left_out),
                   from_segments(trajs, segs, dt), float(in_contact))

    @classmethod
    def stack(cls, sets: list["SegmentSet"]) -> "SegmentSet":
        """The segments of several sets (same physics rate) as one set, in order, to simulate in one
        batch: a rollout's cost is mostly per physics step, not per arm. Shorter command series
        hold their last target and shorter sample rows repeat their last sample time, as ``build``
        pads within a set; ``split`` cuts a simulation of the stack back into the sets' shapes."""
        if len(sets) == 1:
            return sets[0]
        if len({s.dt for s in sets}) != 1:
            raise ValueError("cannot stack segment sets built at different physics rates")
        n_steps = max(s.steps for s in sets)
        n_samp = max(s.pos.shape[1] for s in sets)

        def cat(field: str, n: int, fill=None) -> np.ndarray:
            """The sets' ``field`` padded along axis 1 to n (repeating the last entry, or with ``fill``)."""
            out = []
            for s in sets:
                a = getattr(s, field)
                width = [(0, 0), (0, n - a.shape[1])] + [(0, 0)] * (a.ndim - 2)
                out.append(np.pad(a, width, mode="edge") if fill is None else np.pad(a, width, constant_values=fill))
            return np.concatenate(out)

        trajs, segs = [], []
        for s in sets:
            segs += [Segment(g.traj + len(trajs), g.start, g.stop, g.score_from) for g in s.segments]
            trajs += s.trajs
        scored = [s.mask.sum() for s in sets]
        left_out = sum(s.saturated_fraction * m for s, m in zip(sets, scored)) / max(sum(scored), 1)
        in_contact = sum(s.interaction_fraction * m for s, m in zip(sets, scored)) / max(sum(scored), 1)
        from realm_ms.sysid.closed_loop import from_segments

        return cls(trajs, segs, sets[0].dt, np.concatenate([s.q0 for s in sets]), np.concatenate([s.qd0 for s in sets]),
                   cat("cmd", n_steps), cat("pos", n_samp), cat("meas", n_samp, 0.0), cat("mask", n_samp, False),
                   cat("sample_idx", n_samp, -1), float(left_out), from_segments(trajs, segs, sets[0].dt),
                   float(in_contact))

    @staticmethod
    def split(sets: list["SegmentSet"], sim: np.ndarray, n_candidates: int) -> list[np.ndarray]:
        """A candidate-major simulation (C*N, L, 7) of ``stack(sets)`` -> one (C*N_s, L_s, 7) per set."""
        sim = sim.reshape(n_candidates, -1, *sim.shape[1:])
        out, a = [], 0
        for s in sets:
            out.append(sim[:, a:a + s.n, :s.pos.shape[1]].reshape(n_candidates * s.n, s.pos.shape[1], *sim.shape[3:]))
            a += s.n
        return out

    def sample(self, hist: np.ndarray, seg_idx: np.ndarray | None = None) -> np.ndarray:
        """Simulated q (E, S+1, 7) at physics steps -> at the data samples (E, L, 7)."""
        pos = self.pos if seg_idx is None else self.pos[seg_idx]
        lo = np.clip(np.floor(pos).astype(np.int64), 0, hist.shape[1] - 1)
        hi = np.clip(lo + 1, 0, hist.shape[1] - 1)
        w = (pos - lo)[..., None]
        rows = np.arange(hist.shape[0])[:, None]
        return hist[rows, lo] * (1 - w) + hist[rows, hi] * w


@dataclass
class Scores:
    """Residual statistics of C candidates on one SegmentSet."""

    mse: np.ndarray  # (C,) mean over scored samples and joints, rad^2
    per_joint_mse: np.ndarray  # (C, 7)
    residual: np.ndarray  # (C, N, L, 7) measured - simulated (NaN where not scored)

    @property
    def rmse(self) -> np.ndarray:
        return np.sqrt(self.mse)

    @property
    def per_joint_rmse(self) -> np.ndarray:
        return np.sqrt(self.per_joint_mse)


def score(segset: SegmentSet, sim_q: np.ndarray, n_candidates: int) -> Scores:
    """sim_q: (C*N, L, 7) sampled positions, candidate-major."""
    n = segset.n
    sim_q = sim_q.reshape(n_candidates, n, *sim_q.shape[1:])
    res = segset.meas[None] - sim_q
    m = segset.mask[None, :, :, None]
    res = np.where(m, res, np.nan)
    cnt = segset.mask.sum()
    with np.errstate(invalid="ignore"):
        sq = np.where(np.isfinite(res), res**2, 0.0)
        bad = np.isnan(sim_q).any(axis=(1, 2, 3))
        pj = sq.sum(axis=(1, 2)) / max(cnt, 1)
    pj[bad] = np.inf
    return Scores(pj.mean(axis=1), pj, res)
