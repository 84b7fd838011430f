"""Camera rendering for REALM: the shader of every camera, a ray-tracing denoiser that cannot fail
silently, the raster/ray-tracing light balance, and REALM's V-LIGHT units.

One place decides the shader config of every camera (both exterior cameras and the wrist camera):
:func:`camera_shader_config`. Shaders: ``default`` (raster), ``rt-fast`` / ``rt-med`` / ``rt``
(path tracing, ManiSkill presets), ``minimal``.

Denoiser (ray-tracing shaders only): ``auto`` probes, once per process, OptiX, then OIDN, on a tiny
render in a child process (``realm_ms/render_probe.py``) and takes the first that really denoises (a probe frame must be
non-blank and differ from the undenoised frame: SAPIEN renders undenoised, or black, when a
denoiser fails to initialise, and only logs the error); with no CUDA device it is ``none``. One
warning names the choice. Forcing ``optix`` or ``oidn`` probes that one and raises
:class:`DenoiserUnavailable` when it does not work, instead of rendering black or noisy frames.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import json
import os
import subprocess
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SHADERS = ("default", "rt-fast", "rt-med", "rt", "minimal")
CAMERA_UIDS = ("exterior_1", "exterior_2", "wrist")  # every REALM env's cameras (the task's two + the wrist)
DENOISERS = ("auto", "optix", "oidn", "none")
_AUTO_ORDER = ("optix", "oidn")

# Frames whose per-pixel standard deviation (0..255 scale) is below this are blank (black/flat).
BLANK_STD = 2.0

# Scene lights are calibrated on the raster shader. Path-traced frames with a short path depth
# miss the indirect bounce light and come out darker; every scene multiplies its light colours
# (ambient included) by ``light_gain(shader)``: the one knob of the rt/raster balance, checked by
# tests/test_rendering.py::test_rt_exposure_matches_raster (mean and contrast within tolerance).
LIGHT_GAIN = {"default": 1.0, "minimal": 1.0, "rt-fast": 1.15, "rt-med": 1.05, "rt": 1.0}


class DenoiserUnavailable(RuntimeError):
    """A forced denoiser failed its probe (no NVIDIA GPU, driver too old, OptiX error...)."""


def is_ray_traced(shader: str) -> bool:
    return shader.startswith("rt")


def _check_shader(shader: str) -> None:
    if shader not in SHADERS:
        raise ValueError(f"unknown shader {shader!r}; choose one of {', '.join(SHADERS)}")


def _check_denoiser(denoiser: str) -> None:
    if denoiser not in DENOISERS:
        raise ValueError(f"unknown denoiser {denoiser!r}; choose one of {', '.join(DENOISERS)}")


# ---------------------------------------------------------------------------------------- denoiser
@dataclass(frozen=True)
class ProbeResult:
    denoiser: str
    ok: bool
    reason: str  # why not (or "denoised"), with the renderer's own error lines when there are any


@functools.cache
def cuda_available() -> bool:
    """An NVIDIA driver usable from this process (OptiX and SAPIEN's OIDN build both need one)."""
    try:
        import torch

        return bool(torch.cuda.is_available())
    except Exception:  # noqa: BLE001 - any failure means no usable CUDA driver
        return False


@functools.cache
def probe_denoiser(denoiser: str, timeout_s: float = 180.0) -> ProbeResult:
    """Render a tiny path-traced frame with and without ``denoiser`` in a child process (a failing
    OptiX context cannot poison this one) and check that it is non-blank and really denoised."""
    _check_denoiser(denoiser)
    if denoiser in ("none", "auto"):
        raise ValueError("probe_denoiser checks 'optix' or 'oidn'")
    # run by path, not ``-m``: the child imports sapien only, not realm_ms/mani_skill (seconds saved)
    cmd = [sys.executable, str(Path(__file__).with_name("render_probe.py")), denoiser]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, env=os.environ.copy())
    except subprocess.TimeoutExpired:
        return ProbeResult(denoiser, False, f"probe render timed out after {timeout_s:.0f} s")
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    errors = [ln.split("] ")[-1].strip() for ln in out.stderr.splitlines() if "error" in ln.lower()]
    err = "; ".join(dict.fromkeys(errors))[:300]
    if out.returncode != 0 or not lines:
        return ProbeResult(denoiser, False, f"probe crashed (exit {out.returncode}){': ' + err if err else ''}")
    r = json.loads(lines[-1])
    if r["std"] < BLANK_STD:
        return ProbeResult(denoiser, False, f"blank frame (std {r['std']:.2f}){': ' + err if err else ''}")
    if r["diff"] < 1e-6:
        return ProbeResult(denoiser, False, f"frame not denoised{': ' + err if err else ''}")
    return ProbeResult(denoiser, True, "denoised")


@functools.cache
def resolve_denoiser(requested: str = "auto") -> str:
    """The denoiser ray-traced cameras use in this process (decided once; one warning on ``auto``)."""
    _check_denoiser(requested)
    if requested == "none":
        return "none"
    if requested != "auto":
        res = probe_denoiser(requested)
        if not res.ok:
            raise DenoiserUnavailable(f"denoiser {requested!r} does not work here ({res.reason}); use denoiser='auto' or 'none'")
        return requested
    if not cuda_available():
        _warn("none (no CUDA device: OptiX and OIDN need an NVIDIA GPU); ray-traced frames are noisy")
        return "none"
    failed = []
    for name in _AUTO_ORDER:
        res = probe_denoiser(name)
        if res.ok:
            _warn(name + (f" ({'; '.join(failed)})" if failed else ""))
            return name
        failed.append(f"{name} failed: {res.reason}")
    _warn("none (" + "; ".join(failed) + "); ray-traced frames are noisy")
    return "none"


def _warn(choice: str) -> None:
    warnings.warn(f"realm_ms ray-tracing denoiser: {choice}", RuntimeWarning, stacklevel=3)


# ---------------------------------------------------------------------------------------- shaders
def camera_shader_config(shader: str = "default", denoiser: str = "auto"):
    """The ManiSkill ``ShaderConfig`` for every REALM camera (exterior and wrist).

    Ray-traced shaders get the denoiser :func:`resolve_denoiser` picks (probed once per process);
    raster shaders ignore ``denoiser`` (it is still validated).
    """
    from mani_skill.render.shaders import PREBUILT_SHADER_CONFIGS

    _check_shader(shader)
    _check_denoiser(denoiser)
    cfg = copy.deepcopy(PREBUILT_SHADER_CONFIGS[shader])
    if is_ray_traced(shader):
        cfg.shader_pack_config["ray_tracing_denoiser"] = resolve_denoiser(denoiser)
        if _RT_SPP_OVERRIDE:
            spp = cfg.shader_pack_config["ray_tracing_samples_per_pixel"]
            cfg.shader_pack_config["ray_tracing_samples_per_pixel"] = min(spp, _RT_SPP_OVERRIDE[-1])
    return cfg


_RT_SPP_OVERRIDE: list[int] = []


@contextlib.contextmanager
def rt_samples_per_pixel(spp: int):
    """Cap the samples per pixel of ray-traced cameras created inside the block (CPU previews,
    tests); the path depth and denoiser stay those of the shader."""
    if int(spp) < 1:
        raise ValueError(f"samples per pixel must be >= 1, got {spp}")
    _RT_SPP_OVERRIDE.append(int(spp))
    try:
        yield
    finally:
        _RT_SPP_OVERRIDE.pop()


@dataclass(frozen=True)
class CameraSettings:
    """What every REALM camera (exterior and wrist) renders: observation size in pixels, shader and
    denoiser. One value configures all three cameras, so they can never disagree."""

    width: int = 320
    height: int = 180
    shader: str = "default"
    denoiser: str = "auto"

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 1 <= int(v) <= 8192:
                raise ValueError(f"camera_{name} must be a whole number of pixels in 1..8192, got {v!r}")
            object.__setattr__(self, name, int(v))
        _check_shader(self.shader)
        _check_denoiser(self.denoiser)

    def shader_config(self):
        return camera_shader_config(self.shader, self.denoiser)


#: one render system per render device, alive for the whole process (see keep_renderer)
_KEPT: dict[str, object] = {}


def keep_renderer(device) -> None:
    """Hold a render system on ``device`` (a ``sapien.Device``) for the rest of the process. SAPIEN
    frees its Vulkan renderer when the last scene using it goes, and a new renderer recomputes its
    512 x 512 BRDF lookup table on its first picture: 6.7 s of CPU under lavapipe, paid again by
    every env made after another was closed. Kept alive, only a process's first env pays it."""
    import sapien

    if device is not None and str(device) not in _KEPT:
        _KEPT[str(device)] = sapien.render.RenderSystem(device)


def light_gain(shader: str) -> float:
    """Multiplier a scene applies to all its light colours under ``shader`` (see ``LIGHT_GAIN``)."""
    _check_shader(shader)
    return LIGHT_GAIN[shader]


# ---------------------------------------------------------------------------------------- helpers
def vertical_fov(hfov_deg: float, width: int, height: int) -> float:
    """ManiSkill cameras take the vertical FOV (rad); DROID camera specs give the horizontal one."""
    return float(2 * np.arctan(np.tan(np.deg2rad(hfov_deg) / 2) * height / width))


def frame_stats(img) -> tuple[float, float]:
    """(mean, std) of an RGB frame on the 0..255 scale (uint8 or float in 0..1, any leading dims)."""
    raw = np.asarray(img.cpu() if hasattr(img, "cpu") else img)
    a = raw[..., :3].astype(np.float64)
    if not np.issubdtype(raw.dtype, np.integer):
        a = np.clip(a, 0.0, 1.0) * 255.0
    return float(a.mean()), float(a.std())

