"""Shader selection for REALM cameras: raster (``default``) or ray-traced (``rt``, ``rt-med``, ``rt-fast``).

ManiSkill's ray-tracing presets ask for the OptiX denoiser, which needs an NVIDIA RTX GPU; on
CPU (lavapipe) or other GPUs we drop the denoiser instead of logging errors every frame. The REALM
protocol renders with path tracing (``rt``); raster is orders of magnitude faster on CPU
(see README, "Rendering speed").
"""

from __future__ import annotations

import copy
import functools

import numpy as np
from mani_skill.render.shaders import PREBUILT_SHADER_CONFIGS, ShaderConfig


@functools.cache
def optix_available() -> bool:
    try:
        import torch

        return torch.cuda.is_available()
    except Exception:  # noqa: BLE001 - any failure means no usable CUDA driver
        return False


def shader_config(name: str) -> ShaderConfig:
    if name not in PREBUILT_SHADER_CONFIGS:
        raise ValueError(f"unknown shader {name!r}; choose one of {sorted(PREBUILT_SHADER_CONFIGS)}")
    cfg = copy.deepcopy(PREBUILT_SHADER_CONFIGS[name])
    if cfg.shader_pack_config.get("ray_tracing_denoiser") == "optix" and not optix_available():
        cfg.shader_pack_config["ray_tracing_denoiser"] = "none"
    return cfg


def vertical_fov(hfov_deg: float, width: int, height: int) -> float:
    """ManiSkill cameras take the vertical FOV (rad); DROID camera specs give the horizontal one."""
    return float(2 * np.arctan(np.tan(np.deg2rad(hfov_deg) / 2) * height / width))
