"""The shared interface of all physical effects.

An ``Effect`` is an :class:`~realm_ms.agents.actuation.ActuationStage` (so a fitted robot model plugs
into the benchmark controller unchanged) with

* declared parameters (:class:`~realm_ms.agents.effects.parameter.ParamSpec`: unit, nominal, bounds,
  off-value, lin/log scale, per joint or shared),
* batched parameter values ``theta`` of shape (B, n) -- one row per env, so one simulator batch can
  hold many candidate models (CMA-ES population, finite-difference probes); B = 1 broadcasts,
* a residual signature (``signature``: what it looks like in the position residual; ``evidence``:
  the one-sentence explanation for the diagnosis report).

Torque-path effects override the ``measure`` / ``command`` / ``gains`` / ``actuator`` /
``plant_torque`` hooks; build-time effects (armature, payload) override ``build_target`` and act
on each PhysX articulation through :class:`~realm_ms.agents.effects.build_target.BuildTarget`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import torch

from realm_ms.agents.actuation import ActuationStage
from realm_ms.agents.effects.parameter import NUM_JOINTS, Param, ParamSpec, format_value
from realm_ms.errors import InputError

if TYPE_CHECKING:
    from realm_ms.agents.effects.build_target import BuildTarget


@dataclass
class EffectConfig:
    """Non-fitted settings of an effect (model structure). Subclasses add fields."""


class Effect(ActuationStage):
    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    signature: ClassVar[str] = ""
    order: ClassVar[int] = 50  # position in the stage chain (lower first)
    build_time: ClassVar[bool] = False
    screened: ClassVar[bool] = True  # a default candidate of position-space diagnosis
    # library effects this one contains as a special case (LuGre's σ₂ q̇ is viscous damping): a model
    # holding both is degenerate, so ``auto`` fits this one in place of those
    contains: ClassVar[tuple[str, ...]] = ()
    # what the effect acts on: "arm" (an actuation stage of the arm's controller) or "gripper" (the
    # gripper controller's response, ``gripper_response.py``: the arm replay leaves it out)
    acts_on: ClassVar[str] = "arm"
    # (ms per physics step, + ms per arm it is on) the effect adds to a replay rollout on one core
    # (bench/sysid_effect_cost.py measures both): only a hint with which the evaluator spreads a
    # screening batch's effects over its workers, never part of a result
    step_cost: ClassVar[tuple[float, float]] = (1.0, 0.0)
    Config: ClassVar[type] = EffectConfig

    def __init__(self, config: EffectConfig | None = None, values: dict[str, Any] | None = None):
        self.config = config if config is not None else self.Config()
        self.specs: list[ParamSpec] = self.param_specs(self.config)
        self.params: list[Param] = [p for s in self.specs for p in s.expand(self.name)]
        self._slices: dict[str, slice] = {}
        i = 0
        for s in self.specs:
            n = NUM_JOINTS if s.per_joint else 1
            self._slices[s.name] = slice(i, i + n)
            i += n
        self.theta = torch.tensor([[p.spec.off for p in self.params]], dtype=torch.float32)
        if values:
            self.set_values(values)

    # ------------------------------------------------------------------ parameters
    @classmethod
    def param_specs(cls, config: EffectConfig) -> list[ParamSpec]:
        raise NotImplementedError

    @property
    def free_params(self) -> list[Param]:
        return [p for p in self.params if p.spec.fit_by_default and p.joint in (None, *p.spec.joints)]

    def set_values(self, values: dict[str, Any]) -> None:
        """Set scalar values by local key: ``fc`` (all joints / shared), ``fc4`` (joint 4, 1-based)
        or a list of 7 for a per-joint parameter."""
        row = self.theta[0].clone() if self.theta.shape[0] == 1 else self.theta[0].clone()
        by_key = {p.local_key: i for i, p in enumerate(self.params)}
        for k, v in values.items():
            if k in self._slices:
                sl = self._slices[k]
                row[sl] = torch.as_tensor(_per_joint(k, v, sl.stop - sl.start), dtype=torch.float32)
            elif k in by_key:
                row[by_key[k]] = float(_per_joint(k, v, 1)[0])
            else:
                raise KeyError(
                    f"effect {self.name!r} has no parameter {k!r}; it has "
                    f"{', '.join(s.name + ('1..7' if s.per_joint else '') for s in self.specs)}"
                )
        for i, p in enumerate(self.params):
            lo, hi = p.spec.lo, p.spec.hi
            # theta is float32: a value at a bound (0.005) is stored just outside it (0.0049999999)
            if not float(np.float32(lo)) <= float(row[i]) <= float(np.float32(hi)):
                raise ValueError(f"{p.key} = {float(row[i]):g} {p.unit} is outside its bounds [{lo:g}, {hi:g}]")
        self.theta = row[None]
        self._rows_cache = None

    def values(self, row: int = 0) -> dict[str, float]:
        return {p.local_key: float(self.theta[min(row, self.theta.shape[0] - 1), i]) for i, p in enumerate(self.params)}

    def set_theta(self, theta: torch.Tensor | np.ndarray) -> None:
        """Batched values (B, n) in physical units, one row per env."""
        theta = torch.as_tensor(theta, dtype=torch.float32)
        if theta.ndim != 2 or theta.shape[1] != len(self.params):
            raise ValueError(f"{self.name}: theta must be (B, {len(self.params)}), got {tuple(theta.shape)}")
        self.theta = theta
        self._rows_cache = None

    def active_rows(self, device=None) -> torch.Tensor | None:
        """Indices of the envs where this effect is not at its off-value (None = all / broadcast).
        Expensive hooks compute only there: a screening batch holds many effects, each active on a
        few rows."""
        if self.theta.shape[0] == 1:
            return None
        if getattr(self, "_rows_cache", None) is None or (device is not None and self._rows_cache[1] != device):
            act = self.on_rows()
            rows = None if bool(act.all()) else torch.nonzero(act)[:, 0]
            if rows is not None and device is not None:
                rows = rows.to(device)
            self._rows_cache = (rows, device)
        return self._rows_cache[0]

    def p(self, name: str, like: torch.Tensor | None = None, rows: torch.Tensor | None = None) -> torch.Tensor:
        """Values of one spec, (B, 7) or (B, 1), on ``like``'s device (only ``rows`` if given)."""
        if like is not None and self.theta.device != like.device:
            self.theta = self.theta.to(like.device)
        # the within-step laws read their values at every tick of every step: slice and gather once
        # per theta (the rows come from ``active_rows``, one tensor per theta)
        cache = self.__dict__.get("_p_cache")
        if cache is None or cache[0] is not self.theta or len(cache[1]) > 64:
            cache = self._p_cache = (self.theta, {})
        key = (name, id(rows))
        hit = cache[1].get(key)
        if hit is not None and hit[0] is rows:
            return hit[1]
        v = self.theta[:, self._slices[name]]
        if rows is not None:
            v = v[rows]
        cache[1][key] = (rows, v)
        return v

    def on_rows(self) -> torch.Tensor:
        """(B,) bool: the theta rows where some parameter is not at its off-value."""
        off = torch.tensor([p.spec.off for p in self.params], dtype=self.theta.dtype, device=self.theta.device)
        return (self.theta != off).any(dim=1)

    def is_off(self) -> bool:
        return not bool(self.on_rows().any())

    def config_dict(self) -> dict:
        """The config as ``make_effect`` takes it back (tuples as lists: JSON, YAML and pickles alike)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self.config).items()}

    # ------------------------------------------------------------------ build-time hook
    def build(self, articulation: Any, joint_indices: list[int]) -> None:
        """ActuationStage hook for the benchmark: apply to every PhysX articulation of a ManiSkill
        ``Articulation`` (one per sub-scene; theta row i for sub-scene i, row 0 broadcast)."""
        if not self.build_time:
            return
        from realm_ms.agents.effects.build_target import BuildTarget

        objs = getattr(articulation, "_objs", None) or [articulation]
        for i, obj in enumerate(objs):
            self.build_target(BuildTarget.of(obj, joint_indices), min(i, self.theta.shape[0] - 1))

    def build_target(self, target: "BuildTarget", row: int) -> None:
        """Apply this effect's values (theta row ``row``) to one articulation."""

    # ------------------------------------------------------------------ diagnosis
    # (the evidence sentence of each effect lives in ``sysid/signatures.SENTENCES``, by effect name)
    def describe(self, values: dict[str, float], max_items: int = 3) -> str:
        """Largest parameters (relative to their nominal size) with units, e.g. '0.31 N·m on joint 4'."""
        items = []
        for p in self.free_params:
            v = values.get(p.local_key, p.spec.off)
            # shape parameters whose off-value is their typical value (a Stribeck velocity) count
            # relative to that value, so they do not crowd out the strengths
            scale = abs(p.spec.nominal - p.spec.off) or abs(p.spec.nominal)
            rel = abs(v - p.spec.off) / max(scale, 1e-12)
            where = f" on joint {p.joint + 1}" if p.joint is not None else ""
            items.append((rel, f"{p.spec.name} ≈ {format_value(v, p.unit)}{where}"))
        items.sort(key=lambda t: -t[0])
        return ", ".join(s for _, s in items[:max_items]) or "no parameters"

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name}, B={self.theta.shape[0]})"


def _per_joint(key: str, value: Any, n: int) -> np.ndarray:
    """``value`` as ``n`` finite numbers: one number (every joint) or a list of exactly ``n``."""
    want = "a number" if n == 1 else f"one number or a list of {n} (one per joint)"
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{key}: expected {want}, got {value!r}") from None
    if arr.ndim > 1 or (arr.ndim == 1 and len(arr) != n and not (n > 1 and len(arr) == 1)):
        got = f"a list of {len(arr)}" if arr.ndim == 1 else f"an array of shape {arr.shape}"
        raise InputError(f"{key}: expected {want}, got {got}")
    if not np.isfinite(arr).all():
        raise InputError(f"{key}: expected finite numbers, got {value!r}")
    return np.array(np.broadcast_to(arr.reshape(-1), (n,)))


def config_from_dict(cls: type, data: dict[str, Any]) -> EffectConfig:
    names = {f.name for f in fields(cls)}
    unknown = set(data) - names
    if unknown:
        raise KeyError(f"unknown setting(s) {sorted(unknown)}; allowed: {sorted(names)}")
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in data.items()}
    return cls(**kw)
