"""Physical effects between the joint command and the joint torque: one file per effect, one
interface (:class:`~realm_ms.agents.effects.effect.Effect`, an actuation stage), one registry.

``EFFECTS`` (a :class:`~realm_ms.registry.Registry`) maps the names used on the command line and
in ``MODEL.yaml`` to the effect classes; ``make_effect("coulomb_friction", {"fc4": 0.3})`` builds
one. The sysid workbench identifies them; the benchmark controller runs them through a robot model
(:mod:`realm_ms.agents.robot_model`). Imports are light (torch only).

Module map: ``effect.py`` (interface, config), ``parameter.py`` (units, bounds, unit cube),
``build_target.py`` (articulation edits of build-time effects), ``model_terms.py`` and
``implicit_torque.py`` (numerics shared by torque effects), ``inertial.py`` (physically consistent
inertial parameters and their regressor: payload, link_mass), then one file per effect.
"""

from __future__ import annotations

from typing import Any

from realm_ms.agents.effects.armature import Armature
from realm_ms.agents.effects.backlash import Backlash
from realm_ms.agents.effects.coulomb_friction import CoulombFriction
from realm_ms.agents.effects.effect import Effect, EffectConfig, config_from_dict
from realm_ms.agents.effects.encoder_bias import EncoderBias
from realm_ms.agents.effects.gain_mismatch import GainMismatch
from realm_ms.agents.effects.gravity_comp_error import GravityCompError
from realm_ms.agents.effects.gripper_response import GripperResponse
from realm_ms.agents.effects.latency import Latency
from realm_ms.agents.effects.link_mass import LinkMass
from realm_ms.agents.effects.lugre_friction import LuGreFriction
from realm_ms.agents.effects.payload import Payload
from realm_ms.agents.effects.smooth_friction import SmoothFriction
from realm_ms.agents.effects.stribeck_friction import StribeckFriction
from realm_ms.agents.effects.target_filter import TargetFilter
from realm_ms.agents.effects.target_interpolation import TargetInterpolation
from realm_ms.agents.effects.torque_limit import TorqueLimit
from realm_ms.agents.effects.viscous_damping import ViscousDamping
from realm_ms.errors import InputError
from realm_ms.registry import Registry

EFFECTS: Registry[type[Effect]] = Registry("effect")

for _cls in (CoulombFriction, ViscousDamping, StribeckFriction, SmoothFriction, LuGreFriction, Armature, Payload,
             GravityCompError, Latency, TargetFilter, TargetInterpolation, GainMismatch, TorqueLimit, Backlash, EncoderBias, LinkMass,
             GripperResponse):
    EFFECTS.register(_cls.name, _cls)

#: pairs the position data of one gain setting cannot always separate; diagnosis reports both
CONFOUNDS: list[tuple[str, str]] = [
    ("latency", "viscous_damping"),
    ("latency", "target_filter"),
    ("latency", "target_interpolation"),
    ("target_filter", "target_interpolation"),
    ("payload", "gravity_comp_error"),
    ("coulomb_friction", "stribeck_friction"),
    ("coulomb_friction", "smooth_friction"),
    ("coulomb_friction", "lugre_friction"),
    ("smooth_friction", "lugre_friction"),
    ("stribeck_friction", "lugre_friction"),
    ("backlash", "encoder_bias"),
    ("latency", "torque_limit"),
    ("armature", "gain_mismatch"),
    ("payload", "link_mass"),
]


def arm_effects() -> list[str]:
    """Names of the registered effects that act on the arm (what the arm replay simulates and
    screens); the others act on the gripper (its own channel, ``sysid/gripper.py``)."""
    return [n for n, c in EFFECTS.items() if c.acts_on == "arm"]


def confounded_with(name: str) -> list[str]:
    return [b if a == name else a for a, b in CONFOUNDS if name in (a, b)]


def effect_class(name: str) -> type[Effect]:
    """The effect class registered as ``name``; an unknown name raises ``UnknownNameError`` (a
    ``ValueError``) listing the known ones."""
    if not isinstance(name, str):
        raise InputError(f"an effect name must be a string, got {type(name).__name__} {name!r}")
    return EFFECTS.get(name)


def make_effect(name: str, values: dict[str, Any] | None = None, config: dict[str, Any] | None = None) -> Effect:
    cls = effect_class(name)
    cfg = config_from_dict(cls.Config, config or {})
    return cls(cfg, values)


__all__ = ["EFFECTS", "CONFOUNDS", "Effect", "EffectConfig", "make_effect", "effect_class", "confounded_with"]
