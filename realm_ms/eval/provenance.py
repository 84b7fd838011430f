"""What produced a run, for report headers: the code version (recorded in every episode record) and
what a policy's action vector means in each action space."""

from __future__ import annotations

import functools
import subprocess
from pathlib import Path

CONTROL_HZ = 15  # the REALM envs' control frequency (DROID's), to state horizons in seconds

# DROID's action spaces (realm_ms.agents.droid_action_spaces) and gripper spaces, in words
ARM_SPACES = {
    "joint_position": "7 absolute joint targets (rad)",
    "joint_velocity": "7 joint velocities in [-1, 1] (x 0.2 rad per step)",
    "cartesian_velocity": "6 flange velocities in [-1, 1] (x 0.075 m / 0.15 rad per step)",
    "cartesian_position": "absolute flange pose [x, y, z, roll, pitch, yaw]",
}
GRIPPER_SPACES = {"position": "gripper position in [0, 1] (1 = closed)", "velocity": "gripper velocity in [-1, 1]"}
ALIASES = {"droid_joint_pos": "joint_position:position"}  # the env's control mode = DROID's joint_position


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """``realm-ms VERSION`` plus the git revision (``-dirty`` with local changes) when run from a checkout."""
    from realm_ms import __version__

    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():  # an installed wheel: the version is all there is
        return f"realm-ms {__version__}"
    try:
        out = subprocess.run(["git", "-C", str(root), "describe", "--always", "--dirty", "--abbrev=10"],
                             capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.SubprocessError):
        return f"realm-ms {__version__}"
    rev = out.stdout.strip()
    return f"realm-ms {__version__} ({rev})" if out.returncode == 0 and rev else f"realm-ms {__version__}"


def describe_action_space(name: str) -> str:
    """``joint_position:position`` -> 'joint_position:position (7 absolute joint targets (rad) + gripper ...)'."""
    arm, _, grip = ALIASES.get(name, name).partition(":")
    parts = [ARM_SPACES.get(arm), GRIPPER_SPACES.get(grip or "position")]
    return f"{name} ({' + '.join(parts)})" if parts[0] else name
