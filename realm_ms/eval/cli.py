"""``realm eval``: run a policy under the REALM protocol (resumable), and ``realm eval report``.

    realm eval --policy {expert|zero|random|lerobot:PATH_OR_ID|openpi:HOST:PORT} --tasks ID ... \\
        [--perturbations NAME ...] --episodes N [--seed S] [--max-steps N] [--workers N] --out RUN/
    realm eval report RUN/ --out report.html

Re-running the same command resumes: finished episodes in ``RUN/records.jsonl`` are skipped.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from realm_ms.eval.protocol import PRESETS


def add_parser(sub) -> None:
    p = sub.add_parser("eval", help="evaluate a policy under the REALM protocol; `realm eval report RUN/` for the report")
    p.add_argument("--policy", help="expert | zero | random | lerobot:PATH_OR_ID | openpi:HOST:PORT")
    p.add_argument("--protocol", choices=sorted(PRESETS), default="realm", help="preset the other flags override (default realm)")
    p.add_argument("--tasks", nargs="+", help="env ids, or 'all' (default: the protocol's)")
    p.add_argument("--perturbations", nargs="+", help="names (e.g. Default V-AUG), or 'all' (default: the protocol's)")
    p.add_argument("--episodes", type=int, help="episodes per (task, perturbation) cell (REALM: 25)")
    p.add_argument("--seed", type=int, help="base seed; episode i uses seed + i (REALM: 1234)")
    p.add_argument("--max-steps", type=int, help="control steps per episode (REALM: 800)")
    p.add_argument("--replan-every", type=int, help="actions executed open-loop per policy call (REALM: 8)")
    from realm_ms.validate import integer

    p.add_argument("--workers", type=integer(1), default=None, help="parallel env processes, >= 1 (default: CPU cores, at most 16)")
    p.add_argument("--backend", choices=("auto", "cpu", "gpu", "batched"), default="auto",
                   help="cpu = --workers processes; gpu = ManiSkill GPU simulation, one env of --workers sub-envs (needs SAPIEN GPU PhysX); "
                        "batched = the GPU runner, on CPU physics where GPU PhysX is missing; auto = gpu where it works, else cpu")
    p.add_argument("--ray-address", default=None, help="shard cells over Ray: 'local', 'auto' or ray://HOST:PORT")
    p.add_argument("--camera-size", default=None, help="WxH of the observed camera frames (default 320x180)")
    p.add_argument("--videos", choices=("none", "failures", "all"), default="none", help="exterior + wrist mp4 per episode")
    p.add_argument("--openpi-format", choices=("pi0", "groot"), default="pi0", help="openpi request keys/resolution")
    p.add_argument("--openpi-wait", type=float, default=30.0, help="seconds to retry a down openpi server before failing the episode")
    p.add_argument("--device", default="cpu", help="torch device for LeRobot policies")
    p.add_argument("--no-quality", action="store_true", help="skip trajectory-quality metrics (contacts walk per step)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--out", type=Path, help="run directory (records.jsonl, metrics.json)")
    rsub = p.add_subparsers(dest="eval_command", metavar="report")
    r = rsub.add_parser("report", help="HTML report (+ PNGs, markdown/CSV table) of a run directory")
    r.add_argument("run_dir", type=Path, help="run directory written by `realm eval`")
    r.add_argument("--out", dest="report_out", type=Path, default=None, help="HTML file (default RUN/report.html)")
    r.add_argument("--videos", dest="report_videos", choices=("none", "failures", "all"), default="failures", help="which episode videos to link")
    r.add_argument("--reference", default=None, help="also tabulate REALM's paper numbers for a policy (pi0, pi0-FAST, GR00T)")
    p.set_defaults(func=run)


def _parse_size(text: str | None) -> tuple[int, int] | None:
    from realm_ms.errors import UserError

    if not text:
        return None
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UserError(f"--camera-size must be WxH (e.g. 320x180), got {text!r}") from None
    if not (8 <= w <= 4096 and 8 <= h <= 4096):
        raise UserError(f"--camera-size {text}: width and height must be in [8, 4096]")
    return w, h


def resolve(args):
    """(protocol, tasks, perturbations) from the preset and flags, validated with clear errors."""
    from realm_ms.errors import UserError
    from realm_ms.eval.protocol import available_perturbations, canonical_perturbation
    from realm_ms.tasks import TASKS

    proto = PRESETS[args.protocol].with_overrides(
        episodes=args.episodes, seed=args.seed, max_steps=args.max_steps, replan_every=args.replan_every
    )
    for name in ("episodes", "max_steps", "replan_every"):
        if getattr(proto, name) < 1:
            raise UserError(f"--{name.replace('_', '-')} must be >= 1")
    tasks = args.tasks or (list(proto.tasks) if proto.tasks else ["all"])
    tasks = sorted(TASKS) if tasks == ["all"] else tasks
    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise UserError(f"unknown task(s) {', '.join(unknown)}; known: {', '.join(sorted(TASKS))}")
    avail = available_perturbations()
    perts = args.perturbations or (list(proto.perturbations) if proto.perturbations else ["all"])
    if perts == ["all"]:
        perts = avail
    else:
        out = []
        for p in perts:
            try:
                out.append(canonical_perturbation(p))
            except ValueError as e:  # UnknownNameError lists the known names
                if args.perturbations:
                    raise UserError(str(e)) from None
        perts = out or ["Default"]  # a preset's names that are not registered here are skipped
    return proto, list(dict.fromkeys(tasks)), list(dict.fromkeys(perts))


def run(args) -> int:
    from realm_ms.errors import UserError

    if args.eval_command == "report":
        return run_report(args)
    if not args.policy:
        raise UserError("--policy is required (expert | zero | random | lerobot:PATH_OR_ID | openpi:HOST:PORT)")
    if not args.out:
        raise UserError("--out RUN/ is required")
    os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
    proto, tasks, perts = resolve(args)
    return evaluate(
        args.policy, tasks, perts, proto, args.out, workers=args.workers, backend=args.backend, ray_address=args.ray_address,
        camera_size=_parse_size(args.camera_size), videos=args.videos, quality=not args.no_quality, progress=not args.no_progress,
        policy_options=dict(openpi_format=args.openpi_format, openpi_wait_s=args.openpi_wait, device=args.device),
    )


def evaluate(policy_spec: str, tasks, perturbations, proto, out: Path, workers: int | None = None, backend: str = "auto",
             ray_address: str | None = None, camera_size=None, videos: str = "none", quality: bool = True,
             progress: bool = True, policy_options: dict | None = None, env_kwargs: dict | None = None, quiet: bool = False) -> int:
    """Programmatic ``realm eval`` (used by the CLI, the demo and the expert bench)."""
    from realm_ms.errors import UserError
    from realm_ms.eval.metrics import compute_metrics
    from realm_ms.eval.policies import make_policy
    from realm_ms.eval.protocol import plan
    from realm_ms.eval.records import RecordWriter, read_records
    from realm_ms.eval.runner import RunConfig, default_workers, run_plan
    from realm_ms.eval.workers import choose_backend, run_ray
    from realm_ms.registry import UnknownNameError

    policy_options = policy_options or {}
    try:
        policy = make_policy(policy_spec, **policy_options)
    except (ValueError, OSError, UnknownNameError, ImportError) as e:
        raise UserError(f"cannot load policy {policy_spec!r}: {e}") from None
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    meta_path = out / "run.json"
    meta = dict(policy=policy.spec(), protocol=proto.name, tasks=tasks, perturbations=perturbations, episodes=proto.episodes,
                seed=proto.seed, max_steps=proto.max_steps, replan_every=proto.replan_every, success_tail=proto.success_tail)
    if meta_path.exists():
        old = json.loads(meta_path.read_text())
        for k in ("policy", "max_steps", "replan_every"):
            if old.get(k) != meta[k]:
                raise UserError(f"{out} holds a run with {k}={old.get(k)!r}, this command has {meta[k]!r}: use another --out")
    meta_path.write_text(json.dumps(meta, indent=2))
    req = policy.obs_request()
    if camera_size:
        req.width, req.height = camera_size
    cfg = RunConfig(policy=policy.spec(), env_side=policy.env_side, max_steps=proto.max_steps, replan_every=proto.replan_every,
                    success_tail=proto.success_tail, obs=req, videos=videos, videos_dir=str(out / "videos"), quality=quality,
                    env_kwargs=env_kwargs or {})
    writer = RecordWriter(out / "records.jsonl")
    done = writer.finished_keys()
    keys = [k for k in plan(tasks, perturbations, proto.episodes, proto.seed) if k not in done]
    if not quiet:
        print(f"realm eval: {policy.spec()} on {len(tasks)} task(s) x {len(perturbations)} perturbation(s) x {proto.episodes} episode(s); "
              f"{len(done)} already done, {len(keys)} to run -> {out}/", file=sys.stderr)
    n_workers = workers or default_workers()
    try:
        if keys and ray_address:
            run_ray(keys, policy.spec(), policy_options, cfg, ray_address, writer.append, progress_bar=progress)
        elif keys:
            try:
                be = choose_backend(backend, cfg, min(n_workers, len(keys)))
            except RuntimeError as e:
                raise UserError(str(e)) from None
            try:
                run_plan(keys, policy, be, writer.append, progress_bar=progress, replan_every=proto.replan_every)
            finally:
                be.close()
    finally:
        writer.close()
        policy.close()
        metrics = compute_metrics(read_records(out / "records.jsonl"))
        (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    o = metrics["overall"]
    if not quiet:
        print(f"{o['episodes']} episodes: success {o['success_rate']:.3f} [{o['success_ci'][0]:.3f}, {o['success_ci'][1]:.3f}], "
              f"progression {o['mean_progression']:.3f}; errors {len(metrics['errors'])}; metrics in {out / 'metrics.json'}")
    return 0


def run_report(args) -> int:
    from realm_ms.errors import UserError
    from realm_ms.eval.report import write_report

    if not (args.run_dir / "records.jsonl").exists():
        raise UserError(f"{args.run_dir} has no records.jsonl (run `realm eval ... --out {args.run_dir}` first)")
    path = write_report(args.run_dir, args.report_out or args.run_dir / "report.html", videos=args.report_videos, reference=args.reference)
    print(f"wrote {path}")
    return 0
