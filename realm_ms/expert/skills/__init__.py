"""One module per REALM skill; ``SKILLS`` maps the rubric name to its generator."""

from realm_ms.expert.skills.close_drawer import close_drawer
from realm_ms.expert.skills.open_drawer import open_drawer
from realm_ms.expert.skills.pick import pick
from realm_ms.expert.skills.push import push
from realm_ms.expert.skills.put import put
from realm_ms.expert.skills.rotate import rotate
from realm_ms.expert.skills.stack import stack

SKILLS = {
    "pick": pick,
    "put": put,
    "stack": stack,
    "rotate": rotate,
    "push": push,
    "open_drawer": open_drawer,
    "close_drawer": close_drawer,
}
