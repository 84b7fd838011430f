"""``realm sysid report``: one self-contained HTML page (PNG figures embedded as base64).

Sections (``sections.py``, one function each, in ``SECTIONS`` order): overview error table, the
flange error, lag and response per lab and per trajectory (``alignment.replay_flange``), where the
model fails (conditions and time windows), suspects table, waterfall of held-out error as the
model's effects are added one at a time and with each one left out, fitted parameters with
units/bounds and 95 % confidence intervals (from ``fit --json``), fit history,
overlays, residual vs q̇ / q̈ / g(q), cross-correlation vs lag, hysteresis at reversals.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from realm_ms.atomic import write_text
from realm_ms.html_kit import sections_page
from realm_ms.sysid.optimize import Group, evaluate_groups
from realm_ms.sysid.replay import SegmentSet
from realm_ms.sysid.report.auto_sections import auto_waterfall, friction_curves
from realm_ms.sysid.report.sections import SECTIONS, ReportData, Replay


def _context(ss: SegmentSet, arm_model, gains: str) -> dict:
    import torch

    from realm_ms.agents.control import GAIN_PRESETS, BatchedGains

    vel, acc, err = [], [], []
    rev = []
    for i, s in enumerate(ss.segments):
        tr = ss.trajs[s.traj]
        t = tr.t[s.start:s.stop]
        v = tr.velocity()[s.start:s.stop]
        a = np.gradient(v, t, axis=0)
        m = ss.mask[i, : s.stop - s.start]
        sign = np.sign(v)
        flips = np.zeros_like(v, dtype=bool)
        flips[1:] = (sign[1:] != sign[:-1]) & (np.abs(v[1:]) + np.abs(v[:-1]) > 0.02)
        near = np.zeros_like(flips)
        for j in range(7):
            for k in np.where(flips[:, j])[0]:
                near[np.abs(t - t[k]) <= 0.2, j] = True
        vel.append(v[m]); acc.append(a[m]); rev.append(near[m])
        err.append((tr.q_cmd[s.start:s.stop] - tr.q[s.start:s.stop])[m])
    vel, acc, err, rev = (np.concatenate(x) for x in (vel, acc, err, rev))
    q = torch.as_tensor(ss.meas[ss.mask], dtype=torch.float32)
    with torch.inference_mode():
        grav = arm_model.gravity_torque(q).numpy()
        g = BatchedGains.from_gains(GAIN_PRESETS[gains] if isinstance(gains, str) else gains, len(q), "cpu")
        jac = arm_model.jacobian(q)
        kp = torch.diag_embed(g.kq) + jac.transpose(1, 2) @ (g.kx[..., None] * jac)
        tau = (kp @ torch.as_tensor(err, dtype=torch.float32)[..., None])[..., 0]
    speed, accel = np.abs(vel), np.abs(acc)
    top = lambda x: x >= np.quantile(x, 0.8, axis=0)  # noqa: E731
    return {"vel": vel, "acc": acc, "grav": grav.astype(float), "tau": tau.numpy().astype(float), "err": err,
            "reversal": rev, "hold": speed.max(axis=1) < 0.02, "fast": top(speed), "accel": top(accel),
            "gravload": top(np.abs(grav))}


def build_report(train, heldout, model, out: Path, evaluator, diagnosis=None, fit_result=None, waterfall=True,
                 data_name: str = "", log=print, auto=None) -> Path:
    from realm_ms.sysid.diagnose import DiagnoseConfig, diagnose
    from realm_ms.sysid.signatures import noise_floor

    seg = DiagnoseConfig()
    tr_ss = SegmentSet.build(train, model.physics_hz, seg.segment_s, seg.burn_in_s, gains=model.gains)
    he_ss = SegmentSet.build(heldout, model.physics_hz, seg.segment_s, seg.burn_in_s, gains=model.gains)
    effects = sorted(model.effects, key=lambda f: f.order)
    log("replaying nominal and model")
    groups = [Group.of([]), Group.of(effects)]
    pts = [np.zeros((1, 0)), groups[1].u[None]]
    if waterfall and len(effects) > 1:
        for k in range(1, len(effects)):
            groups.append(Group.of(effects[:k]))
            pts.append(groups[-1].u[None])
        for k in range(len(effects)):  # leave one effect out: what each one is worth in the full model
            groups.append(Group.of(effects[:k] + effects[k + 1:]))
            pts.append(groups[-1].u[None])
    r_tr, r_he = evaluate_groups(evaluator, [tr_ss, he_ss], [], groups, pts)
    rep = lambda label, ss, r: Replay(label, ss, r.sim[0])  # noqa: E731
    name = "model" if model.effects else "nominal"
    d = ReportData(name, data_name, rep("nominal", tr_ss, r_tr[0]), rep("nominal", he_ss, r_he[0]),
                   rep(name, tr_ss, r_tr[1]), rep(name, he_ss, r_he[1]), {}, 0.0, model=model, fit=fit_result,
                   auto=auto)
    floors = [noise_floor(he_ss, x.residual)[0] for x in (d.nominal_held, d.model_held)]
    d.noise_floor = float(min(floors))
    d.context = _context(he_ss, evaluator.sim.model if evaluator.device == "cpu" else _arm(), model.gains)
    if effects:
        wf = [("nominal", r_he[0].rmse)]
        for k in range(1, len(effects)):
            wf.append(("+ " + effects[k - 1].name, r_he[k + 1].rmse))
        wf.append(("+ " + effects[-1].name if len(effects) > 1 else "+ " + effects[0].name, r_he[1].rmse))
        d.waterfall = wf
        if waterfall and len(effects) > 1:
            first = len(effects) + 1
            d.leave_one_out = [("- " + fx.name, r_he[first + k].rmse) for k, fx in enumerate(effects)]
    if diagnosis is None:
        log("diagnosing what is still missing")
        diagnosis = diagnose(train, heldout, model, evaluator=evaluator, log=log).to_json()
    d.diagnosis = diagnosis
    sections = []
    for fn in SECTIONS[:5] + [auto_waterfall, friction_curves] + SECTIONS[5:]:
        try:
            sections.append(fn(d))
        except Exception as e:  # noqa: BLE001 - one failing plot must not lose the whole report
            sections.append((fn.__name__, f"<p class='bad'>section failed: {type(e).__name__}: {e}</p>"))
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, sections_page(f"realm sysid report: {data_name}", sections))
    return out


def _arm():
    from realm_ms.sysid.diagnose import _arm_model

    return _arm_model()
