"""``realm eval report RUN/``: a self-contained HTML report of one run, and ``write_index``: one page
comparing several runs (policies) side by side.

Every page opens with the protocol it shows (tasks, perturbations, episodes, seeds, horizon, action
space, camera size, code version: ``RUN/run.json`` and the records) and how many episodes ended in an
error record. A run's report: headline success rate (95 % Wilson interval) and mean progression (95 %
bootstrap interval); task x perturbation heat-maps; each perturbation's change against Default (or
the words "all deltas are 0" instead of an empty plot); where episodes stall, per task; tables per
task, perturbation and factor group; time to stage; inline episode videos chosen by a rule (the first
``videos_per_cell`` failed episodes by seed in each cell, or all episodes with ``videos="all"``);
errors. ``report_files/`` beside it holds the PNGs, the REALM paper-layout table (``table.md``,
``table.csv``: one row per perturbation then the V / S / B averages, one column per policy, REALM's
published numbers with ``--reference``) and ``metrics.json``.
"""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

from realm_ms.atomic import write_text
from realm_ms.eval import report_figures as figs
from realm_ms.eval.metrics import compute_metrics
from realm_ms.eval.records import latest_by_key, read_records
from realm_ms.eval.report_figures import order
from realm_ms.eval.report_html import error_banner, protocol_block, records_summary, run_protocol, short, video_gallery
from realm_ms.html_kit import esc, figure, page, png, table

# REALM paper, mean task progression per perturbation (realm-spec.md section 6)
PAPER = {
    "pi0": {"Default": .44, "V-AUG": .42, "V-VIEW": .52, "V-SC": .43, "V-LIGHT": .37, "S-PROP": .29, "S-LANG": .36, "S-MO": .35,
            "S-AFF": .30, "S-INT": .29, "B-HOBJ": .32, "SB-NOUN": .28, "SB-VRB": .36, "VB-POSE": .32, "VB-MOBJ": .38, "VSB-NOBJ": .16},
    "pi0-FAST": {"Default": .61, "V-AUG": .64, "V-VIEW": .70, "V-SC": .60, "V-LIGHT": .54, "S-PROP": .53, "S-LANG": .61, "S-MO": .55,
                 "S-AFF": .55, "S-INT": .54, "B-HOBJ": .38, "SB-NOUN": .39, "SB-VRB": .57, "VB-POSE": .49, "VB-MOBJ": .53, "VSB-NOBJ": .26},
    "GR00T": {"Default": .19, "V-AUG": .19, "V-VIEW": .19, "V-SC": .21, "V-LIGHT": .16, "S-PROP": .21, "S-LANG": .21, "S-MO": .20,
              "S-AFF": .21, "S-INT": .20, "B-HOBJ": .16, "SB-NOUN": .17, "SB-VRB": .21, "VB-POSE": .07, "VB-MOBJ": .09, "VSB-NOBJ": .09},
}
PAPER_ORDER = list(PAPER["pi0"])
VIDEOS_PER_CELL = 2


def load_run(run_dir: Path) -> tuple[list[dict], dict]:
    """(one record per episode key, metrics) of a run directory."""
    records = list(latest_by_key(read_records(Path(run_dir) / "records.jsonl")).values())
    return records, compute_metrics(records)


def _counts(metrics: dict, records: list[dict]) -> tuple[int, int, int]:
    n_unsup = sum(r.get("status") == "unsupported" for r in records)
    return metrics["overall"]["episodes"], len(metrics["errors"]), n_unsup


def _succ(s: dict) -> str:
    lo, hi = s["success_ci"]
    return f"{s['successes']}/{s['episodes']} = {s['success_rate']:.2f} [{lo:.2f}, {hi:.2f}]"


def _prog(s: dict) -> str:
    lo, hi = s["progression_ci"]
    return f"{s['mean_progression']:.2f} [{lo:.2f}, {hi:.2f}]"


def _ci(s: dict) -> list[str]:
    return [str(s["episodes"]), _succ(s), _prog(s)]


def headline(metrics: dict) -> str:
    o = metrics["overall"]
    if not o["episodes"]:
        return "<p class='headline'>No finished episodes.</p>"
    return (f"<p class='headline'>Success <b>{o['success_rate']:.2f}</b> ({o['successes']} of {o['episodes']} episodes; "
            f"95 % Wilson interval [{o['success_ci'][0]:.2f}, {o['success_ci'][1]:.2f}]), mean progression "
            f"<b>{o['mean_progression']:.2f}</b> (95 % bootstrap interval [{o['progression_ci'][0]:.2f}, {o['progression_ci'][1]:.2f}]).</p>")


def _figures(metrics: dict, files: Path) -> list[str]:
    n_cell = sorted({s["episodes"] for t in metrics["per_cell"].values() for s in t.values()})
    per = f"{n_cell[0]}" if len(n_cell) == 1 else f"{n_cell[0]}-{n_cell[-1]}" if n_cell else "0"
    out = []
    specs = [
        ("heatmap_progression.png", figs.heatmap(metrics, "mean_progression", "mean progression"),
         f"Mean task progression (share of the task's stages reached: 0 = none, 1 = all) for each task (row) under each "
         f"perturbation (column), over {per} episode(s) per cell."),
        ("heatmap_success.png", figs.heatmap(metrics, "success_rate", "success rate"),
         f"Success rate (episodes that completed the task and held it) per task and perturbation, over {per} episode(s) per cell."),
    ]
    zero_deltas = ""
    if metrics["delta_to_default"]:
        d = figs.deltas(metrics)
        if d is None:
            zero_deltas = ("<p class='note'>Change against Default: all deltas are 0 (every perturbation's mean progression "
                           "and success rate equal Default's on the same tasks), so no delta plot is drawn.</p>")
        else:
            specs.append(("delta_to_default.png", d,
                          "Each perturbation's change against Default: mean over tasks of (task value under the perturbation "
                          "- the same task's value under Default), for mean progression (blue) and success rate (orange). "
                          "Below 0: the perturbation hurts."))
    specs.append(("failure_stages.png", figs.failure_bars(metrics),
                  "Where episodes end, per task over all perturbations: the share that succeeded (green) and the share "
                  "stalled at each stage (the first stage of the task they never reached)."))
    for name, fig, caption in specs:
        if fig is None:
            continue
        data = png(fig)
        (files / name).write_bytes(data)
        out.append(figure(data, f"{esc(caption)} <span class='note'>({esc(name)})</span>", name))
    return [f"<div class='figs'>{''.join(out)}</div>", zero_deltas]


def write_report(run_dir: Path, out: Path, videos: str = "failures", reference: str | None = None,
                 videos_per_cell: int = VIDEOS_PER_CELL) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    run_dir, out = Path(run_dir), Path(out)
    records, metrics = load_run(run_dir)
    if reference and reference not in PAPER:
        raise ValueError(f"unknown reference {reference!r}; known: {', '.join(PAPER)}")
    files = out.parent / (out.stem + "_files")
    files.mkdir(parents=True, exist_ok=True)
    imgs = _figures(metrics, files)
    header, rows = paper_table(metrics, records, reference)
    (files / "table.md").write_text(_md(header, rows))
    with open(files / "table.csv", "w", newline="") as f:
        csv.writer(f).writerows([header, *rows])
    (files / "metrics.json").write_text(json.dumps(metrics, indent=2))
    n_ok, n_err, n_unsup = _counts(metrics, records)
    task_rows = [[t, *_ci(s)] for t, s in metrics["per_task"].items()]
    pert_rows = [[p, *_ci(metrics["per_perturbation"][p]),
                  f"{metrics['delta_to_default'][p]['mean_progression']:+.2f}" if p in metrics["delta_to_default"] else "",
                  f"{metrics['rmsd_to_default'][p]:.3f}" if p in metrics["rmsd_to_default"] else ""]
                 for p in order(metrics["per_perturbation"])]
    group_rows = [[g, *_ci(s)] for g, s in metrics["per_factor_group"].items()]
    tts = [[s, str(v["episodes"]), f"{v['mean_steps']:.1f}", f"{v['median_steps']:.0f}"] for s, v in metrics["time_to_stage"].items()]
    fail = [["succeeded" if s == "DONE" else f"stalled at {s}", f"{v:.2f}"] for s, v in metrics["failure_stages"].items()]
    errors = [[str(e.get(k)) for k in ("task", "perturbation", "seed", "error")] for e in metrics["errors"]]
    policy = ", ".join(metrics["policies"]) or ", ".join(sorted({r.get("policy", "?") for r in records})) or "(no records)"
    policy += "".join(sorted({f" [{r['action_space']}]" for r in records if r.get("action_space", "joint_position:position") != "joint_position:position"}))
    ci = ["task", "episodes", "success k/n = rate [95% Wilson]", "progression [95% bootstrap]"]
    def box(title: str, content: str) -> str:
        return f"<section><h2>{title}</h2>{content}</section>"

    tables = [
        box("Per task", table(ci, task_rows)),
        box("Per perturbation", table(["perturbation", *ci[1:], "delta to Default", "RMSD to Default"], pert_rows)),
        box("Per factor group", table(["group", *ci[1:]], group_rows)),
        box("Where episodes end", table(["outcome", "share of episodes"], fail)),
        box("Time to stage (control steps)", table(["stage", "episodes that reached it", "mean", "median"], tts) if tts
            else "<p class='note'>No episode reached any stage.</p>"),
        box("REALM paper layout (mean progression)", table(header, rows)),
    ]
    sections = [
        f"<h1>REALM evaluation: {esc(policy)}</h1>",
        protocol_block(run_protocol(run_dir, records), n_ok, n_err, n_unsup, run_dir),
        error_banner(n_err), headline(metrics),
        *imgs,
        f"<h2>Episode videos</h2>{video_gallery(records, run_dir, out.parent, videos, videos_per_cell)}" if videos != "none" else "",
        f"<div class='grid'>{''.join(tables)}</div>",
        f"<h2 id='errors'>Errors</h2>{table(['task', 'perturbation', 'seed', 'error'], errors)}" if errors else "",
        f"<p class='note'>Figures, <code>table.md</code>, <code>table.csv</code> and <code>metrics.json</code> are also in "
        f"<code>{esc(files.name)}/</code>.</p>",
    ]
    write_text(out, page(f"realm eval report: {policy}", "\n".join(s for s in sections if s)))
    return out


# ------------------------------------------------------------------------------------ index
def _shade(v: float) -> str:
    return f' style="background:rgba(80,160,80,{0.08 + 0.42 * max(0.0, min(1.0, v)):.2f})"'


def _compare_table(rows: list[tuple[tuple, list]], names: list[str], first: list[str]) -> str:
    """``rows``: (row labels, one summary per run or None); per run two columns, success with its
    Wilson interval and progression with its bootstrap interval, shaded by value."""
    head1 = "".join(f'<th rowspan="2" class="l">{esc(h)}</th>' for h in first)
    head1 += "".join(f'<th colspan="2">{esc(n)}</th>' for n in names)
    head2 = "<th>success k/n = rate [95% CI]</th><th>progression [95% CI]</th>" * len(names)
    body = []
    for key, summaries in rows:
        cells = "".join(f'<td class="l">{esc(v)}</td>' for v in key)
        for s in summaries:
            if s is None or not s["episodes"]:
                cells += "<td>-</td><td>-</td>"
            else:
                cells += (f'<td class="v"{_shade(s["success_rate"])}>{esc(_succ(s))}</td>'
                          f'<td class="v"{_shade(s["mean_progression"])}>{esc(_prog(s))}</td>')
        body.append(f"<tr>{cells}</tr>")
    return f'<table class="cmp"><tr>{head1}</tr><tr>{head2}</tr>{"".join(body)}</table>'


def _rel(path: Path, base: Path) -> str:
    return Path(os.path.relpath(Path(path).resolve(), Path(base).resolve())).as_posix()


def _protocol_table(protos: list[dict], counts: list[tuple], names: list[str], differ: list[str]) -> str:
    """One row per protocol field; a value all runs share spans the runs' columns, one that differs
    is shown per run and flagged."""
    n = len(protos)
    rows = [f'<tr><th class="l"></th>{"".join(f"<th class=l>{esc(x)}</th>" for x in names)}</tr>']
    for f in protos[0]:
        vals = [p.get(f, "") for p in protos]
        if f in differ or (f == "policy" and len(set(vals)) > 1):
            label = f"<b>{esc(f)}</b> <span class='err'>differs</span>" if f in differ else esc(f)
            rows.append(f'<tr><td class="l">{label}</td>{"".join(f"<td class=l>{esc(v)}</td>" for v in vals)}</tr>')
        else:
            rows.append(f'<tr><td class="l">{esc(f)}</td><td class="l" colspan="{n}">{esc(vals[0])}</td></tr>')
    rows.append(f'<tr><td class="l">records</td>{"".join(f"<td class=l>{records_summary(*c)}</td>" for c in counts)}</tr>')
    return f"<table>{''.join(rows)}</table>"


def write_index(run_dirs: list[Path], out: Path, names: list[str] | None = None, reports: list[Path | None] | None = None,
                title: str = "REALM evaluation: policies compared") -> Path:
    """One page comparing the runs in ``run_dirs`` (one policy each) side by side: the protocol of
    each (differences flagged), headline numbers with intervals, then per task, per perturbation and
    per (task, perturbation) cell, and a figure of mean progression per perturbation. ``reports``:
    each run's report (linked; default ``RUN/report.html`` when it exists)."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(out)
    runs = [Path(d) for d in run_dirs]
    loaded = [load_run(d) for d in runs]
    names = list(names) if names else [", ".join(m["policies"]) or d.name for d, (_, m) in zip(runs, loaded)]
    reports = list(reports) if reports else [d / "report.html" if (d / "report.html").exists() else None for d in runs]
    protos = [run_protocol(d, recs) for d, (recs, _) in zip(runs, loaded)]
    counts = [_counts(m, recs) for recs, m in loaded]
    # protocol, one column per run; rows that differ between runs are flagged
    fields = list(protos[0]) if protos else []
    differ = [f for f in fields if f != "policy" and len({p.get(f) for p in protos}) > 1]
    n_err = sum(c[1] for c in counts)
    head = []
    for name, (recs, m), rep, d in zip(names, loaded, reports, runs):
        o = m["overall"]
        link = f'<a href="{esc(_rel(rep, out.parent))}">report</a>' if rep else "-"
        errs = len(m["errors"])
        head.append([name, link, str(o["episodes"]), _succ(o) if o["episodes"] else "-", _prog(o) if o["episodes"] else "-",
                     f'<span class="err">{errs}</span>' if errs else "0"])
    tasks = sorted({t for _, m in loaded for t in m["per_task"]})
    perts = order({p for _, m in loaded for p in m["per_perturbation"]})
    ms = [m for _, m in loaded]
    by_pert = [((p,), [m["per_perturbation"].get(p) for m in ms]) for p in perts]
    by_task = [((short(t),), [m["per_task"].get(t) for m in ms]) for t in tasks]
    by_cell = [((short(t), p), [m["per_cell"].get(t, {}).get(p) for m in ms]) for t in tasks for p in perts
               if any(p in m["per_cell"].get(t, {}) for m in ms)]
    fig = figs.compare_policies([(n, m) for n, (_, m) in zip(names, loaded)])
    parts = [
        f"<h1>{esc(title)}</h1>",
        f"<h2>Protocol</h2>{_protocol_table(protos, counts, names, differ)}" if protos else "",
        (f"<p class='warn'>The runs differ in {esc(', '.join(differ))}: numbers are not directly comparable there.</p>" if differ else ""),
        error_banner(n_err),
        "<h2>Headline</h2>" + table(["policy", "", "episodes", "success k/n = rate [95% Wilson]", "mean progression [95% bootstrap]",
                                     "errors"], head),
        figure(png(fig), "Mean progression per perturbation (over its tasks and episodes) for each policy; whiskers: 95 % "
               "bootstrap interval of the mean.", "policies compared per perturbation") if fig is not None else "",
        "<h2>Per perturbation (over tasks)</h2>" + _compare_table(by_pert, names, ["perturbation"]),
        "<h2>Per task (over perturbations)</h2>" + _compare_table(by_task, names, ["task"]),
        "<h2>Per task and perturbation</h2>" + _compare_table(by_cell, names, ["task", "perturbation"]),
        "<p class='note'>Success: Wilson score interval (95 %); progression: percentile bootstrap interval of the mean "
        "(95 %, 2000 resamples). Error records are not counted. Cell shading follows the value (darker = higher).</p>",
    ]
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, page(title, "\n".join(p for p in parts if p)))
    return out


def paper_table(metrics: dict, records: list[dict], reference: str | None = None) -> tuple[list[str], list[list[str]]]:
    """Rows: perturbations then 'V / S / B avg'; columns: policy (+ reference): REALM's layout."""
    from realm_ms.eval.protocol import factor_groups

    policies = metrics["policies"] or ["policy"]
    by_pol: dict[str, dict[str, list[float]]] = {}
    for r in records:
        if r.get("status", "ok") == "ok":
            by_pol.setdefault(r.get("policy", "policy"), {}).setdefault(r["perturbation"], []).append(float(r["progression"]))
    perts = order({p for v in by_pol.values() for p in v})
    header = ["perturbation", *policies] + ([f"{reference} (paper)"] if reference else [])
    rows = []
    for p in perts:
        row = [p] + [f"{sum(v) / len(v):.2f}" if (v := by_pol.get(pol, {}).get(p)) else "-" for pol in policies]
        if reference:
            row.append(f"{PAPER[reference][p]:.2f}" if p in PAPER[reference] else "-")
        rows.append(row)
    avg = ["V / S / B avg"]
    for pol in policies:
        parts = []
        for g in "VSB":
            vals = [sum(v) / len(v) for p, v in by_pol.get(pol, {}).items() if g in factor_groups(p)]
            parts.append(f"{sum(vals) / len(vals):.2f}" if vals else "-")
        avg.append("/".join(parts))
    if reference:
        parts = []
        for g in "VSB":
            vals = [v for p, v in PAPER[reference].items() if g in factor_groups(p)]
            parts.append(f"{sum(vals) / len(vals):.2f}")
        avg.append("/".join(parts))
    rows.append(avg)
    return header, rows


def _md(header, rows) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out) + "\n"
