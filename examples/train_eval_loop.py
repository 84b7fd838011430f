"""A learned policy on REALM with LeRobot: expert demos -> `lerobot-train` -> `realm eval` -> fine-tune back.

    .venv/bin/python examples/train_eval_loop.py [--out outputs/train_eval] [--device cpu] [--quick]

Stages (each resumes: rerunning the same command skips finished work):
1. demos      `realm export` of scripted-expert demonstrations, one dataset per task (its episodes over
              `--workers` env processes), seeds from 100000 so evaluation seeds (from 0) are never demo seeds;
2. dataset    LeRobot's `aggregate_datasets` merges them into one training set;
3. train      `lerobot-train` an ACT policy from scratch (nothing can be downloaded) on it; the loss
              curve goes to `learning_curve.csv/.png`; every saved checkpoint is then evaluated on
              validation seeds (from 50000) and the best one is the policy (validation curve beside
              the loss curve);
4. default    `realm eval` of the checkpoint on Default (20 episodes per task, seeds 0-19);
5. table      `realm eval` under all 16 REALM settings (5 episodes per cell; paper-layout table);
6. worst      `realm eval` under the perturbation that hurt most (20 episodes per task);
7. finetune   expert demos under that perturbation, merged with the original demos,
              `lerobot-train --policy.path=CHECKPOINT` on them, checkpoint selection as in 3 (on
              Default and that perturbation), and the evaluation of 4 and 6 for it;
8. report     `realm eval report` of every run and an index with both policies side by side; the
              final table (success with Wilson intervals, fine-tuning delta with Newcombe's interval)
              on stdout and in `summary.json`.

`realm eval` and `realm export` run in this process (``realm()``: the installed command's own
``main``), so the imports and the renderer's set-up are paid once; training is a child process.
`--quick` is the CI variant: every stage with a handful of steps (no success expected).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEMO_SEED = 100_000  # demos use seeds DEMO_SEED + k; evaluation uses seeds from 0
FINETUNE_SEED = 200_000
VALIDATION_SEED = 50_000  # checkpoint selection: episodes neither demonstrated nor in the reported evaluation


@dataclass
class Recipe:
    out: Path = Path("outputs/train_eval")
    tasks: tuple[str, ...] = ("REALM-PickApple-v1", "REALM-OpenDrawer-v1")
    demos: tuple[int, ...] = (60, 40)  # expert demonstrations per task
    demo_max_steps: int = 200
    success_only: bool = True  # keep successful demos only (further seeds replace failures)
    width: int = 64
    height: int = 48
    # ACT trained from scratch, sized for ~1 h on 2 CPU cores
    steps: int = 2000
    batch_size: int = 16
    lr: float = 1e-4
    dim_model: int = 256
    n_heads: int = 4
    dim_feedforward: int = 1024
    n_encoder_layers: int = 2
    chunk_size: int = 20
    n_action_steps: int = 10
    save_freq: int = 1000
    log_freq: int = 50
    # checkpoint selection: every saved checkpoint on validation seeds, the best one is evaluated
    val_episodes: int = 5
    # evaluation
    eval_episodes: int = 20
    table_episodes: int = 5
    table_perturbations: tuple[str, ...] = ("all",)
    eval_max_steps: int = 200  # the demos' horizon
    replan_every: int = 10
    workers: int = 2
    # fine-tuning under the perturbation that hurt most
    finetune_demos: int = 10
    finetune_steps: int = 400
    device: str = "cpu"
    threads: int | None = None
    # data-loader processes for lerobot-train; None: 0 on CPU (the cores train), most cores on a GPU
    loader_workers: int | None = None

    def __post_init__(self):
        # main() pairs tasks with counts: a count missing for a task would drop the task unseen
        if len(self.demos) != len(self.tasks) or min(self.demos, default=0) < 1:
            raise ValueError(f"demos: one count >= 1 per task ({', '.join(map(short, self.tasks))}); "
                             f"got {','.join(map(str, self.demos))}")

    def dataloader_workers(self) -> int:
        if self.loader_workers is not None:
            return self.loader_workers
        return 0 if self.device == "cpu" else max(0, (os.cpu_count() or 1) - 2)

    @classmethod
    def quick(cls, **kw) -> Recipe:
        small = dict(tasks=("REALM-PickApple-v1",), demos=(1,), demo_max_steps=8, success_only=False, steps=2, batch_size=4,
                     dim_model=32, n_heads=2, dim_feedforward=64, n_encoder_layers=1, chunk_size=4, n_action_steps=4,
                     save_freq=2, log_freq=1, val_episodes=1, eval_episodes=1, table_episodes=1,
                     table_perturbations=("Default", "V-AUG"), eval_max_steps=4, replan_every=4, workers=1,
                     finetune_demos=1, finetune_steps=2)
        return cls(**(small | kw))


def short(task: str) -> str:
    return task.removeprefix("REALM-").removesuffix("-v1")


def stage(msg: str) -> None:
    print(f"\n=== {msg}", flush=True)


def child_env(threads: int | None) -> dict:
    """Environment of the `lerobot-train` process; ``threads``: its torch CPU threads."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
               MS_SKIP_ASSET_DOWNLOAD_PROMPT="1")
    if threads:
        env["OMP_NUM_THREADS"] = str(threads)
    return env


# ---------------------------------------------------------------- demos and dataset


def export_demos(r: Recipe, jobs: list[tuple[str, str, int, int, Path]]) -> list[Path]:
    """Expert demos, one `realm export` per (task, perturbation, episodes, seed, root), each over
    ``r.workers`` env processes (`realm export --workers`, the eval driver's own pool; with one worker
    the episodes run in this process, beside the evaluations' renderer)."""
    for task, pert, n, seed, root in jobs:
        root.parent.mkdir(parents=True, exist_ok=True)
        with one_torch_thread():
            rc = realm(["export", "--tasks", task, "--perturbations", pert, "--episodes", str(n), "--seed", str(seed),
                        "--width", str(r.width), "--height", str(r.height), "--max-steps", str(r.demo_max_steps),
                        "--workers", str(r.workers), "--out", str(root), "--repo-id", f"realm/{root.name}"]
                       + (["--success-only"] if r.success_only else []))
        if rc != 0:
            raise SystemExit(f"realm export into {root} failed (exit {rc})")
    return [j[4] for j in jobs]


def merge(roots: list[Path], out: Path, repo_id: str) -> Path:
    """One training set from several exports (LeRobot's own aggregation); redone when a source grew."""
    from lerobot.datasets.aggregate import aggregate_datasets

    want = sum(json.loads((s / "meta" / "info.json").read_text())["total_episodes"] for s in roots)
    info = out / "meta" / "info.json"
    if info.exists() and json.loads(info.read_text())["total_episodes"] == want:
        return out
    shutil.rmtree(out, ignore_errors=True)
    aggregate_datasets([f"realm/{s.name}" for s in roots], repo_id, roots=roots, aggr_root=out)
    return out


# ---------------------------------------------------------------- training


def checkpoint_step(run: Path) -> int:
    f = run / "checkpoints" / "last" / "training_state" / "training_step.json"
    return json.loads(f.read_text())["step"] if f.exists() else 0


def train(r: Recipe, dataset: Path, run: Path, steps: int, init: Path | None = None, save_freq: int | None = None) -> Path:
    """`lerobot-train` ACT on ``dataset`` (from ``init`` when fine-tuning); resumes an interrupted run."""
    from tqdm import tqdm

    ckpt = run / "checkpoints" / "last" / "pretrained_model"
    done = checkpoint_step(run)
    if done >= steps:
        print(f"checkpoint at step {done} exists ({ckpt}), skipping")
        return ckpt
    log = run.parent / f"{run.name}.log"
    if done:
        cmd = ["--resume=true", f"--config_path={ckpt / 'train_config.json'}"]
    else:
        shutil.rmtree(run, ignore_errors=True)  # lerobot-train refuses an existing output dir without --resume
        log.unlink(missing_ok=True)
        policy = ([f"--policy.path={init}"] if init else [
            "--policy.type=act", "--policy.pretrained_backbone_weights=null", f"--policy.dim_model={r.dim_model}",
            f"--policy.n_heads={r.n_heads}", f"--policy.dim_feedforward={r.dim_feedforward}",
            f"--policy.n_encoder_layers={r.n_encoder_layers}", "--policy.n_decoder_layers=1",
            "--policy.n_vae_encoder_layers=1", f"--policy.chunk_size={r.chunk_size}",
            f"--policy.n_action_steps={r.n_action_steps}"])
        cmd = policy + [
            f"--dataset.repo_id=realm/{dataset.name}", f"--dataset.root={dataset}", "--dataset.video_backend=pyav",
            f"--policy.device={r.device}", "--policy.push_to_hub=false", f"--policy.optimizer_lr={r.lr}",
            f"--policy.optimizer_lr_backbone={r.lr}", f"--steps={steps}", f"--batch_size={r.batch_size}",
            f"--num_workers={r.dataloader_workers()}", f"--save_freq={save_freq or r.save_freq}", f"--log_freq={r.log_freq}", f"--output_dir={run}",
            "--wandb.enable=false"]
    cmd = [sys.executable, "-m", "realm_ms.lerobot.train"] + cmd  # lerobot-train, frames decoded once
    with open(log, "a") as f, tqdm(total=steps, initial=done, desc=f"lerobot-train {run.name}", unit="step") as bar:
        f.write(f"# {' '.join(cmd)}\n# start step {done}\n")
        f.flush()
        threads = r.threads or (os.cpu_count() if r.device == "cpu" else None)
        p = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=ROOT, env=child_env(threads))
        while p.poll() is None:
            time.sleep(2)
            curve = learning_curve(log, r.log_freq)
            if curve:
                bar.n = curve[-1]["step"]
                bar.set_postfix(loss=f"{curve[-1]['loss']:.3f}")
                bar.refresh()
    if p.returncode != 0:
        raise SystemExit(f"lerobot-train failed (exit {p.returncode}); see {log}")
    return ckpt


LOG_LINE = re.compile(r"step:\S+ .*?\bloss:([0-9.eE+-]+).*?l1_loss:([0-9.eE+-]+)")


def learning_curve(log: Path, log_freq: int) -> list[dict]:
    """Loss per logged step from a `lerobot-train` log. LeRobot prints steps rounded ("5K"), so the
    step is counted from each segment's start step (a resumed run writes a new "# start step")."""
    rows, step = [], 0
    if not log.exists():
        return rows
    for line in log.read_text(errors="replace").splitlines():
        if line.startswith("# start step"):
            step = int(line.split()[-1])
        elif m := LOG_LINE.search(line):
            step += log_freq
            rows.append({"step": step, "loss": float(m.group(1)), "l1_loss": float(m.group(2))})
    return rows


def plot_curves(curves: dict[str, list[dict]], validation: dict[str, list[dict]], out: Path) -> None:
    """Training L1 loss per step (left) and each checkpoint's validation success and progression (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, av) = plt.subplots(1, 2, figsize=(11, 3.8))
    for name, rows in validation.items():
        steps = [x["step"] for x in rows]
        av.plot(steps, [x["successes"] / max(1, x["episodes"]) for x in rows], "o-", label=f"{name}: success")
        av.plot(steps, [x["progression"] for x in rows], "s--", label=f"{name}: progression")
    av.set_xlabel("checkpoint step")
    av.set_ylabel("validation episodes")
    av.set_ylim(-0.02, 1.02)
    av.grid(alpha=0.3)
    av.legend(fontsize=8)
    for name, rows in curves.items():
        if rows:
            ax.plot([x["step"] for x in rows], [x["l1_loss"] for x in rows], label=f"{name}: L1 (action chunk)")
    ax.set_yscale("log")
    ax.set_xlabel("optimisation step")
    ax.set_ylabel("training L1 loss (normalised actions)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


# ---------------------------------------------------------------- evaluation


def realm(argv: list[str], quiet: bool = False) -> int:
    """The ``realm`` command with ``argv``, run in this process: the same parser and code as the installed
    script, while the imports and the renderer (whose first picture costs seconds on a CPU) are paid
    once for every evaluation of the recipe instead of once per command."""
    import io

    from realm_ms.cli import main as realm_main

    with contextlib.redirect_stdout(io.StringIO()) if quiet else contextlib.nullcontext():
        return realm_main(argv)


@contextlib.contextmanager
def one_torch_thread():
    """This process's torch on one CPU thread while the env processes beside it run on the other cores."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def evaluate(r: Recipe, ckpt: Path, run: Path, perturbations: list[str], episodes: int, seed: int = 0) -> Path:
    """`realm eval` of the checkpoint into ``run`` (resumes it); the policy on one torch thread."""
    with one_torch_thread():
        rc = realm([
            "eval", "--policy", f"lerobot:{ckpt}", "--tasks", *r.tasks, "--perturbations", *perturbations,
            "--episodes", str(episodes), "--seed", str(seed), "--max-steps", str(r.eval_max_steps),
            "--replan-every", str(r.replan_every), "--workers", str(r.workers), "--camera-size", f"{r.width}x{r.height}",
            "--device", r.device, "--out", str(run)])
    if rc != 0:
        raise SystemExit(f"realm eval into {run} failed (exit {rc})")
    return run


def select_checkpoint(r: Recipe, train_run: Path, perturbations: list[str], out: Path) -> tuple[Path, list[dict]]:
    """Every checkpoint ``train_run`` saved, evaluated on validation seeds (``VALIDATION_SEED`` on); the
    best by success, then mean progression, then the later step. Returns it and the validation curve."""
    rows = []
    for d in sorted(p for p in (train_run / "checkpoints").iterdir() if p.name.isdigit()):
        run = evaluate(r, d / "pretrained_model", out / f"val_{train_run.name}_{d.name}", perturbations, r.val_episodes,
                       seed=VALIDATION_SEED)
        o = run_metrics(run)["overall"]
        rows.append({"step": int(d.name), "checkpoint": str(d / "pretrained_model"), "episodes": o["episodes"],
                     "successes": o["successes"], "progression": o["mean_progression"]})
    best = max(rows, key=lambda x: (x["successes"] / max(1, x["episodes"]), x["progression"], x["step"]))
    print(f"validation ({r.val_episodes} episodes per task and setting, seeds from {VALIDATION_SEED}): "
          + ", ".join(f"step {x['step']}: {x['successes']}/{x['episodes']} prog {x['progression']:.2f}" for x in rows)
          + f" -> step {best['step']}")
    return Path(best["checkpoint"]), rows


def run_metrics(run: Path) -> dict:
    """The run's metrics (`realm eval`'s own aggregation, as in its metrics.json)."""
    from realm_ms.eval.metrics import compute_metrics
    from realm_ms.eval.records import read_records

    return compute_metrics(read_records(run / "records.jsonl"))


def cell_counts(run: Path) -> dict[tuple[str, str], tuple[int, int]]:
    """(task, perturbation) -> (successes, episodes) over the run's finished records."""
    return {(t, p): (c["successes"], c["episodes"]) for t, cells in run_metrics(run)["per_cell"].items()
            for p, c in cells.items()}


def observable(perturbation: str, language: bool) -> bool:
    """Whether a policy can see the perturbation: S-* and SB-* change the task only through the
    instruction, which a policy without a language input (ACT) never reads, so no demonstration can
    teach it those; every other factor changes what the cameras or the robot see (a composition is
    observable when any of its parts is)."""
    return language or any(not part.startswith("S") for part in perturbation.split("+"))


def worst_perturbation(table: Path, language: bool) -> str:
    """The perturbation the policy can observe (``observable``) with the lowest success rate over the
    tasks (ties: lowest mean progression)."""
    from realm_ms.task_index import DEFAULT

    per = {p: m for p, m in run_metrics(table)["per_perturbation"].items() if p != DEFAULT and observable(p, language)}
    if not per:
        raise SystemExit(f"no perturbed episodes in {table}: cannot choose the perturbation to fine-tune on")
    return min(per, key=lambda p: (per[p]["success_rate"], per[p]["mean_progression"]))


# ---------------------------------------------------------------- summary


def rate(k: int, n: int) -> str:
    from realm_ms.eval.metrics import wilson_interval

    lo, hi = wilson_interval(k, n)
    return f"{k}/{n} = {k / n:.0%} [{lo:.0%}, {hi:.0%}]" if n else "-"


def summarize(tasks, worst: str, table, base, tuned) -> dict:
    """Success per task (Wilson 95 %) for both policies on Default and ``worst``, the fine-tuning delta
    (Newcombe 95 %), and the 16-setting table of the base policy."""
    from realm_ms.eval.metrics import difference_interval

    rows = []
    for t in tasks:
        for p in ("Default", worst):
            (kb, nb), (kt, nt) = base.get((t, p), (0, 0)), tuned.get((t, p), (0, 0))
            lo, hi = difference_interval(kb, nb, kt, nt) if nb and nt else (float("nan"),) * 2
            rows.append({"task": t, "perturbation": p, "base": [kb, nb], "finetuned": [kt, nt],
                         "delta": (kt / nt - kb / nb) if nb and nt else None, "delta_interval": [lo, hi]})
    perts = sorted({p for _, p in table}, key=lambda p: (p != "Default", p))
    return {"worst_perturbation": worst, "rows": rows,
            "table": {t: {p: list(table.get((t, p), (0, 0))) for p in perts} for t in tasks}}


def write_summary(summary: dict, path: Path) -> str:
    """``summary.json`` and the text printed at the end of the run."""
    path.write_text(json.dumps(summary, indent=1))
    lines = ["success [95% Wilson]; fine-tuning delta [95% Newcombe]",
             f"{'task':<12} {'setting':<10} {'base':<24} {'fine-tuned':<24} delta"]
    for x in summary["rows"]:
        lo, hi = x["delta_interval"]
        delta = f"{x['delta']:+.0%} [{lo:+.0%}, {hi:+.0%}]" if x["delta"] is not None else "-"
        lines.append(f"{short(x['task']):<12} {x['perturbation']:<10} {rate(*x['base']):<24} {rate(*x['finetuned']):<24} {delta}")
    table = summary["table"]
    perts = list(next(iter(table.values()))) if table else []
    lines += ["", "base policy, success k/n under each setting:", f"{'setting':<12}" + "".join(f"{short(t):>12}" for t in table)]
    lines += [f"{p:<12}" + "".join(f"{'%d/%d' % tuple(table[t][p]):>12}" for t in table) for p in perts]
    return "\n".join(lines)


# ---------------------------------------------------------------- main


def parse(argv=None) -> Recipe:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    from realm_ms.validate import InputError, check_device, check_output_dir, integer

    # every flag is checked here, before any stage runs (a bad one used to surface after hours of work)
    ap.add_argument("--out", type=Path, default=Recipe.out, help="output directory (default outputs/train_eval)")
    ap.add_argument("--device", default="cpu", help="torch device for training and the policy: cpu | cuda")
    ap.add_argument("--threads", type=integer(1), default=None, help="torch CPU threads for training (default: all cores)")
    ap.add_argument("--steps", type=integer(1), default=None, help="training steps (default 2000; --quick 2)")
    ap.add_argument("--workers", type=integer(1), default=None, help="parallel env processes for realm eval and realm export (default 2)")
    ap.add_argument("--batch-size", type=integer(1), default=None, help="training batch size (default 16)")
    ap.add_argument("--camera-size", default=None, metavar="WxH",
                    help="camera size of the demos, training and eval (default 64x48; 128x96 localises better, ~4x the compute)")
    ap.add_argument("--loader-workers", type=integer(0), default=None,
                    help="data-loader processes for training (default: 0 on cpu, all cores but 2 on cuda)")
    ap.add_argument("--demos", default=None, metavar="N,N",
                    help="expert demonstrations per task, one count per task (default 60,40)")
    ap.add_argument("--quick", action="store_true", help="CI: every stage with a handful of steps (no success expected)")
    a = ap.parse_args(argv)
    try:
        check_device(a.device)
        check_output_dir(a.out, "--out")
    except InputError as e:
        ap.error(str(e))
    from realm_ms.errors import UserError
    from realm_ms.eval.cli import parse_camera_size  # the check `realm eval --camera-size` applies

    try:
        a.width, a.height = parse_camera_size(a.camera_size) or (None, None)
    except UserError as e:
        ap.error(str(e))
    if a.demos is not None:
        try:
            a.demos = tuple(int(x) for x in a.demos.split(","))
        except ValueError:
            ap.error(f"--demos {a.demos!r}: give whole numbers separated by commas, e.g. 60,40")
    kw = {k: v for k, v in (("out", a.out), ("device", a.device), ("threads", a.threads), ("steps", a.steps),
                            ("workers", a.workers), ("batch_size", a.batch_size),
                            ("loader_workers", a.loader_workers), ("width", a.width), ("demos", a.demos),
                            ("height", a.height)) if v is not None}
    try:
        return Recipe.quick(**kw) if a.quick else Recipe(**kw)
    except ValueError as e:  # the recipe's own check (one demo count per task)
        ap.error(f"--{e}")


def main(argv=None) -> int:
    r = parse(argv)
    out = r.out
    out.mkdir(parents=True, exist_ok=True)
    times: dict[str, float] = json.loads((out / "timings.json").read_text()) if (out / "timings.json").exists() else {}

    def timed(name, fn, *a, **kw):
        t0 = time.perf_counter()
        result = fn(*a, **kw)
        times[name] = times.get(name, 0.0) + time.perf_counter() - t0
        (out / "timings.json").write_text(json.dumps(times, indent=1))
        return result

    stage(f"1/8 expert demos: {', '.join(f'{n} x {short(t)}' for t, n in zip(r.tasks, r.demos))} at {r.width}x{r.height}")
    demo_roots = timed("demos", export_demos, r, [(t, "Default", n, DEMO_SEED, out / "demos" / f"demos_{short(t)}")
                                                 for t, n in zip(r.tasks, r.demos)])
    stage("2/8 one training set (LeRobot aggregate_datasets)")
    dataset = timed("dataset", merge, demo_roots, out / "dataset", "realm/dataset")
    stage(f"3/8 lerobot-train ACT from scratch, {r.steps} steps on {r.device}")
    timed("train", train, r, dataset, out / "train", r.steps)
    ckpt, val = timed("validate", select_checkpoint, r, out / "train", ["Default"], out / "eval")
    stage(f"4/8 realm eval on Default, {r.eval_episodes} episodes per task")
    default = timed("default", evaluate, r, ckpt, out / "eval" / "default", ["Default"], r.eval_episodes)
    stage(f"5/8 realm eval: the 16-setting table, {r.table_episodes} episodes per cell")
    table = timed("table", evaluate, r, ckpt, out / "eval" / "table", list(r.table_perturbations), r.table_episodes)
    worst = worst_perturbation(table, language=False)  # ACT takes no instruction
    stage(f"6/8 realm eval under {worst} (hurt most), {r.eval_episodes} episodes per task")
    base_worst = timed("worst", evaluate, r, ckpt, out / "eval" / "worst", [worst], r.eval_episodes)
    stage(f"7/8 fine-tune: expert demos under {worst} + the original demos, {r.finetune_steps} steps from the checkpoint")
    tag = worst.replace("+", "_")
    ft_roots = timed("finetune_demos", export_demos, r, [
        (t, worst, r.finetune_demos, FINETUNE_SEED, out / "demos" / f"demos_{short(t)}_{tag}") for t in r.tasks])
    ft_data = timed("finetune_dataset", merge, demo_roots + ft_roots, out / f"dataset_{tag}", f"realm/dataset_{tag}")
    timed("finetune", train, r, ft_data, out / "finetune", r.finetune_steps, init=ckpt,
          save_freq=max(1, r.finetune_steps // 2))
    ft_ckpt, ft_val = timed("finetune_validate", select_checkpoint, r, out / "finetune", ["Default", worst], out / "eval")
    tuned = timed("finetuned", evaluate, r, ft_ckpt, out / "eval" / "finetuned", ["Default", worst], r.eval_episodes)
    stage("8/8 reports")
    curves = {"train": learning_curve(out / "train.log", r.log_freq),
              "finetune": learning_curve(out / "finetune.log", r.log_freq)}
    with open(out / "learning_curve.csv", "w") as f:
        f.write("run,step,loss,l1_loss\n")
        f.writelines(f"{n},{x['step']},{x['loss']},{x['l1_loss']}\n" for n, rows in curves.items() for x in rows)
    plot_curves(curves, {"train (Default)": val, f"finetune (Default + {worst})": ft_val}, out / "learning_curve.png")
    for run in (default, table, base_worst, tuned):
        if realm(["eval", "report", str(run)], quiet=True) != 0:
            raise SystemExit(f"realm eval report {run} failed")
    index = out / "report.html"
    # both policies side by side (the base policy's Default and worst-perturbation runs, the fine-tuned one)
    from realm_ms.eval.report import write_index

    write_index([default, base_worst, tuned], index, names=["base: Default", f"base: {worst}", "fine-tuned"],
                title=f"ACT trained on expert demos, and fine-tuned under {worst}")
    summary = summarize(r.tasks, worst, cell_counts(table), cell_counts(default) | cell_counts(base_worst),
                        cell_counts(tuned))
    summary.update(recipe={k: (str(v) if isinstance(v, Path) else v) for k, v in dataclasses.asdict(r).items()},
                   wall_s={k: round(v) for k, v in times.items()}, validation={"train": val, "finetune": ft_val},
                   final_l1_loss=curves["train"][-1]["l1_loss"] if curves["train"] else None)
    text = write_summary(summary, out / "summary.json")
    print("\n" + text)
    print(f"\nreport: {index.resolve()}\ncheckpoints: {ckpt} (base), {ft_ckpt} (fine-tuned)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
