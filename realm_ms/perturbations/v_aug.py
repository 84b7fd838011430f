"""1 V-AUG: Gaussian blur then contrast on every camera image (exterior + wrist), drawn per reset.

REALM (paper-era ``reset()``): sigma ~ U(0, 2.5), odd kernel ``int(4 sigma + 1)``, then
``clip(img * alpha, 0, 255)`` with alpha ~ U(0.25, 1.5). Batched: one separable convolution over
all sub-envs with a per-sub-env kernel (zero weights outside each sub-env's own kernel size).
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from realm_ms.tasks.perturbation import Perturbation, as_float

SIGMA = (0.0, 2.5)
ALPHA = (0.25, 1.5)
MAX_K = int(4 * SIGMA[1] + 1) | 1  # 11


def kernel_size(sigma: float) -> int:
    k = int(4 * sigma + 1)
    return k if k % 2 else k + 1


def gaussian_kernels(sigmas: torch.Tensor, size: int = MAX_K) -> torch.Tensor:
    """(B,) sigmas -> (B, size) normalised 1-D kernels, truncated to each sigma's own odd size
    (OpenCV's GaussianBlur with ksize = int(4 sigma + 1)); sigma 0 is the identity."""
    x = torch.arange(size, dtype=torch.float32, device=sigmas.device) - size // 2
    s = sigmas.float().clamp(min=1e-6)[:, None]
    w = torch.exp(-0.5 * (x[None] / s) ** 2)
    half = torch.tensor([kernel_size(float(v)) // 2 for v in sigmas.cpu()], device=sigmas.device)[:, None]
    w = w * (x[None].abs() <= half)
    return w / w.sum(dim=1, keepdim=True)


def blur_contrast(img: torch.Tensor, sigma: torch.Tensor, alpha: torch.Tensor) -> torch.Tensor:
    """img (B, H, W, C) uint8 -> same dtype; per-image sigma and alpha (B,). CPU tensors go through
    OpenCV (REALM's own ``cv2.GaussianBlur``; torch's threads are slow on a busy CPU), others
    through the batched torch path (same kernel; uint8 rounding may differ by 1)."""
    if img.device.type == "cpu":
        try:
            import cv2
        except ImportError:
            return blur_contrast_torch(img, sigma, alpha)
        out = img.numpy().copy()
        for i, (s, a) in enumerate(zip(sigma.tolist(), alpha.tolist())):
            if s > 0:
                k = kernel_size(s)
                out[i] = cv2.GaussianBlur(out[i], (k, k), s)
            out[i] = np.clip(out[i].astype(np.float32) * a, 0, 255).astype(np.uint8)
        return torch.from_numpy(out)
    return blur_contrast_torch(img, sigma, alpha)


def blur_contrast_torch(img: torch.Tensor, sigma: torch.Tensor, alpha: torch.Tensor) -> torch.Tensor:
    """The batched torch path: separable blur as a sum of shifted slices (11 taps)."""
    x = img.float().permute(0, 3, 1, 2)  # (B, C, H, W)
    k = gaussian_kernels(sigma.to(img.device))[:, :, None, None, None]  # (B, K, 1, 1, 1)
    p = MAX_K // 2
    h, w = x.shape[-2:]
    xp = F.pad(x, (p, p, 0, 0), mode="reflect")  # OpenCV's default border (reflect-101)
    x = sum(k[:, t] * xp[..., t : t + w] for t in range(MAX_K))
    xp = F.pad(x, (0, 0, p, p), mode="reflect")
    x = sum(k[:, t] * xp[..., t : t + h, :] for t in range(MAX_K))
    x = x.round() * alpha.to(img.device).float()[:, None, None, None]
    return x.clamp(0, 255).to(img.dtype).permute(0, 2, 3, 1)


class VAug(Perturbation):
    pid = 1
    name = "V-AUG"
    acts_on = "camera images (exterior + wrist), after rendering"
    ranges = f"blur sigma ~ U{SIGMA} (kernel int(4 sigma + 1)), contrast alpha ~ U{ALPHA}"

    def draw(self, rng, ctx):
        return dict(sigma=as_float(rng.uniform(*SIGMA)), alpha=as_float(rng.uniform(*ALPHA)))

    def on_observation(self, env, sensor_data, params):
        sigma = torch.tensor([p["sigma"] for p in params])
        alpha = torch.tensor([p["alpha"] for p in params])
        cams = [c for c in sensor_data.values() if "rgb" in c]
        by_shape: dict = {}
        for c in cams:  # one batched pass per image size (all cameras share it by default)
            by_shape.setdefault(tuple(c["rgb"].shape), []).append(c)
        for group in by_shape.values():
            n = len(group)
            out = blur_contrast(torch.cat([c["rgb"] for c in group]), sigma.repeat(n), alpha.repeat(n))
            for c, img in zip(group, out.chunk(n)):
                c["rgb"] = img
        return sensor_data
