"""``lerobot-train`` with each training video decoded once into memory (:mod:`realm_ms.lerobot.frame_cache`).

    python -m realm_ms.lerobot.train ARGS...     # ARGS exactly as for lerobot-train

LeRobot's own training script runs unchanged: its dataset reader's frame decoder is swapped for the
in-memory one and its Adam is built fused, so policy, update rule, checkpoints and logs are those of
``lerobot-train``.
``REALM_FRAME_CACHE_GB`` (default 8) caps the decoded frames held; a larger dataset is decoded per
sample by LeRobot as before. Data-loader workers are forked (unless ``--dataloader_multiprocessing_context``
says otherwise) so that they share the decoded frames; LeRobot's default, spawn, would start each
worker without them. glibc's allocator is told to keep freed memory (:func:`keep_freed_memory`;
``REALM_KEEP_FREED_MEMORY=0`` leaves its defaults), and LeRobot's Adam presets use torch's fused kernel
(:func:`fuse_adam`; ``REALM_FUSED_ADAM=0`` leaves LeRobot's build). ``bench/train_step.py`` compares each.
"""

from __future__ import annotations


def keep_freed_memory() -> bool:
    """Have glibc's malloc keep the memory a training step frees for the next step. By default it
    returns the top of the heap to the kernel once more than 128 KiB is free there, and a step's
    activations and gradients free and re-take megabytes, so every step paid page faults on fresh
    pages: 15 of 55 s of CPU was the kernel's in 150 steps of the small ACT in
    ``tests/lerobot/test_policy_transfer.py`` (1 s with this). Returns whether it applied (glibc only)."""
    import ctypes
    import ctypes.util

    M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        # no trimming; blocks up to 32 MiB (glibc's largest threshold) from the heap, not mmap
        return bool(libc.mallopt(M_TRIM_THRESHOLD, 2**31 - 1)) and bool(libc.mallopt(M_MMAP_THRESHOLD, 32 * 2**20))
    except (OSError, AttributeError):  # not glibc (musl, macOS): its own allocator's defaults
        return False


def fuse_adam() -> None:
    """Have LeRobot's Adam and AdamW presets (ACT, Diffusion, ...) use torch's fused kernel where every
    parameter allows it (floating point, on CPU or CUDA). LeRobot builds them with torch's defaults,
    which on CPU update each tensor in its own loop of element-wise ops: ~50 ms a step for ResNet-18's
    11.7 M parameters on one core, ~8 ms fused. Same update rule (equal to the float on the checks of
    ``tests/lerobot/test_train.py``). ``REALM_FUSED_ADAM=0`` leaves LeRobot's build."""
    from dataclasses import asdict

    import torch
    from lerobot.optim import optimizers

    def fusable(params: list) -> bool:
        tensors = [t for x in params for t in (x["params"] if isinstance(x, dict) else [x])]
        return bool(tensors) and all(t.is_floating_point() and t.device.type in ("cpu", "cuda") for t in tensors)

    for config, optim in ((optimizers.AdamConfig, torch.optim.Adam), (optimizers.AdamWConfig, torch.optim.AdamW)):
        if getattr(config.build, "fused", False):
            continue

        def build(self, params, optim=optim, lerobot_build=config.build):
            if isinstance(params, dict):  # named parameters: LeRobot's own build
                return lerobot_build(self, params)
            # a parameter group's iterator is read twice (the check, the optimiser)
            params = [dict(x, params=list(x["params"])) if isinstance(x, dict) else x for x in params]
            if not fusable(params):
                return lerobot_build(self, params)
            kwargs = asdict(self)
            kwargs.pop("grad_clip_norm")  # as LeRobot's build, plus fused=True
            return optim(params, **kwargs, fused=True)

        build.fused = True
        config.build = build


def main() -> None:
    import os
    import sys

    if os.environ.get("REALM_KEEP_FREED_MEMORY", "1") != "0":
        keep_freed_memory()

    if os.environ.get("REALM_FUSED_ADAM", "1") != "0":
        fuse_adam()
    from lerobot.scripts import lerobot_train

    from realm_ms.lerobot import frame_cache

    frame_cache.install(lerobot_train)
    if not any(a.startswith("--dataloader_multiprocessing_context") for a in sys.argv[1:]):
        sys.argv.append("--dataloader_multiprocessing_context=fork")
    lerobot_train.main()


if __name__ == "__main__":
    main()
