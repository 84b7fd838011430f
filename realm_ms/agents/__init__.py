"""Robots of realm-ms. Importing registers the ``panda_droid`` agent with ManiSkill."""

from realm_ms.agents.panda_droid import PandaDroid  # noqa: F401
