"""``python -m realm_ms.lerobot.train``: glibc's allocator keeps the memory a training step frees
(``bench/train_step.py`` measures what it saves); the frame cache is tested in test_frame_cache.py."""

import platform
import subprocess
import sys

import pytest


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt is glibc's")
def test_the_trainer_keeps_freed_memory_under_glibc():
    # in a child: the setting lasts for the process, and a test worker should keep glibc's defaults
    code = "from realm_ms.lerobot.train import keep_freed_memory; raise SystemExit(0 if keep_freed_memory() else 3)"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0
