"""Metrics and validation of `realm eval`: intervals, aggregation, failure stages, Pearson/MMRV/RMSD."""

import json
import math

import numpy as np
import pytest

from realm_ms.cli import main
from realm_ms.eval.metrics import bootstrap_interval, compute_metrics, difference_interval, wilson_interval
from realm_ms.eval.real_vs_sim import mmrv, pearson_r, rmsd


def test_wilson_matches_hand_computation():
    lo, hi = wilson_interval(8, 10)
    z = 1.959963984540054
    centre = (0.8 + z * z / 20) / (1 + z * z / 10)
    half = z * math.sqrt(0.8 * 0.2 / 10 + z * z / 400) / (1 + z * z / 10)
    assert (lo, hi) == pytest.approx((centre - half, centre + half))
    assert (round(lo, 3), round(hi, 3)) == (0.49, 0.943)  # textbook values for 8/10
    assert wilson_interval(0, 5)[0] == 0.0 and wilson_interval(5, 5)[1] == 1.0


def test_bootstrap_interval_covers_the_mean_and_narrows():
    rng = np.random.default_rng(1)
    v = rng.uniform(0, 1, 40)
    lo, hi = bootstrap_interval(v)
    assert lo < v.mean() < hi
    lo2, hi2 = bootstrap_interval(np.tile(v, 10))
    assert hi2 - lo2 < (hi - lo) / 2
    assert bootstrap_interval([0.5, 0.5]) == (0.5, 0.5)


def _rec(task, pert, seed, prog, stalled, stages=None, status="ok", success=None):
    return dict(task=task, perturbation=pert, seed=seed, policy="p", status=status, progression=prog,
                success=prog >= 1.0 if success is None else success, stalled_stage=stalled, steps=10, stages=stages or {})


def test_compute_metrics_aggregates_cells_groups_and_failures():
    recs = [
        _rec("A", "Default", 0, 1.0, "DONE", {"REACH": 3, "GRASP": 7}),
        _rec("A", "Default", 1, 0.5, "LIFT", {"REACH": 5}),
        _rec("A", "VB-POSE", 0, 0.0, "REACH"),
        _rec("A", "VB-POSE", 1, 0.5, "LIFT", {"REACH": 9}),
        _rec("B", "Default", 0, 0.0, "REACH"),
        _rec("B", "VB-POSE", 0, 0.0, "REACH"),
        _rec("B", "VB-POSE", 1, 0.0, "REACH", status="error"),  # errors never count
        _rec("B", "Default", 1, 0.0, "REACH", status="error"),
        _rec("B", "Default", 1, 1.0, "DONE"),  # the retry of that error: the one that counts
    ]
    m = compute_metrics(recs)
    assert m["overall"]["episodes"] == 7
    assert m["per_task"]["A"]["success_rate"] == 0.25 and m["per_task"]["A"]["mean_progression"] == 0.5
    assert m["per_perturbation"]["Default"]["episodes"] == 4 and m["per_perturbation"]["Default"]["success_rate"] == 0.5
    assert m["per_cell"]["B"]["Default"]["mean_progression"] == 0.5
    # VB-POSE belongs to both the V and the B factor groups
    assert m["per_factor_group"]["V"]["episodes"] == 3 and m["per_factor_group"]["B"]["episodes"] == 3
    # delta: A 0.25 - 0.75 = -0.5, B 0 - 0.5 = -0.5; RMSD sqrt((0.25 + 0.25) / 2)
    assert m["delta_to_default"]["VB-POSE"]["mean_progression"] == pytest.approx(-0.5)
    assert m["rmsd_to_default"]["VB-POSE"] == pytest.approx(0.5)
    assert m["failure_stages"] == pytest.approx({"REACH": 3 / 7, "DONE": 2 / 7, "LIFT": 2 / 7})
    assert m["time_to_stage"]["REACH"]["episodes"] == 3 and m["time_to_stage"]["REACH"]["mean_steps"] == pytest.approx(17 / 3)
    assert len(m["errors"]) == 1 and m["errors"][0]["seed"] == 1 and m["errors"][0]["task"] == "B"
    for key in ("overall", "per_task", "per_perturbation", "failure_stages"):
        assert key in m


PAIRED = """policy,task,real,sim
p1,A,0.2,0.3
p2,A,0.5,0.4
p3,A,0.8,0.9
p1,B,0.6,0.3
p2,B,0.4,0.5
p3,B,0.1,0.2
"""


def _hand():
    # task A: centred real (-.3, 0, .3), sim (-.7/3, -.4/3, 1.1/3); sum s*r = .18, sum s^2 = .62/3, sum r^2 = .18
    r_a = 0.18 / math.sqrt(0.62 / 3 * 0.18)
    # task B: centred real (.7/3, .1/3, -.8/3), sim (-.1/3, .5/3, -.4/3)
    sr = (0.7 * -0.1 + 0.1 * 0.5 + -0.8 * -0.4) / 9
    r_b = sr / math.sqrt((0.49 + 0.01 + 0.64) / 9 * (0.01 + 0.25 + 0.16) / 9)
    # MMRV: A has no order violation; B: p1/p2 disagree (sim .3 < .5, real .6 > .4) -> RV = .2, .2, 0
    mmrv_a, mmrv_b = 0.0, 0.4 / 3
    rmsd_a, rmsd_b = 0.1, math.sqrt((0.09 + 0.01 + 0.01) / 3)
    return dict(A=(r_a, mmrv_a, rmsd_a), B=(r_b, mmrv_b, rmsd_b))


def test_metric_functions_match_hand_computation():
    h = _hand()
    assert pearson_r([0.3, 0.4, 0.9], [0.2, 0.5, 0.8]) == pytest.approx(h["A"][0], abs=1e-7)
    assert pearson_r([0.3, 0.5, 0.2], [0.6, 0.4, 0.1]) == pytest.approx(h["B"][0], abs=1e-7)
    assert mmrv([0.3, 0.5, 0.2], [0.6, 0.4, 0.1]) == pytest.approx(h["B"][1])
    assert rmsd([0.3, 0.5, 0.2], [0.6, 0.4, 0.1]) == pytest.approx(h["B"][2])
    assert pearson_r([1, 2, 3], [1, 2, 3]) == 1.0  # identical centred vectors
    # MMRV is asymmetric: the penalty uses the second (real) argument
    assert mmrv([0.6, 0.4], [0.1, 0.9]) == pytest.approx(0.8) and mmrv([0.1, 0.9], [0.6, 0.4]) == pytest.approx(0.2)


def test_realm_validate_cli_reproduces_hand_numbers(tmp_path, capsys):
    csv_path = tmp_path / "paired.csv"
    csv_path.write_text(PAIRED)
    out = tmp_path / "v.json"
    assert main(["validate", str(csv_path), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    h = _hand()
    for task in "AB":
        got = res["per_task"][task]
        assert (got["pearson_r"], got["mmrv"], got["rmsd"]) == pytest.approx(h[task], abs=1e-7)
    assert res["mean"]["pearson_r"] == pytest.approx((h["A"][0] + h["B"][0]) / 2, abs=1e-7)
    assert res["mean"]["mmrv"] == pytest.approx((h["A"][1] + h["B"][1]) / 2)
    assert res["mean"]["rmsd"] == pytest.approx((h["A"][2] + h["B"][2]) / 2)
    assert "pearson_r" in capsys.readouterr().out


def test_realm_validate_bad_input_is_one_line_error(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("policy,task,real\np,A,0.1\n")
    assert main(["validate", str(bad)]) == 2
    assert main(["validate", str(tmp_path / "missing.csv")]) == 2
    bad.write_text("policy,task,real,sim\np,A,zero,0.1\n")
    assert main(["validate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "policy,task,real,sim" in err and "Traceback" not in err


def test_difference_interval_matches_newcombe_1998():
    # Newcombe (1998), Statistics in Medicine 17:873, method 10, example (56/70 vs 48/80): 0.0524 to 0.3339
    lo, hi = difference_interval(48, 80, 56, 70)
    assert lo == pytest.approx(0.0524, abs=5e-4) and hi == pytest.approx(0.3339, abs=5e-4)
    lo, hi = difference_interval(56, 70, 48, 80)  # the other way round: mirrored
    assert (lo, hi) == pytest.approx((-0.3339, -0.0524), abs=5e-4)
    lo, hi = difference_interval(0, 20, 20, 20)  # 0 % -> 100 %: stays inside [-1, 1]
    assert 0.6 < lo < hi == pytest.approx(1.0)
