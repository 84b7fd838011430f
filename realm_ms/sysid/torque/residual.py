"""The inverse-dynamics residual of torque space (``space.py`` holds its verbs).

Data: trajectories with measured joint torque ``tau`` (N·m) from any controller (``q_cmd`` not
needed). ``q̈`` and the consistently smoothed torque come from ``smoothing.smooth`` (Savitzky-Golay).
The residual ``r = tau - ID(q, q̇, q̈) - Σ terms`` (``terms.py``) is scored per joint in N·m; the
first and last window of every trajectory (where the SG fit extrapolates) are not scored.

Fitting is a bounded nonlinear least squares (``scipy.optimize.least_squares``, trust region
reflective) in the parameters' unit coordinates, from the off-values and from the typical
strengths (the better wins): no simulation, so a diagnosis fits every candidate fully.

Noise floor: the sensor noises propagated through the smoothing (``smoothing.noise_floor``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch

from realm_ms.errors import InputError
from realm_ms.sysid.timeseries import Trajectory, check_torque_rate
from realm_ms.sysid.torque.smoothing import SmoothingConfig, noise_floor, smooth
from realm_ms.sysid.torque.terms import TERMS, TRACKING_ONLY, Samples, Series

UNIT = "N·m"


@dataclass
class TorqueSet:
    """Scored samples of a list of trajectories: measured torque and the nominal residual."""

    samples: Samples
    tau: np.ndarray  # (N, 7)
    nominal: np.ndarray  # (N, 7) ID of the URDF at the smoothed state
    noise: np.ndarray  # (7,) noise-floor estimate per joint
    lengths: list[int] = field(default_factory=list)  # scored samples per trajectory (unthinned sets)
    dt: float = 0.0  # median sample interval, s

    @classmethod
    def build(cls, trajs: list[Trajectory], arm, smoothing: SmoothingConfig = SmoothingConfig(),
              max_samples: int | None = None) -> "TorqueSet":
        parts, noise_var, weights, dts, series = [], [], [], [], []
        for tr in trajs:
            if tr.tau is None:
                raise InputError(f"{tr.name}: no `tau` (measured joint torque, N·m); torque-space work needs it")
            check_torque_rate(tr)
            sm = smooth(tr.t, tr.q, tr.tau, tr.qd, smoothing)
            dt = float(np.median(np.diff(tr.t)))
            dts.append(dt)
            cut = max(1, int(round(smoothing.window_s / dt)))  # SG extrapolates near the ends
            sl = slice(cut, len(sm.tau) - cut)
            if sl.stop - sl.start < 10:
                raise InputError(f"{tr.name}: too short for torque space ({len(tr.t)} samples)")
            parts.append((sm.q[sl], sm.qd[sl], sm.qdd[sl], sm.tau[sl]))
            series.append(Series(torch.as_tensor(sm.qd, dtype=torch.float64), dt, sl))
            qt = torch.as_tensor(sm.q[sl][:: max(1, (sl.stop - sl.start) // 200)], dtype=torch.float64)
            with torch.inference_mode():
                msq = (arm.mass_matrix(qt) ** 2).mean(0).numpy()
            noise_var.append(noise_floor(sm, msq) ** 2)
            weights.append(sl.stop - sl.start)
        q, v, a, tau = (np.concatenate([p[i] for p in parts]) for i in range(4))
        lengths, idx = list(weights), None
        if max_samples and len(q) > max_samples:  # evenly thinned: the fit needs coverage, not every ms
            idx = np.linspace(0, len(q) - 1, max_samples).astype(int)
            q, v, a, tau = q[idx], v[idx], a[idx], tau[idx]
            lengths = []  # thinned: no longer contiguous time series
        t64 = lambda x: torch.as_tensor(x, dtype=torch.float64)  # noqa: E731
        s = Samples(t64(q), t64(v), t64(a), arm, series=series, index=None if idx is None else torch.as_tensor(idx))
        with torch.inference_mode():
            nominal = arm.rnea(s.q, s.qd, s.qdd).numpy()
        noise = np.sqrt(np.average(np.array(noise_var), axis=0, weights=weights))
        return cls(s, tau, nominal, noise, lengths, float(np.median(dts)))


def torque_arm():
    from realm_ms.sysid.diagnose import _arm_model

    return _arm_model().to(dtype=torch.float64)


# ---------------------------------------------------------------------------- parameters
@dataclass
class Term:
    """One effect in torque space: name, config, and its free parameters (key -> spec)."""

    name: str
    config: object
    specs: list  # [(key, ParamSpec)]
    values: dict[str, float] = field(default_factory=dict)

    @classmethod
    def make(cls, name: str, values: dict | None = None, config: dict | None = None) -> "Term":
        """``config``: the effect's settings (e.g. ``{"fit_com": True}`` for link_mass), as a dict."""
        if name in TRACKING_ONLY:
            raise InputError(f"{name} acts through the position controller (tracking): it needs `q_cmd` in the data; "
                             "in torque space use friction, viscous, armature, payload, gravity or link-mass effects")
        if name not in TERMS:
            raise InputError(f"unknown torque-space effect {name!r}; known: {', '.join(TERMS)}")
        from realm_ms.agents.effects import make_effect

        fx = make_effect(name, None, config)
        specs, config = fx.specs, fx.config
        keys = []
        for sp in specs:
            if not sp.fit_by_default:
                continue
            if sp.per_joint:
                keys += [(f"{sp.name}{j + 1}", sp) for j in sp.joints]
            else:
                keys.append((sp.name, sp))
        t = cls(name, config, keys, {k: sp.off for k, sp in keys})
        if values:
            t.values.update({k: float(v) for k, v in values.items() if k in t.values})
        return t

    def config_dict(self) -> dict:
        from dataclasses import asdict

        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self.config).items()}

    def nominal_values(self) -> dict[str, float]:
        return {k: sp.nominal for k, sp in self.specs}

    def torque(self, s: Samples) -> np.ndarray:
        with torch.inference_mode():
            return TERMS[self.name](self.values, s, self.config).numpy()


def terms_of(model, log=print) -> list[Term]:
    """The model's torque-space terms (tracking effects are skipped with a note)."""
    out = []
    for fx in model.effects if model is not None else []:
        if fx.name in TRACKING_ONLY:
            log(f"note: {fx.name} is a tracking effect (needs q_cmd); it is ignored in torque space")
            continue
        out.append(Term.make(fx.name, fx.values(), fx.config_dict()))
    return out


def _pack(terms: list[Term]):
    keys = [(t, k, sp) for t in terms for k, sp in t.specs]
    lo = np.array([sp.lo for _, _, sp in keys])
    hi = np.array([sp.hi for _, _, sp in keys])
    return keys, lo, hi


def _set(keys, x):
    for (t, k, sp), v in zip(keys, x):  # clipped: lo + u (hi - lo) at u = 0 can round just below lo
        t.values[k] = float(min(max(v, sp.lo), sp.hi))


def predict(terms: list[Term], s: Samples, n: int) -> np.ndarray:
    out = np.zeros((n, 7))
    for t in terms:
        out += t.torque(s)
    return out


def rmse(ts: TorqueSet, terms: list[Term]) -> tuple[float, np.ndarray]:
    r = ts.tau - ts.nominal - predict(terms, ts.samples, len(ts.tau))
    return float(np.sqrt(np.mean(r**2))), np.sqrt(np.mean(r**2, axis=0))


def residual_bands(ts: TorqueSet, terms: list[Term]) -> dict:
    """The residual left by ``terms`` split into frequency bands (``spectrum.py``)."""
    from realm_ms.sysid.torque.spectrum import band_rms, summary

    if not ts.lengths:
        raise ValueError("residual bands need an unthinned sample set (contiguous time series)")
    r = ts.tau - ts.nominal - predict(terms, ts.samples, len(ts.tau))
    return summary(band_rms(r, ts.lengths, ts.dt))


def fit_terms(train: TorqueSet, terms: list[Term], starts: tuple[str, ...] = ("current", "nominal")) -> float:
    """Least squares of all free parameters of ``terms`` on ``train`` (in place); train RMSE."""
    from scipy.optimize import least_squares

    keys, lo, hi = _pack(terms)
    if not keys:
        return rmse(train, terms)[0]
    span = hi - lo
    target = train.tau - train.nominal

    def resid(u):
        _set(keys, lo + u * span)
        return (target - predict(terms, train.samples, len(target))).ravel()

    best = None
    for start in starts:
        x0 = np.array([t.values[k] if start == "current" else sp.nominal for t, k, sp in keys])
        u0 = np.clip((x0 - lo) / span, 0, 1)
        sol = least_squares(resid, u0, bounds=(0, 1), method="trf", x_scale=1.0, max_nfev=60)
        if best is None or sol.cost < best.cost:
            best = sol
    _set(keys, lo + best.x * span)
    return rmse(train, terms)[0]
