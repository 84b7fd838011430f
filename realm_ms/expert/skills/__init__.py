"""One module per REALM skill; ``SKILLS`` maps each ``Skill`` to its scripted program (a generator)."""

from realm_ms.expert.skills.close_drawer import close_drawer
from realm_ms.expert.skills.open_drawer import open_drawer
from realm_ms.expert.skills.pick import pick
from realm_ms.expert.skills.push import push
from realm_ms.expert.skills.put import put
from realm_ms.expert.skills.rotate import rotate
from realm_ms.expert.skills.stack import stack
from realm_ms.registry import Registry
from realm_ms.tasks.skills import Skill

SKILLS = Registry("expert skill")
for _skill, _program in {
    Skill.PICK: pick,
    Skill.PUT: put,
    Skill.STACK: stack,
    Skill.ROTATE: rotate,
    Skill.PUSH: push,
    Skill.OPEN_DRAWER: open_drawer,
    Skill.CLOSE_DRAWER: close_drawer,
}.items():
    SKILLS.register(_skill, _program)
