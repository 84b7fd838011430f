"""`realm sysid ...` end to end on a tiny synthetic data set: documented JSON outputs, report,
clear errors on bad input (exit code 2, one line, no traceback)."""

import json

import numpy as np
import pytest

from realm_ms.agents.effects import EFFECTS
from realm_ms.cli import main


def run(capsys, *argv):
    code = main(["sysid", *map(str, argv)])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli") / "data"
    assert main(["sysid", "synth", "--hidden", "latency:delay=0.02", "--out", str(d), "--seed", "1",
                 "--n-train", "3", "--n-heldout", "2", "--duration", "3"]) == 0
    return d


def test_effects_lists_the_library(capsys):
    code, out, _ = run(capsys, "effects", "--json")
    lib = json.loads(out)
    assert code == 0 and [e["name"] for e in lib] == list(EFFECTS)
    lat = next(e for e in lib if e["name"] == "latency")
    assert lat["params"][0]["unit"] == "s" and lat["params"][0]["bounds"] == [0.0, 0.3]


def test_excite_writes_command_trajectories(tmp_path, capsys):
    code, out, _ = run(capsys, "excite", "--out", tmp_path, "--n", 2, "--duration", 6)
    assert code == 0
    z = np.load(tmp_path / "excite_000.npz")
    assert z["q_cmd"].shape == (91, 7) and float(z["control_hz"]) == 15.0
    assert np.abs(np.diff(z["q_cmd"], axis=0)).max() <= 0.2 + 1e-9


def test_synth_layout(data):
    assert len(list((data / "train").glob("*.npz"))) == 3 and len(list((data / "heldout").glob("*.npz"))) == 2
    info = json.loads((data / "synth.json").read_text())
    assert info["truth"]["latency.delay"] == pytest.approx(0.02)


def test_compare(data, capsys, tmp_path):
    # the README's `realm sysid compare data/` on synth's train/ + heldout/ layout: all trajectories
    code, out, _ = run(capsys, "compare", data, "--workers", 1, "--json", tmp_path / "c.json")
    assert code == 0 and "RMSE" in out
    c = json.loads((tmp_path / "c.json").read_text())
    assert len(c["per_joint_rmse_rad"]) == 7 and c["noise_floor_rad"] > 0 and c["error_over_time"]
    names = json.loads((data / "synth.json").read_text())["config"]
    assert len(c["trajectories"]) == names["n_train"] + names["n_heldout"]
    # the flange beside the joints: one run, a row per trajectory, one lab (synth writes no index.json)
    (run_,) = c["flange"]["runs"]
    assert len(run_["episodes"]) == len(c["trajectories"]) and [lab["lab"] for lab in run_["labs"]] == ["all"]
    o = run_["overall"]
    assert o["flange_mm"] > 0 and o["lag_real"] >= 0 and o["lag_sim"] >= 0 and 0 < o["b_real"] < 1.5
    assert f"flange: {o['flange_mm']:.1f} mm median" in out


@pytest.fixture(scope="module")
def outdir(tmp_path_factory):
    return tmp_path_factory.mktemp("cli_out")


def test_diagnose_json_schema(data, capsys, outdir):
    code, out, err = run(capsys, "diagnose", data, "--workers", 1, "--json", outdir / "d.json")
    assert code == 0
    d = json.loads((outdir / "d.json").read_text())
    assert (out + err).count(d["message"]) == 1  # the verdict, printed once (stdout)
    assert set(d["baseline"]) >= {"heldout_rmse_rad", "noise_floor_rad"}
    assert isinstance(d["missing_effect_found"], bool)
    assert sorted(s["effect"] for s in d["suspects"]) == sorted(n for n, c in EFFECTS.items() if c.screened)
    for s in d["suspects"]:
        assert set(s) >= {"effect", "score", "heldout_rmse_after_rad", "params", "evidence"}
        assert isinstance(s["score"], float) and isinstance(s["evidence"], str) and s["evidence"]
    scores = [s["score"] for s in d["suspects"]]
    assert scores == sorted(scores, reverse=True)
    assert d["suspects"][0]["effect"] == "latency" and d["missing_effect_found"]
    # the effects inert at their off-values (payload CoM, Stribeck and smooth shapes) are screened
    # again from typical strengths exactly when no first-pass candidate already reaches the floor
    rescreened = [m for m in err.splitlines() if m.startswith(("re-screening", "not re-screening"))]
    assert len(rescreened) == 1, err
    if rescreened[0].startswith("not"):
        assert d["verdict"] == "found" and ": latency already" in rescreened[0], (rescreened, d["message"])
    (base,) = d["flange"]["runs"]
    assert base["model"] == "baseline" and len(base["episodes"]) == 2 and f"flange: {base['overall']['flange_mm']:.1f}" in out


def test_fit_json_schema_model_and_report(data, capsys, tmp_path, outdir):
    model = tmp_path / "MODEL.yaml"
    # --noise-stop 0: every generation runs, even where the linearised start is at the noise
    code, out, err = run(capsys, "fit", data, "--add", "latency", "--out", model, "--workers", 1,
                         "--generations", 4, "--noise-stop", 0, "--no-progress", "--json", tmp_path / "f.json")
    assert code == 0, err
    f = json.loads((tmp_path / "f.json").read_text())
    assert f["effects"] == ["latency"] and set(f["params"]) == {"latency.delay"}
    for k in ("before", "after"):
        assert set(f[k]) >= {"train_rmse_rad", "heldout_rmse_rad", "per_joint_heldout_rmse_rad"}
        assert len(f[k]["per_joint_heldout_rmse_rad"]) == 7
    assert len(f["history"]) == 4 and set(f["history"][0]) == {"generation", "best_loss", "median_loss"}
    assert f["cma_stop"] == "max_generations" and f["noise_rmse_rad"] > 0
    assert f["after"]["heldout_rmse_rad"] < 0.2 * f["before"]["heldout_rmse_rad"]
    assert f["params"]["latency.delay"] == pytest.approx(0.02, rel=0.2)
    before, after = (r["overall"] for r in f["flange"]["runs"])
    assert after["flange_mm"] < 0.5 * before["flange_mm"] and before["lag_real"] == after["lag_real"]
    assert f"flange: {before['flange_mm']:.1f} -> {after['flange_mm']:.1f} mm median" in out
    from realm_ms.sysid import load_actuation_model

    assert [s.name for s in load_actuation_model(model).stages] == ["latency"]
    html = tmp_path / "r.html"
    code, out, err = run(capsys, "report", data, "--model", model, "--out", html, "--workers", 1,
                         "--fit", tmp_path / "f.json", "--diagnosis", outdir / "d.json")
    assert code == 0, err
    text = html.read_text()
    for title in ("Overview", "Where the model fails", "Suspects", "Waterfall", "Fitted parameters", "Overlays",
                  "Residual vs velocity", "Cross-correlation", "Hysteresis", "Fit history"):
        assert title in text, title
    assert text.count("data:image/png;base64,") >= 6 and "section failed" not in text
    # the flange tables: per lab (one group, so no separate overall row) and per trajectory, nominal beside the model
    labs, trajs = _tables_after(text, "Flange: simulated beside real")[:2]
    assert [r[0] for r in labs[1:]] == ["all"] and "model: mm" in labs[0]
    assert len(trajs) - 1 == 5 and sum(r[0].endswith("(held-out)") for r in trajs[1:]) == 2
    assert all(float(r[trajs[0].index("model mm")]) < float(r[trajs[0].index("nominal mm")]) for r in trajs[1:])


def _tables_after(html: str, heading: str) -> list[list[list[str]]]:
    """The tables (rows of cell texts, the header first) of the section titled ``heading``."""
    from html.parser import HTMLParser

    class Tables(HTMLParser):
        def __init__(self):
            super().__init__()
            self.tables, self.cell, self.on = [], None, False

        def handle_starttag(self, tag, attrs):
            if tag == "h2":
                self.on = None
            elif self.on and tag == "table":
                self.tables.append([])
            elif self.on and tag == "tr":
                self.tables[-1].append([])
            elif self.on and tag in ("td", "th"):
                self.cell = ""

        def handle_endtag(self, tag):
            if self.on and tag in ("td", "th"):
                self.tables[-1][-1].append(self.cell.strip())
                self.cell = None

        def handle_data(self, data):
            if self.on is None:
                self.on = data.strip().startswith(heading)
            elif self.cell is not None:
                self.cell += data

    p = Tables()
    p.feed(html)
    return p.tables


@pytest.mark.parametrize("argv, msg", [
    (["compare", "/nonexistent/data"], "does not exist"),
    (["synth", "--hidden", "friction", "--out", "{tmp}/x"], "unknown effect"),
    (["synth", "--hidden", "latency:delay=9", "--out", "{tmp}/x"], "outside its bounds"),
    (["fit", "{tmp}/deg", "--add", "latency", "--out", "{tmp}/m.yaml"], "degrees"),
    (["fit", "{data}", "--add", "warp_drive", "--out", "{tmp}/m.yaml"], "unknown effect"),
    (["compare", "{data}/train", "--model", "{tmp}/missing.yaml"], "not found"),
    (["report", "{data}", "--out", "{tmp}/r.html", "--diagnosis", "{data}/synth.json"], "not a `diagnose --json` output"),
])
def test_bad_input_is_a_clear_error(argv, msg, tmp_path, data, capsys):
    t = np.arange(40) / 15.0
    q = np.rad2deg(np.array([0, -0.6, 0, -2.4, 0, 1.9, 0]))[None].repeat(40, 0)
    (tmp_path / "deg").mkdir()
    for i in range(2):
        np.savez(tmp_path / "deg" / f"d{i}.npz", t=t, q=q, q_cmd=q)
    code, out, err = run(capsys, *[a.format(tmp=tmp_path, data=data) for a in argv])
    assert code == 2 and msg in err and "Traceback" not in err


def test_auto_json_schema_and_report(data, capsys, tmp_path, outdir):
    """`auto`: the documented JSON (unit, nominal, steps, final with verdict, friction curve)."""
    code, out, err = run(capsys, "auto", data, "--workers", 1, "--max-steps", 1, "--generations", 2, "--no-progress",
                         "--out", tmp_path / "M.yaml", "--json", tmp_path / "a.json")
    assert code == 0, err
    a = json.loads((tmp_path / "a.json").read_text())
    assert a["unit"] == "rad" and set(a["final"]) == {"heldout_rmse", "noise_floor", "verdict", "confounded"}
    assert a["final"]["verdict"] in ("at_floor", "partially_explained", "unexplained")
    assert [s["effect"] for s in a["steps"]] == ["latency"]
    st = a["steps"][0]
    assert set(st) == {"effect", "params", "heldout_rmse"} and "latency.delay" in st["params"]
    assert st["heldout_rmse"] < 0.5 * a["nominal_heldout_rmse"] and a["final"]["heldout_rmse"] == st["heldout_rmse"]
    # the hidden delay, fitted, brings the held-out error to the noise and 5x down from the start
    assert a["final"]["verdict"] == "at_floor" and a["final"]["heldout_rmse"] <= 1.5 * a["final"]["noise_floor"]
    assert a["nominal_heldout_rmse"] >= 5 * st["heldout_rmse"]
    assert st["params"]["latency.delay"] == pytest.approx(0.02, rel=0.2)
    fc = a["friction_curve"]
    assert len(fc["qd"]) == len(fc["tau"]) and all(len(r) == 7 for r in fc["tau"])
    assert "auto" in out or "final" in out
    start, final = (r["overall"] for r in a["flange"]["runs"])
    assert final["flange_mm"] < start["flange_mm"] and f"-> {final['flange_mm']:.1f} mm median" in out
    # the diagnosis test's JSON: the report does not diagnose again (its own diagnosis is
    # test_friction_laws.py's and test_torque.py's report)
    code, out, err = run(capsys, "report", data, "--model", tmp_path / "M.yaml", "--auto", tmp_path / "a.json",
                         "--diagnosis", outdir / "d.json", "--out", tmp_path / "r.html", "--workers", 1, "--no-waterfall")
    assert code == 0, err
    html = (tmp_path / "r.html").read_text()
    assert "Auto: nominal" in html and "Friction curves" in html and "section failed" not in html
