"""Procedural textures (numpy -> ``sapien.render.RenderTexture2D``): wood grain, planks, tiles, fabric.

Generated deterministically from a seed, cached per process. Building a texture needs a render
system; ``textured_material`` falls back to a plain colour when none is available (state-only
envs with ``render_backend="none"``).
"""

from __future__ import annotations


import numpy as np
import sapien


def _noise(rng: np.random.Generator, h: int, w: int, scale: int) -> np.ndarray:
    """Smooth value noise in [0, 1] (bilinear upsampling of a coarse random grid)."""
    gh, gw = max(h // scale, 2), max(w // scale, 2)
    g = rng.random((gh + 1, gw + 1))
    y = np.linspace(0, gh, h, endpoint=False)
    x = np.linspace(0, gw, w, endpoint=False)
    y0, x0 = y.astype(int), x.astype(int)
    fy, fx = (y - y0)[:, None], (x - x0)[None, :]
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    a = g[y0][:, x0]
    b = g[y0][:, x0 + 1]
    c = g[y0 + 1][:, x0]
    d = g[y0 + 1][:, x0 + 1]
    return a * (1 - fx) * (1 - fy) + b * fx * (1 - fy) + c * (1 - fx) * fy + d * fx * fy


def wood(base_rgb, dark_rgb, seed: int = 0, size: int = 256, rings: float = 18.0, planks: int = 0) -> np.ndarray:
    """Wood grain (rings stretched along the texture's u axis); ``planks`` > 0 adds plank seams."""
    rng = np.random.default_rng(seed)
    h = w = size
    n = _noise(rng, h, w, 32) * 0.6 + _noise(rng, h, w, 8) * 0.15
    v = np.linspace(0, 1, h)[:, None]
    grain = np.sin((v * rings + n * 3.0) * 2 * np.pi) * 0.5 + 0.5
    grain = grain**3
    t = np.clip(grain * 0.75 + _noise(rng, h, w, 4) * 0.25, 0, 1)[..., None]
    if planks:
        rows = (np.arange(h) * planks // h)
        shade = rng.uniform(0.85, 1.1, planks)[rows][:, None, None]
        seam = ((np.arange(h) * planks) % h < max(h // 128, 1))[:, None, None]
        offs = rng.integers(0, w, planks)
        cut = (((np.arange(w)[None, :] + offs[rows][:, None]) % w) < 2)[..., None]
    else:
        shade, seam, cut = 1.0, False, False
    rgb = (np.asarray(base_rgb) * (1 - t) + np.asarray(dark_rgb) * t) * shade
    rgb = np.where(seam | cut, np.asarray(dark_rgb) * 0.6, rgb)
    return _rgba(rgb)


def tiles(rgb_a, rgb_b, grout_rgb, n: int = 8, seed: int = 0, size: int = 256, checker: bool = True) -> np.ndarray:
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size]
    cell = size // n
    iy, ix = y // cell, x // cell
    pick = ((iy + ix) % 2 == 0) if checker else np.ones_like(iy, bool)
    rgb = np.where(pick[..., None], np.asarray(rgb_a), np.asarray(rgb_b)).astype(float)
    rgb *= (0.94 + 0.06 * _noise(rng, size, size, 16))[..., None]
    grout = ((y % cell) < 2) | ((x % cell) < 2)
    rgb[grout] = grout_rgb
    return _rgba(rgb)


def fabric(rgb, seed: int = 0, size: int = 256) -> np.ndarray:
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size]
    weave = 0.9 + 0.1 * ((np.sin(x * 1.7) * np.sin(y * 1.7)) > 0)
    rgb = np.asarray(rgb) * (weave * (0.9 + 0.1 * _noise(rng, size, size, 8)))[..., None]
    return _rgba(rgb)


def plaster(rgb, seed: int = 0, size: int = 128) -> np.ndarray:
    rng = np.random.default_rng(seed)
    n = _noise(rng, size, size, 16) * 0.5 + _noise(rng, size, size, 4) * 0.5
    return _rgba(np.asarray(rgb) * (0.93 + 0.07 * n)[..., None])


def _rgba(rgb: np.ndarray) -> np.ndarray:
    rgb = np.clip(rgb, 0, 1)
    out = np.ones(rgb.shape[:2] + (4,), np.uint8) * 255
    out[..., :3] = (rgb * 255).astype(np.uint8)
    return out


_TEXTURES: dict = {}


def textured_material(key: str, make, fallback_rgba, roughness: float = 0.6, metallic: float = 0.0) -> sapien.render.RenderMaterial:
    """A material whose base colour is the procedural texture ``make()`` (cached under ``key``)."""
    m = sapien.render.RenderMaterial(base_color=list(fallback_rgba), roughness=roughness, metallic=metallic)
    apply_texture(m, key, make, fallback_rgba)
    return m


def apply_texture(m: sapien.render.RenderMaterial, key: str, make, fallback_rgba) -> None:
    """Give ``m`` the texture ``make()`` (cached under ``key``), or the plain ``fallback_rgba``
    without a render device. Works on a built scene too (per-episode material draws)."""
    try:
        if key not in _TEXTURES:
            _TEXTURES[key] = sapien.render.RenderTexture2D(make(), "R8G8B8A8Unorm", mipmap_levels=4, srgb=True)
        m.base_color = [1.0, 1.0, 1.0, 1.0]
        m.set_base_color_texture(_TEXTURES[key])
    except Exception:  # no render device: plain colour
        m.base_color = list(fallback_rgba)
