"""Scripted-expert success table: REALM tasks x perturbations x N seeds, through `realm eval`'s runner.

    .venv/bin/python bench/expert_success.py [--seeds 20] [--tasks ID ...] [--perturbation NAME|all]
        [--workers N] [--max-steps 800] [--out outputs/expert_success]

Runs the privileged expert (CPU sim, state obs) with the same episode loop, records and resume as
``realm eval --policy expert`` (``OUT/records.jsonl``, ``OUT/metrics.json``), then prints a
task x perturbation table of success rates (and mean progression, stalled stages per task).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections import Counter
from pathlib import Path

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")


def table(records: list[dict], tasks: list[str], perts: list[str]) -> str:
    cells: dict = {}
    for r in records:
        if r.get("status", "ok") == "ok":
            cells.setdefault((r["task"], r["perturbation"]), []).append(r)
    unsupported = {(r["task"], r["perturbation"]) for r in records if r.get("status") == "unsupported"}
    w = max(len(p) for p in perts) + 2
    lines = [f"{'task':30s}" + "".join(f"{p:>{max(w, 9)}s}" for p in perts) + "   progr.  stalled at"]
    for t in tasks:
        row, allr = f"{t.removeprefix('REALM-'):30s}", []
        for p in perts:
            rs = cells.get((t, p), [])
            allr += rs
            txt = "n/a" if (t, p) in unsupported else (f"{sum(r['success'] for r in rs)}/{len(rs)}" if rs else "-")
            row += f"{txt:>{max(w, 9)}s}"
        prog = sum(r["progression"] for r in allr) / len(allr) if allr else 0.0
        stalled = dict(Counter(r["stalled_stage"] for r in allr if r["stalled_stage"] != "DONE"))
        lines.append(row + f"  {prog:6.3f}  {stalled or ''}")
    ok = [r for r in records if r.get("status", "ok") == "ok"]
    if ok:
        lines.append(f"overall: {sum(r['success'] for r in ok)}/{len(ok)} episodes succeeded")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20, help="episodes per (task, perturbation), seeds 0..N-1")
    ap.add_argument("--tasks", nargs="*", default=None)
    ap.add_argument("--perturbation", default="Default", help="a perturbation name, or 'all' (every registered one)")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: CPU cores)")
    ap.add_argument("--max-steps", type=int, default=800)
    ap.add_argument("--out", default="outputs/expert_success")
    args = ap.parse_args(argv)

    import realm_ms  # noqa: F401
    from realm_ms.errors import UserError
    from realm_ms.eval.cli import evaluate
    from realm_ms.eval.protocol import PRESETS, available_perturbations, canonical_perturbation
    from realm_ms.eval.records import latest_by_key, read_records
    from realm_ms.tasks import TASKS

    tasks = args.tasks or sorted(TASKS)
    try:
        perts = available_perturbations() if args.perturbation == "all" else [canonical_perturbation(args.perturbation)]
        proto = PRESETS["realm"].with_overrides(episodes=args.seeds, seed=0, max_steps=args.max_steps)
        evaluate("expert", tasks, perts, proto, Path(args.out), workers=args.workers, quiet=False)
    except (UserError, ValueError) as e:
        print(f"expert_success: error: {e}", file=sys.stderr)
        return 2
    recs = list(latest_by_key(read_records(Path(args.out) / "records.jsonl")).values())
    recs = [r for r in recs if r["task"] in tasks and r["perturbation"] in perts and int(r["seed"]) < args.seeds]
    print(table(recs, tasks, perts))
    (Path(args.out) / "table.txt").write_text(table(recs, tasks, perts) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
