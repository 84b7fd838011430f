"""``realm validate PAIRED.csv``: real-vs-sim agreement of policy rankings, as SimplerEnv and REALM.

CSV columns ``policy,task,real,sim`` (success rates or progressions). Per task, over its policies:

- Pearson r (SimplerEnv ``pearson_correlation``): centre both vectors; 1 if the centred vectors are
  identical, else sum(s * r) / (sqrt(sum(s^2) * sum(r^2)) + 1e-8);
- MMRV (SimplerEnv ``mean_maximum_rank_violation(sim, real)``): for each policy i,
  RV_i = max |real_i - real_j| over j whose sim order disagrees with the real order
  ((sim_i > sim_j) != (real_i > real_j)), 0 if none; MMRV = mean_i RV_i;
- RMSD: sqrt(mean_i (sim_i - real_i)^2) (REALM's root-mean-square deviation, between paired values).

"mean" averages the per-task values (as SimplerEnv's tables); "pooled" computes each metric once
over every (policy, task) pair.
"""

from __future__ import annotations

import csv
import json
import math
from collections import defaultdict
from pathlib import Path

import numpy as np


def pearson_r(sim, real) -> float:
    s = np.asarray(sim, dtype=np.float64)
    r = np.asarray(real, dtype=np.float64)
    s, r = s - s.mean(), r - r.mean()
    if np.all(s == r):
        return 1.0
    return float(np.sum(s * r) / (np.sqrt(np.sum(s**2) * np.sum(r**2)) + 1e-8))


def mmrv(sim, real) -> float:
    s = np.asarray(sim, dtype=np.float64)
    r = np.asarray(real, dtype=np.float64)
    n = len(s)
    rv = []
    for i in range(n):
        worst = 0.0
        for j in range(n):
            if (s[i] > s[j]) != (r[i] > r[j]):
                worst = max(worst, abs(r[i] - r[j]))
        rv.append(worst)
    return float(np.mean(rv)) if rv else 0.0


def rmsd(sim, real) -> float:
    s = np.asarray(sim, dtype=np.float64)
    r = np.asarray(real, dtype=np.float64)
    return float(np.sqrt(np.mean((s - r) ** 2))) if len(s) else math.nan


def read_paired(path: Path) -> dict[str, list[tuple[str, float, float]]]:
    """task -> [(policy, real, sim)]; raises ValueError with a one-line reason on bad input."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        need = {"policy", "task", "real", "sim"}
        if reader.fieldnames is None or not need <= {c.strip() for c in reader.fieldnames}:
            raise ValueError(f"{path}: needs the columns policy,task,real,sim (has {reader.fieldnames})")
        by_task: dict[str, list] = defaultdict(list)
        for n, row in enumerate(reader, start=2):
            row = {k.strip(): (v or "").strip() for k, v in row.items() if k}
            try:
                real, sim = float(row["real"]), float(row["sim"])
            except ValueError:
                raise ValueError(f"{path}:{n}: real/sim must be numbers, got {row['real']!r}, {row['sim']!r}") from None
            if not (math.isfinite(real) and math.isfinite(sim)):
                raise ValueError(f"{path}:{n}: real/sim must be finite")
            by_task[row["task"]].append((row["policy"], real, sim))
    if not by_task:
        raise ValueError(f"{path}: no rows")
    return dict(by_task)


def validate(by_task: dict[str, list[tuple[str, float, float]]]) -> dict:
    per_task = {}
    for task, rows in sorted(by_task.items()):
        real = [r for _, r, _ in rows]
        sim = [s for _, _, s in rows]
        per_task[task] = {"policies": len(rows), "pearson_r": pearson_r(sim, real), "mmrv": mmrv(sim, real), "rmsd": rmsd(sim, real)}
    keys = ("pearson_r", "mmrv", "rmsd")
    mean = {k: float(np.mean([v[k] for v in per_task.values()])) for k in keys}
    all_real = [r for rows in by_task.values() for _, r, _ in rows]
    all_sim = [s for rows in by_task.values() for _, _, s in rows]
    pooled = {"pearson_r": pearson_r(all_sim, all_real), "mmrv": mmrv(all_sim, all_real), "rmsd": rmsd(all_sim, all_real)}
    return {"per_task": per_task, "mean": mean, "pooled": pooled}


def format_table(result: dict) -> str:
    lines = [f"{'task':36s} {'n':>3s} {'pearson_r':>10s} {'mmrv':>8s} {'rmsd':>8s}"]
    for t, v in result["per_task"].items():
        lines.append(f"{t:36s} {v['policies']:3d} {v['pearson_r']:10.4f} {v['mmrv']:8.4f} {v['rmsd']:8.4f}")
    for name in ("mean", "pooled"):
        v = result[name]
        lines.append(f"{name:36s} {'':3s} {v['pearson_r']:10.4f} {v['mmrv']:8.4f} {v['rmsd']:8.4f}")
    return "\n".join(lines)


def add_parser(sub) -> None:
    p = sub.add_parser("validate", help="real-vs-sim validation: Pearson r, MMRV, RMSD from a paired CSV")
    p.add_argument("paired", type=Path, help="CSV with columns policy,task,real,sim")
    p.add_argument("--json", type=Path, default=None, help="also write the result as JSON here")
    p.set_defaults(func=run)


def run(args) -> int:
    from realm_ms.errors import UserError

    if not args.paired.is_file():
        raise UserError(f"no such file: {args.paired}")
    try:
        result = validate(read_paired(args.paired))
    except (ValueError, KeyError, csv.Error) as e:
        raise UserError(str(e)) from None
    print(format_table(result))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=2))
        print(f"wrote {args.json}")
    return 0
