"""`realm demo`: a quick-protocol evaluation run ending in its HTML report.

Two policies through ``realm eval``'s runner on a few tasks and perturbations: the scripted expert
(privileged, solves the tasks) and a tiny randomly initialised LeRobot ACT policy made locally
(``save_pretrained`` then loaded back by path: the LeRobot path end to end, no download). Writes
``OUT/expert/`` and ``OUT/lerobot_tiny/`` (records.jsonl, metrics.json, report.html with figures
and, unless ``--no-video``, exterior + wrist mp4s: every expert episode, the tiny policy's failures)
and ``OUT/index.html``, which compares the two side by side with their protocols.
Re-running resumes (finished episodes are skipped); a few minutes on 2 CPU cores.
"""

from __future__ import annotations

import os
from pathlib import Path

from realm_ms.task_index import DEFAULT

DEFAULT_OUT = Path("outputs/demo")
DEMO_TASKS = ("REALM-PickApple-v1", "REALM-PushSwitch-v1")
DEMO_PERTURBATIONS = (DEFAULT, "V-AUG", "VB-POSE")


def add_parser(sub) -> None:
    from realm_ms.validate import integer

    p = sub.add_parser("demo", help="quick REALM protocol run (expert + a tiny LeRobot policy) ending in an HTML report")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output directory (default {DEFAULT_OUT})")
    p.add_argument("--tasks", nargs="+", default=list(DEMO_TASKS), help=f"env ids (default {' '.join(DEMO_TASKS)})")
    p.add_argument("--perturbations", nargs="+", default=list(DEMO_PERTURBATIONS),
                   help="perturbation names; ones not registered in this checkout are skipped "
                   f"(default {' '.join(DEMO_PERTURBATIONS)})")
    p.add_argument("--episodes", type=integer(1), default=1, help="episodes per (task, perturbation), >= 1 (default 1)")
    p.add_argument("--max-steps", type=integer(1), default=200, help="control steps per expert episode (default 200; REALM: 800)")
    p.add_argument("--workers", type=integer(1), default=None, help="worker processes (default: CPU cores)")
    p.add_argument("--no-video", action="store_true", help="skip the episode videos (faster)")
    p.set_defaults(func=run)


def run(args) -> int:
    from realm_ms.errors import UserError
    from realm_ms.eval import evaluate
    from realm_ms.eval.policies.lerobot import make_tiny_policy
    from realm_ms.eval.protocol import PRESETS, available_perturbations, canonical_perturbation
    from realm_ms.eval.report import write_index, write_report
    from realm_ms.tasks import TASKS

    os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
    unknown = [t for t in args.tasks if t not in TASKS]
    if unknown:
        raise UserError(f"unknown task(s) {', '.join(unknown)}; known: {', '.join(sorted(TASKS))}")
    avail = set(available_perturbations())
    perts = []
    for name in args.perturbations:
        try:
            c = canonical_perturbation(name)
        except ValueError:
            continue
        if c in avail:
            perts.append(c)
    perts = perts or [DEFAULT]
    args.out.mkdir(parents=True, exist_ok=True)
    proto = PRESETS["quick"].with_overrides(episodes=args.episodes, max_steps=args.max_steps)
    print(f"realm demo: {len(args.tasks)} task(s) x {', '.join(perts)} x {args.episodes} episode(s)")
    reports = []
    # 160x90 camera frames keep CPU rendering (lavapipe) to a few minutes for the whole demo
    rc = evaluate("expert", args.tasks, perts, proto, args.out / "expert", workers=args.workers, camera_size=(160, 90),
                  videos="none" if args.no_video else "all")
    reports.append(("scripted expert", write_report(args.out / "expert", args.out / "expert" / "report.html", videos="all")))
    ckpt = args.out / "tiny_act"
    if not (ckpt / "config.json").exists():
        make_tiny_policy(ckpt)
    tiny = proto.with_overrides(max_steps=min(args.max_steps, 60))
    # the learned policy's failures are recorded too, so its report shows what it did
    rc = max(rc, evaluate(f"lerobot:{ckpt}", args.tasks, perts, tiny, args.out / "lerobot_tiny", workers=args.workers,
                          camera_size=(160, 90), videos="none" if args.no_video else "failures"))
    reports.append(("tiny LeRobot ACT (random init)", write_report(args.out / "lerobot_tiny", args.out / "lerobot_tiny" / "report.html")))
    write_index([args.out / "expert", args.out / "lerobot_tiny"], args.out / "index.html", names=[n for n, _ in reports],
                reports=[p for _, p in reports], title="realm demo: scripted expert vs a tiny LeRobot ACT policy")
    for name, p in reports:
        print(f"{name}: {p}")
    print(f"open {args.out / 'index.html'}")
    return rc  # non-zero when an episode ended in an error record (``evaluate`` says how many and where)
