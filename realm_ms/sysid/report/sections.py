"""Report sections. Each function takes the shared ``ReportData`` and returns (title, html)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.agents.effects.parameter import format_value
from realm_ms.html_kit import esc, table
from realm_ms.sysid.report.figures import new, to_img
from realm_ms.sysid.saturation import PAD_S

JOINTS = [f"J{i}" for i in range(1, 8)]


@dataclass
class Replay:
    """One model replayed on one segment set: residual at scored samples + per-sample context."""

    label: str
    segset: object
    sim: np.ndarray  # (N, L, 7)

    @property
    def residual(self) -> np.ndarray:
        return np.where(self.segset.mask[..., None], self.segset.meas - self.sim, np.nan)

    def flat(self) -> np.ndarray:
        return (self.segset.meas - self.sim)[self.segset.mask]

    def rmse(self) -> float:
        return float(np.sqrt(np.mean(self.flat() ** 2)))

    def per_joint(self) -> np.ndarray:
        return np.sqrt(np.mean(self.flat() ** 2, axis=0))


@dataclass
class ReportData:
    model_name: str
    data_name: str
    nominal_train: Replay
    nominal_held: Replay
    model_train: Replay
    model_held: Replay
    context: dict  # flat per-sample arrays on the held-out scored samples: vel, acc, grav, cmd_err, reversal, hold
    noise_floor: float
    diagnosis: dict | None = None
    fit: dict | None = None
    waterfall: list[tuple[str, float]] = field(default_factory=list)
    leave_one_out: list[tuple[str, float]] = field(default_factory=list)  # full model minus one effect
    model: object = None
    auto: dict | None = None  # `realm sysid auto --json` output


def _fmt(v: float) -> str:
    return f"{v:.2e}"


def overview(d: ReportData):
    rows, cls = [], []
    for label, tr, he in (("nominal robot", d.nominal_train, d.nominal_held), (d.model_name, d.model_train, d.model_held)):
        pj = he.per_joint()
        rows.append([label, _fmt(tr.rmse()), _fmt(he.rmse()), f"{he.rmse() / max(d.noise_floor, 1e-12):.1f}"] + [_fmt(v) for v in pj])
        cls.append(["", "", "", "good" if he.rmse() <= 1.5 * d.noise_floor else "bad"] + [""] * 7)
    intro = (f"<p>Data: <b>{esc(d.data_name)}</b> ({len(d.model_train.segset.trajs)} train / {len(d.model_held.segset.trajs)} "
             f"held-out trajectories). Replay: the benchmark's DROID controller and URDF at {d.model.physics_hz:g} Hz, "
             f"multiple shooting from the measured state. Noise floor (sensor noise estimate) ≈ {d.noise_floor:.2e} rad."
             + (f" {d.model_held.segset.saturated_fraction:.1%} of the held-out samples lie in torque-saturated bursts "
                f"(a motor at its 87/12 N·m limit, ± {PAD_S:g} s): simulated, not scored." if d.model_held.segset.saturated_fraction else "")
             + "</p>")
    return "Overview: error per joint", intro + table(
        ["model", "train RMSE [rad]", "held-out RMSE [rad]", "held-out / noise"] + [f"{j} held-out" for j in JOINTS], rows, classes=cls)


def where_it_fails(d: ReportData):
    res = d.model_held.flat()
    ctx = d.context
    conds = {
        "all samples": np.ones(len(res), bool),
        "holds (|q̇| < 0.02 rad/s)": ctx["hold"],
        "reversals (±0.2 s around a q̇ sign change)": ctx["reversal"],
        "high speed (top 20 % |q̇|)": ctx["fast"],
        "high acceleration (top 20 % |q̈|)": ctx["accel"],
        "high gravity load (top 20 % |g(q)|)": ctx["gravload"],
    }
    rows, cls = [], []
    base = np.sqrt(np.mean(res**2, axis=0))
    for name, m in conds.items():
        if m.ndim == 1:
            m = np.repeat(m[:, None], 7, 1)
        vals = [np.sqrt(np.mean(res[m[:, j], j] ** 2)) if m[:, j].sum() > 3 else np.nan for j in range(7)]
        rows.append([name, f"{100 * m.mean():.0f}%"] + [("–" if np.isnan(v) else _fmt(v)) for v in vals])
        cls.append(["", ""] + ["bad" if (not np.isnan(v) and v > 1.5 * base[j] and v > 2 * d.noise_floor) else "" for j, v in enumerate(vals)])
    # time windows: worst 1-s windows of the held-out data
    ss = d.model_held.segset
    worst = []
    for i, s in enumerate(ss.segments):
        tr = ss.trajs[s.traj]
        m = ss.mask[i, : s.stop - s.start]
        t = tr.t[s.start:s.stop][m]
        r = (ss.meas[i] - d.model_held.sim[i])[: s.stop - s.start][m]
        for w0 in np.arange(t[0], t[-1], 1.0):
            k = (t >= w0) & (t < w0 + 1.0)
            if k.sum() > 2:
                e = np.sqrt(np.mean(r[k] ** 2, axis=0))
                worst.append((float(np.sqrt(np.mean(e**2))), tr.name, w0, int(np.argmax(e))))
    worst.sort(reverse=True)
    wt = table(["trajectory", "window [s]", "RMSE [rad]", "worst joint"],
               [[n, f"{w:.0f}–{w + 1:.0f}", _fmt(e), JOINTS[j]] for e, n, w, j in worst[:6]])
    return "Where the model fails (held-out, by condition and time window)", (
        "<p class='note'>Held-out RMSE per joint restricted to each condition; red: over 1.5× the joint's overall RMSE "
        "and 2× the noise floor.</p>" + table(["condition", "share"] + JOINTS, rows, classes=cls) + "<p>Worst 1-s windows:</p>" + wt)


def overlays(d: ReportData):
    ss = d.model_held.segset
    rms = [np.sqrt(np.nanmean(d.model_held.residual[i] ** 2)) for i in range(ss.n)]
    i = int(np.nanargmax(rms))
    s = ss.segments[i]
    tr = ss.trajs[s.traj]
    n = s.stop - s.start
    t = tr.t[s.start:s.stop]
    # after the burn-in, unscored samples are the torque-saturated bursts (``saturation.py``)
    unscored = ~ss.mask[i, :n] & (np.arange(n) >= s.score_from - s.start)
    edges = np.flatnonzero(np.diff(np.r_[0, unscored.astype(np.int8), 0]))
    saturated_spans = [(t[a0], t[min(a1, n - 1)]) for a0, a1 in zip(edges[::2], edges[1::2])]
    fig, ax = new(7, 2, 12, 1.5)
    for j in range(7):
        a = ax[j, 0]
        a.step(t, tr.q_cmd[s.start:s.stop, j], where="post", color="0.6", lw=1, label="command")
        a.plot(t, tr.q[s.start:s.stop, j], ".", ms=3, color="k", label="measured")
        a.plot(t, d.nominal_held.sim[i, :n, j], color="tab:red", lw=1, label="sim nominal")
        a.plot(t, d.model_held.sim[i, :n, j], color="tab:blue", lw=1, label=f"sim {d.model_name}")
        a.set_ylabel(f"{JOINTS[j]} [rad]")
        b = ax[j, 1]
        b.plot(t, 1e3 * (tr.q[s.start:s.stop, j] - d.nominal_held.sim[i, :n, j]), color="tab:red", lw=1)
        b.plot(t, 1e3 * (tr.q[s.start:s.stop, j] - d.model_held.sim[i, :n, j]), color="tab:blue", lw=1)
        b.axhspan(-1e3 * d.noise_floor, 1e3 * d.noise_floor, color="0.85")
        b.axvspan(t[0], tr.t[s.score_from], color="0.93")
        for a0, a1 in saturated_spans:
            for c in (a, b):
                c.axvspan(a0, a1, color="tab:orange", alpha=0.15, lw=0)
        b.set_ylabel("residual [mrad]")
    ax[0, 0].legend(fontsize=7, ncol=4)
    ax[-1, 0].set_xlabel("t [s]")
    ax[-1, 1].set_xlabel("t [s]  (grey band: ± noise floor; grey: burn-in, orange: torque-saturated burst; neither scored)")
    return f"Overlays: command / measured / simulated (worst held-out segment, {esc(tr.name)})", to_img(fig, "overlays")


def _binned(ax, x, y, bins=15, **kw):
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if len(x) < bins * 3:
        return
    edges = np.quantile(x, np.linspace(0, 1, bins + 1))
    idx = np.clip(np.searchsorted(edges, x) - 1, 0, bins - 1)
    cx = np.array([x[idx == b].mean() if (idx == b).any() else np.nan for b in range(bins)])
    cy = np.array([y[idx == b].mean() if (idx == b).any() else np.nan for b in range(bins)])
    ax.plot(cx, cy, "-o", ms=3, **kw)


def residual_scatter(d: ReportData):
    ctx = d.context
    fig, ax = new(3, 7, 16, 2.2)
    for label, rep, col in (("nominal", d.nominal_held, "tab:red"), (d.model_name, d.model_held, "tab:blue")):
        r = 1e3 * rep.flat()
        for j in range(7):
            for row, (key, xl) in enumerate((("vel", "q̇ [rad/s]"), ("acc", "q̈ [rad/s²]"), ("grav", "g(q) [N·m]"))):
                a = ax[row, j]
                a.plot(ctx[key][:, j], r[:, j], ",", color=col, alpha=0.3)
                _binned(a, ctx[key][:, j], r[:, j], color=col, label=label)
                if j == 0:
                    a.set_ylabel("residual [mrad]")
                a.set_xlabel(xl, fontsize=7)
                if row == 0:
                    a.set_title(JOINTS[j])
    ax[0, 0].legend(fontsize=6)
    return "Residual vs velocity, acceleration and gravity torque (held-out, binned means)", (
        "<p class='note'>Coulomb: step at q̇ = 0, flat elsewhere; viscous / latency: line through the origin; "
        "armature: slope vs q̈; payload / gravity-compensation error / backlash: pattern vs g(q).</p>" + to_img(fig, "residual scatter"))


def xcorr(d: ReportData):
    from realm_ms.sysid.signatures import estimate_lag

    ss = d.model_held.segset
    fig, ax = new(1, 2, 12, 3)
    lags_out = []
    for label, rep, col in (("nominal", d.nominal_held, "tab:red"), (d.model_name, d.model_held, "tab:blue")):
        lag_j = []
        for j in range(7):
            vm, vs = [], []
            for i, s in enumerate(ss.segments):
                tr = ss.trajs[s.traj]
                m = ss.mask[i, : s.stop - s.start]
                t = tr.t[s.start:s.stop]
                vm.append(np.gradient(tr.q[s.start:s.stop, j], t)[m])
                vs.append(np.gradient(rep.sim[i, : s.stop - s.start, j], t)[m])
            vm, vs = np.concatenate(vm), np.concatenate(vs)
            dt = float(np.median(np.diff(ss.trajs[0].t)))
            lag_j.append(estimate_lag(vm, vs, dt))
            if j == 3 or j == 6:
                k = int(round(0.15 / dt))
                ks = np.arange(-k, k + 1)
                n = len(vm)
                c = [np.dot(vm[max(0, q):n + min(0, q)], vs[max(0, -q):n - max(0, q)]) / (n - abs(q)) for q in ks]
                ax[0, 0].plot(ks * dt * 1e3, np.array(c) / max(np.max(np.abs(c)), 1e-12), color=col,
                              ls="-" if j == 3 else "--", label=f"{label} {JOINTS[j]}")
        ax[0, 1].bar(np.arange(7) + (0 if label == "nominal" else 0.4), np.array(lag_j) * 1e3, 0.4, color=col, label=label)
        lags_out.append((label, lag_j))
    ax[0, 0].set_xlabel("lag [ms] (measured vs simulated velocity)")
    ax[0, 0].set_ylabel("normalised cross-correlation")
    ax[0, 0].legend(fontsize=7)
    ax[0, 1].set_xticks(np.arange(7) + 0.2, JOINTS)
    ax[0, 1].set_ylabel("best-aligning lag [ms]")
    ax[0, 1].legend(fontsize=7)
    return "Cross-correlation vs lag", ("<p class='note'>A pure command latency shows the same positive lag on all joints.</p>"
                                        + to_img(fig, "cross-correlation"))


def hysteresis(d: ReportData):
    ctx = d.context
    fig, ax = new(2, 7, 16, 2.2)
    for label, rep, col in (("nominal", d.nominal_held, "tab:red"), (d.model_name, d.model_held, "tab:blue")):
        r = 1e3 * rep.flat()
        near = ctx["reversal"]
        for j in range(7):
            m = near[:, j]
            ax[0, j].plot(ctx["vel"][m, j], r[m, j], ".", ms=2, color=col, alpha=0.5)
            ax[1, j].plot(ctx["tau"][m, j], r[m, j], ".", ms=2, color=col, alpha=0.5, label=label)
            ax[0, j].set_title(JOINTS[j])
            ax[0, j].set_xlabel("q̇ [rad/s]", fontsize=7)
            ax[1, j].set_xlabel("Kp·(q*−q) [N·m]", fontsize=7)
    ax[0, 0].set_ylabel("residual [mrad]")
    ax[1, 0].set_ylabel("residual [mrad]")
    ax[1, 0].legend(fontsize=6)
    return "Hysteresis at reversals", ("<p class='note'>Samples within 0.2 s of a velocity reversal. A loop vs q̇ "
                                       "points at friction, a loop vs the transmitted torque at backlash.</p>" + to_img(fig, "hysteresis"))


def suspects(d: ReportData):
    if not d.diagnosis:
        return "Suspects", "<p>No diagnosis run.</p>"
    dg = d.diagnosis
    b = dg["baseline"]
    rows = []
    for i, s in enumerate(dg["suspects"], 1):
        rows.append([f"{i}. {s['effect']}", f"{s['score']:+.2f}", _fmt(s["heldout_rmse_after_rad"]), s["evidence"]])
    head = (f"<p>Baseline ({esc(d.model_name)}): held-out RMSE {b['heldout_rmse_rad']:.2e} rad, noise floor ≈ "
            f"{b['noise_floor_rad']:.2e} rad. <b>{esc(dg.get('message', ''))}</b></p>")
    return "Suspects: which effect is missing", head + table(["effect", "score", "held-out RMSE after [rad]", "evidence"], rows)


def waterfall(d: ReportData):
    if not d.waterfall:
        return "Waterfall", "<p>The model has no effects.</p>"
    labels = [w[0] for w in d.waterfall]
    vals = np.array([w[1] for w in d.waterfall])
    fig, ax = new(1, 1, 9, 3.2)
    a = ax[0, 0]
    a.bar(range(len(vals)), vals * 1e3, color=["tab:red"] + ["tab:blue"] * (len(vals) - 1))
    a.axhline(d.noise_floor * 1e3, color="k", ls="--", lw=1, label="noise floor")
    a.set_xticks(range(len(vals)), labels, rotation=20, fontsize=8)
    a.set_ylabel("held-out RMSE [mrad]")
    a.legend(fontsize=8)
    rows = [[l, _fmt(v), f"{v / max(d.noise_floor, 1e-12):.1f}"] for l, v in zip(labels, vals)]
    html = to_img(fig, "waterfall") + table(["model", "held-out RMSE [rad]", "/ noise"], rows)
    if d.leave_one_out:
        full = vals[-1]
        rows = [[l, _fmt(v), f"{v / max(d.noise_floor, 1e-12):.1f}", f"{(v - full) / max(full, 1e-12):+.0%}"]
                for l, v in d.leave_one_out]
        html += ("<p>Leave one effect out (the full model without it): an effect whose removal barely "
                 "raises the held-out error is not needed.</p>"
                 + table(["model", "held-out RMSE [rad]", "/ noise", "vs full model"], rows))
    return "Waterfall: held-out error as effects are added (and left out)", html


def parameters(d: ReportData):
    rows, cls = [], []
    for fx in d.model.effects:
        vals = fx.values()
        for p in fx.params:
            v = vals[p.local_key]
            at_bound = p.spec.fit_by_default and (abs(v - p.spec.lo) < 1e-6 * (p.spec.hi - p.spec.lo) + 1e-12 or
                                                   abs(v - p.spec.hi) < 1e-6 * (p.spec.hi - p.spec.lo) + 1e-12) and v != p.spec.off
            unc = ((d.fit or {}).get("uncertainty") or {}).get(f"{fx.name}.{p.local_key}")
            ci = (f"[{format_value(unc['ci95'][0], p.unit)}, {format_value(unc['ci95'][1], p.unit)}]" if unc else "")
            rows.append([fx.name, p.local_key, format_value(v, p.unit), ci, p.unit, f"[{p.spec.lo:g}, {p.spec.hi:g}]",
                         f"{p.spec.off:g}", "at bound" if at_bound else ("fixed" if not p.spec.fit_by_default else "")])
            cls.append([""] * 7 + ["bad" if at_bound else ""])
    if not rows:
        return "Fitted parameters", "<p>The model has no effects (nominal robot).</p>"
    prov = d.model.provenance
    extra = f"<p class='note'>gains preset <b>{esc(d.model.gains)}</b>, joint physics <b>{esc(d.model.joint_physics)}</b>, {d.model.physics_hz:g} Hz; provenance: {esc(', '.join(f'{k}={v}' for k, v in prov.items() if not isinstance(v, list)))}</p>"
    return "Fitted parameters (units, bounds, 95 % CI)", extra + table(["effect", "parameter", "value", "95 % CI", "unit", "bounds", "off", ""], rows, left=2, classes=cls)


def fit_health(d: ReportData):
    if not d.fit or "train_rmse_rad" not in (d.fit.get("before") or {}):  # none, or a torque-space fit
        return "Fit history", "<p>No fit history given (pass <code>--fit FIT.json</code>).</p>"
    h = d.fit.get("history") or []
    fig, ax = new(1, 2, 12, 3)
    g = [x["generation"] for x in h]
    lin = d.fit.get("linearized_start") or []
    xs = [-len(lin)] + [-len(lin) + 1 + i for i in range(len(lin))]
    ys = [d.fit["before"]["train_rmse_rad"]] + [x["train_rmse_rad"] for x in lin]
    ax[0, 0].semilogy(xs, ys, "o-", color="tab:red", label="before / linearised start")
    if h:  # none where the linearised start was already at the noise
        ax[0, 0].semilogy([xs[-1]] + g, [ys[-1]] + [x["best_loss"] for x in h], "o-", ms=3, label="CMA-ES best")
        ax[0, 0].semilogy(g, [x["median_loss"] for x in h], label="CMA-ES median", alpha=0.6)
    ax[0, 0].set_xlabel("step (≤ 0: before and linearised start; > 0: CMA-ES generation)")
    ax[0, 0].set_ylabel("train RMSE [rad]")
    ax[0, 0].legend()
    b, a = d.fit["before"], d.fit["after"]
    x = np.arange(7)
    ax[0, 1].bar(x - 0.2, np.array(b["per_joint_heldout_rmse_rad"]) * 1e3, 0.4, label="before", color="tab:red")
    ax[0, 1].bar(x + 0.2, np.array(a["per_joint_heldout_rmse_rad"]) * 1e3, 0.4, label="after", color="tab:blue")
    ax[0, 1].set_xticks(x, JOINTS)
    ax[0, 1].set_ylabel("held-out RMSE [mrad]")
    ax[0, 1].legend()
    note = ""
    if d.fit.get("cma_stop") == "target":
        note = (f"<p class='note'>CMA-ES {'stopped after ' + str(len(h)) + ' generations' if h else 'was not run'}: the "
                f"train RMSE is within the measurement noise ({d.fit.get('noise_rmse_rad') or 0:.2e} rad, "
                "estimated at the linearised start) times <code>--noise-stop</code>; what is left is noise.</p>")
    return "Fit history: the error falling, before/after per joint", note + to_img(fig, "fit history")


def flange(d: ReportData):
    """Flange mm, lag and b per lab and per trajectory (train and held-out), nominal beside the model,
    with the tables of the alignment page (``report/align_report.py``)."""
    from realm_ms.sysid.alignment import replay_flange, tabulate
    from realm_ms.sysid.report.align_report import ModelRun, _episodes, _labs

    pairs = [("nominal", d.nominal_train, d.nominal_held), (d.model_name, d.model_train, d.model_held)]
    runs = []
    for label, train, held in pairs[: 1 if d.model_name == "nominal" else 2]:
        (he,) = replay_flange(held.segset, [(label, held.sim)]).runs
        (tr,) = replay_flange(train.segset, [(label, train.sim)]).runs
        for e in he.episodes:
            e.name += " (held-out)"
        runs.append(ModelRun.of(tabulate(he.episodes + tr.episodes, label, 0.0)))
    singular = {t.name: t.meta.get("interaction", {}).get("singular", 0.0)
                for t in d.model_held.segset.trajs + d.model_train.segset.trajs}
    shares = [{"masked": e.masked, "singular": singular.get(e.name.removesuffix(" (held-out)"), 0.0)} for e in runs[0].rows]
    intro = ("<p>The replay above seen at the flange (<code>panda_link8</code>, forward kinematics of q): flange error "
             "|p<sub>sim</sub> − p<sub>real</sub>| in mm (median over the scored samples; <i>free</i>: the samples not "
             "saturated, grasping, stalled or near-singular), and against the command's flange target (the Cartesian "
             "command when it is replayed as one, else the pose of the joint target), the lag (commands after which "
             "the flange is closest to where a command pointed) and the first-order response b "
             "(p[t+1] − p[t] = b (c[t] − p[t])) of the simulated and the real arm. Labs: <code>index.json</code> "
             "beside the data or the file's own <code>lab</code>, else one group.</p>")
    return ("Flange: simulated beside real, per lab and per trajectory",
            intro + "<h3>Per lab</h3>" + _labs(runs)[1] + "<h3>Per trajectory (worst first under the nominal robot)</h3>"
            + _episodes(runs, shares)[1])


SECTIONS = [overview, flange, where_it_fails, suspects, waterfall, parameters, fit_health, overlays, residual_scatter, xcorr, hysteresis]
