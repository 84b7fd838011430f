"""Report sections for ``realm sysid auto``: the waterfall of kept steps and the friction curves."""

from __future__ import annotations

import numpy as np

from realm_ms.html_kit import esc, table
from realm_ms.sysid.diagnose import DiagnoseConfig
from realm_ms.sysid.report.figures import new, to_img
from realm_ms.sysid.report.sections import JOINTS, ReportData


def auto_waterfall(d: ReportData):
    from realm_ms.sysid.auto import step_label

    a = getattr(d, "auto", None)
    if not a:
        return "Auto waterfall", "<p>No <code>auto --json</code> given (pass <code>--auto AUTO.json</code>).</p>"
    unit = a.get("unit", "rad")
    scale, shown = (1e3, "mrad") if unit == "rad" else (1.0, unit)
    labels = ["nominal"] + [step_label(s) for s in a["steps"]]
    vals = np.array([a["nominal_heldout_rmse"]] + [s["heldout_rmse"] for s in a["steps"]])
    fin = a["final"]
    details = a.get("details") or {}
    floor = details.get("judging_floor", fin["noise_floor"])
    factor = details.get("found_factor", DiagnoseConfig.found_factor)  # absent from older auto JSON
    fig, ax = new(1, 1, 9, 3.2)
    x = ax[0, 0]
    x.bar(range(len(vals)), vals * scale, color=["tab:red"] + ["tab:blue"] * (len(vals) - 1))
    x.axhline(fin["noise_floor"] * scale, color="k", ls="--", lw=1, label="noise floor")
    x.axhline(factor * floor * scale, color="tab:green", ls=":", lw=1, label=f"{factor:g}x judging floor")
    x.set_xticks(range(len(vals)), labels, rotation=20, fontsize=8)
    x.set_ylabel(f"held-out RMSE [{shown}]")
    x.legend(fontsize=8)
    rows = [[lab, f"{v:.3e}", _ratio(v, floor)] for lab, v in zip(labels, vals)]
    for r in details.get("rejected", []):
        rows.append([f"(rejected) {step_label(r).lstrip('+')}", f"{r['heldout_rmse']:.3e}", _ratio(r['heldout_rmse'], floor)])
    msg = details.get("message", "")
    head = f"<p>verdict <b>{esc(fin['verdict'])}</b>. {esc(msg)}</p>"
    return ("Auto: nominal → + effect → …", head + to_img(fig, "auto waterfall")
            + table(["model", f"held-out RMSE [{unit}]", "/ judging floor"], rows))


def friction_curves(d: ReportData):
    from realm_ms.sysid.auto import friction_curve

    if d.model is None:
        return "Friction curves", "<p>No model.</p>"
    fc = friction_curve(d.model)
    tau = np.array(fc["tau"])
    if not np.any(tau):
        return "Friction curves", "<p>The model has no friction effect.</p>"
    qd = np.array(fc["qd"])
    fig, ax = new(1, 1, 9, 3.2)
    a = ax[0, 0]
    for j in range(7):
        a.plot(qd[qd < 0], tau[qd < 0, j], color=f"C{j}", label=JOINTS[j])
        a.plot(qd[qd > 0], tau[qd > 0, j], color=f"C{j}")
    a.axhline(0, color="k", lw=0.5)
    a.set_xlabel("joint velocity [rad/s]")
    a.set_ylabel("friction torque [N·m]")
    a.legend(fontsize=7, ncol=7)
    return ("Friction curves of the model (steady sliding)",
            "<p class='note'>Torque needed to keep each joint sliding at q̇ (same sign as q̇, as in Gaz et al. 2019); "
            "the same grid as <code>auto --json</code> → <code>friction_curve</code>.</p>" + to_img(fig, "friction curves"))


def _ratio(v: float, floor: float) -> str:
    return f"{v / floor:.1f}" if floor > 0 else "- (floor 0)"  # a zero floor is never divided
