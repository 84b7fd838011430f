"""Residual signatures: features of the position residual that point at physical effects, and the
one-sentence evidence each effect gets in the diagnosis.

Computed on scored samples of the baseline residual r = q_measured - q_simulated with the measured
velocity q̇ (finite differences when not logged), acceleration q̈, the controller model's gravity
torque g(q), the tracking error e = q* - q, and the sign of q̇. Per joint:

* ``corr_sign``: correlation of r with tanh(q̇ / 0.05) (Coulomb / stiction / backlash-like)
* ``corr_vel``, ``corr_acc``, ``corr_grav``, ``corr_err``: correlations with q̇, q̈, g_i(q), e
* ``slow_fast``: |r| at low speed over |r| at high speed (Stribeck > 1, viscous < 1, Coulomb ≈ 1)
* ``mean``: constant offset (bias), ``hold_rms`` / ``move_rms``: residual in holds vs in motion
* ``lag_s``: delay that best aligns simulated and measured velocity (cross-correlation peak with a
  sub-sample parabola), common to all joints for a pure latency
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from realm_ms.agents.effects.parameter import format_value


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a - a.mean(), b - b.mean()
    d = np.sqrt((a * a).sum() * (b * b).sum())
    return float((a * b).sum() / d) if d > 0 else 0.0


@dataclass
class Features:
    corr_sign: np.ndarray
    corr_vel: np.ndarray
    corr_acc: np.ndarray
    corr_grav: np.ndarray
    corr_err: np.ndarray
    slow_fast: np.ndarray
    mean: np.ndarray
    rms: np.ndarray
    hold_rms: np.ndarray
    move_rms: np.ndarray
    lag_s: np.ndarray  # per joint
    extra: dict = field(default_factory=dict)

    def worst_joint(self) -> int:
        return int(np.argmax(self.rms))

    def to_dict(self) -> dict:
        keys = ("corr_sign", "corr_vel", "corr_acc", "corr_grav", "corr_err", "slow_fast", "mean", "rms",
                "hold_rms", "move_rms", "lag_s")
        return {k: [round(float(x), 6) for x in getattr(self, k)] for k in keys}


def estimate_lag(vm: np.ndarray, vs: np.ndarray, dt: float, max_lag_s: float = 0.15) -> float:
    """Delay (s) of measured vs simulated velocity from the cross-correlation peak (parabolic
    sub-sample refinement). Positive: the measurement lags the simulation."""
    n = len(vm)
    if n < 8 or np.std(vm) == 0 or np.std(vs) == 0:
        return 0.0
    kmax = max(1, min(n // 4, int(round(max_lag_s / dt))))
    lags = np.arange(-kmax, kmax + 1)
    c = np.array([np.dot(vm[max(0, k):n + min(0, k)], vs[max(0, -k):n - max(0, k)]) / (n - abs(k)) for k in lags])
    i = int(np.argmax(c))
    off = 0.0
    if 0 < i < len(c) - 1:
        den = c[i - 1] - 2 * c[i] + c[i + 1]
        off = 0.5 * (c[i - 1] - c[i + 1]) / den if den != 0 else 0.0
    return float((lags[i] + off) * dt)


def compute(segset, sim_q: np.ndarray, gravity: np.ndarray | None = None) -> Features:
    """``sim_q``: (N, L, 7) simulated positions at the samples of ``segset`` (one candidate)."""
    mask = segset.mask
    res = (segset.meas - sim_q)[mask]  # (M, 7)
    vel_all, acc_all, err_all, simv_all, measv_all = [], [], [], [], []
    for i, s in enumerate(segset.segments):
        tr = segset.trajs[s.traj]
        v = tr.velocity()[s.start:s.stop]
        t = tr.t[s.start:s.stop]
        a = np.gradient(v, t, axis=0) if len(t) > 2 else np.zeros_like(v)
        m = mask[i, : s.stop - s.start]
        vel_all.append(v[m])
        acc_all.append(a[m])
        err_all.append((tr.q_cmd[s.start:s.stop] - tr.q[s.start:s.stop])[m])
        sq = sim_q[i, : s.stop - s.start]
        simv_all.append(np.gradient(sq, t, axis=0)[m] if len(t) > 2 else np.zeros_like(v[m]))
        measv_all.append(v[m])
    vel, acc, err = np.concatenate(vel_all), np.concatenate(acc_all), np.concatenate(err_all)
    simv, measv = np.concatenate(simv_all), np.concatenate(measv_all)
    dt = float(np.median(np.diff(segset.trajs[0].t)))
    grav = gravity if gravity is not None else np.zeros_like(res)
    out = {k: np.zeros(7) for k in ("corr_sign", "corr_vel", "corr_acc", "corr_grav", "corr_err", "slow_fast",
                                    "mean", "rms", "hold_rms", "move_rms", "lag_s")}
    for j in range(7):
        r, v = res[:, j], vel[:, j]
        out["corr_sign"][j] = _corr(r, np.tanh(v / 0.05))
        out["corr_vel"][j] = _corr(r, v)
        out["corr_acc"][j] = _corr(r, acc[:, j])
        out["corr_grav"][j] = _corr(r, grav[:, j])
        out["corr_err"][j] = _corr(r, err[:, j])
        speed = np.abs(v)
        moving = speed > 0.02
        if moving.sum() > 10:
            med = np.median(speed[moving])
            slow, fast = moving & (speed <= med), moving & (speed > med)
            fast_rms = np.sqrt(np.mean(r[fast] ** 2))
            # no residual at speed: no ratio (0, as for a joint that hardly moves), never x / 1e-12
            out["slow_fast"][j] = np.sqrt(np.mean(r[slow] ** 2)) / fast_rms if fast_rms > 0 else 0.0
        out["mean"][j] = r.mean()
        out["rms"][j] = np.sqrt(np.mean(r**2))
        out["hold_rms"][j] = np.sqrt(np.mean(r[~moving] ** 2)) if (~moving).sum() > 3 else 0.0
        out["move_rms"][j] = np.sqrt(np.mean(r[moving] ** 2)) if moving.sum() > 3 else 0.0
        out["lag_s"][j] = estimate_lag(measv[:, j], simv[:, j], dt)
    return Features(**out)


def _j(i: int) -> str:
    return f"joint {i + 1}"


def _ratio(a: float, b: float) -> str:
    """a / b to 2 decimals, or "n/a" where b is 0 (a zero is never divided into a huge number)."""
    return f"{a / b:.2f}" if b > 0 else "n/a"


def _top(arr: np.ndarray, feats: Features) -> int:
    return int(np.argmax(np.abs(arr) * feats.rms))


def _coulomb(f, fx, v, size):
    j = _top(f.corr_sign, f)
    return (f"residual flips sign with velocity (corr {f.corr_sign[j]:+.2f} with sign(q̇) on {_j(j)}), "
            f"about the same size at slow and fast speeds (slow/fast {f.slow_fast[j]:.1f}) → Coulomb friction, {size}")


def _viscous(f, fx, v, size):
    j = _top(f.corr_vel, f)
    return (f"residual grows in proportion to velocity (corr {f.corr_vel[j]:+.2f} with q̇ on {_j(j)}, slow/fast "
            f"{f.slow_fast[j]:.1f}), no offset in holds → viscous damping, {size}")


def _stribeck(f, fx, v, size):
    j = _top(f.corr_sign, f)
    return (f"residual is largest at low speed and around reversals (slow/fast {f.slow_fast[j]:.1f} on {_j(j)}, "
            f"corr {f.corr_sign[j]:+.2f} with sign(q̇)) → Stribeck friction / stiction, {size}")


def _smooth(f, fx, v, size):
    j = _top(f.corr_vel, f)
    return (f"residual follows velocity at low speed and levels off at high speed (corr {f.corr_vel[j]:+.2f} with q̇ on "
            f"{_j(j)}, slow/fast {f.slow_fast[j]:.1f}) → smooth friction without stiction, {size}")


def _lugre(f, fx, v, size):
    j = _top(f.corr_sign, f)
    return (f"residual flips sign with velocity (corr {f.corr_sign[j]:+.2f} with sign(q̇) on {_j(j)}) and is largest "
            f"at low speed (slow/fast {f.slow_fast[j]:.1f}), with a springy give at reversals → LuGre friction "
            f"(pre-sliding + Stribeck), {size}")


def _armature(f, fx, v, size):
    j = _top(f.corr_acc, f)
    return (f"residual follows acceleration (corr {f.corr_acc[j]:+.2f} with q̈ on {_j(j)}) and vanishes in holds "
            f"(hold/move rms {_ratio(f.hold_rms[j], f.move_rms[j])}) → armature, {size}")


def _payload(f, fx, v, size):
    j = _top(f.corr_grav, f)
    return (f"static sag that follows the gravity torque (corr {f.corr_grav[j]:+.2f} with g(q) on {_j(j)}), "
            f"present at rest → unmodelled payload, {size}")


def _gravity(f, fx, v, size):
    j = _top(f.corr_grav, f)
    return (f"offset proportional to each joint's gravity torque (corr {f.corr_grav[j]:+.2f} on {_j(j)}), present at rest "
            f"→ gravity-compensation error, {size}")


def _latency(f, fx, v, size):
    lag = float(np.median(f.lag_s))
    return (f"measured motion lags the simulation by {lag * 1e3:.0f} ms on all joints (cross-correlation; spread "
            f"{np.std(f.lag_s) * 1e3:.0f} ms), residual ∝ -q̇ → command latency, {size}")


def _target_filter(f, fx, v, size):
    lag = float(np.median(f.lag_s))
    j = _top(f.corr_vel, f)
    return (f"measured motion lags the simulation by {lag * 1e3:.0f} ms on all joints and is smoother (residual ∝ -q̇, "
            f"corr {f.corr_vel[j]:+.2f} on {_j(j)}) → a low-pass filter on the targets, {size}")


def _target_interpolation(f, fx, v, size):
    lag = float(np.median(f.lag_s))
    j = _top(f.corr_vel, f)
    return (f"measured motion lags the simulation by {lag * 1e3:.0f} ms on all joints, residual ∝ -q̇ (corr "
            f"{f.corr_vel[j]:+.2f} on {_j(j)}), target steps followed as ramps → an interpolator between the "
            f"targets, {size}")


def _gain(f, fx, v, size):
    j = _top(f.corr_err, f)
    return (f"residual scales with the tracking error (corr {f.corr_err[j]:+.2f} with q*-q on {_j(j)}) on all joints "
            f"→ controller gain mismatch, {size}")


def _torque_limit(f, fx, v, size):
    lag = float(np.median(f.lag_s))
    j = _top(f.corr_acc, f)
    return (f"lag after large target jumps ({lag * 1e3:.0f} ms median), residual tied to acceleration on {_j(j)} "
            f"(corr {f.corr_acc[j]:+.2f}) → torque saturation / rate limit, {size}")


def _backlash(f, fx, v, size):
    j = _top(f.corr_grav, f)
    return (f"offset that switches with the sign of the gravity load (corr {f.corr_grav[j]:+.2f} with g(q) on {_j(j)}), "
            f"independent of speed → backlash, {size}")


def _bias(f, fx, v, size):
    j = int(np.argmax(np.abs(f.mean)))
    return (f"constant offset {format_value(-f.mean[j], 'rad')} on {_j(j)} in holds and in motion "
            f"(mean/rms {_ratio(abs(f.mean[j]), f.rms[j])}) → encoder bias, {size}")


SENTENCES: dict[str, Callable] = {
    "coulomb_friction": _coulomb,
    "viscous_damping": _viscous,
    "stribeck_friction": _stribeck,
    "smooth_friction": _smooth,
    "lugre_friction": _lugre,
    "armature": _armature,
    "payload": _payload,
    "gravity_comp_error": _gravity,
    "latency": _latency,
    "target_filter": _target_filter,
    "target_interpolation": _target_interpolation,
    "gain_mismatch": _gain,
    "torque_limit": _torque_limit,
    "backlash": _backlash,
    "encoder_bias": _bias,
}


def evidence(effect, values: dict[str, float], features: Features) -> str:
    """One sentence for the diagnosis: what in the residual points at ``effect`` (``SENTENCES``, by
    effect name) and how big it is; an effect without a sentence gets its summary."""
    fn = SENTENCES.get(effect.name)
    if fn is None:
        return f"{effect.summary}: {effect.describe(values)}"
    return fn(features, effect, values, effect.describe(values, max_items=2))


def noise_floor(segset, residual: np.ndarray) -> tuple[float, np.ndarray]:
    """Sensor-noise estimate (rad) from the residual's second differences (robust MAD): white
    noise gives var(Δ²r) = 6σ², a model error that varies smoothly between samples adds little.
    ``residual``: (N, L, 7) with NaN outside scored samples. Returns (overall, per joint)."""
    d2 = []
    for i, s in enumerate(segset.segments):
        m = segset.mask[i]
        r = residual[i][m]
        if len(r) >= 3:
            d2.append(r[2:] - 2 * r[1:-1] + r[:-2])
    if not d2:
        return 0.0, np.zeros(7)
    d = np.concatenate(d2)
    sigma = np.median(np.abs(d - np.median(d, axis=0)), axis=0) / 0.6745 / np.sqrt(6.0)
    return float(np.sqrt(np.mean(sigma**2))), sigma


def noise_floor_of(segset, sim: np.ndarray) -> tuple[float, np.ndarray]:
    """``noise_floor`` of the residual of a simulation (N, L, 7) of ``segset`` at its data samples."""
    return noise_floor(segset, np.where(segset.mask[..., None], segset.meas - sim, np.nan))
