"""Train-eval loop on REALM with LeRobot: expert demos -> `lerobot-train` -> `realm eval` -> report.

    .venv/bin/python examples/train_eval_loop.py [--out outputs/train_eval] [--task REALM-PickApple-v1]
        [--episodes 2] [--steps 200] [--perturbation V-AUG] [--device cpu] [--smoke]

1. `realm export`: scripted-expert demonstrations of one task as a LeRobot v3.0 dataset (DROID features);
2. `lerobot-train`: a small ACT policy (tiny transformer, ResNet-18 from scratch: nothing is
   downloaded) on it, with LeRobot's in-training evaluation on the `realm` env type
   (`--env.type=realm`, plugin `lerobot_env_realm`) at the end of training;
3. `realm eval --policy lerobot:CHECKPOINT` under Default and one perturbation;
4. `realm eval report`: prints the report path.

On CPU the defaults run end to end in a few minutes (no success is expected from 200 steps);
`--smoke` is the CI variant (a handful of steps everywhere). Every stage resumes: the export skips
episodes already written, the eval skips finished episodes; training reruns only if its checkpoint
is missing.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def parse(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("outputs/train_eval"))
    ap.add_argument("--task", default="REALM-PickApple-v1")
    ap.add_argument("--episodes", type=int, default=2, help="expert demonstrations to export")
    ap.add_argument("--demo-steps", type=int, default=150, help="control steps per demonstration")
    ap.add_argument("--steps", type=int, default=200, help="lerobot-train optimisation steps")
    ap.add_argument("--batch-size", type=int, default=8)
    ap.add_argument("--size", default="64x48", help="camera WxH for export, training and eval (CPU default; 320x180 = DROID)")
    ap.add_argument("--perturbation", default="V-AUG", help="evaluated besides Default")
    ap.add_argument("--eval-episodes", type=int, default=1, help="per (task, perturbation)")
    ap.add_argument("--eval-steps", type=int, default=100, help="control steps per evaluation episode")
    ap.add_argument("--device", default="cpu", help="cpu | cuda")
    ap.add_argument("--threads", type=int, default=None,
                    help="torch CPU threads for training (default 1 on CPU: on a busy 2-core machine 2 threads spin ~8x the CPU time)")
    ap.add_argument("--smoke", action="store_true", help="CI: 1 short demo, 2 training steps, 1 short eval episode per cell")
    args = ap.parse_args(argv)
    if args.smoke:
        args.episodes, args.demo_steps, args.steps, args.batch_size = 1, 10, 2, 4
        args.size, args.eval_episodes, args.eval_steps = "64x48", 1, 5
    args.width, args.height = (int(v) for v in args.size.lower().split("x"))
    return args


def stage(msg: str) -> None:
    print(f"\n=== {msg}", flush=True)


def export(args) -> Path:
    from realm_ms.lerobot.export import ExportConfig, export_dataset

    root = args.out / "dataset"
    stage(f"export {args.episodes} expert demonstration(s) of {args.task} -> {root}")
    export_dataset(ExportConfig(out=root, tasks=[args.task], episodes=args.episodes, width=args.width, height=args.height,
                                max_steps=args.demo_steps, repo_id="realm/train_eval_demos"))
    return root


def train(args, dataset: Path) -> Path:
    run = args.out / "train"
    ckpt = run / "checkpoints" / "last" / "pretrained_model"
    if (ckpt / "model.safetensors").exists():
        stage(f"lerobot-train: checkpoint exists ({ckpt}), skipping")
        return ckpt
    stage(f"lerobot-train ACT (small) for {args.steps} steps on {args.device} -> {run}")
    if run.exists():  # lerobot-train refuses an existing output dir without --resume
        import shutil

        shutil.rmtree(run)
    cmd = [
        sys.executable, "-m", "lerobot.scripts.lerobot_train",
        "--dataset.repo_id=realm/train_eval_demos", f"--dataset.root={dataset}", "--dataset.video_backend=pyav",
        "--policy.type=act", f"--policy.device={args.device}", "--policy.push_to_hub=false",
        "--policy.pretrained_backbone_weights=null", "--policy.dim_model=64", "--policy.n_heads=2",
        "--policy.dim_feedforward=128", "--policy.n_encoder_layers=1", "--policy.n_decoder_layers=1",
        "--policy.n_vae_encoder_layers=1", "--policy.chunk_size=16", "--policy.n_action_steps=8",
        f"--steps={args.steps}", f"--batch_size={args.batch_size}", "--num_workers=0", f"--save_freq={args.steps}",
        f"--log_freq={max(1, args.steps // 10)}", f"--output_dir={run}", "--wandb.enable=false",
        # LeRobot's own in-training evaluation on our env type, once at the end of training
        "--env.type=realm", "--env.discover_packages_path=lerobot_env_realm", f"--env.task={args.task}",
        f"--env.observation_width={args.width}", f"--env.observation_height={args.height}",
        f"--env.episode_length={args.eval_steps}", f"--env_eval_freq={args.steps}", "--eval.n_episodes=1",
        "--eval.batch_size=1", "--eval.use_async_envs=false",
    ]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    threads = args.threads or (1 if args.device == "cpu" else None)
    if threads:
        env["OMP_NUM_THREADS"] = str(threads)
    subprocess.run(cmd, check=True, cwd=ROOT, env=env)
    return ckpt


def evaluate(args, ckpt: Path) -> Path:
    from realm_ms.cli import main as realm

    run = args.out / "eval"
    perts = ["Default"] + ([args.perturbation] if args.perturbation and args.perturbation != "Default" else [])
    stage(f"realm eval --policy lerobot:{ckpt} under {', '.join(perts)} -> {run}")
    rc = realm(["eval", "--policy", f"lerobot:{ckpt}", "--tasks", args.task, "--perturbations", *perts,
                "--episodes", str(args.eval_episodes), "--max-steps", str(args.eval_steps), "--workers", "1",
                "--camera-size", f"{args.width}x{args.height}", "--device", args.device, "--no-progress", "--out", str(run)])
    if rc != 0:
        raise SystemExit(f"realm eval failed (exit {rc})")
    report = run / "report.html"
    rc = realm(["eval", "report", str(run), "--out", str(report)])
    if rc != 0:
        raise SystemExit(f"realm eval report failed (exit {rc})")
    return report


def main(argv=None) -> int:
    args = parse(argv)
    os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
    t0 = time.perf_counter()
    dataset = export(args)
    ckpt = train(args, dataset)
    report = evaluate(args, ckpt)
    print(f"\ntrain-eval loop done in {time.perf_counter() - t0:.0f} s")
    print(f"dataset: {dataset}\ncheckpoint: {ckpt}\nreport: {report.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
