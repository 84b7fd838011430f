"""realm-ms: the REALM generalization benchmark as a ManiSkill3 task pack, plus a sysid workbench.

``import realm_ms`` registers every ``REALM-*`` id with gymnasium, in every process however it was
started (the ``realm`` command, its workers, Ray tasks, ``lerobot-eval``, a notebook). It costs a
gymnasium import: ManiSkill, torch and the tasks load with the first env made
(:mod:`realm_ms.registration`). :func:`register_envs` loads them now, which also registers the
``panda_droid`` agent for ManiSkill's own envs.
"""

from realm_ms.registration import load_task_pack as register_envs
from realm_ms.registration import register_ids as _register_ids

__version__ = "0.1.0"

_register_ids()

__all__ = ["__version__", "register_envs"]
