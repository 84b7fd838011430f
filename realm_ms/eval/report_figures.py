"""Matplotlib figures of the eval reports. Each returns a figure, or ``None`` when it would show
nothing (the caller then says so in words instead of drawing an empty box)."""

from __future__ import annotations

PAPER_ORDER = ["Default", "V-AUG", "V-VIEW", "V-SC", "V-LIGHT", "S-PROP", "S-LANG", "S-MO", "S-AFF", "S-INT", "B-HOBJ",
               "SB-NOUN", "SB-VRB", "VB-POSE", "VB-MOBJ", "VSB-NOBJ"]  # REALM's table order
SUCCESS_COLOR = "#5a5"


def order(perts) -> list[str]:
    return sorted(perts, key=lambda p: (PAPER_ORDER.index(p) if p in PAPER_ORDER else len(PAPER_ORDER), p))


def _short(t: str) -> str:
    return t.removeprefix("REALM-").removesuffix("-v1")


def heatmap(metrics: dict, field: str, title: str):
    import matplotlib.pyplot as plt
    import numpy as np

    cells = metrics["per_cell"]
    if not cells:
        return None
    tasks = sorted(cells)
    perts = order({p for t in cells for p in cells[t]})
    m = np.full((len(tasks), len(perts)), np.nan)
    for i, t in enumerate(tasks):
        for j, p in enumerate(perts):
            if p in cells[t]:
                m[i, j] = cells[t][p][field]
    fig, ax = plt.subplots(figsize=(2.2 + 0.8 * len(perts), 1.1 + 0.42 * len(tasks)))
    im = ax.imshow(m, vmin=0, vmax=1, cmap="viridis", aspect="auto")
    ax.set_xticks(range(len(perts)), perts, rotation=45 if len(perts) > 3 else 0, ha="right" if len(perts) > 3 else "center")
    ax.set_yticks(range(len(tasks)), [_short(t) for t in tasks])
    for i in range(len(tasks)):
        for j in range(len(perts)):
            if not np.isnan(m[i, j]):
                ax.text(j, i, f"{m[i, j]:.2f}", ha="center", va="center", color="w" if m[i, j] < 0.6 else "k", fontsize=8)
    fig.colorbar(im, ax=ax, fraction=0.04)
    ax.set_title(title, fontsize=10)
    return fig


def deltas(metrics: dict):
    """Bars of each perturbation's change against Default (progression and success rate); None when
    there is nothing to compare or every delta is 0."""
    import matplotlib.pyplot as plt
    import numpy as np

    d = metrics["delta_to_default"]
    perts = order(d)
    prog = np.array([d[p]["mean_progression"] for p in perts])
    succ = np.array([d[p]["success_rate"] for p in perts])
    if not perts or (np.allclose(prog, 0) and np.allclose(succ, 0)):
        return None
    x = np.arange(len(perts))
    fig, ax = plt.subplots(figsize=(2.5 + 0.8 * len(perts), 3.0))
    ax.bar(x - 0.2, prog, 0.4, label="mean progression", color="#4878b0")
    ax.bar(x + 0.2, succ, 0.4, label="success rate", color="#e0a040")
    ax.axhline(0, color="k", lw=0.8)
    lim = max(0.1, float(np.abs(np.concatenate([prog, succ])).max()) * 1.15)
    ax.set_ylim(-lim, lim)
    ax.set_xticks(x, perts, rotation=45 if len(perts) > 3 else 0, ha="right" if len(perts) > 3 else "center")
    ax.set_ylabel("perturbation - Default")
    ax.legend(fontsize=8, loc="best")
    return fig


def failure_bars(metrics: dict):
    """Per task, stacked shares of episodes that succeeded or stalled at each stage."""
    import matplotlib.pyplot as plt
    import numpy as np

    per = metrics["failure_stages_per_task"]
    if not per:
        return None
    tasks = sorted(per)
    stages: list[str] = []
    for t in tasks:
        stages += [s for s in per[t] if s not in stages and s != "DONE"]
    fig, ax = plt.subplots(figsize=(8, 1.1 + 0.42 * len(tasks)))
    left = np.zeros(len(tasks))
    cmap = plt.get_cmap("tab10")
    palette = [cmap(k) for k in (3, 1, 4, 5, 6, 7, 8, 9, 0)]
    series = ([("DONE", "succeeded", SUCCESS_COLOR)] if any("DONE" in per[t] for t in tasks) else []) + \
             [(s, f"stalled at {s}", palette[k % len(palette)]) for k, s in enumerate(stages)]
    for key, label, color in series:
        v = np.array([per[t].get(key, 0.0) for t in tasks])
        ax.barh(range(len(tasks)), v, left=left, label=label, color=color)
        left += v
    ax.set_yticks(range(len(tasks)), [_short(t) for t in tasks])
    ax.set_xlabel("share of the task's episodes")
    ax.invert_yaxis()  # first task on top, as in the heat-maps
    ax.set_xlim(0, 1)
    ax.legend(fontsize=8, bbox_to_anchor=(1.01, 1), loc="upper left")
    return fig


def compare_policies(runs: list[tuple[str, dict]]):
    """Grouped bars: mean progression per perturbation (over tasks) for each policy, with its 95 %
    bootstrap interval; None when no run has finished episodes."""
    import matplotlib.pyplot as plt
    import numpy as np

    perts = order({p for _, m in runs for p in m["per_perturbation"]})
    if not perts:
        return None
    n = len(runs)
    width = 0.8 / max(n, 1)
    x = np.arange(len(perts))
    fig, ax = plt.subplots(figsize=(3 + 1.0 * len(perts) * max(1, n / 2), 3.2))
    cmap = plt.get_cmap("tab10")
    for k, (name, m) in enumerate(runs):
        pp = m["per_perturbation"]
        vals = np.array([pp[p]["mean_progression"] if p in pp else np.nan for p in perts])
        lo = np.array([pp[p]["progression_ci"][0] if p in pp else np.nan for p in perts])
        hi = np.array([pp[p]["progression_ci"][1] if p in pp else np.nan for p in perts])
        xs = x - 0.4 + width * (k + 0.5)
        ax.bar(xs, np.nan_to_num(vals), width * 0.95, color=cmap(k % 10), label=name)
        ax.errorbar(xs, vals, yerr=[vals - lo, hi - vals], fmt="none", ecolor="k", elinewidth=1, capsize=3)
        for xv, v, h in zip(xs, vals, hi):  # the value above each bar: a bar at 0 is otherwise invisible
            if not np.isnan(v):
                ax.text(xv, min(h, 1.0) + 0.02, f"{v:.2f}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x, perts, rotation=45 if len(perts) > 4 else 0, ha="right" if len(perts) > 4 else "center")
    ax.set_ylim(0, 1.12)
    ax.set_ylabel("mean progression")
    ax.legend(fontsize=8, bbox_to_anchor=(1.01, 1), loc="upper left")
    return fig
