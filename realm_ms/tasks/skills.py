"""REALM's seven skills: the key shared by a task's rubric (``progression.RUBRICS``) and the
scripted expert's skill program (``realm_ms.expert.skills.SKILLS``).

``Skill`` is a ``str`` enum, so ``Skill.PICK == "pick"`` and task declarations may use either.
"""

from __future__ import annotations

import enum


class Skill(str, enum.Enum):
    PICK = "pick"
    PUT = "put"
    STACK = "stack"
    ROTATE = "rotate"
    PUSH = "push"
    OPEN_DRAWER = "open_drawer"
    CLOSE_DRAWER = "close_drawer"

    def __str__(self) -> str:
        return self.value


def as_skill(name: str | Skill) -> Skill:
    """The ``Skill`` for a name, with an error that lists the known skills."""
    try:
        return Skill(name)
    except ValueError:
        raise ValueError(f"unknown skill {name!r}; known: {', '.join(s.value for s in Skill)}") from None
