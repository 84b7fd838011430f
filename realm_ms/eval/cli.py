"""``realm eval``: run a policy under the REALM protocol (resumable), and ``realm eval report``.

    realm eval --policy {expert|zero|random|lerobot:PATH_OR_ID|openpi:HOST:PORT|roboarena:HOST:PORT} --tasks ID ... \\
        [--perturbations NAME ...] --episodes N [--seed S] [--max-steps N] [--workers N] --out RUN/
    realm eval report RUN/ --out report.html

Re-running the same command resumes: finished episodes in ``RUN/records.jsonl`` are skipped.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from realm_ms.eval.protocol import DEFAULT, PRESETS

MAX_EPISODES = 100_000  # per (task, perturbation) cell; REALM runs 25


def add_parser(sub) -> None:
    p = sub.add_parser("eval", help="evaluate a policy under the REALM protocol; `realm eval report RUN/` for the report",
                       usage="realm eval --policy SPEC --out RUN/ [options]\n       realm eval report RUN/ [--out FILE] [--videos ...] [--reference POLICY]")
    p.add_argument("--policy", help="required: expert | zero | random | lerobot:PATH_OR_ID | openpi:HOST:PORT[,HOST:PORT...] | "
                   "roboarena:HOST:PORT[,HOST:PORT...]")
    p.add_argument("--protocol", choices=sorted(PRESETS), default="realm", help="preset the other flags override (default realm)")
    p.add_argument("--tasks", nargs="+", help="env ids, or 'all' (default: the protocol's)")
    p.add_argument("--perturbations", nargs="+", help="names (e.g. Default V-AUG), or 'all' (default: the protocol's)")
    p.add_argument("--episodes", type=int, help="episodes per (task, perturbation) cell (REALM: 25)")
    from realm_ms.validate import integer, positive, seed

    p.add_argument("--seed", type=seed(), help="base seed, an integer in [0, 2**32); episode i uses seed + i (REALM: 1234)")
    p.add_argument("--max-steps", type=int, help="control steps per episode (REALM: 800)")
    p.add_argument("--replan-every", type=int, help="actions executed open-loop per policy call (REALM: 8)")

    p.add_argument("--workers", type=integer(1), default=None, help="parallel env processes, >= 1 (default: CPU cores, at most 16)")
    p.add_argument("--backend", choices=("auto", "cpu", "gpu", "batched"), default="auto",
                   help="cpu = --workers processes; gpu = ManiSkill GPU simulation, one env of --workers sub-envs (needs SAPIEN GPU PhysX); "
                        "batched = the GPU runner, on CPU physics where GPU PhysX is missing; auto = gpu where it works, else cpu")
    p.add_argument("--ray-address", default=None, help="shard cells over Ray: 'local', 'auto' or ray://HOST:PORT")
    p.add_argument("--camera-size", default=None, help="WxH of the observed camera frames (default 320x180)")
    p.add_argument("--videos", choices=("none", "failures", "all"), default="none", help="exterior + wrist mp4 per episode")
    p.add_argument("--openpi-format", choices=("pi0", "groot"), default="pi0", help="openpi request keys/resolution")
    p.add_argument("--openpi-wait", type=positive("s"), default=30.0,
                   help="seconds (finite, > 0) to retry a down policy server (openpi or RoboArena) before failing the episode")
    p.add_argument("--policy-latency", type=_latency, default="0",
                   help="the real robot's clock: the arm keeps tracking its previous target for the policy's latency before each new "
                        "chunk: 0 (default, time stops during inference, as REALM), SECONDS, or 'measured' (each request's wall time)")
    p.add_argument("--action-space", default=None, help="DROID action space the policy acts in: joint_position (default) | joint_velocity | "
                   "cartesian_velocity | cartesian_position, optionally :position or :velocity for the gripper (e.g. joint_velocity:position, "
                   "pi0-FAST-DROID); default: what an openpi server's metadata declares (a RoboArena server's config decides)")
    p.add_argument("--robot-model", default=None, metavar="NAME|MODEL.yaml",
                   help="robot the envs run: a named model (droid-aligned) or a MODEL.yaml from `realm sysid fit` "
                        "(default: the nominal DROID robot)")
    p.add_argument("--device", default="cpu", help="torch device for LeRobot policies")
    p.add_argument("--no-quality", action="store_true", help="skip trajectory-quality metrics (contacts walk per step)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--out", type=Path, help="required: run directory (run.json, records.jsonl, metrics.json); the same --out resumes")
    rsub = p.add_subparsers(dest="eval_command", title="report a finished run", metavar="report RUN/")
    r = rsub.add_parser("report", prog="realm eval report",
                        help="HTML report (+ PNGs, markdown/CSV table) of a run directory; several: one index comparing them")
    r.add_argument("run_dir", type=Path, nargs="+", metavar="RUN",
                   help="run directory written by `realm eval`; give several (one policy each) for an index page comparing them")
    r.add_argument("--out", dest="report_out", type=Path, default=None,
                   help="HTML file (default RUN/report.html; required with several RUN)")
    r.add_argument("--videos", dest="report_videos", choices=("none", "failures", "all"), default="failures", help="which episode videos to link")
    r.add_argument("--reference", default=None, help="also tabulate REALM's paper numbers for a policy (pi0, pi0-FAST, GR00T)")
    p.set_defaults(func=run)


def parse_camera_size(text: str | None) -> tuple[int, int] | None:
    """``--camera-size WxH`` -> (width, height); None when not given. Bad text raises ``UserError``."""
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
    if proto.episodes > MAX_EPISODES:  # the plan lists every episode: 10**9 would never start
        raise UserError(f"--episodes {proto.episodes}: at most {MAX_EPISODES} per (task, perturbation) cell")
    from realm_ms.validate import check_seed

    check_seed(proto.seed, "--seed", proto.episodes)  # every episode's seed + i, not only the first
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
        perts = out or [DEFAULT]  # a preset's names that are not registered here are skipped
    return proto, list(dict.fromkeys(tasks)), list(dict.fromkeys(perts))


def run(args) -> int:
    from realm_ms.errors import UserError

    if args.eval_command == "report":
        return run_report(args)
    if not args.policy:
        raise UserError("--policy is required (expert | zero | random | lerobot:PATH_OR_ID | openpi:HOST:PORT | roboarena:HOST:PORT)")
    if not args.out:
        raise UserError("--out RUN/ is required")
    from realm_ms.eval.rundir import check_run_paths

    check_run_paths(args.out, args.videos)  # before a policy loads or an env is built
    check_policy_spec(args.policy)
    env_kwargs = robot_model_kwargs(args.robot_model)
    if args.ray_address:
        from realm_ms.eval.backends.ray import check_ray_address

        check_ray_address(args.ray_address)
    os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
    proto, tasks, perts = resolve(args)
    from realm_ms.eval.evaluation import evaluate

    return evaluate(
        args.policy, tasks, perts, proto, args.out, workers=args.workers, backend=args.backend, ray_address=args.ray_address,
        camera_size=parse_camera_size(args.camera_size), videos=args.videos, quality=not args.no_quality, progress=not args.no_progress,
        policy_options=dict(openpi_format=args.openpi_format, openpi_wait_s=args.openpi_wait, device=args.device, action_space=args.action_space),
        policy_latency=args.policy_latency,
        env_kwargs=env_kwargs,
    )


def _latency(text: str) -> str:
    """argparse type of ``--policy-latency`` (``latency.parse_latency``)."""
    import argparse

    from realm_ms.eval.latency import parse_latency

    try:
        return parse_latency(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("--policy-latency: ")) from None


def robot_model_kwargs(robot_model: str | None, flag: str = "--robot-model") -> dict:
    """``{"robot_model": ...}`` for a robot model that loads (checked here, before any env is built),
    ``{}`` for None (the nominal robot)."""
    from realm_ms.agents.robot_model import load_robot_model
    from realm_ms.errors import InputError, UserError

    if robot_model is None:
        return {}
    try:
        load_robot_model(robot_model)
    except (InputError, FileNotFoundError) as e:  # the loader's own complaints; any other error is a bug
        raise UserError(f"{flag} {robot_model}: {e}") from None
    return {"robot_model": robot_model}


def check_policy_spec(spec: str) -> None:
    """A policy spec that cannot work fails here, in one line, before anything loads: ``lerobot:``
    without an argument, or naming a local path that does not exist (not a Hub lookup)."""
    from realm_ms.errors import UserError

    kind, sep, arg = spec.partition(":")
    if kind == "lerobot":
        if not arg.strip():
            raise UserError("--policy lerobot: needs a checkpoint: lerobot:PATH (a local directory) or lerobot:OWNER/NAME (a Hub repo id)")
        looks_local = arg.startswith(("/", ".", "~")) or arg.count("/") >= 2 or arg.endswith("/") or "\\" in arg
        path = Path(arg).expanduser()
        if looks_local and not path.exists():
            raise UserError(f"--policy lerobot:{arg}: no such checkpoint directory {path} (a Hub repo id is OWNER/NAME)")
        if path.exists() and not path.is_dir():
            raise UserError(f"--policy lerobot:{arg}: {path} is a file; give the checkpoint directory (with config.json)")
    elif kind in ("openpi", "roboarena"):
        from realm_ms.eval.policies.websocket_client import parse_addresses

        if not arg:
            raise UserError(f"--policy {kind} needs the server address: {kind}:HOST:PORT")
        try:
            parse_addresses(arg, kind)  # strictly, once, before anything loads
        except ValueError as e:
            raise UserError(f"--policy {e}") from None


def run_report(args) -> int:
    from realm_ms.errors import UserError
    from realm_ms.eval.report import PAPER, write_index, write_report
    from realm_ms.validate import check_output_path

    if args.reference is not None and args.reference not in PAPER:
        raise UserError(f"--reference {args.reference!r}: no paper numbers for it; known: {', '.join(PAPER)}")
    runs = list(dict.fromkeys(args.run_dir))
    for run_dir in runs:
        _check_report_run(run_dir)
    if len(runs) > 1:  # one page comparing the runs side by side, linking each run's own report
        if args.report_out is None:
            raise UserError(f"{len(runs)} RUN directories make one index page: name it with --out (e.g. --out index.html)")
        out = check_output_path(args.report_out, "--out", "file", example="index.html")
        print(f"wrote {write_index(runs, out)}")
        return 0
    out = check_output_path(args.report_out or runs[0] / "report.html", "--out", "file", example="report.html")
    check_output_path(out.parent / (out.stem + "_files"), "--out (its figures directory)", "dir")
    path = write_report(runs[0], out, videos=args.report_videos, reference=args.reference)
    print(f"wrote {path}")
    return 0


def _check_report_run(run_dir: Path) -> None:
    """A readable run of one setup, or one line saying what is wrong; unreadable lines are a warning."""
    from realm_ms.errors import UserError
    from realm_ms.eval.records import format_problems, numbered_records

    if not run_dir.is_dir():
        what = "is a file" if run_dir.exists() else "does not exist"
        raise UserError(f"RUN {run_dir} {what}; give the run directory of `realm eval --out RUN`")
    records_path = run_dir / "records.jsonl"
    if not records_path.exists():
        raise UserError(f"{run_dir} has no records.jsonl (run `realm eval ... --out {run_dir}` first)")
    problems: list[str] = []
    numbered = numbered_records(records_path, problems)
    if not numbered:
        raise UserError(f"{records_path}: no readable records" + (f" ({problems[0]})" if problems else ""))
    first = numbered[0][1].get("fingerprint")
    other = next(((n, r.get("fingerprint")) for n, r in numbered if r.get("fingerprint") != first), None)
    if other is not None:  # records of two setups in one run directory: one report would mix them
        from realm_ms.eval.rundir import differences

        n, theirs = other
        diff = "; ".join(differences(theirs, first)) if isinstance(theirs, dict) and isinstance(first, dict) else "one has no run fingerprint"
        raise UserError(f"{records_path}: line {n} was made differently from line {numbered[0][0]} ({diff}); "
                        "keep one run per directory (`realm eval` refuses to mix them)")
    if problems:
        print(f"realm eval report: warning: {len(problems)} line(s) of {records_path} are not records and are left out:\n"
              f"{format_problems(problems)}", file=sys.stderr)
