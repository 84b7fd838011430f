"""Grasps, pushes and contacts in real DROID episodes: stretches an arm-only replay cannot model.

The replay simulates the arm alone (gripper locked, no scene). In a real episode the arm also
carries what it grasped and presses against objects and furniture; there the real arm is held or
loaded by something the simulator does not have, and its residual says nothing about the robot
model. Two signatures, found from the 15 Hz log alone (no torque, no velocity in DROID's data):

- **grasp**: the gripper is closed but stopped short of closed-on-nothing (an object between the
  fingers): measured gripper position in [``GRASP_MIN``, ``GRASP_MAX``] and still
  (|Δg| < ``GRASP_STILL`` per step) for at least ``MIN_S``;
- **stall**: the commanded flange target is far from the flange (> ``STALL_GAP_M``) while the
  flange hardly moves (< ``STALL_SPEED_M_S``) for at least ``MIN_S``: pushing against
  something (an arm in free space closes such a gap in a few steps).

Flagged samples, widened by ``PAD_S`` on both sides, still drive the simulation; only their residual
is left out of RMSEs, fits and verdicts (the same contract as ``saturation.py``). How much was left
out, per episode and in total, is reported. Thresholds were set on the real episodes' logs: a free
DROID arm follows its command within ~2 cm at 15 Hz (``docs/results.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from realm_ms.sysid.timeseries import Trajectory

GRASP_MIN = 0.05  # gripper position (0 open .. 1 closed): above it the fingers are closing
GRASP_MAX = 0.95  # below it they stopped on something
GRASP_STILL = 0.01  # per step
STALL_GAP_M = 0.04
STALL_SPEED_M_S = 0.01
MIN_S = 0.3  # s a signature must hold (5 steps at DROID's 15 Hz)
PAD_S = 0.2


@dataclass
class Interaction:
    grasp: np.ndarray  # (T,) bool
    stall: np.ndarray  # (T,) bool

    @property
    def masked(self) -> np.ndarray:
        return self.grasp | self.stall

    def summary(self) -> dict:
        n = max(len(self.grasp), 1)
        return {"grasp": round(float(self.grasp.sum() / n), 4), "stall": round(float(self.stall.sum() / n), 4),
                "masked": round(float(self.masked.sum() / n), 4)}


def _runs(flag: np.ndarray, min_len: int) -> np.ndarray:
    """``flag`` kept only where it holds for ``min_len`` consecutive samples."""
    out = np.zeros_like(flag)
    i = 0
    while i < len(flag):
        if flag[i]:
            j = i
            while j < len(flag) and flag[j]:
                j += 1
            if j - i >= min_len:
                out[i:j] = True
            i = j
        else:
            i += 1
    return out


def _pad(flag: np.ndarray, t: np.ndarray, pad_s: float) -> np.ndarray:
    idx = np.flatnonzero(flag)
    out = flag.copy()
    for i in idx:
        out[(t >= t[i] - pad_s) & (t <= t[i] + pad_s)] = True
    return out


def detect(tr: Trajectory, ik=None) -> Interaction:
    """Grasp and stall samples of one trajectory (both widened by ``PAD_S``)."""
    n = len(tr.t)
    min_len = max(2, int(np.ceil(MIN_S * tr.rate_hz - 1e-9)))
    grasp = np.zeros(n, bool)
    if tr.gripper is not None:
        g = tr.gripper
        still = np.r_[True, np.abs(np.diff(g)) < GRASP_STILL]
        grasp = _runs((g > GRASP_MIN) & (g < GRASP_MAX) & still, min_len)
    stall = np.zeros(n, bool)
    if tr.q_cmd is not None:
        from realm_ms.agents.droid_action_spaces import DroidIK

        ik = ik or DroidIK()
        p = ik.flange(tr.q)[:, :3, 3]
        gap = np.linalg.norm(ik.flange(tr.q_cmd)[:, :3, 3] - p, axis=1)
        speed = np.linalg.norm(np.gradient(p, tr.t, axis=0), axis=1)
        stall = _runs((gap > STALL_GAP_M) & (speed < STALL_SPEED_M_S), min_len)
    return Interaction(_pad(grasp, tr.t, PAD_S), _pad(stall, tr.t, PAD_S))


def free_motion(tr: Trajectory) -> np.ndarray:
    """(T,) True where the arm moves free (neither grasping nor stalled); the per-episode summary
    is stored in ``tr.meta["interaction"]``."""
    hit = detect(tr)
    tr.meta["interaction"] = hit.summary()
    return ~hit.masked
