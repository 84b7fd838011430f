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

Statistics that are undefined are reported as undefined, with the reason, never as a number:
Pearson r needs >= 3 policies and sim and real values that vary (SimplerEnv's function returns 1.0
for one policy); MMRV needs >= 2 policies. "mean" averages the tasks where a value is defined.
Values are rates in [0, 1]; ``--percent`` reads 0-100 instead. Each (policy, task) pair is given
once (a repeated pair is an error, whether or not its values agree).
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


MIN_POLICIES = {"pearson_r": 3, "mmrv": 2, "rmsd": 1}
METRICS = {"pearson_r": pearson_r, "mmrv": mmrv, "rmsd": rmsd}


def undefined_reason(metric: str, sim, real) -> str | None:
    """Why ``metric`` is undefined over these paired values, or None."""
    n = len(sim)
    need = MIN_POLICIES[metric]
    if n < need:
        return f"{n} {'policy' if n == 1 else 'policies'}, needs >= {need}"
    if metric == "pearson_r":
        for name, v in (("sim", sim), ("real", real)):
            if np.ptp(np.asarray(v, dtype=np.float64)) == 0:
                return f"zero variance: every {name} value is {v[0]:g}"
    return None


def read_paired(path: Path, percent: bool = False) -> dict[str, list[tuple[str, float, float]]]:
    """task -> [(policy, real, sim)] as rates in [0, 1] (``percent``: the file holds 0-100);
    raises ValueError with a one-line reason naming the line on bad input."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:  # -sig: a spreadsheet's byte-order mark is not part of "policy"
            return _read_rows(path, csv.DictReader(f), percent)
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a UTF-8 text (CSV) file") from None


def _read_rows(path: Path, reader: csv.DictReader, percent: bool) -> dict[str, list[tuple[str, float, float]]]:
    need = {"policy", "task", "real", "sim"}
    if reader.fieldnames is None or not need <= {c.strip() for c in reader.fieldnames if c}:
        raise ValueError(f"{path}: needs the columns policy,task,real,sim (has {reader.fieldnames})")
    top, unit = (100.0, " (--percent)") if percent else (1.0, "; rates are fractions, give --percent for 0-100 values")
    by_task: dict[str, list] = defaultdict(list)
    seen: dict[tuple[str, str], int] = {}
    fractions: list[tuple[int, float]] = []  # with --percent: non-integer values below 1 (likely fractions)
    wide: list[tuple[int, float]] = []  # with --percent: values above 1
    for n, row in enumerate(reader, start=2):
        row = {k.strip(): (v or "").strip() for k, v in row.items() if k}
        if not row["policy"] or not row["task"]:
            raise ValueError(f"{path}:{n}: empty policy or task name")
        vals = []
        for col in ("real", "sim"):
            try:
                v = float(row[col])
            except ValueError:
                raise ValueError(f"{path}:{n}: {col} must be a number, got {row[col]!r}") from None
            if not math.isfinite(v):
                raise ValueError(f"{path}:{n}: {col} must be finite, got {row[col]!r}")
            if not 0.0 <= v <= top:
                raise ValueError(f"{path}:{n}: {col} = {row[col]} is outside [0, {top:g}]{unit}")
            (fractions if 0 < v < 1 and v != int(v) else wide if v > 1 else []).append((n, v))
            vals.append(v / top)
        pair = (row["policy"], row["task"])
        if pair in seen:
            raise ValueError(f"{path}:{n}: policy {pair[0]!r} on task {pair[1]!r} is given again (first on line {seen[pair]}); "
                             "give each (policy, task) pair once")
        seen[pair] = n
        by_task[row["task"]].append((row["policy"], *vals))
    if percent and fractions and wide:
        raise ValueError(f"{path}: fractions mixed with percentages (line {fractions[0][0]}: {fractions[0][1]:g}, "
                         f"line {wide[0][0]}: {wide[0][1]:g}); with --percent every value is 0-100")
    if not by_task:
        raise ValueError(f"{path}: no rows")
    return dict(by_task)


def _metrics(sim, real) -> dict:
    out: dict = {}
    why: dict[str, str] = {}
    for name, fn in METRICS.items():
        reason = undefined_reason(name, sim, real)
        out[name] = None if reason else fn(sim, real)
        if reason:
            why[name] = reason
    if why:
        out["undefined"] = why
    return out


def validate(by_task: dict[str, list[tuple[str, float, float]]]) -> dict:
    per_task = {}
    for task, rows in sorted(by_task.items()):
        real = [r for _, r, _ in rows]
        sim = [s for _, _, s in rows]
        per_task[task] = {"policies": len(rows), **_metrics(sim, real)}
    mean: dict = {}
    for k in METRICS:
        vals = [v[k] for v in per_task.values() if v[k] is not None]
        mean[k] = float(np.mean(vals)) if vals else None
        if not vals:
            mean.setdefault("undefined", {})[k] = "undefined on every task"
    mean["tasks"] = {k: sum(v[k] is not None for v in per_task.values()) for k in METRICS}
    all_real = [r for rows in by_task.values() for _, r, _ in rows]
    all_sim = [s for rows in by_task.values() for _, _, s in rows]
    return {"per_task": per_task, "mean": mean, "pooled": _metrics(all_sim, all_real)}


def _cell(v, width: int) -> str:
    return f"{'undefined':>{width}s}" if v is None else f"{v:{width}.4f}"


def format_table(result: dict) -> str:
    lines = [f"{'task':36s} {'n':>3s} {'pearson_r':>10s} {'mmrv':>10s} {'rmsd':>8s}"]
    notes = []
    rows = [(t, v, f"{v['policies']:3d}") for t, v in result["per_task"].items()]
    rows += [(name, result[name], f"{'':3s}") for name in ("mean", "pooled")]
    for t, v, n in rows:
        lines.append(f"{t:36s} {n} {_cell(v['pearson_r'], 10)} {_cell(v['mmrv'], 10)} {_cell(v['rmsd'], 8)}")
        notes += [f"  {t}: {k} undefined ({why})" for k, why in v.get("undefined", {}).items()]
    m = result["mean"]["tasks"]
    if any(c < len(result["per_task"]) for c in m.values()):
        notes.append(f"  mean: over the tasks where each is defined (pearson_r {m['pearson_r']}, mmrv {m['mmrv']}, "
                     f"rmsd {m['rmsd']} of {len(result['per_task'])})")
    return "\n".join(lines + (["undefined statistics:"] + notes if notes else []))


def add_parser(sub) -> None:
    p = sub.add_parser("validate", help="real-vs-sim statistics of policy rankings: Pearson r, MMRV, RMSD from a paired CSV")
    p.add_argument("paired", type=Path, help="CSV with columns policy,task,real,sim")
    p.add_argument("--json", type=Path, default=None, help="also write the result as JSON here (a file path)")
    p.add_argument("--percent", action="store_true", help="real/sim are percentages (0-100); default: rates in [0, 1]")
    p.set_defaults(func=run)


def run(args) -> int:
    from realm_ms.errors import UserError

    from realm_ms.validate import check_output_path

    if not args.paired.is_file():
        raise UserError(f"{args.paired} is a directory, expected a CSV file" if args.paired.is_dir() else f"no such file: {args.paired}")
    if args.json:
        check_output_path(args.json, "--json", "file", example="validation.json")
    try:
        result = validate(read_paired(args.paired, percent=args.percent))
    except (ValueError, KeyError, csv.Error) as e:
        raise UserError(str(e)) from None
    print(format_table(result))
    if args.json:
        from realm_ms.atomic import write_json

        write_json(args.json, result, indent=2)
        print(f"wrote {args.json}")
    return 0
