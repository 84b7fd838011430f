"""Effect library: one file per physical effect, one interface (``base.Effect``), one registry.

``EFFECTS`` maps the names used on the command line and in ``MODEL.yaml`` to the effect classes;
``make_effect("coulomb_friction", {"fc4": 0.3})`` builds one. Imports are light (torch only).
"""

from __future__ import annotations

from typing import Any

from realm_ms.sysid.effects.armature import Armature
from realm_ms.sysid.effects.backlash import Backlash
from realm_ms.sysid.effects.base import BuildTarget, Effect, EffectConfig, config_from_dict
from realm_ms.sysid.effects.coulomb_friction import CoulombFriction
from realm_ms.sysid.effects.encoder_bias import EncoderBias
from realm_ms.sysid.effects.gain_mismatch import GainMismatch
from realm_ms.sysid.effects.gravity_comp_error import GravityCompError
from realm_ms.sysid.effects.latency import Latency
from realm_ms.sysid.effects.payload import Payload
from realm_ms.sysid.effects.stribeck_friction import StribeckFriction
from realm_ms.sysid.effects.torque_limit import TorqueLimit
from realm_ms.sysid.effects.viscous_damping import ViscousDamping

EFFECTS: dict[str, type[Effect]] = {}


def register(cls: type[Effect]) -> type[Effect]:
    if not cls.name or cls.name in EFFECTS:
        raise ValueError(f"effect name {cls.name!r} missing or already registered")
    EFFECTS[cls.name] = cls
    return cls


for _cls in (CoulombFriction, ViscousDamping, StribeckFriction, Armature, Payload, GravityCompError,
             Latency, GainMismatch, TorqueLimit, Backlash, EncoderBias):
    register(_cls)

#: pairs the position data of one gain setting cannot always separate; diagnosis reports both
CONFOUNDS: list[tuple[str, str]] = [
    ("latency", "viscous_damping"),
    ("payload", "gravity_comp_error"),
    ("coulomb_friction", "stribeck_friction"),
    ("backlash", "encoder_bias"),
    ("latency", "torque_limit"),
    ("armature", "gain_mismatch"),
]


def confounded_with(name: str) -> list[str]:
    return [b if a == name else a for a, b in CONFOUNDS if name in (a, b)]


def effect_class(name: str) -> type[Effect]:
    try:
        return EFFECTS[name]
    except KeyError:
        raise KeyError(f"unknown effect {name!r}; known effects: {', '.join(EFFECTS)}") from None


def make_effect(name: str, values: dict[str, Any] | None = None, config: dict[str, Any] | None = None) -> Effect:
    cls = effect_class(name)
    cfg = config_from_dict(cls.Config, config or {})
    return cls(cfg, values)


__all__ = ["EFFECTS", "CONFOUNDS", "Effect", "EffectConfig", "BuildTarget", "register", "make_effect",
           "effect_class", "confounded_with"]
