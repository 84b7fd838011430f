"""Scripted-expert success table: REALM tasks x perturbations x N seeds, through `realm eval`'s runner.

    .venv/bin/python bench/expert_success.py [--seeds 20] [--tasks ID ...] [--perturbation NAME|all]
        [--workers N] [--max-steps 800] [--action-space SPACE[:GRIPPER]] [--robot-model NAME|MODEL.yaml]
        [--out outputs/expert_success]

Runs the privileged expert (CPU physics, state obs: nothing is rendered) with the same episode
loop, records and resume as ``realm eval --policy expert``: every finished episode is appended to
``OUT/records.jsonl`` at once, and re-running the same command skips the episodes already there
(so an interrupted run resumes; a finished one only re-tabulates). Writes, in ``OUT``:

- ``table.md``: markdown, rows tasks, columns perturbations, cells ``successes/episodes``; cells
  under ``--threshold`` (default 80 %) are listed below the table;
- ``expert_success.json``: the same cells (successes, episodes, rate, stalled stages, errors);
- ``table.txt``: the plain-text table (+ mean progression and stalled stages per task), also printed.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections import Counter
from pathlib import Path

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")

UNSUPPORTED = "unsupported"


def cells(records: list[dict], tasks: list[str], perts: list[str]) -> dict[str, dict[str, dict]]:
    """``{task: {perturbation: {successes, episodes, rate, stalled, errors, unsupported}}}``."""
    out: dict[str, dict[str, dict]] = {t: {p: dict(successes=0, episodes=0, rate=None, stalled={}, errors=0, unsupported=False)
                                           for p in perts} for t in tasks}
    for r in records:
        c = out.get(r["task"], {}).get(r["perturbation"])
        if c is None:
            continue
        status = r.get("status", "ok")
        if status == UNSUPPORTED:
            c["unsupported"] = True
            continue
        c["episodes"] += 1
        if status != "ok":  # an episode that crashed counts as a failure of the cell
            c["errors"] += 1
            continue
        c["successes"] += int(bool(r["success"]))
        if r.get("stalled_stage", "DONE") != "DONE":
            c["stalled"][r["stalled_stage"]] = c["stalled"].get(r["stalled_stage"], 0) + 1
    for row in out.values():
        for c in row.values():
            c["rate"] = c["successes"] / c["episodes"] if c["episodes"] else None
    return out


def below(table: dict, threshold: float) -> list[tuple[str, str, dict]]:
    return [(t, p, c) for t, row in table.items() for p, c in row.items() if c["rate"] is not None and c["rate"] < threshold]


def cell_text(c: dict) -> str:
    if c["unsupported"]:
        return "n/a"
    return f"{c['successes']}/{c['episodes']}" if c["episodes"] else "-"


def markdown(table: dict, perts: list[str], threshold: float) -> str:
    lines = ["| task | " + " | ".join(perts) + " |", "|---|" + "---:|" * len(perts)]
    for t, row in table.items():
        lines.append(f"| {t.removeprefix('REALM-').removesuffix('-v1')} | " + " | ".join(cell_text(row[p]) for p in perts) + " |")
    eps = [c for row in table.values() for c in row.values()]
    n, s = sum(c["episodes"] for c in eps), sum(c["successes"] for c in eps)
    lines.append("")
    lines.append(f"{s}/{n} episodes succeeded; {sum(c['episodes'] > 0 for c in eps)} cells run.")
    bad = below(table, threshold)
    if bad:
        lines.append(f"Cells below {threshold:.0%}: " + ", ".join(f"{t.removeprefix('REALM-')} x {p} ({cell_text(c)}, stalled {c['stalled']})" for t, p, c in bad))
    else:
        lines.append(f"Every cell run is at or above {threshold:.0%}.")
    return "\n".join(lines)


def text(records: list[dict], table: dict, perts: list[str]) -> str:
    w = max(max(len(p) for p in perts) + 2, 9)
    lines = [f"{'task':30s}" + "".join(f"{p:>{w}s}" for p in perts) + "   progr.  stalled at"]
    for t, row in table.items():
        rs = [r for r in records if r["task"] == t and r.get("status", "ok") == "ok"]
        prog = sum(r["progression"] for r in rs) / len(rs) if rs else 0.0
        stalled = dict(Counter(r["stalled_stage"] for r in rs if r["stalled_stage"] != "DONE"))
        lines.append(f"{t.removeprefix('REALM-'):30s}" + "".join(f"{cell_text(row[p]):>{w}s}" for p in perts) + f"  {prog:6.3f}  {stalled or ''}")
    ok = [r for r in records if r.get("status", "ok") == "ok"]
    if ok:
        lines.append(f"overall: {sum(r['success'] for r in ok)}/{len(ok)} episodes succeeded")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20, help="episodes per (task, perturbation), seeds 0..N-1")
    ap.add_argument("--tasks", nargs="*", default=None, help="env ids (default: every REALM task)")
    ap.add_argument("--perturbation", default="Default", help="a perturbation name or id, a comma-separated list of them, or 'all' (Default + the 15)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: CPU cores)")
    ap.add_argument("--max-steps", type=int, default=800)
    ap.add_argument("--threshold", type=float, default=0.8, help="success rate a cell must reach (listed when below)")
    ap.add_argument("--out", default="outputs/expert_success", help="run directory; re-run with the same one to resume")
    ap.add_argument("--action-space", default="joint_position", help="DROID action space the expert drives: joint_position | "
                    "joint_velocity | cartesian_velocity | cartesian_position, optionally :position or :velocity for the gripper")
    ap.add_argument("--robot-model", default=None, help="a named robot model (droid-aligned) or a MODEL.yaml (default: the nominal robot)")
    args = ap.parse_args(argv)

    import realm_ms  # noqa: F401
    from realm_ms.errors import UserError
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS, available_perturbations, canonical_perturbation
    from realm_ms.eval.records import latest_by_key, read_records
    from realm_ms.tasks import TASKS

    tasks = args.tasks or sorted(TASKS)
    out = Path(args.out)
    try:
        if args.seeds < 1:
            raise UserError(f"--seeds must be >= 1, got {args.seeds}")
        unknown = [t for t in tasks if t not in TASKS]
        if unknown:
            raise UserError(f"unknown task(s) {unknown}; known: {sorted(TASKS)}")
        perts = available_perturbations() if args.perturbation == "all" else [canonical_perturbation(p.strip()) for p in args.perturbation.split(",")]
        proto = PRESETS["realm"].with_overrides(episodes=args.seeds, seed=0, max_steps=args.max_steps)
        from realm_ms.agents.droid_action_spaces import parse_action_space_flag

        from realm_ms.eval.cli import robot_model_kwargs

        env_kwargs = parse_action_space_flag(args.action_space) | robot_model_kwargs(args.robot_model)
        evaluate("expert", tasks, perts, proto, out, workers=args.workers, quiet=False, env_kwargs=env_kwargs)
    except (UserError, ValueError) as e:
        print(f"expert_success: error: {e}", file=sys.stderr)
        return 2
    recs = list(latest_by_key(read_records(out / "records.jsonl")).values())
    recs = [r for r in recs if r["task"] in tasks and r["perturbation"] in perts and int(r["seed"]) < args.seeds]
    table = cells(recs, tasks, perts)
    txt = text(recs, table, perts)
    md = markdown(table, perts, args.threshold)
    print(txt + "\n\n" + md)
    (out / "table.txt").write_text(txt + "\n")
    (out / "table.md").write_text(md + "\n")
    (out / "expert_success.json").write_text(json.dumps(dict(
        seeds=args.seeds, max_steps=args.max_steps, threshold=args.threshold, tasks=tasks, perturbations=perts, cells=table,
        below_threshold=[dict(task=t, perturbation=p, successes=c["successes"], episodes=c["episodes"]) for t, p, c in below(table, args.threshold)],
        episodes=sum(c["episodes"] for row in table.values() for c in row.values()),
        successes=sum(c["successes"] for row in table.values() for c in row.values()),
    ), indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
