"""Third-party warnings known to be harmless here, silenced so that a run shows what matters.

Each entry names the message and why it says nothing to a realm-ms user. ``REALM_MS_VERBOSE=1``
(``realm --verbose``; inherited by worker processes) keeps every warning. Warnings that had a cause
we could remove were fixed at their source instead (the agent's collision meshes are OBJ, not STL;
envs ask ManiSkill for the CPU renderer where there is no CUDA; videos are written at sizes the codec
takes as they are).
"""

from __future__ import annotations

import os
import warnings

KNOWN: tuple[tuple[str, str], ...] = (
    (r".*Box (low|high)'s precision lowered by casting to float32",
     "ManiSkill's passive gripper-joint controller builds an empty float64 Box: nothing is cast"),
)


def verbose() -> bool:
    return os.environ.get("REALM_MS_VERBOSE", "") not in ("", "0")


def install() -> None:
    """Silence the ``KNOWN`` warnings in this process (idempotent) unless ``REALM_MS_VERBOSE`` is set."""
    if verbose():
        return
    for message, _why in KNOWN:
        warnings.filterwarnings("ignore", message=message)
