"""Torque-saturated bursts: samples where a motor sits at its effort limit, and the excursion around
them. A position replay does not score them.

With a motor at its limit the loop is open: the arm swings on its own dynamics and small differences
grow. On the MuJoCo-native payload plant (measured 2026-11-25, no command in the repository),
MuJoCo's own plant integrated at 1 kHz instead of 4 kHz ends 11 mrad away on joint 6 within one
such burst, and 2.7 mrad at 16 kHz. No
120 Hz replay can follow there, whatever its model: one burst in 4.5 % of a log's samples held
a true payload's replay at 1.36 mrad, 0.42 mrad without it. The samples still drive the simulation
(segments run through them); only their residual is left out of RMSEs, fits and verdicts.

Where the log has the joint torque (``tau``) it is used. Otherwise the law's torque is rebuilt from
the logged state and command: Kp(q)(q_cmd - q) - Kd(q) q̇ + the feed-forward (the nominal
Polymetis law, ``control/law.py``). A lowered effort limit (``torque_limit``) stays visible: the
bursts are found at the *nominal* limits.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from realm_ms.agents.effects.torque_limit import NOMINAL_LIMITS
from realm_ms.sysid.timeseries import Trajectory

AT_LIMIT = 0.98  # a torque within 2 % of its limit is saturated
PAD_S = 0.2  # s around a saturated sample: the excursion it starts or ends
_CHUNK = 4096
VELOCITY_SPAN_S = 0.005  # s: half-span of the central difference when the log has no velocity


def velocity(tr: Trajectory) -> np.ndarray:
    """The logged velocity, else central differences over +-5 ms (adjacent 1 kHz samples would turn
    0.1 mrad of encoder noise into 0.07 rad/s, enough to touch a wrist limit that is not reached)."""
    if tr.qd is not None:
        return tr.qd
    h = max(VELOCITY_SPAN_S, 0.5 * tr.duration / max(len(tr.t) - 1, 1))
    lo, hi = np.clip(tr.t - h, tr.t[0], tr.t[-1]), np.clip(tr.t + h, tr.t[0], tr.t[-1])
    at = lambda x: np.stack([np.interp(x, tr.t, tr.q[:, j]) for j in range(tr.q.shape[1])], 1)  # noqa: E731
    return (at(hi) - at(lo)) / np.maximum(hi - lo, 1e-9)[:, None]


@lru_cache(maxsize=4)
def _driver(gains: str):
    from realm_ms.agents.arm_model import ArmModel
    from realm_ms.agents.control import DroidArmDriver, DroidControlConfig
    from realm_ms.sysid.locked_urdf import BASE_LINK, TIP_LINK, source_urdf_path

    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    return DroidArmDriver(model, DroidControlConfig(gains=gains), 1, "cpu")


def law_torque(tr: Trajectory, gains: str = "polymetis") -> np.ndarray:
    """(T, 7) N·m: the nominal law's torque at every sample, from ``q``, the velocity and ``q_cmd``."""
    import torch

    from realm_ms.agents.control.law import terms_at

    if tr.q_cmd is None:
        raise ValueError(f"{tr.name}: no q_cmd, the law's torque cannot be rebuilt")
    drv = _driver(gains)
    out = np.empty_like(tr.q)
    v = velocity(tr)
    for a in range(0, len(tr.t), _CHUNK):
        sl = slice(a, a + _CHUNK)
        q, qd, qc = (torch.as_tensor(x[sl], dtype=torch.float32) for x in (tr.q, v, tr.q_cmd))
        g = drv.gains.map(lambda x: x[:1].expand(q.shape[0], -1))
        with torch.inference_mode():
            t = terms_at(drv.be, drv.config, q, qd, g, drv.arm)
            tau = (t["kp"] @ (qc - q)[..., None] - t["kd"] @ qd[..., None])[..., 0] + t["bias"]
        out[sl] = tau.double().numpy()
    return out


def saturated(tr: Trajectory, gains: str = "polymetis") -> np.ndarray:
    """(T,) bool: some joint's torque (logged, else the law's) within ``AT_LIMIT`` of its limit."""
    if tr.tau is not None:
        tau = tr.tau
    elif tr.q_cmd is not None:
        tau = law_torque(tr, gains)
    else:
        return np.zeros(len(tr.t), dtype=bool)
    return (np.abs(tau) >= AT_LIMIT * np.asarray(NOMINAL_LIMITS)).any(axis=1)


def unsaturated(tr: Trajectory, gains: str = "polymetis", pad_s: float = PAD_S) -> np.ndarray:
    """(T,) bool: samples farther than ``pad_s`` from every saturated sample (the ones to score)."""
    sat = saturated(tr, gains)
    keep = np.ones(len(tr.t), dtype=bool)
    if not sat.any():
        return keep
    times = tr.t[sat]
    lo = np.searchsorted(tr.t, times - pad_s, side="left")
    hi = np.searchsorted(tr.t, times + pad_s, side="right")
    # mark each padded interval by a +1/-1 difference array: O(T) however many saturated samples
    d = np.zeros(len(tr.t) + 1, dtype=np.int64)
    np.add.at(d, lo, 1)
    np.add.at(d, hi, -1)
    keep &= np.cumsum(d)[:-1] == 0
    return keep
