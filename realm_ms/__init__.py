"""realm-ms: the REALM generalization benchmark as a ManiSkill3 task pack, plus a sysid workbench.

``import realm_ms`` registers the ``panda_droid`` agent and every ``REALM-*`` env with gymnasium
(:func:`register_envs`). The ``realm`` command line is the one exception: it defers that (ManiSkill
and torch take seconds to import) to the verbs that need envs, so ``realm --help`` is instant.
"""

import os as _os
import sys as _sys

__version__ = "0.1.0"


def register_envs() -> None:
    """Register the ``panda_droid`` agent and the ``REALM-*`` envs (idempotent: imports do it once)."""
    from realm_ms import agents as _agents  # noqa: F401  (registers panda_droid)
    from realm_ms import tasks as _tasks  # noqa: F401  (registers REALM-* envs)
    from realm_ms import perturbations as _perturbations  # noqa: F401  (gym.make(..., perturbation=...))


def _launched_by_realm_cli() -> bool:
    # the `realm` console script (and worker processes it spawns, which inherit its argv)
    return bool(_sys.argv) and _os.path.basename(_sys.argv[0]).removesuffix(".exe") == "realm"


if not _launched_by_realm_cli():
    register_envs()
