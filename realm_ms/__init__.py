"""realm-ms: the REALM generalization benchmark as a ManiSkill3 task pack, plus a sysid workbench.

``import realm_ms`` registers the ``panda_droid`` agent and every ``REALM-*`` env with gymnasium.
"""

__version__ = "0.1.0"

from realm_ms import agents as _agents  # noqa: F401  (registers panda_droid)
from realm_ms import tasks as _tasks  # noqa: F401  (registers REALM-* envs)
