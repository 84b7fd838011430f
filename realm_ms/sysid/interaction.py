"""Grasps, pushes, contacts and near-singular postures in real DROID episodes: stretches an
arm-only replay cannot score.

The replay simulates the arm alone (gripper locked, no scene). In a real episode the arm also
carries what it grasped and presses against objects and furniture; there the real arm is held or
loaded by something the simulator does not have, and its residual says nothing about the robot
model. Near a singularity the command itself is ill-defined. Three signatures, found from the 15 Hz
log alone (no torque, no velocity in DROID's data):

- **grasp**: the gripper is closed but stopped short of closed-on-nothing (an object between the
  fingers): measured gripper position in [``GRASP_MIN``, ``GRASP_MAX``] and still
  (|Δg| < ``GRASP_STILL`` per step) for at least ``MIN_S``;
- **stall**: the commanded flange target is far from the flange (> ``STALL_GAP_M``) while the
  flange hardly moves (< ``STALL_SPEED_M_S``) for at least ``MIN_S``: pushing against
  something (an arm in free space closes such a gap in a few steps);
- **singular**: the smallest singular value of the 6x7 flange Jacobian (linear rows in m/rad,
  angular in rad/rad, as DROID's IK solves with it) is below ``SINGULAR_SIGMA`` for at least
  ``MIN_S`` (arm stretched: elbow straight at q4 ~ -0.47, or wrist axes aligned). Only where the
  joint target comes from IK: a Cartesian command rebuilt or replayed closed loop
  (``droid_formats``: ``rebuild`` / ``closed_loop`` modes); there DROID's damped least squares
  (``DroidIK``) falls short of the commanded step along the weak direction and its joint target
  hinges on the damping and null-space choices, so a joint residual says little about the robot.
  A logged joint target (``logged`` mode, workbench ``q_cmd``) is the robot's own, valid there.

Flagged samples, widened by ``PAD_S`` on both sides, still drive the simulation; only their residual
is left out of RMSEs, fits and verdicts (the same contract as ``saturation.py``). How much was left
out, per episode and in total, is reported. Thresholds were set on the real episodes' logs: a free
DROID arm follows its command within ~2 cm at 15 Hz; below ``SINGULAR_SIGMA`` the rebuilt target
misses more of the commanded flange step and the closed-loop replay's joints drift off fastest
(``docs/results.md``).
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
#: smallest singular value of the flange Jacobian below which a posture is near-singular: the damping
#: scale of DROID's IK (sqrt of its 1e-2 regularisation), where its least squares passes half of a step
#: along the weak direction and its answer is most sensitive to the command (gain s / (s^2 + 1e-2) peaks);
#: checked on the real episodes (``bench/droid_singularity.py``, ``docs/results.md``)
SINGULAR_SIGMA = 0.1
IK_MODES = ("rebuild", "closed_loop")  # command modes whose joint target comes from DROID's IK
MIN_S = 0.3  # s a signature must hold (5 steps at DROID's 15 Hz)
PAD_S = 0.2
SIGNATURES = ("grasp", "stall", "singular")


@dataclass
class Interaction:
    grasp: np.ndarray  # (T,) bool
    stall: np.ndarray  # (T,) bool
    singular: np.ndarray  # (T,) bool

    @property
    def masked(self) -> np.ndarray:
        return self.grasp | self.stall | self.singular

    def summary(self) -> dict:
        """Share of the samples per signature and masked in all (signatures may overlap)."""
        n = max(len(self.grasp), 1)
        return {k: round(float(getattr(self, k).sum() / n), 4) for k in SIGNATURES + ("masked",)}


def describe(trajs) -> str:
    """'grasp 3.1 %, stall 0.4 %, singular 2.0 %': each signature's share of all samples of
    ``trajs`` (their ``meta["interaction"]``, set by ``free_motion``), for the log lines."""
    n = sum(len(tr.t) for tr in trajs if "interaction" in tr.meta)
    share = {k: sum(tr.meta["interaction"][k] * len(tr.t) for tr in trajs if "interaction" in tr.meta) / max(n, 1)
             for k in SIGNATURES}
    return ", ".join(f"{k} {v:.1%}" for k, v in share.items())


def ik_command(tr: Trajectory) -> bool:
    """Whether ``tr``'s joint target comes from DROID's IK (a Cartesian command rebuilt or replayed)."""
    return tr.meta.get("command_mode") in IK_MODES and str(tr.meta.get("command_space", "")).startswith("cartesian")


def sigma_min(q: np.ndarray, ik) -> np.ndarray:
    """(T,) smallest singular value of the 6x7 flange Jacobian at each posture."""
    return np.linalg.svd(ik.jacobian(q), compute_uv=False)[:, -1]


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


def held_samples(rate_hz: float) -> int:
    """Samples a signature must hold: ``MIN_S`` at the log's rate, at least 2."""
    return max(2, int(np.ceil(MIN_S * rate_hz - 1e-9)))


def _pad(flag: np.ndarray, t: np.ndarray, pad_s: float) -> np.ndarray:
    idx = np.flatnonzero(flag)
    out = flag.copy()
    for i in idx:
        out[(t >= t[i] - pad_s) & (t <= t[i] + pad_s)] = True
    return out


def detect(tr: Trajectory, ik=None) -> Interaction:
    """Grasp, stall and (IK commands only) near-singular samples of one trajectory, widened by ``PAD_S``."""
    n = len(tr.t)
    min_len = held_samples(tr.rate_hz)
    grasp = np.zeros(n, bool)
    if tr.gripper is not None:
        g = tr.gripper
        still = np.r_[True, np.abs(np.diff(g)) < GRASP_STILL]
        grasp = _runs((g > GRASP_MIN) & (g < GRASP_MAX) & still, min_len)
    stall = np.zeros(n, bool)
    singular = np.zeros(n, bool)
    if tr.q_cmd is not None:
        from realm_ms.agents.droid_action_spaces import DroidIK

        ik = ik or DroidIK()
        p = ik.flange(tr.q)[:, :3, 3]
        gap = np.linalg.norm(ik.flange(tr.q_cmd)[:, :3, 3] - p, axis=1)
        speed = np.linalg.norm(np.gradient(p, tr.t, axis=0), axis=1)
        stall = _runs((gap > STALL_GAP_M) & (speed < STALL_SPEED_M_S), min_len)
        if ik_command(tr):
            singular = _runs(sigma_min(tr.q, ik) < SINGULAR_SIGMA, min_len)
    return Interaction(*(_pad(f, tr.t, PAD_S) for f in (grasp, stall, singular)))


def free_motion(tr: Trajectory) -> np.ndarray:
    """(T,) True where the arm moves free (neither grasping, stalled nor near-singular); the per-episode summary
    is stored in ``tr.meta["interaction"]``."""
    hit = detect(tr)
    tr.meta["interaction"] = hit.summary()
    return ~hit.masked
