"""CPU seconds of ``python -m realm_ms.lerobot.train`` (the small ACT of
``tests/lerobot/test_policy_transfer.py``, one thread) with one of its changes to LeRobot's trainer
off (the baseline) and on (the default), in the same run: user and system time of each, and their ratio.

    .venv/bin/python bench/train_step.py --root DATASET [--steps 150] [--batch-size 8] [--switch freed-memory|fused-adam]

``freed-memory``: glibc's malloc at its defaults (``REALM_KEEP_FREED_MEMORY=0``) against keeping the
memory a step frees; ``fused-adam``: LeRobot's Adam build (``REALM_FUSED_ADAM=0``) against torch's
fused kernel.

DATASET: a LeRobot dataset `realm export` wrote (e.g. ``realm export --tasks REALM-PushSwitch-v1
--episodes 1 --width 32 --height 24 --out DATASET``).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


SWITCHES = {"freed-memory": "REALM_KEEP_FREED_MEMORY", "fused-adam": "REALM_FUSED_ADAM"}


def train(root: Path, steps: int, batch: int, switch: str, on: bool) -> tuple[float, float, float]:
    """(wall, user, system) seconds of one training run."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [sys.executable, "-m", "realm_ms.lerobot.train", f"--dataset.repo_id=realm/{root.name}", f"--dataset.root={root}",
               "--dataset.video_backend=pyav", "--policy.type=act", "--policy.device=cpu", "--policy.push_to_hub=false",
               "--policy.pretrained_backbone_weights=null", "--policy.dim_model=64", "--policy.n_heads=2",
               "--policy.dim_feedforward=128", "--policy.n_encoder_layers=1", "--policy.n_decoder_layers=1",
               "--policy.use_vae=false", "--policy.dropout=0", "--policy.chunk_size=8", "--policy.n_action_steps=8",
               "--policy.optimizer_lr=5e-4", "--policy.optimizer_lr_backbone=5e-4", f"--steps={steps}",
               f"--batch_size={batch}", "--num_workers=0", f"--save_freq={steps}", "--log_freq=50",
               f"--output_dir={Path(out) / 'run'}", "--wandb.enable=false"]
        env = dict(os.environ, OMP_NUM_THREADS="1", **{SWITCHES[switch]: "1" if on else "0"})
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.perf_counter() - t
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, required=True)
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--batch-size", type=int, default=8)
    ap.add_argument("--switch", choices=sorted(SWITCHES), default="freed-memory")
    a = ap.parse_args(argv)
    rows = {f"{a.switch} off": train(a.root, a.steps, a.batch_size, a.switch, on=False),
            f"{a.switch} on": train(a.root, a.steps, a.batch_size, a.switch, on=True)}
    print(f"{a.steps} steps of batch {a.batch_size}, one thread:")
    for name, (wall, user, sys_) in rows.items():
        print(f"  {name:18s} wall {wall:6.1f} s   user {user:6.1f} s   system {sys_:5.1f} s")
    (w0, u0, s0), (w1, u1, s1) = rows.values()
    print(f"CPU (user + system) off / on = {(u0 + s0) / (u1 + s1):.2f}x; wall {w0 / w1:.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
