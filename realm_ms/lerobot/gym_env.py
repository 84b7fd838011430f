"""``RealmLeRobotEnv``: one REALM env as the plain numpy gym env LeRobot's eval loop expects.

REALM envs are ManiSkill envs: batched torch observations even with ``num_envs = 1``. LeRobot's
``lerobot-eval`` / ``lerobot-train`` stack single envs in a ``gymnasium.vector`` env and feed
``preprocess_observation`` with ``{"pixels": {cam: (B, H, W, 3) uint8}, "agent_pos": (B, 8)}``,
read ``task_description``, ``_max_episode_steps`` and ``info["is_success"]``, and record videos
with ``render()`` at ``metadata["render_fps"]``. This adapter provides exactly that, with the
DROID camera names of ``realm export`` datasets (``features.CAMERAS``), so a policy trained on an
export sees the same keys, shapes and value ranges in evaluation.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from realm_ms.lerobot.features import CAMERAS, DEFAULT_SIZE, FPS, obs_to_numpy


class RealmLeRobotEnv(gym.Env):
    """``gym.make(task, obs_mode="rgb", ...)`` behind a numpy, unbatched interface."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": FPS}

    def __init__(self, task: str = "REALM-PickApple-v1", observation_width: int = DEFAULT_SIZE[0],
                 observation_height: int = DEFAULT_SIZE[1], episode_length: int | None = None,
                 shader: str = "default", perturbation: str | None = None, render_mode: str = "rgb_array", **env_kwargs):
        super().__init__()
        from realm_ms.eval.policies.policy import ObsRequest
        from realm_ms.eval.runner import RunConfig, cell_config
        from realm_ms.tasks.config import make_env

        self.task = task
        self.render_mode = render_mode
        # the env of realm export's datasets: RGB cameras at the dataset's size, built by the one recipe
        run = RunConfig(obs=ObsRequest(cameras=tuple(CAMERAS.values()), width=observation_width, height=observation_height),
                        max_steps=episode_length or None, shader=shader, env_kwargs=env_kwargs)
        self.config, rest = cell_config(task, perturbation, run)
        self._env = make_env(self.config, **rest)
        u = self._env.unwrapped
        self._max_episode_steps = int(episode_length or u.spec.max_episode_steps or u.task_spec.horizon)
        self.task_description = u.get_language_instruction()[0]
        h, w = observation_height, observation_width
        self.observation_space = spaces.Dict({
            "pixels": spaces.Dict({cam: spaces.Box(0, 255, shape=(h, w, 3), dtype=np.uint8) for cam in CAMERAS}),
            "agent_pos": spaces.Box(-np.inf, np.inf, shape=(8,), dtype=np.float32),
        })
        a = u.single_action_space
        self.action_space = spaces.Box(a.low.astype(np.float32), a.high.astype(np.float32), dtype=np.float32)
        self._last: dict | None = None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        # LeRobot passes its own rollout markers in options; REALM reset options are not exposed here
        obs, info = self._env.reset(seed=seed)
        self.task_description = self._env.unwrapped.get_language_instruction()[0]  # perturbations may change it
        self._last = obs_to_numpy(obs)
        return self._last, {"is_success": False, "progression": 0.0}

    def step(self, action):
        import torch

        u = self._env.unwrapped
        a = torch.as_tensor(np.asarray(action, dtype=np.float32).reshape(1, -1), device=u.device)
        obs, reward, term, trunc, info = self._env.step(a)
        self._last = obs_to_numpy(obs)
        out = {"is_success": bool(info["success"][0]), "progression": float(info["progression"][0])}
        return self._last, float(reward[0]), bool(term[0]), bool(trunc[0]), out

    def render(self) -> np.ndarray:
        """The three cameras side by side (no extra rendering: the last observation's frames)."""
        if self._last is None:
            w, h = self.observation_space["pixels"]["wrist_left"].shape[1], self.observation_space["pixels"]["wrist_left"].shape[0]
            return np.zeros((h, 3 * w, 3), dtype=np.uint8)
        return np.concatenate([self._last["pixels"][cam] for cam in CAMERAS], axis=1)

    def close(self):
        if getattr(self, "_env", None) is not None:
            self._env.close()
            self._env = None
