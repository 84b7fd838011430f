"""Evaluated policies behind one interface (``base.Policy``) and one registry.

``make_policy("zero")``, ``make_policy("lerobot:PATH_OR_ID")``, ``make_policy("openpi:HOST:PORT")``:
the text before the first ``:`` names a registry entry, the rest is its argument.
"""

from __future__ import annotations

from realm_ms.eval.policies.base import (  # noqa: F401
    CAMERAS,
    ObsRequest,
    Policy,
    PolicyError,
    PolicyInput,
    PolicyOutput,
)
from realm_ms.registry import Registry

# name -> factory(arg: str | None, **options) -> Policy
POLICIES: Registry = Registry("policy")


def _register_builtins() -> None:
    from realm_ms.eval.policies import baselines, expert, lerobot, openpi  # noqa: F401


def make_policy(spec: str, **options) -> Policy:
    """Build a policy from its spec string (``kind`` or ``kind:arg``); unknown kinds list the known ones."""
    if not POLICIES.names():
        _register_builtins()
    kind, _, arg = spec.partition(":")
    factory = POLICIES.get(kind)
    return factory(arg or None, **options)


def policy_names() -> list[str]:
    if not POLICIES.names():
        _register_builtins()
    return POLICIES.names()
