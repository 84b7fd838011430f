"""Articulated task objects built in code (no asset files): a drawer cabinet and a light switch.

Both implement :class:`realm_ms.tasks.objects.TaskObject` and register the asset prefix
``articulated``: ``SceneObject("cabinet", "articulated/drawer_cabinet?open=1", role="main", ...)``.
Asset names: ``articulated/drawer_cabinet[?open=<fraction of the top drawer at reset>]`` and
``articulated/light_switch[?on=<0|1>]``.
"""

from __future__ import annotations

from urllib.parse import parse_qsl

from realm_ms.tasks.articulated.drawer_cabinet import DrawerCabinet, CabinetGeometry  # noqa: F401
from realm_ms.tasks.articulated.light_switch import LightSwitch, SwitchGeometry  # noqa: F401
from realm_ms.tasks.objects import register_object_builder

KINDS = {"drawer_cabinet": DrawerCabinet, "light_switch": LightSwitch}


def parse_asset(asset: str) -> tuple[str, dict]:
    """``"articulated/drawer_cabinet?open=1"`` -> ``("drawer_cabinet", {"open": "1"})``."""
    path, _, query = asset.partition("?")
    parts = path.split("/")
    if len(parts) != 2 or parts[0] != "articulated" or parts[1] not in KINDS:
        raise ValueError(f"unknown articulated asset {asset!r}; known: {['articulated/' + k for k in KINDS]}")
    return parts[1], dict(parse_qsl(query))


@register_object_builder("articulated")
def build_articulated(env, spec):
    kind, params = parse_asset(spec.asset)
    return KINDS[kind](env, spec, **params)
