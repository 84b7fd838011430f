"""The shared interface of all physical effects.

An ``Effect`` is an :class:`~realm_ms.agents.actuation.ActuationStage` (so a fitted robot model plugs
into the benchmark controller unchanged) with

* declared parameters (:class:`~realm_ms.sysid.parameter.ParamSpec`: unit, nominal, bounds,
  off-value, lin/log scale, per joint or shared),
* batched parameter values ``theta`` of shape (B, n) -- one row per env, so one simulator batch can
  hold many candidate models (CMA-ES population, finite-difference probes); B = 1 broadcasts,
* a residual signature (``signature``: what it looks like in the position residual; ``evidence``:
  the one-sentence explanation for the diagnosis report).

Torque-path effects override the ``measure`` / ``command`` / ``gains`` / ``actuator`` /
``plant_torque`` hooks; build-time effects (armature, payload) override ``build_target`` and act
on each PhysX articulation through :class:`BuildTarget`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np
import torch

from realm_ms.agents.actuation import ActuationStage, ControlState
from realm_ms.sysid.parameter import NUM_JOINTS, Param, ParamSpec, format_value


@dataclass
class EffectConfig:
    """Non-fitted settings of an effect (model structure). Subclasses add fields."""


class Effect(ActuationStage):
    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    signature: ClassVar[str] = ""
    order: ClassVar[int] = 50  # position in the stage chain (lower first)
    build_time: ClassVar[bool] = False
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
                arr = np.array(np.broadcast_to(np.asarray(v, dtype=float), (sl.stop - sl.start,)))
                row[sl] = torch.as_tensor(arr, dtype=torch.float32)
            elif k in by_key:
                row[by_key[k]] = float(v)
            else:
                raise KeyError(
                    f"effect {self.name!r} has no parameter {k!r}; it has "
                    f"{', '.join(s.name + ('1..7' if s.per_joint else '') for s in self.specs)}"
                )
        for i, p in enumerate(self.params):
            lo, hi = p.spec.lo, p.spec.hi
            if not lo <= float(row[i]) <= hi:
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
            off = torch.tensor([p.spec.off for p in self.params], dtype=self.theta.dtype, device=self.theta.device)
            act = (self.theta != off).any(dim=1)
            rows = None if bool(act.all()) else torch.nonzero(act)[:, 0]
            if rows is not None and device is not None:
                rows = rows.to(device)
            self._rows_cache = (rows, device)
        return self._rows_cache[0]

    def p(self, name: str, like: torch.Tensor | None = None, rows: torch.Tensor | None = None) -> torch.Tensor:
        """Values of one spec, (B, 7) or (B, 1), on ``like``'s device (only ``rows`` if given)."""
        if like is not None and self.theta.device != like.device:
            self.theta = self.theta.to(like.device)
        v = self.theta[:, self._slices[name]]
        if rows is not None:
            v = v[rows]
        return v

    def is_off(self) -> bool:
        off = torch.tensor([p.spec.off for p in self.params], dtype=torch.float32, device=self.theta.device)
        return bool(torch.all(self.theta == off))

    # ------------------------------------------------------------------ build-time hook
    def build(self, articulation: Any, joint_indices: list[int]) -> None:
        """ActuationStage hook for the benchmark: apply to every PhysX articulation of a ManiSkill
        ``Articulation`` (one per sub-scene; theta row i for sub-scene i, row 0 broadcast)."""
        if not self.build_time:
            return
        objs = getattr(articulation, "_objs", None) or [articulation]
        for i, obj in enumerate(objs):
            self.build_target(BuildTarget.of(obj, joint_indices), min(i, self.theta.shape[0] - 1))

    def build_target(self, target: "BuildTarget", row: int) -> None:
        """Apply this effect's values (theta row ``row``) to one articulation."""

    # ------------------------------------------------------------------ diagnosis
    def evidence(self, values: dict[str, float], features: "Any") -> str:
        """One sentence: what in the residual points at this effect, and how big it is."""
        return f"{self.summary}: {self.describe(values)}"

    def describe(self, values: dict[str, float], max_items: int = 3) -> str:
        """Largest parameters (relative to their nominal size) with units, e.g. '0.31 N·m on joint 4'."""
        items = []
        for p in self.free_params:
            v = values.get(p.local_key, p.spec.off)
            rel = abs(v - p.spec.off) / max(abs(p.spec.nominal - p.spec.off), 1e-12)
            where = f" on joint {p.joint + 1}" if p.joint is not None else ""
            items.append((rel, f"{p.spec.name} ≈ {format_value(v, p.unit)}{where}"))
        items.sort(key=lambda t: -t[0])
        return ", ".join(s for _, s in items[:max_items]) or "no parameters"

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name}, B={self.theta.shape[0]})"


def config_from_dict(cls: type, data: dict[str, Any]) -> EffectConfig:
    names = {f.name for f in fields(cls)}
    unknown = set(data) - names
    if unknown:
        raise KeyError(f"unknown setting(s) {sorted(unknown)}; allowed: {sorted(names)}")
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in data.items()}
    return cls(**kw)


# ---------------------------------------------------------------------------- build targets
class BuildTarget:
    """One PhysX articulation whose nominal joint/link properties are remembered on first use, so
    build-time effects set *absolute* values (nominal + effect) and can be re-applied per rollout."""

    _cache: dict[int, "BuildTarget"] = {}

    def __init__(self, articulation: Any, joint_indices: list[int] | None = None):
        from realm_ms.sysid.urdf import flange_offset_in_link7

        self.art = articulation
        joints = articulation.get_active_joints()
        idx = list(range(NUM_JOINTS)) if joint_indices is None else [int(i) for i in joint_indices]
        self.joints = [joints[i] for i in idx]
        self.nominal_armature = [float(np.asarray(j.get_armature()).reshape(-1)[0]) for j in self.joints]
        # ManiSkill prefixes link names per sub-scene ("scene-0-panda_droid_panda_link8"): key by suffix
        links = {}
        for l in articulation.get_links():
            name = l.get_name()
            for base in ("panda_link8", "panda_link7"):
                if name == base or name.endswith("_" + base):
                    links[base] = l
        if "panda_link8" in links:
            self.flange, self.flange_offset = links["panda_link8"], np.zeros(3)
        else:  # locked replay URDF: the flange is lumped into link 7
            self.flange, self.flange_offset = links["panda_link7"], flange_offset_in_link7()
        self.nominal_mass = float(self.flange.get_mass())
        self.nominal_cmass = self.flange.get_cmass_local_pose()
        self.nominal_inertia = np.asarray(self.flange.get_inertia(), dtype=float)

    @classmethod
    def of(cls, articulation: Any, joint_indices: list[int] | None = None) -> "BuildTarget":
        key = id(articulation)
        t = cls._cache.get(key)
        if t is None or t.art is not articulation:
            t = cls._cache[key] = cls(articulation, joint_indices)
        return t

    def reset(self) -> None:
        for j, a in zip(self.joints, self.nominal_armature):
            j.set_armature([a])
        self.flange.set_mass(self.nominal_mass)
        self.flange.set_cmass_local_pose(self.nominal_cmass)
        self.flange.set_inertia(self.nominal_inertia)

    def add_armature(self, values: np.ndarray) -> None:
        for j, a, v in zip(self.joints, self.nominal_armature, values):
            j.set_armature([a + float(v)])

    def add_point_mass(self, mass: float, offset_in_flange: np.ndarray) -> None:
        """Rigidly attach a point mass at ``offset_in_flange`` (m, flange frame) to the flange link."""
        if mass <= 0:
            return
        import sapien
        from realm_ms.agents.arm_model import _Inertial

        pose = self.nominal_cmass
        rot = _quat_to_matrix(pose.q)
        body = _Inertial(self.nominal_mass, np.asarray(pose.p, dtype=float), rot @ np.diag(self.nominal_inertia) @ rot.T)
        point = _Inertial(float(mass), self.flange_offset + np.asarray(offset_in_flange, dtype=float), np.zeros((3, 3)))
        merged = _Inertial.merge([body, point])
        w, v = np.linalg.eigh(merged.inertia)
        if np.linalg.det(v) < 0:
            v[:, 0] = -v[:, 0]
        self.flange.set_mass(merged.mass)
        self.flange.set_cmass_local_pose(sapien.Pose(merged.com.astype(np.float32), _matrix_to_quat(v)))
        self.flange.set_inertia(np.maximum(w, 1e-8).astype(np.float32))


def _quat_to_matrix(q) -> np.ndarray:
    w, x, y, z = (float(v) for v in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _matrix_to_quat(m: np.ndarray) -> np.ndarray:
    t = np.trace(m)
    if t > 0:
        s = 0.5 / np.sqrt(t + 1.0)
        q = [0.25 / s, (m[2, 1] - m[1, 2]) * s, (m[0, 2] - m[2, 0]) * s, (m[1, 0] - m[0, 1]) * s]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(max(1.0 + m[i, i] - m[j, j] - m[k, k], 1e-12))
        q = [0.0] * 4
        q[0] = (m[k, j] - m[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j, i] + m[i, j]) / s
        q[1 + k] = (m[k, i] + m[i, k]) / s
    q = np.asarray(q, dtype=np.float32)
    return q / np.linalg.norm(q)


# ---------------------------------------------------------------------------- shared numerics
def _model_terms(state: ControlState) -> tuple[torch.Tensor, torch.Tensor]:
    """(C(q, qd) qd + g(q), g(q)) of the controller's model at the true state for the whole batch,
    in one batched RNEA call, cached for this physics step. Computing all rows once is cheaper than
    per-effect subsets: at these batch sizes the call overhead dominates."""
    terms = state.extra.get("_sysid_terms")
    if terms is None:
        b = state.q.shape[0]
        out = state.model.rnea(torch.cat([state.q, state.q]), torch.cat([state.qd, torch.zeros_like(state.qd)]))
        terms = state.extra["_sysid_terms"] = (out[:b], out[b:])
    return terms


def model_gravity(state: ControlState, rows: torch.Tensor | None = None) -> torch.Tensor:
    """g_model(q) of the controller's own model at the true state (``rows`` only), cached per step."""
    g = _model_terms(state)[1]
    return g if rows is None else g[rows]


def model_bias(state: ControlState, rows: torch.Tensor | None = None) -> torch.Tensor:
    """C(q, qd) qd + g(q) of the controller's model; the driver's own value when it shares it
    (``state.extra["bias"]``, at the measured state), else computed here."""
    b = state.extra.get("bias")
    if b is None:
        b = _model_terms(state)[0]
    return b if rows is None else b[rows]


def scatter_rows(full_like: torch.Tensor, rows: torch.Tensor | None, part: torch.Tensor) -> torch.Tensor:
    if rows is None:
        return part
    out = torch.zeros_like(full_like)
    out[rows] = part
    return out


class ImplicitJointTorque(Effect):
    """Base of friction-like effects that must stay stable at 120 Hz on light wrist joints.

    An explicit friction torque -F tanh(qd/eps) with eps small is a stiff damper (h F / (eps I) >> 2
    on joint 7, I ~ 5e-3 kg.m^2) and explodes. These effects are integrated *semi-implicitly* per
    joint with the joint's apparent inertia I_j = 1/(M^-1)_jj: the velocity the joint would reach
    this step without the effect is v_free = qd + h (tau_motor - b_model(q, qd)) / I_j, and the
    effect's torque is computed from v_free (Karnopp stick-slip for dry friction, backward Euler
    for viscous damping). I_j is evaluated at the configuration of each reset (a few percent error
    along a segment only softens the stick phase, it never destabilises it: a 0.8 safety factor
    keeps the deadbeat stop from overshooting).
    """

    order = 90
    SAFETY = 0.8

    def reset(self, num_envs, device, env_idx, q):
        self._num_envs = num_envs
        if env_idx is None or getattr(self, "_inertia", None) is None or self._inertia.shape[0] != num_envs:
            self._inertia = None
        else:
            self._stale[env_idx] = True

    def _joint_inertia(self, state: ControlState) -> torch.Tensor:
        """SAFETY / (M^-1)_jj for every env (rows where the effect is off keep a placeholder 1)."""
        rows = self.active_rows(state.q.device)
        if getattr(self, "_inertia", None) is None or self._inertia.shape[0] != state.q.shape[0]:
            self._inertia = torch.ones_like(state.q)
            self._stale = torch.ones(state.q.shape[0], dtype=torch.bool, device=state.q.device)
        need = self._stale.clone()
        if rows is not None:
            mask = torch.zeros_like(need)
            mask[rows] = True
            need &= mask
        if bool(need.any()):
            idx = torch.nonzero(need)[:, 0]
            minv = torch.linalg.inv(state.model.mass_matrix(state.q[idx]))
            self._inertia[idx] = self.SAFETY / torch.diagonal(minv, dim1=1, dim2=2)
            self._stale[idx] = False
        return self._inertia

    def actuator(self, tau, state):
        state.extra["tau_motor"] = tau
        return tau

    def free_velocity(self, state: ControlState, rows: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """(v_free, I_j) on ``rows``: the velocity this step would end with without this effect."""
        inertia = self._joint_inertia(state)
        qd = state.qd
        if rows is not None:
            inertia, qd = inertia[rows], qd[rows]
        tau = state.extra.get("tau_motor")
        if tau is None:
            return qd, inertia
        if rows is not None:
            tau = tau[rows]
        net = tau - model_bias(state, rows)
        return qd + state.dt * net / inertia, inertia

    def plant_torque(self, state):
        rows = self.active_rows(state.q.device)
        if rows is not None and rows.numel() == 0:
            return None
        v_free, inertia = self.free_velocity(state, rows)
        return scatter_rows(state.q, rows, self.friction_torque(v_free, inertia, state, rows))

    def friction_torque(self, v_free, inertia, state, rows) -> torch.Tensor:
        raise NotImplementedError
