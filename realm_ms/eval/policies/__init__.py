"""Evaluated policies behind one interface (``base.Policy``) and one registry.

``make_policy("zero")``, ``make_policy("lerobot:PATH_OR_ID")``, ``make_policy("openpi:HOST:PORT")``:
the text before the first ``:`` names a registry entry, the rest is its argument.
"""

from __future__ import annotations

from realm_ms.eval.policies.policy import (  # noqa: F401
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
    # importing a module registers its kinds (idempotent: modules import once); lerobot is imported
    # lazily inside its factory's policy class, so this stays light
    from realm_ms.eval.policies import baselines, expert, lerobot, openpi, roboarena  # noqa: F401


def make_policy(spec: str, **options) -> Policy:
    """Build a policy from its spec string (``kind`` or ``kind:arg``); unknown kinds list the known ones."""
    _register_builtins()
    kind, _, arg = spec.partition(":")
    factory = POLICIES.get(kind)
    return factory(arg or None, **options)


def policy_names() -> list[str]:
    _register_builtins()
    return POLICIES.names()


def policy_action_space(policy: Policy, options: dict | None = None) -> dict:
    """Env keywords of the DROID action space ``policy`` acts in: its own declaration
    (``env_action_space()``, e.g. a policy server's metadata), else ``options["action_space"]``
    (``SPACE[:GRIPPER]``, ``realm eval --action-space``); ``{}`` = joint_position. A server's bad
    declaration is reported as the server's, never as a flag's."""
    from realm_ms.agents.droid_action_spaces import parse_action_space_flag
    from realm_ms.errors import UserError
    from realm_ms.eval.policies.replies import ReplyError

    try:
        if hasattr(policy, "env_action_space"):
            return policy.env_action_space()
        return parse_action_space_flag((options or {}).get("action_space"))
    except ReplyError as e:
        raise UserError(str(e)) from None
    except ValueError as e:
        raise UserError(f"--action-space: {e}") from None
