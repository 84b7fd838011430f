"""Joint velocity and acceleration from logged positions: Savitzky-Golay derivatives.

A Savitzky-Golay filter fits a polynomial of degree ``order`` by least squares in a sliding window
of ``window_s`` seconds and differentiates the polynomial: zero phase (no lag, unlike a causal
filter), and its frequency response is flat up to about ``(order + 1) / (window length)``.
Defaults: a cubic over 51 ms. At 1 kHz that passes the arm's motion (a few Hz) and attenuates
encoder noise: with sigma_q noise the acceleration noise is ~ sigma_q * 2e5 s^-2 at 1 kHz
(0.1 mrad -> ~20 rad/s² raw double difference, ~0.3 rad/s² after the filter; checked in
``tests/test_sysid_torque.py``). The logged ``qd``, when present, is smoothed and differentiated once instead.

The timestamps must be (nearly) uniform: SG assumes a fixed step (the median is used; a log with
> 5 % step jitter is resampled first by the caller).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SmoothingConfig:
    window_s: float = 0.051  # SG window length in seconds
    order: int = 3  # polynomial degree


def _window(n: int, dt: float, cfg: SmoothingConfig) -> int:
    w = max(cfg.order + 2, int(round(cfg.window_s / dt)))
    w += 1 - w % 2  # odd
    return min(w, n - 1 - (n % 2 == 0))


def derivatives(t: np.ndarray, q: np.ndarray, qd: np.ndarray | None = None,
                cfg: SmoothingConfig = SmoothingConfig()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q_smooth, qd, qdd), each (T, 7), by Savitzky-Golay on a uniform grid of step median(dt)."""
    from scipy.signal import savgol_filter

    dt = float(np.median(np.diff(t)))
    w = _window(len(t), dt, cfg)
    if w <= cfg.order:
        raise ValueError(f"too few samples ({len(t)}) for a Savitzky-Golay window of order {cfg.order}")
    qs = savgol_filter(q, w, cfg.order, axis=0, mode="interp")
    if qd is None:
        v = savgol_filter(q, w, cfg.order, deriv=1, delta=dt, axis=0, mode="interp")
        a = savgol_filter(q, w, cfg.order, deriv=2, delta=dt, axis=0, mode="interp")
    else:
        v = savgol_filter(qd, w, cfg.order, axis=0, mode="interp")
        a = savgol_filter(qd, w, cfg.order, deriv=1, delta=dt, axis=0, mode="interp")
    return qs, v, a
