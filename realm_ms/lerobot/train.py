"""``lerobot-train`` with each training video decoded once into memory (:mod:`realm_ms.lerobot.frame_cache`).

    python -m realm_ms.lerobot.train ARGS...     # ARGS exactly as for lerobot-train

LeRobot's own training script runs unchanged: only its dataset reader's frame decoder is swapped for
the in-memory one, so policy, optimiser, checkpoints and logs are those of ``lerobot-train``.
``REALM_FRAME_CACHE_GB`` (default 8) caps the decoded frames held; a larger dataset is decoded per
sample by LeRobot as before. Data-loader workers are forked (unless ``--dataloader_multiprocessing_context``
says otherwise) so that they share the decoded frames; LeRobot's default, spawn, would start each
worker without them.
"""

from __future__ import annotations


def main() -> None:
    import sys

    from lerobot.scripts import lerobot_train

    from realm_ms.lerobot import frame_cache

    frame_cache.install(lerobot_train)
    if not any(a.startswith("--dataloader_multiprocessing_context") for a in sys.argv[1:]):
        sys.argv.append("--dataloader_multiprocessing_context=fork")
    lerobot_train.main()


if __name__ == "__main__":
    main()
