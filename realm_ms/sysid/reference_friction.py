"""Friction laws of the MuJoCo-native reference plant, written independently of realm-ms's effects.

Both return the friction torque on each joint (same sign as q̇: the plant applies ``u - f``) and
are stepped once per plant substep from the substep's joint velocity.

* **Gaz et al. 2019** (RA-L 4(4), identified on a real Panda from joint torques):
  f(q̇) = φ₁ / (1 + exp(−φ₂ (q̇ + φ₃))) − φ₁ / (1 + exp(−φ₂ φ₃)), per joint (``GAZ_PHI``):
  a smooth, asymmetric, saturating curve (0.1–0.7 N·m by ~0.3–0.5 rad/s), zero at rest.
* **LuGre** (Canudas de Wit et al. 1995): a bristle deflection z per joint,
  ż = q̇ − σ₀ |q̇| z / g(q̇), g(q̇) = Fc + (Fs − Fc) exp(−(q̇/vs)²),
  f = σ₀ z + σ₁ ż + σ₂ q̇. Steady sliding gives g(q̇) sign(q̇) + σ₂ q̇ (Stribeck + viscous);
  reversals go through pre-sliding (a spring of stiffness σ₀, damped by σ₁). z is advanced exactly
  for a velocity held over the substep (an exponential approach to its steady state g sign(q̇)/σ₀),
  so the stiff bristle stays stable at any σ₀.
"""

from __future__ import annotations

import numpy as np

#: Gaz et al. 2019, Table: (φ₁ [N·m], φ₂ [s/rad], φ₃ [rad/s]) for joints 1..7
GAZ_PHI = np.array([
    [0.54615, 5.1181, 0.039533],
    [0.87224, 9.0657, 0.025882],
    [0.64068, 10.136, -0.04607],
    [1.2794, 5.5903, 0.036194],
    [0.83904, 8.3469, 0.026226],
    [0.30301, 17.133, -0.021047],
    [0.56489, 10.336, 0.0035526],
])


def gaz_friction(qd: np.ndarray, scale: float = 1.0, phi: np.ndarray = GAZ_PHI) -> np.ndarray:
    p1, p2, p3 = phi[:, 0] * scale, phi[:, 1], phi[:, 2]
    sig = lambda x: 0.5 * (1 + np.tanh(0.5 * x))  # noqa: E731 - 1 / (1 + exp(-x)) without overflow
    return p1 * sig(p2 * (qd + p3)) - p1 * sig(p2 * p3)


class LuGre:
    def __init__(self, fc, fs_ratio: float, vs: float, sigma0: float, sigma1: float, sigma2, dt: float):
        self.fc = np.asarray(fc, dtype=float)
        self.fs = self.fc * fs_ratio
        self.vs, self.s0, self.s1 = vs, sigma0, sigma1
        self.s2 = np.asarray(sigma2, dtype=float)
        self.dt = dt
        self.z = np.zeros(len(self.fc))
        self.on = self.fc > 0

    def step(self, v: np.ndarray) -> np.ndarray:
        g = self.fc + (self.fs - self.fc) * np.exp(-((v / self.vs) ** 2))
        g = np.where(self.on, np.maximum(g, 1e-12), 1.0)
        z_ss = g * np.sign(v) / self.s0
        z_new = z_ss + (self.z - z_ss) * np.exp(-self.s0 * np.abs(v) * self.dt / g)
        zd = (z_new - self.z) / self.dt
        self.z = np.where(self.on, z_new, 0.0)
        return np.where(self.on, self.s0 * self.z + self.s1 * zd, 0.0) + self.s2 * v


class PlantFriction:
    """The Gaz and LuGre terms of a ``NativeEffects`` for one rollout (LuGre keeps state)."""

    def __init__(self, gaz: float, lugre: LuGre | None):
        self.gaz, self.lugre = gaz, lugre

    @classmethod
    def of(cls, fx, dt: float) -> "PlantFriction | None":
        lugre = None
        if any(f > 0 for f in fx.lugre_fc) or any(s > 0 for s in fx.lugre_sigma2):
            lugre = LuGre(fx.lugre_fc, fx.lugre_fs_ratio, fx.lugre_vs, fx.lugre_sigma0, fx.lugre_sigma1,
                          fx.lugre_sigma2, dt)
        if fx.gaz == 0 and lugre is None:
            return None
        return cls(fx.gaz, lugre)

    def step(self, qd: np.ndarray) -> np.ndarray:
        f = gaz_friction(qd, self.gaz) if self.gaz else np.zeros(len(qd))
        return f + self.lugre.step(qd) if self.lugre is not None else f
