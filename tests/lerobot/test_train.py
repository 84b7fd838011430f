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


def test_the_trainer_builds_lerobots_adam_fused_with_the_same_update():
    # in a child: fuse_adam changes LeRobot's optimiser configs for the process
    code = """
import torch
from lerobot.optim.optimizers import AdamConfig, AdamWConfig
from realm_ms.lerobot.train import fuse_adam

def steps(config):
    torch.manual_seed(0)
    net = torch.nn.Linear(5, 3)
    opt = config.build([{"params": net.parameters()}])
    for _ in range(3):
        opt.zero_grad()
        net(torch.ones(4, 5)).square().sum().backward()
        opt.step()
    return opt, net.weight.detach().clone()

cfg = AdamWConfig(lr=1e-2, weight_decay=1e-2)
plain, w_plain = steps(cfg)
fuse_adam()
fused, w_fused = steps(cfg)
assert not plain.defaults["fused"] and fused.defaults["fused"] is True, (plain.defaults, fused.defaults)
assert isinstance(fused, torch.optim.AdamW) and torch.allclose(w_plain, w_fused, atol=1e-6), (w_plain - w_fused)
assert AdamConfig(lr=1e-3).build(torch.nn.Linear(2, 2).parameters()).defaults["fused"] is True
# a parameter the fused kernel cannot take (not floating point) keeps LeRobot's build
assert not AdamConfig(lr=1e-3).build([torch.zeros(2, dtype=torch.complex64, requires_grad=True)]).defaults["fused"]
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr[-2000:]
