"""``lerobot-train`` with each training video decoded once into memory (:mod:`realm_ms.lerobot.frame_cache`).

    python -m realm_ms.lerobot.train ARGS...     # ARGS exactly as for lerobot-train

LeRobot's own training script runs unchanged: only its dataset reader's frame decoder is swapped for
the in-memory one, so policy, optimiser, checkpoints and logs are those of ``lerobot-train``.
``REALM_FRAME_CACHE_GB`` (default 8) caps the decoded frames held; a larger dataset is decoded per
sample by LeRobot as before. Data-loader workers are forked (unless ``--dataloader_multiprocessing_context``
says otherwise) so that they share the decoded frames; LeRobot's default, spawn, would start each
worker without them. glibc's allocator is told to keep freed memory (:func:`keep_freed_memory`;
``REALM_KEEP_FREED_MEMORY=0`` leaves its defaults, as ``bench/train_step.py`` compares).
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


def main() -> None:
    import os
    import sys

    if os.environ.get("REALM_KEEP_FREED_MEMORY", "1") != "0":
        keep_freed_memory()

    from lerobot.scripts import lerobot_train

    from realm_ms.lerobot import frame_cache

    frame_cache.install(lerobot_train)
    if not any(a.startswith("--dataloader_multiprocessing_context") for a in sys.argv[1:]):
        sys.argv.append("--dataloader_multiprocessing_context=fork")
    lerobot_train.main()


if __name__ == "__main__":
    main()
