"""Effect specifications on the command line: ``EFFECT[:key=value,...][,EFFECT...]``.

Keys are parameter names (``fc=0.3`` sets all joints, ``fc4=0.5`` joint 4 only, 1-based) or
config fields (``asymmetric=true``). Commas separate both items and effects: a token without ``=``
starts a new effect. ``none`` (alone) means no effect.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Literal

from realm_ms.agents.effects import EFFECTS, Effect, effect_class, make_effect
from realm_ms.agents.robot_model import check_effects
from realm_ms.errors import InputError


def _value(text: str, key: str = "value"):
    low = text.strip().lower()
    if low in ("true", "yes", "on"):
        return True
    if low in ("false", "no", "off"):
        return False
    try:
        x = float(text)
    except ValueError:
        raise InputError(f"{key}={text!r}: expected a number (or true/false)") from None
    if x != x or x in (float("inf"), float("-inf")):
        raise InputError(f"{key}={text!r}: expected a finite number")
    return x


def split_specs(text: str) -> list[tuple[str, dict[str, str]]]:
    items: list[tuple[str, dict[str, str]]] = []
    for raw in [t.strip() for t in text.split(",") if t.strip()]:
        if "=" in raw and ":" not in raw:
            if not items:
                raise InputError(f"{raw!r}: a parameter needs an effect before it (EFFECT:param=value)")
            k, v = raw.split("=", 1)
            items[-1][1][k.strip()] = v.strip()
            continue
        name, _, rest = raw.partition(":")
        kv: dict[str, str] = {}
        if rest:
            if "=" not in rest:
                raise InputError(f"{raw!r}: expected EFFECT:param=value")
            k, v = rest.split("=", 1)
            kv[k.strip()] = v.strip()
        items.append((name.strip(), kv))
    return items


def parse_effects(text: str, default_values: Literal["off", "nominal"] = "off") -> list[Effect]:
    """Effects from a spec string. ``default_values='nominal'`` (synth) starts unspecified
    parameters at their typical strength instead of off."""
    if text.strip().lower() in ("", "none"):
        return []
    out = []
    for name, kv in split_specs(text):
        if name.lower() == "none":
            continue
        if name not in EFFECTS:
            raise InputError(f"unknown effect {name!r}; known: {', '.join(EFFECTS)}")
        cls = effect_class(name)
        cfg_names = {f.name for f in fields(cls.Config)}
        config = {k: _value(v, k) for k, v in kv.items() if k in cfg_names}
        values = {k: _value(v, k) for k, v in kv.items() if k not in cfg_names}
        fx = make_effect(name, None, config)
        if default_values == "nominal":
            # unspecified parameters at their typical strength -- except the other joints of a
            # per-joint parameter given joint by joint (``half_gap2=...``): those stay off
            by_joint = {p.spec.name for p in fx.params if p.joint is not None and p.local_key in values}
            fx.set_values({p.local_key: p.spec.nominal for p in fx.free_params if p.spec.name not in by_joint})
        try:
            fx.set_values(values)
        except (KeyError, ValueError) as e:
            raise InputError(e.args[0] if e.args else str(e)) from None
        out.append(fx)
    check_effects(out, "")  # what a MODEL.yaml's loader checks: fit never writes a file it refuses
    return out
