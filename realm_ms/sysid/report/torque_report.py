"""``realm sysid report`` on torque logs: per-joint measured vs model torque residual overlays (N·m).

The residual is the inverse dynamics of the URDF at the measured state, ``tau − ID(q, q̇, q̈)``
(``sysid/torque/residual.py``); the model's terms should reproduce it. Sections: per-joint held-out
RMSE (nominal, model, noise floor), overlays of the measured residual and the model's terms on the
first held-out trajectory, the residual left by frequency band, residual left vs q̇, and the ``auto``
waterfall / friction curves.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from realm_ms.atomic import write_text
from realm_ms.html_kit import esc, sections_page, table
from realm_ms.sysid.report.figures import new, to_img
from realm_ms.sysid.report.sections import JOINTS

UNIT = "N·m"


def torque_sections(train, held, model=None, auto=None) -> list[tuple[str, str]]:
    from realm_ms.sysid.torque.residual import TorqueSet, predict, residual_bands, rmse, terms_of, torque_arm

    arm = torque_arm()
    terms = terms_of(model, log=lambda *a: None)
    he = TorqueSet.build(held, arm)
    nom, nom_j = rmse(he, [])
    mod, mod_j = rmse(he, terms)
    names = ", ".join(t.name for t in terms) or "none"
    rows = [["nominal URDF", f"{nom:.4f}"] + [f"{x:.3f}" for x in nom_j],
            [f"model ({names})", f"{mod:.4f}"] + [f"{x:.3f}" for x in mod_j],
            ["noise floor", f"{np.sqrt(np.mean(he.noise ** 2)):.4f}"] + [f"{x:.3f}" for x in he.noise]]
    out = [("Held-out torque residual per joint [N·m]",
            "<p class='note'>RMSE of τ − M q̈ − C q̇ − g (minus the model's terms) over the held-out trajectories, "
            "q̈ and τ through the same Savitzky–Golay kernel.</p>"
            + table(["", f"all [{UNIT}]"] + list(JOINTS), rows))]

    one = TorqueSet.build(held[:1], arm)  # overlays on one trajectory: a time axis a reader can follow
    meas = one.tau - one.nominal
    pred = predict(terms, one.samples, len(meas))
    dt = float(np.median(np.diff(held[0].t)))
    t = np.arange(len(meas)) * dt
    fig, ax = new(7, 1, 11, 1.6)
    for j in range(7):
        a = ax[j, 0]
        a.plot(t, meas[:, j], color="0.5", lw=0.6, label="measured τ − ID")
        a.plot(t, pred[:, j], color="tab:blue", lw=0.9, label="model terms")
        a.plot(t, meas[:, j] - pred[:, j], color="tab:red", lw=0.6, label="left")
        r = np.sqrt(np.mean((meas[:, j] - pred[:, j]) ** 2))
        a.set_ylabel(f"{JOINTS[j]} [{UNIT}]", fontsize=7)
        a.set_title(f"{JOINTS[j]}: RMSE left {r:.3f} {UNIT}", fontsize=8, loc="left")
        if j == 0:
            a.legend(fontsize=7, ncol=3, loc="upper right")
    ax[-1, 0].set_xlabel(f"time in {held[0].name} (scored part) [s]")
    out.append(("Torque residual overlays (held-out)", to_img(fig, "torque overlays")))

    bands = residual_bands(he, terms)
    rows = [[name, f"{100 * share:.1f}%"] + [f"{x:.3f}" for x in row]
            for name, share, row in zip(bands["bands"], bands["share"], bands["rms_per_joint"])]
    out.append(("Residual left by frequency band (held-out)",
                "<p class='note'>RMS of what the model leaves, split by an FFT mask per trajectory (the squares add "
                "up). Rigid-body and friction terms act at the motion's frequencies; what is left above 10 Hz "
                "(joint elasticity, structural modes, torque-sensor dynamics) no library effect reaches.</p>"
                + table(["band", "share of power"] + [f"{j} [{UNIT}]" for j in JOINTS], rows)))

    left = he.tau - he.nominal - predict(terms, he.samples, len(he.tau))
    v = he.samples.qd.numpy()
    fig, ax = new(1, 7, 14, 2.4)
    edges = np.linspace(-1.5, 1.5, 31)
    for j in range(7):
        idx = np.digitize(v[:, j], edges)
        mids, means = [], []
        for b in range(1, len(edges)):
            m = idx == b
            if m.sum() >= 20:
                mids.append(0.5 * (edges[b - 1] + edges[b]))
                means.append(left[m, j].mean())
        ax[0, j].plot(mids, means, ".-", color=f"C{j}")
        ax[0, j].axhline(0, color="k", lw=0.5)
        ax[0, j].set_title(JOINTS[j], fontsize=8)
        ax[0, j].set_xlabel("q̇ [rad/s]", fontsize=7)
    ax[0, 0].set_ylabel(f"residual left [{UNIT}]")
    out.append(("Residual left vs joint velocity (binned means)",
                "<p class='note'>A step at q̇ = 0 left over points at dry friction, a slope at viscous friction, "
                "a curve that saturates at a smooth (sigmoid) friction law.</p>" + to_img(fig, "residual vs velocity")))
    if auto is not None or model is not None:
        from types import SimpleNamespace

        from realm_ms.sysid.report.auto_sections import auto_waterfall, friction_curves

        d = SimpleNamespace(auto=auto, model=model)
        out += [auto_waterfall(d), friction_curves(d)]
    return out


def build_torque_report(train, held, model, out: Path, data_name: str = "", auto=None) -> Path:
    sections = torque_sections(train, held, model, auto)
    head = ("Torque space", f"<p>Data <code>{esc(data_name)}</code>: {len(train)} train + {len(held)} held-out "
            "trajectories with measured joint torque; the model is compared on the inverse-dynamics residual.</p>")
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, sections_page(f"realm sysid report (torque space): {data_name}", [head] + sections))
    return out
