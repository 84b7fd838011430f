"""LeRobot ``PreTrainedPolicy`` checkpoints (local directory or hub id) as a policy.

Loaded through LeRobot's own factory: ``PreTrainedConfig.from_pretrained`` ->
``get_policy_class(cfg.type).from_pretrained`` and ``make_pre_post_processors`` (the checkpoint's
saved normalisation / tokenisation / device pipelines; fresh ones from the config when the
checkpoint has none). Inputs are mapped by name from the policy's ``input_features``:

- ``observation.images.<key>`` -> our camera whose uid appears in ``key`` (``exterior_1``,
  ``exterior_2``, ``wrist``), else by DROID naming (``wrist*`` -> wrist, ``*2*`` -> exterior_2,
  any other image -> exterior_1), resized to the feature's (C, H, W) as float [0, 1];
- ``observation.state`` -> ``droid_state`` (8: 7 joints + gripper; a 7-D state gets the joints);
- ``task`` -> the episode's instruction.

``predict_action_chunk`` gives (B, T, action_dim) per round (stateless across slots, so episodes in
a batch never share an action queue); a 7-D action is completed with the gripper kept as is.
"""

from __future__ import annotations

import numpy as np

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.policy import CAMERAS, ObsRequest, Policy, PolicyInput, PolicyOutput

IMAGE_PREFIX = "observation.images."


def camera_for_feature(key: str) -> str:
    """Our camera uid for a policy image feature name (see module docstring)."""
    name = key[len(IMAGE_PREFIX):] if key.startswith(IMAGE_PREFIX) else key.rsplit(".", 1)[-1]
    for cam in CAMERAS:
        if cam in name:
            return cam
    low = name.lower()
    if "wrist" in low or "hand" in low or "gripper" in low:
        return "wrist"
    if "2" in low or "right" in low:
        return "exterior_2"
    return "exterior_1"


class LeRobotPolicy(Policy):
    name = "lerobot"

    def __init__(self, path: str, device: str = "cpu", camera_map: dict[str, str] | None = None):
        import torch
        from lerobot.configs.policies import PreTrainedConfig
        from lerobot.configs.types import FeatureType
        from lerobot.policies.factory import get_policy_class, make_pre_post_processors

        self.path, self.device = str(path), device
        cfg = PreTrainedConfig.from_pretrained(self.path)
        cfg.pretrained_path = self.path
        cfg.device = device
        self.policy = get_policy_class(cfg.type).from_pretrained(self.path, config=cfg)
        self.policy.to(device).eval()
        self.cfg = cfg
        try:
            self.pre, self.post = make_pre_post_processors(
                cfg, pretrained_path=self.path, preprocessor_overrides={"device_processor": {"device": device}}
            )
        except (FileNotFoundError, OSError):  # checkpoint without saved processors
            self.pre, self.post = make_pre_post_processors(cfg)
        self.image_keys = {k: (camera_map or {}).get(k, camera_for_feature(k)) for k, f in cfg.input_features.items() if f.type is FeatureType.VISUAL}
        self.image_shapes = {k: tuple(cfg.input_features[k].shape) for k in self.image_keys}
        state = [k for k, f in cfg.input_features.items() if f.type is FeatureType.STATE]
        self.state_key = state[0] if state else None
        self.state_dim = int(cfg.input_features[self.state_key].shape[0]) if self.state_key else 0
        if self.state_dim not in (0, 7, 8):
            raise ValueError(f"LeRobot policy {path}: state feature {self.state_key} has {self.state_dim} dims; expected 8 (DROID joints + gripper) or 7")
        out = [f for f in cfg.output_features.values() if f.type is FeatureType.ACTION]
        self.action_dim = int(out[0].shape[0]) if out else 8
        if self.action_dim not in (7, 8):
            raise ValueError(f"LeRobot policy {path}: action has {self.action_dim} dims; expected 8 droid_joint_pos (or 7 joints)")
        self.chunk = int(getattr(cfg, "n_action_steps", None) or getattr(cfg, "chunk_size", 8) or 8)
        self._torch = torch

    def obs_request(self) -> ObsRequest:
        cams = tuple(c for c in CAMERAS if c in set(self.image_keys.values()))
        return ObsRequest(cams)

    def spec(self) -> str:
        return f"lerobot:{self.path}"

    def reset(self, slots: list[int]) -> None:
        self.policy.reset()

    def _batch(self, batch: PolicyInput) -> dict:
        import torch.nn.functional as F

        torch = self._torch
        out: dict = {"task": list(batch.instructions)}
        for key, cam in self.image_keys.items():
            img = torch.from_numpy(np.ascontiguousarray(batch.images[cam])).permute(0, 3, 1, 2).float() / 255.0
            c, h, w = self.image_shapes[key]
            if img.shape[-2:] != (h, w):
                img = F.interpolate(img, size=(h, w), mode="bilinear", align_corners=False, antialias=True)
            out[key] = img[:, :c]
        if self.state_key:
            out[self.state_key] = torch.from_numpy(batch.state[:, : self.state_dim].astype(np.float32))
        return out

    def act(self, batch: PolicyInput) -> PolicyOutput:
        torch = self._torch
        with torch.inference_mode():
            obs = self.pre(self._batch(batch))
            chunk = self.policy.predict_action_chunk(obs)
            if chunk.ndim == 2:  # (B, A): single-step policies
                chunk = chunk[:, None]
            b, t, a = chunk.shape
            actions = self.post(chunk.reshape(b * t, a))
        actions = actions.detach().float().cpu().numpy().reshape(b, t, -1)
        if actions.shape[-1] == 7:  # joints only: keep the gripper where it is
            g = np.repeat(batch.state[:, None, 7:8], t, axis=1)
            actions = np.concatenate([actions, g], -1)
        actions[..., 7] = np.clip(actions[..., 7], 0.0, 1.0)
        return PolicyOutput(actions.astype(np.float32))


POLICIES.register("lerobot", lambda arg, **kw: LeRobotPolicy(arg, device=kw.get("device") or "cpu"))


def make_tiny_policy(out_dir, image_size: tuple[int, int] = (48, 64), cameras: tuple[str, ...] = ("exterior_1_left", "wrist_left"), seed: int = 0):
    """A tiny randomly initialised ACT policy with DROID features, saved (weights + processors) to
    ``out_dir`` so it loads back by path: for tests and the demo (no download, no training).

    Normalisation stats are the DROID reset pose +- 1 rad so the untrained net's outputs stay near it."""
    import torch
    from lerobot.configs.types import FeatureType, NormalizationMode, PolicyFeature
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.act.modeling_act import ACTPolicy
    from lerobot.policies.factory import make_pre_post_processors

    torch.manual_seed(seed)
    h, w = image_size
    inputs = {f"{IMAGE_PREFIX}{c}": PolicyFeature(FeatureType.VISUAL, (3, h, w)) for c in cameras}
    inputs["observation.state"] = PolicyFeature(FeatureType.STATE, (8,))
    cfg = ACTConfig(
        input_features=inputs,
        output_features={"action": PolicyFeature(FeatureType.ACTION, (8,))},
        chunk_size=8, n_action_steps=8, dim_model=32, n_heads=2, dim_feedforward=64,
        n_encoder_layers=1, n_decoder_layers=1, use_vae=False, pretrained_backbone_weights=None,
        vision_backbone="resnet18", device="cpu",
        normalization_mapping={"VISUAL": NormalizationMode.MEAN_STD, "STATE": NormalizationMode.MEAN_STD, "ACTION": NormalizationMode.MEAN_STD},
    )
    policy = ACTPolicy(cfg)
    reset = torch.tensor([0.0, -0.628, 0.0, -2.513, 0.0, 1.885, 0.0, 0.0])
    stats = {"observation.state": {"mean": reset, "std": torch.ones(8)}, "action": {"mean": reset, "std": torch.full((8,), 0.05)}}
    for k in inputs:
        if k.startswith(IMAGE_PREFIX):
            stats[k] = {"mean": torch.full((3, 1, 1), 0.5), "std": torch.full((3, 1, 1), 0.25)}
    pre, post = make_pre_post_processors(cfg, dataset_stats=stats)
    policy.save_pretrained(out_dir)
    pre.save_pretrained(out_dir)
    post.save_pretrained(out_dir)
    return out_dir
