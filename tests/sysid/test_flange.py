"""Flange mm, lag and b beside a multiple-shooting replay (``alignment.replay_flange``), on cases
computed by hand: the "simulation" is the measured trajectory itself, or it shifted in time."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from realm_ms.agents.urdf import DROID_RESET_QPOS
from realm_ms.sysid.alignment import replay_flange
from realm_ms.sysid.replay import SegmentSet
from realm_ms.sysid.timeseries import Trajectory


def _delayed(a: np.ndarray, k: int) -> np.ndarray:
    """a[t - k], the first sample held before the start."""
    return np.concatenate([np.repeat(a[:1], k, 0), a[:-k]]) if k else a.copy()


def _traj(name: str, rate_hz: float, delay_samples: int, lab: str | None) -> Trajectory:
    """Joint targets swinging around DROID's reset pose; the 'measured' arm follows them ``delay_samples`` late."""
    t = np.arange(int(10 * rate_hz)) / rate_hz
    q_cmd = np.asarray(DROID_RESET_QPOS)[None] + 0.15 * np.stack(
        [np.sin((0.8 + 0.1 * j) * t + j) for j in range(7)], 1)
    return Trajectory(name, t, _delayed(q_cmd, delay_samples), q_cmd, control_hz=15.0, meta={"lab": lab} if lab else {})


def _shifted_sim(ss: SegmentSet, k: int) -> np.ndarray:
    """A 'simulation' that answers ``k`` samples later than the measured arm, at every segment sample."""
    sim = ss.meas.copy()
    for i, s in enumerate(ss.segments):
        idx = ss.sample_idx[i, : s.stop - s.start]
        sim[i, : len(idx)] = ss.trajs[s.traj].q[np.maximum(idx - k, 0)]
    return sim


@pytest.fixture(scope="module")
def segset():
    # a 15 Hz log 3 commands late and a 60 Hz log 2 commands (8 samples) late, in two labs
    trajs = [_traj("a", 15.0, 3, "LAB_A"), _traj("b", 60.0, 8, "LAB_B")]
    return SegmentSet.build(trajs, 120.0, 4.0, 1.0)


def test_sim_equal_to_real_is_zero_mm_and_the_same_lag(segset):
    (res,) = replay_flange(segset, [("same", segset.meas.copy())]).runs
    by = {e.name: e for e in res.episodes}
    assert by["a"].lag_real == by["a"].lag_sim == 3
    assert by["b"].lag_real == by["b"].lag_sim == 2  # in commands, not samples
    for e in res.episodes:
        assert e.flange_mm == pytest.approx(0.0, abs=1e-9) and e.free_mm == pytest.approx(0.0, abs=1e-9)
        assert e.b_sim == pytest.approx(e.b_real)
        assert max(e.joint_mrad) == pytest.approx(0.0, abs=1e-9)
    # every sample after the first 1 s burn-in, once
    assert by["a"].steps == 150 - 15 and by["b"].steps == 600 - 60
    assert [lab.lab for lab in res.labs] == ["LAB_A", "LAB_B"] and res.overall.episodes == 2


def test_a_later_simulation_shifts_the_lag_and_opens_a_flange_error(segset):
    flange = replay_flange(segset, [("same", segset.meas.copy()), ("late", _shifted_sim(segset, 4))])
    same, late = flange.runs
    by = {e.name: e for e in late.episodes}
    assert by["a"].lag_sim == 3 + 4 and by["a"].lag_real == 3
    assert by["b"].lag_sim == 2 + 1  # 4 samples at 60 Hz: one command
    assert all(e.flange_mm > 1.0 for e in late.episodes)
    # hand check of one episode's median: |FK(q[t - 4]) - FK(q[t])| over its scored samples
    from realm_ms.agents.droid_action_spaces import DroidIK

    ik, tr = DroidIK(), segset.trajs[0]
    p = ik.flange(tr.q)[:, :3, 3]
    d = np.linalg.norm(_delayed(p, 4) - p, axis=1)[15:] * 1e3
    assert by["a"].flange_mm == pytest.approx(float(np.median(d)), rel=1e-9)
    line = flange.line()
    assert line.startswith("flange: 0.0 -> ") and "(real " in line and "lag " in line and "b " in line
    doc = flange.to_json()
    assert [r["model"] for r in doc["runs"]] == ["same", "late"]
    assert json.loads(json.dumps(doc))["runs"][1]["overall"]["lag_sim"] == late.overall.lag_sim


def test_index_json_names_the_labs_of_the_workbench_npz(tmp_path):
    from realm_ms.sysid.data_io import load_dir, write_npz

    for name in ("e0", "e1"):
        write_npz(tmp_path / f"{name}.npz", _traj(name, 15.0, 2, None))
    (tmp_path / "index.json").write_text(json.dumps([{"file": "e0.npz", "lab": "TRI"}]))
    write_npz(tmp_path / "e2.npz", _traj("e2", 15.0, 2, "OWN"))  # a lab of its own, in the file
    labs = {tr.name: tr.meta.get("lab") for tr in load_dir(tmp_path)}
    assert labs == {"e0": "TRI", "e1": None, "e2": "OWN"}


def test_the_per_lab_table_has_an_overall_row_only_beside_two_or_more_labs(segset):
    from realm_ms.sysid.alignment import tabulate
    from realm_ms.sysid.report.align_report import ModelRun, _labs

    (run,) = replay_flange(segset, [("nominal", segset.meas.copy())]).runs

    def lab_rows(episodes):
        html = _labs([ModelRun.of(tabulate(episodes, "nominal", 0.0))])[1]
        return re.findall(r'<tr><td class="l">([^<]*)</td>', html)  # each body row's first cell

    assert lab_rows(run.episodes) == ["LAB_A", "LAB_B", "all"]
    assert lab_rows([e for e in run.episodes if e.lab == "LAB_A"]) == ["LAB_A"]  # not LAB_A and an equal "all"
