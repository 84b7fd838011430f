"""Metrics over episode records: success rate and mean progression with intervals, per task,
perturbation, (task, perturbation) cell and REALM factor group (V / S / B), deltas and RMSD to
Default, failure-stage attribution and time-to-stage.

- success rate: Wilson score interval (95 %);
- mean progression: percentile bootstrap interval of the mean (95 %, 2000 resamples, seeded);
- failure stages: share of episodes whose first unmet stage is each stage ("DONE" = success);
- time to stage: control steps at which each stage latched, over the episodes that reached it;
- delta to Default: per perturbation, the mean over tasks of (task mean - task Default mean), on
  tasks that have both; RMSD to Default: REALM section 5.3.2 with one model,
  sqrt(mean over tasks of (progression_t,p - progression_t,Default)^2).
Only ``status == "ok"`` records count; errors and unsupported cells are listed separately.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from realm_ms.eval.protocol import DEFAULT, factor_groups
from realm_ms.eval.latency import latency_summary
from realm_ms.eval.records import latest_by_key

Z95 = 1.959963984540054


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion (0, 0 for n = 0... returns (0, 1))."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def difference_interval(k1: int, n1: int, k2: int, n2: int, z: float = Z95) -> tuple[float, float]:
    """Interval for the difference of two proportions k2/n2 - k1/n1 (Newcombe's hybrid score method,
    built from the two Wilson intervals; it stays inside [-1, 1] and behaves at 0 % and 100 %)."""
    p1, p2 = (k1 / n1 if n1 else 0.0), (k2 / n2 if n2 else 0.0)
    l1, u1 = wilson_interval(k1, n1, z)
    l2, u2 = wilson_interval(k2, n2, z)
    d = p2 - p1
    return d - math.sqrt((p2 - l2) ** 2 + (u1 - p1) ** 2), d + math.sqrt((u2 - p2) ** 2 + (p1 - l1) ** 2)


def bootstrap_interval(values, n_boot: int = 2000, alpha: float = 0.05, seed: int = 0) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean."""
    v = np.asarray(values, dtype=np.float64)
    if v.size == 0:
        return 0.0, 1.0
    if v.size == 1 or np.all(v == v[0]):
        return float(v[0]), float(v[0])
    rng = np.random.default_rng(seed)
    means = v[rng.integers(0, v.size, size=(n_boot, v.size))].mean(axis=1)
    return float(np.quantile(means, alpha / 2)), float(np.quantile(means, 1 - alpha / 2))


def summarize(records: list[dict]) -> dict:
    n = len(records)
    k = sum(bool(r["success"]) for r in records)
    prog = [float(r["progression"]) for r in records]
    lo, hi = wilson_interval(k, n)
    plo, phi = bootstrap_interval(prog)
    return {
        "episodes": n,
        "successes": k,
        "success_rate": k / n if n else 0.0,
        "success_ci": [lo, hi],
        "mean_progression": float(np.mean(prog)) if n else 0.0,
        "progression_ci": [plo, phi],
        "mean_steps": float(np.mean([r.get("steps", 0) for r in records])) if n else 0.0,
    }


def failure_stages(records: list[dict]) -> dict[str, float]:
    n = len(records)
    counts: dict[str, int] = defaultdict(int)
    for r in records:
        counts[r.get("stalled_stage") or "UNKNOWN"] += 1
    return {s: c / n for s, c in sorted(counts.items(), key=lambda kv: -kv[1])} if n else {}


def time_to_stage(records: list[dict]) -> dict[str, dict]:
    steps: dict[str, list[int]] = defaultdict(list)
    for r in records:
        for s, t in (r.get("stages") or {}).items():
            if t is not None:
                steps[s].append(int(t))
    return {s: {"episodes": len(v), "mean_steps": float(np.mean(v)), "median_steps": float(np.median(v))} for s, v in steps.items()}


def _group(records, key) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = defaultdict(list)
    for r in records:
        for k in key(r):
            out[k].append(r)
    return dict(out)


def compute_metrics(records: list[dict]) -> dict:
    """The ``RUN/metrics.json`` object (see the module docstring)."""
    latest = list(latest_by_key(records).values())
    ok = [r for r in latest if r.get("status", "ok") == "ok"]
    per_task = {t: summarize(rs) for t, rs in sorted(_group(ok, lambda r: [r["task"]]).items())}
    per_pert_recs = _group(ok, lambda r: [r["perturbation"]])
    per_pert = {p: summarize(rs) for p, rs in per_pert_recs.items()}
    cells: dict[str, dict[str, dict]] = defaultdict(dict)
    for (t, p), rs in _group(ok, lambda r: [(r["task"], r["perturbation"])]).items():
        cells[t][p] = summarize(rs)
    groups = {g: summarize(rs) for g, rs in sorted(_group(ok, lambda r: factor_groups(r["perturbation"])).items())}
    delta, rmsd = {}, {}
    for p in per_pert:
        if p == DEFAULT:
            continue
        pairs = [(cells[t][p], cells[t][DEFAULT]) for t in cells if p in cells[t] and DEFAULT in cells[t]]
        if not pairs:
            continue
        dp = [a["mean_progression"] - b["mean_progression"] for a, b in pairs]
        ds = [a["success_rate"] - b["success_rate"] for a, b in pairs]
        delta[p] = {"tasks": len(pairs), "mean_progression": float(np.mean(dp)), "success_rate": float(np.mean(ds))}
        rmsd[p] = float(np.sqrt(np.mean(np.square(dp))))
    return {
        "overall": summarize(ok),
        "per_task": per_task,
        "per_perturbation": per_pert,
        "per_cell": {t: dict(v) for t, v in sorted(cells.items())},
        "per_factor_group": groups,
        "delta_to_default": delta,
        "rmsd_to_default": rmsd,
        "failure_stages": failure_stages(ok),
        "failure_stages_per_task": {t: failure_stages(rs) for t, rs in sorted(_group(ok, lambda r: [r["task"]]).items())},
        "time_to_stage": time_to_stage(ok),
        "errors": [{k: r.get(k) for k in ("task", "perturbation", "seed", "error")} for r in latest if r.get("status") == "error"],
        "policy_latency": latency_summary(latest),  # the setting(s) and per-server median / p95 of the measured latencies
        "unsupported_cells": sorted({(r["task"], r["perturbation"]) for r in latest if r.get("status") == "unsupported"}),
        "policies": sorted({r.get("policy", "?") for r in ok}),
    }
