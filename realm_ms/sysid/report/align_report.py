"""The alignment report (``realm sysid align``): how closely the simulated DROID arm answers real
DROID commands, before and after a robot model, on one self-contained HTML page.

Each episode is replayed closed loop in DROID's ``cartesian_position`` space from the simulated
state (``alignment.replay_closed_loop``) under the nominal robot, each step of the model's
waterfall (its gain preset, then its effects added one at a time) and the full model; the metrics
are ``alignment.py``'s (flange error in mm, lag in steps, first-order response b), next to the
per-joint error in mrad, with the response time tau = -dt / ln(1 - b) beside them. Grasps and
stalls against the scene and near-singular postures (``interaction.py``) stay in the replay; the
flange error over the free samples alone is reported beside the error over all of them, with the
share left out and the near-singular share of it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from realm_ms.atomic import write_text
from realm_ms.html_kit import esc, sections_page, table
from realm_ms.sysid.report.figures import new, to_img


@dataclass
class ModelRun:
    """One robot model's closed-loop replay of every episode, with its metrics."""

    label: str
    sims: list[np.ndarray]
    rows: list  # alignment.EpisodeAlignment per episode
    free_mm: list[float]  # median flange error over the free (not grasping/stalled/near-singular) samples
    overall: object = None  # alignment.LabAlignment named "all"
    labs: list = field(default_factory=list)

    @classmethod
    def of(cls, res, sims: list[np.ndarray] | None = None) -> "ModelRun":
        """The run of an ``alignment.AlignmentResult`` (``sims``: its simulated joints, for the overlays)."""
        return cls(res.model, sims or [], res.episodes, [r.free_mm for r in res.episodes], res.overall, res.labs)


def response_time_ms(b: float, hz: float = 15.0) -> float:
    """First-order time constant of a per-step response b: the time to 63 % of a step."""
    if not np.isfinite(b) or b <= 0 or b >= 1:
        return float("nan")
    return float(-1e3 / hz / np.log(1.0 - b))


def run_model(label: str, episodes, model) -> ModelRun:
    from realm_ms.agents.droid_action_spaces import DroidIK
    from realm_ms.sysid.alignment import compare_episode, replay_closed_loop, tabulate

    sims = replay_closed_loop(episodes, model)
    ik = DroidIK()
    return ModelRun.of(tabulate([compare_episode(e, s, ik) for e, s in zip(episodes, sims)], label, 0.0), sims)


def waterfall_models(model):
    """(label, RobotModel) steps from the nominal robot to ``model``: its gain preset, then its
    effects added one at a time in the model's order."""
    from realm_ms.agents.robot_model import RobotModel

    steps = [("nominal", RobotModel())]
    if model is None:
        return steps
    base = dict(gains=model.gains, joint_physics=model.joint_physics, physics_hz=model.physics_hz)
    if (model.gains, model.joint_physics) != ("polymetis", "none"):
        steps.append((f"gains {model.gains}, joint physics {model.joint_physics}", RobotModel(**base)))
    arm = model.arm_effects  # the gripper's effects: the gripper row, not the arm's replay
    for k in range(1, len(arm) + 1):
        steps.append((f"+ {arm[k - 1].name}", RobotModel(list(arm[:k]), **base)))
    return steps


# ---------------------------------------------------------------------------- sections
def _med(xs) -> float:
    xs = [x for x in xs if np.isfinite(x)]
    return float(np.median(xs)) if xs else float("nan")


def _overview(data_name, episodes, skipped, shares, runs, model_name, seconds) -> tuple[str, str]:
    first, last = runs[0], runs[-1]
    real_b = first.overall.b_real
    html = (f"<p>Data: <code>{esc(data_name)}</code>, {len(episodes)} episodes, {sum(e.steps for e in episodes)} steps "
            f"at 15 Hz, {len({e.lab for e in episodes})} labs. Robot model: <b>{esc(model_name)}</b>. "
            f"Replay: closed loop in DROID's <code>cartesian_position</code> space from the simulated state "
            f"({seconds:.0f} s).</p>")
    if skipped:
        html += "<p class='bad'>Skipped (unreadable or invalid): " + "; ".join(esc(s) for s in skipped) + "</p>"
    masked, singular = [s["masked"] for s in shares], [s["singular"] for s in shares]
    html += (f"<p>Grasps and stalls against the scene (an arm-only replay does not model them) and near-singular "
             f"postures (the IK's joint target is ill-defined there): {np.mean(masked):.0%} of the steps on average "
             f"(median {np.median(masked):.0%} per episode; near-singular {np.mean(singular):.1%} on average, in "
             f"{sum(s > 0 for s in singular)} episodes); the <i>free</i> columns leave them out.</p>")
    rows = []
    for r in (first, last) if last is not first else (first,):
        o = r.overall
        rows.append([r.label, f"{o.flange_mm:.1f}", f"{_med(r.free_mm):.1f}", f"{o.lag_real:.1f}", f"{o.lag_sim:.1f}",
                     f"{o.b_real:.2f}", f"{o.b_sim:.2f}", f"{response_time_ms(o.b_real):.0f}", f"{response_time_ms(o.b_sim):.0f}"])
    html += table(["robot", "flange mm (median)", "free mm", "lag real", "lag sim", "b real", "b sim", "tau real ms",
                   "tau sim ms"], rows)
    html += (f"<p class='note'>lag: control steps after which the flange is closest to where a command pointed; "
             f"b: p[t+1] - p[t] = b (c[t] - p[t]); tau = -dt / ln(1 - b). Real b {real_b:.2f}.</p>")
    return "Overview: simulated against real", html


def _labs(runs) -> tuple[str, str]:
    header = ["lab", "episodes", "lag real", "b real"]
    for r in runs:
        header += [f"{r.label}: mm", "lag", "b"]
    body = []
    # with one lab its row is the overall row: showing both would print the same figures twice
    rows = runs[0].labs + ([runs[0].overall] if len(runs[0].labs) > 1 else [])
    for i, lab in enumerate(rows):
        row = [lab.lab, lab.episodes, f"{lab.lag_real:.1f}", f"{lab.b_real:.2f}"]
        for r in runs:
            x = (r.labs + [r.overall])[i]
            row += [f"{x.flange_mm:.1f}", f"{x.lag_sim:.1f}", f"{x.b_sim:.2f}"]
        body.append(row)
    return "Per lab", table(header, body)


def _joints(mrad: list[float]) -> str:
    """Per-joint error in mrad as 'median over joints / worst (its joint)'; the JSON has all seven."""
    k = int(np.argmax(mrad))
    return f"<span style='white-space:nowrap'>{np.median(mrad):.0f} / {mrad[k]:.0f} J{k + 1}</span>"


def _episodes(runs, shares) -> tuple[str, str]:
    first, last = runs[0], runs[-1]
    header = ["episode", "lab", "steps", "masked", "singular", "lag real", "b real", f"{first.label} mm", "free mm",
              "lag", "b", "mrad med / worst"]
    if last is not first:
        header += [f"{last.label} mm", "free mm", "lag", "b", "mrad med / worst"]
    body, cls = [], []
    order = np.argsort([-r.flange_mm for r in first.rows])
    for i in order:
        a = first.rows[i]
        row = [a.name, a.lab, a.steps, f"{shares[i]['masked']:.0%}", f"{shares[i]['singular']:.0%}", a.lag_real,
               f"{a.b_real:.2f}", f"{a.flange_mm:.1f}", f"{first.free_mm[i]:.1f}", a.lag_sim, f"{a.b_sim:.2f}",
               _joints(a.joint_mrad)]
        c = [""] * len(row)
        if last is not first:
            z = last.rows[i]
            row += [f"{z.flange_mm:.1f}", f"{last.free_mm[i]:.1f}", z.lag_sim, f"{z.b_sim:.2f}", _joints(z.joint_mrad)]
            c += ["good" if z.flange_mm < a.flange_mm else "bad", "", "", "", ""]
        body.append(row)
        cls.append(c)
    return "Per episode (worst first under the nominal robot)", table(header, body, left=2, classes=cls)


def _overlays(episodes, runs, free, n_worst: int = 3) -> tuple[str, str]:
    first, last = runs[0], runs[-1]
    html = ""
    for i in np.argsort([-r.flange_mm for r in first.rows])[:n_worst]:
        e = episodes[i]
        t = np.arange(e.steps) / e.control_hz
        fig, ax = new(4, 2, 11, 2.0)
        for j in range(7):
            a = ax[j // 2, j % 2]
            a.plot(t, e.q[:, j], "k", lw=1.2, label="real")
            a.plot(t, first.sims[i][:, j], "tab:red", lw=1, label=first.label)
            if last is not first:
                a.plot(t, last.sims[i][:, j], "tab:blue", lw=1, label=last.label)
            bad = ~free[i]
            if bad.any():
                a.fill_between(t, *a.get_ylim(), where=bad, color="0.85", zorder=0, label="masked")
            a.set_ylabel(f"J{j + 1} [rad]", fontsize=8)
        ax[0, 0].legend(fontsize=7, ncol=4)
        ax[3, 1].axis("off")
        html += f"<h3>{esc(e.name)} ({esc(e.lab)}): {first.rows[i].flange_mm:.1f} mm nominal</h3>" + to_img(fig, e.name)
    return "Per-joint overlays of the worst episodes", html


def _waterfall(runs) -> tuple[str, str]:
    labels = [r.label for r in runs]
    mm = np.array([r.overall.flange_mm for r in runs])
    fig, ax = new(1, 2, 11, 3.2)
    a = ax[0, 0]
    a.bar(range(len(mm)), mm, color=["tab:red"] + ["tab:blue"] * (len(mm) - 1))
    a.set_xticks(range(len(mm)), labels, rotation=20, fontsize=8)
    a.set_ylabel("flange error, median [mm]")
    b = ax[0, 1]
    b.bar(range(len(mm)), [r.overall.b_sim for r in runs], color="tab:blue")
    b.axhline(runs[0].overall.b_real, color="k", ls="--", lw=1, label="real")
    b.set_xticks(range(len(mm)), labels, rotation=20, fontsize=8)
    b.set_ylabel("first-order response b")
    b.legend(fontsize=8)
    rows = [[r.label, f"{r.overall.flange_mm:.1f}", f"{_med(r.free_mm):.1f}", f"{r.overall.lag_sim:.1f}",
             f"{r.overall.b_sim:.2f}", f"{response_time_ms(r.overall.b_sim):.0f}"] for r in runs]
    return ("Waterfall: the model's effects added one at a time",
            to_img(fig, "waterfall") + table(["robot", "flange mm", "free mm", "lag sim", "b sim", "tau sim ms"], rows))


# ---------------------------------------------------------------------------- entry point
def build_align_report(episodes, model, model_name: str, out: Path, data_name: str = "",
                       skipped: list[str] | None = None, waterfall: bool = True, log=print) -> dict:
    """Write the page for ``episodes`` (``alignment.read_droid_episodes``) to ``out``; return its
    numbers (the JSON ``realm sysid align --json`` writes)."""
    import time

    from realm_ms.sysid.interaction import detect

    t0 = time.perf_counter()
    hits = [detect(e.traj) for e in episodes]
    free = [~h.masked for h in hits]
    shares = [h.summary() for h in hits]
    steps = waterfall_models(model) if waterfall or model is None else [("nominal", None)]
    if model is not None and (not waterfall or len(steps) == 1):
        steps.append((model_name, model))
    runs = []
    for label, m in steps:
        log(f"align: replaying {len(episodes)} episodes closed loop under {label}")
        runs.append(run_model(label, episodes, m))
    if model is not None:
        runs[-1].label = model_name
    seconds = time.perf_counter() - t0
    sections = [_overview(data_name, episodes, skipped or [], shares, runs, model_name, seconds), _labs(runs),
                _episodes(runs, shares), _overlays(episodes, runs, free)]
    if len(runs) > 2:
        sections.append(_waterfall(runs))
    sections.append(("Credit", "<p>Real episodes: DROID (Khazatsky et al., \"DROID: A Large-Scale In-The-Wild Robot "
                               "Manipulation Dataset\", RSS 2024), CC-BY 4.0.</p>"))
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, sections_page("DROID alignment: simulated against real", sections))
    doc = {"model": model_name, "seconds": seconds, "skipped": skipped or [],
           "runs": [{"label": r.label, "overall": r.overall.__dict__, "labs": [x.__dict__ for x in r.labs],
                     "free_flange_mm": _med(r.free_mm),
                     "episodes": [dict(x.__dict__, free_flange_mm=f, masked=m["masked"], singular=m["singular"])
                                  for x, f, m in zip(r.rows, r.free_mm, shares)]}
                    for r in runs]}
    return json.loads(json.dumps(doc, default=float))
