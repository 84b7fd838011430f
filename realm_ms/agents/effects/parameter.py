"""Identifiable parameters: physical units, bounds, off-values and the normalised coordinates
the optimisers work in.

Every effect declares ``ParamSpec``s (one per physical quantity, per joint or shared);
``ParamSpec.expand`` turns a per-joint spec into 7 scalar ``Param``s. A ``ParamSet`` is the ordered
list of scalar parameters of a robot model being fitted: it maps physical vectors to the unit cube
(linear or log per parameter) and back, and groups the values per effect as the effects expect.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterable, Literal

import numpy as np

NUM_JOINTS = 7


@dataclass(frozen=True)
class ParamSpec:
    """One physical quantity of an effect.

    ``per_joint``: 7 values (``name1`` .. ``name7`` in files) or one shared value. ``nominal`` is the
    typical value used to start searches and as the finite-difference probe size; ``off`` is the
    value that switches the effect off (the default robot); ``lo``/``hi`` are hard bounds.
    ``fit_by_default=False`` keeps a parameter at its current value unless asked for (e.g. the
    asymmetric part of Coulomb friction).
    """

    name: str
    unit: str
    nominal: float
    lo: float
    hi: float
    off: float = 0.0
    per_joint: bool = True
    scale: Literal["lin", "log"] = "lin"
    doc: str = ""
    fit_by_default: bool = True
    joints: tuple[int, ...] = tuple(range(NUM_JOINTS))  # joints where the parameter is meaningful

    def __post_init__(self):
        if not (self.lo <= self.off <= self.hi or math.isinf(self.off)) and self.off != 0:
            raise ValueError(f"off-value of {self.name} outside its bounds")
        if not self.lo < self.hi:
            raise ValueError(f"bounds of {self.name}: lo must be < hi")
        if self.scale == "log" and self.lo <= 0:
            raise ValueError(f"log-scaled {self.name} needs lo > 0")

    def at_bound(self, value: float, rel_tol: float = 1e-3) -> str | None:
        """"lower"/"upper" when ``value`` sits on a bound that is not its off-value (a fit pressed
        against a bound: the effect is asked to explain something it cannot), else None."""
        tol = rel_tol * (self.hi - self.lo)
        if abs(value - self.off) <= tol:
            return None
        if value <= self.lo + tol:
            return "lower"
        if value >= self.hi - tol:
            return "upper"
        return None

    def expand(self, effect: str) -> list["Param"]:
        if not self.per_joint:
            return [Param(effect, self, None)]
        return [Param(effect, self, j) for j in range(NUM_JOINTS)]


@dataclass(frozen=True)
class Param:
    """A scalar parameter: ``effect.name`` or ``effect.name<j>`` (joint j is 1-based in keys)."""

    effect: str
    spec: ParamSpec
    joint: int | None  # 0-based, None = shared

    @property
    def key(self) -> str:
        return f"{self.effect}.{self.local_key}"

    @property
    def local_key(self) -> str:
        return self.spec.name if self.joint is None else f"{self.spec.name}{self.joint + 1}"

    @property
    def unit(self) -> str:
        return self.spec.unit

    def to_unit(self, x: np.ndarray | float) -> np.ndarray:
        s = self.spec
        x = np.clip(np.asarray(x, dtype=float), s.lo, s.hi)
        if s.scale == "log":
            return np.log(x / s.lo) / math.log(s.hi / s.lo)
        return (x - s.lo) / (s.hi - s.lo)

    def from_unit(self, u: np.ndarray | float) -> np.ndarray:
        s = self.spec
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        if s.scale == "log":
            return s.lo * (s.hi / s.lo) ** u
        return s.lo + u * (s.hi - s.lo)


@dataclass
class ParamSet:
    """Ordered scalar parameters (the free ones of the effects being fitted)."""

    params: list[Param] = field(default_factory=list)

    @classmethod
    def of(cls, params: Iterable[Param]) -> "ParamSet":
        return cls(list(params))

    def __len__(self) -> int:
        return len(self.params)

    def __iter__(self):
        return iter(self.params)

    @property
    def keys(self) -> list[str]:
        return [p.key for p in self.params]

    def to_unit(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if not self.params:
            return np.zeros(x.shape[:-1] + (0,)) if x.ndim else np.zeros(0)
        return np.stack([p.to_unit(x[..., i]) for i, p in enumerate(self.params)], axis=-1)

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=float)
        if not self.params:
            return np.zeros(u.shape[:-1] + (0,)) if u.ndim else np.zeros(0)
        return np.stack([p.from_unit(u[..., i]) for i, p in enumerate(self.params)], axis=-1)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([p.spec.lo for p in self.params]), np.array([p.spec.hi for p in self.params])

    def off(self) -> np.ndarray:
        return np.array([p.spec.off for p in self.params], dtype=float)

    def nominal(self) -> np.ndarray:
        return np.array([p.spec.nominal for p in self.params], dtype=float)

    def as_dict(self, x: np.ndarray) -> dict[str, float]:
        return {p.key: float(v) for p, v in zip(self.params, np.asarray(x, dtype=float))}


def format_value(value: float, unit: str) -> str:
    """Human formatting with units: 0.0123 s -> '12.3 ms', 0.0021 rad -> '2.1 mrad'."""
    if unit in ("s", "rad") and abs(value) < 0.1:
        return f"{value * 1e3:.3g} m{unit}"
    return f"{value:.3g} {unit}".strip()
