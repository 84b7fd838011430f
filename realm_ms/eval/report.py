"""``realm eval report RUN/``: a self-contained HTML report (PNGs embedded, also written beside it),
and the REALM paper's table layout as markdown and CSV.

Figures: task x perturbation heat-maps (mean progression, success rate), each perturbation's delta
to Default, failure-stage bars per task; plus per-task / per-perturbation tables with intervals,
time-to-stage, errors, and links to episode videos (``--videos failures|all|none``).
Paper table (``table.md``, ``table.csv``): one row per perturbation (mean progression over tasks),
then the V / S / B averages, one column per policy in the run (and REALM's published numbers
with ``--reference``).
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
from pathlib import Path

from realm_ms.eval.metrics import compute_metrics
from realm_ms.eval.protocol import DEFAULT
from realm_ms.eval.records import latest_by_key, read_records

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


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    return buf.getvalue()


def _order(perts) -> list[str]:
    return sorted(perts, key=lambda p: (PAPER_ORDER.index(p) if p in PAPER_ORDER else len(PAPER_ORDER), p))


def _heatmap(metrics: dict, field: str, title: str):
    import matplotlib.pyplot as plt
    import numpy as np

    cells = metrics["per_cell"]
    tasks = sorted(cells)
    perts = _order({p for t in cells for p in cells[t]})
    m = np.full((len(tasks), len(perts)), np.nan)
    for i, t in enumerate(tasks):
        for j, p in enumerate(perts):
            if p in cells[t]:
                m[i, j] = cells[t][p][field]
    fig, ax = plt.subplots(figsize=(1.2 + 0.75 * len(perts), 0.9 + 0.42 * len(tasks)))
    im = ax.imshow(m, vmin=0, vmax=1, cmap="viridis", aspect="auto")
    ax.set_xticks(range(len(perts)), perts, rotation=45, ha="right")
    ax.set_yticks(range(len(tasks)), [t.removeprefix("REALM-").removesuffix("-v1") for t in tasks])
    for i in range(len(tasks)):
        for j in range(len(perts)):
            if not np.isnan(m[i, j]):
                ax.text(j, i, f"{m[i, j]:.2f}", ha="center", va="center", color="w" if m[i, j] < 0.6 else "k", fontsize=8)
    fig.colorbar(im, ax=ax, fraction=0.04)
    ax.set_title(title)
    return fig


def _deltas(metrics: dict):
    import matplotlib.pyplot as plt

    d = metrics["delta_to_default"]
    perts = _order(d)
    fig, ax = plt.subplots(figsize=(1.5 + 0.6 * max(1, len(perts)), 3.2))
    vals = [d[p]["mean_progression"] for p in perts]
    ax.bar(perts, vals, color=["#c44" if v < 0 else "#4a4" for v in vals])
    ax.axhline(0, color="k", lw=0.8)
    ax.set_ylabel("mean progression - Default")
    ax.set_title("delta to Default (paired over tasks)")
    ax.tick_params(axis="x", rotation=45)
    return fig


def _failure_bars(metrics: dict):
    import matplotlib.pyplot as plt
    import numpy as np

    per = metrics["failure_stages_per_task"]
    tasks = sorted(per)
    stages = []
    for t in tasks:
        for s in per[t]:
            if s not in stages:
                stages.append(s)
    stages = [s for s in stages if s != "DONE"] + (["DONE"] if any("DONE" in per[t] for t in tasks) else [])
    fig, ax = plt.subplots(figsize=(8, 0.9 + 0.42 * len(tasks)))
    left = np.zeros(len(tasks))
    cmap = plt.get_cmap("tab20")
    for k, s in enumerate(stages):
        v = np.array([per[t].get(s, 0.0) for t in tasks])
        ax.barh(range(len(tasks)), v, left=left, label=s, color="#8c8" if s == "DONE" else cmap(k % 20))
        left += v
    ax.set_yticks(range(len(tasks)), [t.removeprefix("REALM-").removesuffix("-v1") for t in tasks])
    ax.set_xlabel("share of episodes stalled at stage (DONE = success)")
    ax.set_xlim(0, 1)
    ax.legend(fontsize=7, bbox_to_anchor=(1.01, 1), loc="upper left")
    ax.set_title("where it fails")
    return fig


def paper_table(metrics: dict, records: list[dict], reference: str | None = None) -> tuple[list[str], list[list[str]]]:
    """Rows: perturbations then 'V / S / B avg'; columns: policy (+ reference): REALM's layout."""
    from realm_ms.eval.protocol import factor_groups

    policies = metrics["policies"] or ["policy"]
    by_pol: dict[str, dict[str, list[float]]] = {}
    for r in records:
        if r.get("status", "ok") == "ok":
            by_pol.setdefault(r.get("policy", "policy"), {}).setdefault(r["perturbation"], []).append(float(r["progression"]))
    perts = _order({p for v in by_pol.values() for p in v})
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


def _html_table(header, rows) -> str:
    h = "".join(f"<th>{html.escape(str(c))}</th>" for c in header)
    b = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{b}</table>"


def _ci(s: dict) -> list[str]:
    return [str(s["episodes"]), f"{s['success_rate']:.2f} [{s['success_ci'][0]:.2f}, {s['success_ci'][1]:.2f}]",
            f"{s['mean_progression']:.2f} [{s['progression_ci'][0]:.2f}, {s['progression_ci'][1]:.2f}]"]


def write_report(run_dir: Path, out: Path, videos: str = "failures", reference: str | None = None) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run_dir, out = Path(run_dir), Path(out)
    records = list(latest_by_key(read_records(run_dir / "records.jsonl")).values())
    metrics = compute_metrics(records)
    if reference and reference not in PAPER:
        raise ValueError(f"unknown reference {reference!r}; known: {', '.join(PAPER)}")
    files = out.parent / (out.stem + "_files")
    files.mkdir(parents=True, exist_ok=True)
    figs = {}
    if metrics["per_cell"]:
        figs["heatmap_progression.png"] = _heatmap(metrics, "mean_progression", "mean progression (task x perturbation)")
        figs["heatmap_success.png"] = _heatmap(metrics, "success_rate", "success rate (task x perturbation)")
        figs["failure_stages.png"] = _failure_bars(metrics)
    if metrics["delta_to_default"]:
        figs["delta_to_default.png"] = _deltas(metrics)
    imgs = []
    for name, fig in figs.items():
        data = _png(fig)
        plt.close(fig)
        (files / name).write_bytes(data)
        imgs.append(f'<figure><img src="data:image/png;base64,{base64.b64encode(data).decode()}" alt="{name}"><figcaption>{name}</figcaption></figure>')
    header, rows = paper_table(metrics, records, reference)
    (files / "table.md").write_text(_md(header, rows))
    with open(files / "table.csv", "w", newline="") as f:
        csv.writer(f).writerows([header, *rows])
    (files / "metrics.json").write_text(json.dumps(metrics, indent=2))
    o = metrics["overall"]
    task_rows = [[t, *_ci(s)] for t, s in metrics["per_task"].items()]
    pert_rows = [[p, *_ci(metrics["per_perturbation"][p]),
                  f"{metrics['delta_to_default'][p]['mean_progression']:+.2f}" if p in metrics["delta_to_default"] else "",
                  f"{metrics['rmsd_to_default'][p]:.3f}" if p in metrics["rmsd_to_default"] else ""]
                 for p in _order(metrics["per_perturbation"])]
    group_rows = [[g, *_ci(s)] for g, s in metrics["per_factor_group"].items()]
    tts = [[s, str(v["episodes"]), f"{v['mean_steps']:.1f}", f"{v['median_steps']:.0f}"] for s, v in metrics["time_to_stage"].items()]
    fail = [[s, f"{v:.2f}"] for s, v in metrics["failure_stages"].items()]
    vids = []
    if videos != "none":
        for r in records:
            if r.get("video") and (videos == "all" or not r.get("success")):
                rel = Path(r["video"])
                try:
                    rel = Path(r["video"]).resolve().relative_to(out.parent.resolve())
                except ValueError:
                    pass
                vids.append(f'<li><a href="{html.escape(str(rel))}">{html.escape(r["task"])} / {html.escape(r["perturbation"])} / seed {r["seed"]}</a> '
                            f'progression {r["progression"]:.2f}, stalled at {html.escape(str(r.get("stalled_stage")))}</li>')
    errors = [[str(e.get(k)) for k in ("task", "perturbation", "seed", "error")] for e in metrics["errors"]]
    body = f"""<!doctype html><html><head><meta charset="utf-8"><title>realm eval report: {html.escape(', '.join(metrics['policies']))}</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:auto;padding:1em}}table{{border-collapse:collapse;margin:.5em 0}}
td,th{{border:1px solid #ccc;padding:2px 8px;text-align:right}}td:first-child,th:first-child{{text-align:left}}img{{max-width:100%}}
figure{{display:inline-block;margin:.5em}}</style></head><body>
<h1>REALM evaluation: {html.escape(', '.join(metrics['policies']) or '(no finished episodes)')}</h1>
<p>{o['episodes']} episodes, success rate {o['success_rate']:.3f} (95 % Wilson [{o['success_ci'][0]:.3f}, {o['success_ci'][1]:.3f}]),
mean progression {o['mean_progression']:.3f} (95 % bootstrap [{o['progression_ci'][0]:.3f}, {o['progression_ci'][1]:.3f}]);
{len(metrics['errors'])} errored, {len(metrics['unsupported_cells'])} unsupported cell(s). Run directory: {html.escape(str(run_dir))}.</p>
{''.join(imgs)}
<h2>REALM paper layout (mean progression)</h2>{_html_table(header, rows)}
<h2>Per task</h2>{_html_table(['task', 'episodes', 'success [95% CI]', 'progression [95% CI]'], task_rows)}
<h2>Per perturbation</h2>{_html_table(['perturbation', 'episodes', 'success [95% CI]', 'progression [95% CI]', 'delta to Default', 'RMSD to Default'], pert_rows)}
<h2>Per factor group</h2>{_html_table(['group', 'episodes', 'success [95% CI]', 'progression [95% CI]'], group_rows)}
<h2>Failure attribution (share of episodes stalled at each stage)</h2>{_html_table(['stage', 'share'], fail)}
<h2>Time to stage (control steps, episodes that reached it)</h2>{_html_table(['stage', 'episodes', 'mean', 'median'], tts)}
{'<h2>Videos</h2><ul>' + ''.join(vids) + '</ul>' if vids else ''}
{'<h2>Errors</h2>' + _html_table(['task', 'perturbation', 'seed', 'error'], errors) if errors else ''}
<p>Figures, <code>table.md</code>, <code>table.csv</code> and <code>metrics.json</code> are also in {html.escape(files.name)}/.</p>
</body></html>"""
    out.write_text(body)
    return out
