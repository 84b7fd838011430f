"""The DROID feature layout shared by ``realm export`` datasets and the LeRobot ``realm`` env.

One place defines the names, shapes and dtypes so that a policy trained on an export is evaluated
on the env plugin without any renaming:

=================================  ============================  ================================
dataset feature                    env observation (gym)         REALM source
=================================  ============================  ================================
``observation.images.<cam>``       ``pixels/<cam>`` (HWC uint8)  ``sensor_data/<realm cam>/rgb``
``observation.state`` (8)          ``agent_pos``                 ``agent/droid_state``
``action`` (8)                     action                        ``droid_joint_pos`` targets
=================================  ============================  ================================

with ``<cam>`` one of DROID's ``exterior_1_left``, ``exterior_2_left``, ``wrist_left``. Extras of
the export (not policy inputs: LeRobot only feeds ``observation.*`` keys to a policy):
``progression`` / ``success`` after the frame's action, ``next.done``.
"""

from __future__ import annotations

import numpy as np

FPS = 15  # droid_joint_pos control rate
DEFAULT_SIZE = (320, 180)  # width, height (DROID's LeRobot port / GR00T-style frames)
ROBOT_TYPE = "panda_droid"

# DROID camera name -> REALM camera uid
CAMERAS: dict[str, str] = {
    "exterior_1_left": "exterior_1",
    "exterior_2_left": "exterior_2",
    "wrist_left": "wrist",
}
STATE_NAMES = [f"joint_{i}" for i in range(7)] + ["gripper_position"]
ACTION_NAMES = [f"joint_{i}_target" for i in range(7)] + ["gripper_command"]

OBS_STATE = "observation.state"
ACTION = "action"


def image_key(cam: str) -> str:
    return f"observation.images.{cam}"


def dataset_features(width: int = DEFAULT_SIZE[0], height: int = DEFAULT_SIZE[1], use_videos: bool = True) -> dict:
    """``LeRobotDataset.create(features=...)`` for a REALM export."""
    feats: dict[str, dict] = {}
    for cam in CAMERAS:
        feats[image_key(cam)] = {
            "dtype": "video" if use_videos else "image",
            "shape": (height, width, 3),
            "names": ["height", "width", "channels"],
        }
    feats[OBS_STATE] = {"dtype": "float32", "shape": (8,), "names": STATE_NAMES}
    feats[ACTION] = {"dtype": "float32", "shape": (8,), "names": ACTION_NAMES}
    feats["progression"] = {"dtype": "float32", "shape": (1,), "names": None}
    feats["success"] = {"dtype": "bool", "shape": (1,), "names": None}
    feats["next.done"] = {"dtype": "bool", "shape": (1,), "names": None}
    return feats


def obs_to_numpy(obs: dict, index: int = 0) -> dict:
    """One env's REALM observation (batched torch, obs_mode rgb) -> ``{"pixels": {cam: HWC uint8}, "agent_pos": (8,)}``."""
    pixels = {cam: obs["sensor_data"][uid]["rgb"][index].cpu().numpy() for cam, uid in CAMERAS.items()}
    state = obs["agent"]["droid_state"][index].detach().cpu().numpy().astype(np.float32)
    return {"pixels": pixels, "agent_pos": state}


def dataset_frame(np_obs: dict, action: np.ndarray, progression: float, success: bool, done: bool, task: str) -> dict:
    """A frame for ``LeRobotDataset.add_frame`` from ``obs_to_numpy`` output and the action taken."""
    frame = {image_key(cam): img for cam, img in np_obs["pixels"].items()}
    frame[OBS_STATE] = np_obs["agent_pos"].astype(np.float32)
    frame[ACTION] = np.asarray(action, dtype=np.float32).reshape(8)
    frame["progression"] = np.array([progression], dtype=np.float32)
    frame["success"] = np.array([success], dtype=bool)
    frame["next.done"] = np.array([done], dtype=bool)
    frame["task"] = task
    return frame
