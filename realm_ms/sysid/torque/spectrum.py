"""Where in frequency a torque residual lives: its RMS split into bands.

A rigid-body model with friction acts at the frequencies of the motion (a few Hz for 15 Hz
command steps or exciting trajectories). What a real arm leaves above ~10 Hz -- joint elasticity,
structural vibration, torque-sensor dynamics -- no effect of the library can reach, and the
white-noise floor (``smoothing.noise_floor``) does not count it either. So the bands tell a user
whether the residual left after a fit is a missing low-frequency effect (worth another suspect) or
high-frequency structure (a different kind of model).

Each scored trajectory is split into bands with an FFT mask (its mean goes to the lowest band);
band signals are orthogonal, so the squares of the band RMS values add up to the total mean square.
"""

from __future__ import annotations

import numpy as np

EDGES_HZ = (2.0, 10.0)  # band edges: slow (< 2 Hz), motion (2-10 Hz), fast (> 10 Hz)


def band_names(edges: tuple[float, ...] = EDGES_HZ) -> list[str]:
    lo = (0.0,) + tuple(edges)
    return [f"{a:g}-{b:g} Hz" for a, b in zip(lo, edges)] + [f">{edges[-1]:g} Hz"]


def band_rms(residual: np.ndarray, lengths: list[int], dt: float,
             edges: tuple[float, ...] = EDGES_HZ) -> np.ndarray:
    """(bands, 7) RMS of ``residual`` (N, 7; trajectories of ``lengths`` back to back, sampled every
    ``dt`` s) in each band; the bands' squares sum to the residual's mean square."""
    if sum(lengths) != len(residual):
        raise ValueError(f"lengths add up to {sum(lengths)}, residual has {len(residual)} samples")
    power = np.zeros((len(edges) + 1, residual.shape[1]))
    start = 0
    for n in lengths:
        seg = residual[start:start + n]
        start += n
        spec = np.fft.rfft(seg, axis=0)
        freq = np.fft.rfftfreq(n, dt)
        idx = np.searchsorted(np.asarray(edges), freq, side="right")  # band of each frequency bin
        for b in range(len(edges) + 1):
            part = np.fft.irfft(np.where((idx == b)[:, None], spec, 0), n=n, axis=0)
            power[b] += (part**2).sum(0)
    return np.sqrt(power / max(len(residual), 1))


def summary(bands: np.ndarray, edges: tuple[float, ...] = EDGES_HZ) -> dict:
    """JSON form: band names, per-band per-joint RMS and each band's share of the residual power."""
    total = (bands**2).sum()
    return {"bands": band_names(edges), "rms": [float(np.sqrt(np.mean(row**2))) for row in bands],
            "rms_per_joint": [[float(x) for x in row] for row in bands],
            "share": [float((row**2).sum() / total) if total > 0 else 0.0 for row in bands]}


def high_frequency_note(s: dict, unit: str = "N·m", threshold: float = 0.5) -> str:
    """A sentence when most of a residual lies in the top band, else ''."""
    share = s["share"][-1]
    if share < threshold:
        return ""
    below = float(np.sqrt(sum(r**2 for r in s["rms"][:-1])))
    return (f"{100 * share:.0f}% of the residual power lies {s['bands'][-1].replace('>', 'above ')} (joint "
            f"elasticity, vibration or torque-sensor dynamics: no effect in the library acts there); below that "
            f"{below:.2e} {unit} is left")
