"""Gain and joint-physics presets of the DROID arm, and the gains as batched arrays."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from realm_ms.errors import InputError

FRANKA_EFFORT_LIMITS = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)


def check_lengths(owner: str, obj, lengths: dict[str, int]) -> None:
    """ValueError naming ``owner.field`` when a per-joint (or per-axis) field is not that many finite
    numbers (a list of 3 used to surface as numpy's broadcast message deep in the controller)."""
    import math

    for name, n in lengths.items():
        v = getattr(obj, name)
        if v is None:
            continue
        try:
            values = [float(x) for x in v]
        except (TypeError, ValueError):
            raise InputError(f"{owner}.{name}: expected a list of {n} numbers, got {v!r}") from None
        if len(values) != n or not all(math.isfinite(x) for x in values):
            raise InputError(f"{owner}.{name}: expected {n} finite numbers (one per {'joint' if n == 7 else 'axis'}), "
                             f"got {len(values)}: {list(v)}")


@dataclass(frozen=True)
class ImpedanceGains:
    """Polymetis hybrid joint impedance gains (joint: N.m/rad, N.m.s/rad; Cartesian: N/m, N.m/rad)."""

    kq: tuple[float, ...]
    kqd: tuple[float, ...]
    kx: tuple[float, ...]
    kxd: tuple[float, ...]

    def __post_init__(self):
        check_lengths("gains", self, {"kq": 7, "kqd": 7, "kx": 6, "kxd": 6})


GAIN_PRESETS: dict[str, ImpedanceGains] = {
    # fairo franka_hardware.yaml since 2022-08-09 (commit 2de742c): what current DROID sites run
    "polymetis": ImpedanceGains((40, 30, 50, 25, 35, 25, 10), (4, 6, 5, 5, 3, 2, 1), (750,) * 3 + (15,) * 3, (37,) * 3 + (2,) * 3),
    # REALM's aligned control (realm/config/robots/franka_robotiq.yaml): Kq4 = 35, Kx = 400
    "realm": ImpedanceGains((40, 30, 50, 35, 35, 25, 10), (4, 6, 5, 5, 3, 2, 1), (400,) * 3 + (15,) * 3, (37,) * 3 + (2,) * 3),
    # fairo 2022-02 .. 2022-08
    "polymetis_2022_02": ImpedanceGains((80, 120, 100, 100, 70, 50, 20), (10, 10, 10, 10, 5, 5, 5), (150,) * 3 + (10,) * 3, (25,) * 3 + (7,) * 3),
}


@dataclass(frozen=True)
class JointPhysics:
    """Joint physics beyond the rigid URDF: smooth Coulomb ``friction`` in N.m (applied by the
    driver as an explicit torque) and rotor ``armature`` in kg.m^2 (an articulation property).

    REALM's friction numbers were PhysX joint-friction coefficients. In SAPIEN's PhysX that
    coefficient is unitless and load-proportional; applied literally it locks the wrist (a 0.3 rad
    step leaves 0.28 rad of error on joint 5; README, "The DROID controller"). Read as N.m they match the
    Franka's measured Coulomb friction (0.1-0.7 N.m, Gaz et al. 2019), which is how we apply them.
    """

    friction: tuple[float, ...]
    armature: tuple[float, ...]
    friction_velocity: float = 0.02  # rad/s, tanh smoothing of sgn(qd)

    def __post_init__(self):
        check_lengths("joint_physics", self, {"friction": 7, "armature": 7})


JOINT_PHYSICS_PRESETS: dict[str, JointPhysics] = {
    # REALM's identified values (realm_environment_dynamic.py; later DROID.yaml), friction as N.m
    "realm": JointPhysics((0.05, 0.10, 0.05, 0.10, 0.75, 0.425, 0.20), (0.25, 0.50, 0.25, 0.50, 0.25, 0.15, 0.0)),
    # the rigid URDF alone: the sysid workbench's baseline, every effect is then explicit
    "none": JointPhysics((0.0,) * 7, (0.0,) * 7),
}


def resolve(preset_or_value, presets: dict, what: str):
    if isinstance(preset_or_value, str):
        if preset_or_value not in presets:
            raise InputError(f"unknown {what} preset {preset_or_value!r}; choose one of {sorted(presets)}")
        return presets[preset_or_value]
    return preset_or_value


@dataclass
class BatchedGains:
    """Gains as batched arrays (B, 7) / (B, 6), torch or numpy, so each env may run different gains (sysid)."""

    kq: torch.Tensor
    kqd: torch.Tensor
    kx: torch.Tensor
    kxd: torch.Tensor

    @classmethod
    def from_gains(cls, g: ImpedanceGains, num_envs: int, device, dtype=torch.float32) -> "BatchedGains":
        t = lambda v: torch.as_tensor(v, device=device, dtype=dtype).expand(num_envs, -1).clone()  # noqa: E731
        return cls(t(g.kq), t(g.kqd), t(g.kx), t(g.kxd))

    def map(self, fn) -> "BatchedGains":
        return BatchedGains(fn(self.kq), fn(self.kqd), fn(self.kx), fn(self.kxd))
