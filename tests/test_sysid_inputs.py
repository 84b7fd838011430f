"""Workbench input handling: repeated effect flags, the encoder-bias sign, off-grid logs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from realm_ms.cli import main

POSE = np.array([0.0, -0.6, 0.0, -2.4, 0.0, 1.9, 0.0])


def _write(d, t, control_hz=None, n=2):
    d.mkdir(parents=True, exist_ok=True)
    q = POSE[None].repeat(len(t), 0)
    for i in range(n):
        kw = {} if control_hz is None else {"control_hz": control_hz}
        np.savez(d / f"traj_{i}.npz", t=t, q=q, q_cmd=q, **kw)
    return d


def test_repeated_add_accumulates(tmp_path, capsys, monkeypatch):
    """`--add A --add B` fits both (argparse alone would silently keep B only)."""
    from realm_ms.sysid import api

    seen = {}

    def fake_fit(data, add, *a, **k):  # the CLI's job ends at handing the joined spec to the api
        seen["add"] = add
        raise api.DataError("stop here")

    monkeypatch.setattr(api, "fit", fake_fit)
    data = _write(tmp_path / "d", np.arange(40) / 15.0)
    code = main(["sysid", "fit", str(data), "--add", "coulomb_friction", "--add", "payload:mass=0.5",
                 "--out", str(tmp_path / "m.yaml")])
    assert code == 2 and seen["add"] == "coulomb_friction,payload:mass=0.5"


@pytest.mark.parametrize("adds, msg", [
    (["latency", "latency"], "given twice"),
    (["coulomb_friction,payload", "payload"], "given twice"),
    (["latency", "none"], "cannot be combined"),
])
def test_duplicate_add_is_an_error(adds, msg, tmp_path, capsys):
    data = _write(tmp_path / "d", np.arange(40) / 15.0)
    argv = ["sysid", "fit", str(data), "--out", str(tmp_path / "m.yaml")]
    for a in adds:
        argv += ["--add", a]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and msg in err and "Traceback" not in err


def test_off_grid_logger_warns_with_the_drift(tmp_path, capsys):
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.timeseries import DataWarning

    off = _write(tmp_path / "off", np.arange(150) * 0.067, control_hz=15.0)
    with pytest.warns(DataWarning, match=r"67.00 ms under 15 Hz.*\+0.333 ms per command.*50 ms over"):
        load_dir(off)
    # no control_hz in the file: a log within 5 % of 15 Hz is checked against DROID's 15 Hz
    with pytest.warns(DataWarning, match="assumed DROID 15 Hz"):
        load_dir(_write(tmp_path / "nohz", np.arange(150) * 0.067))
    for t, hz in ((np.arange(150) / 15.0, 15.0), (np.arange(1000) / 100.0, 15.0), (np.arange(300) / 30.0, 15.0)):
        with warnings.catch_warnings():
            warnings.simplefilter("error", DataWarning)
            load_dir(_write(tmp_path / f"ok{len(t)}", t, control_hz=hz))  # on the grid: silent
    # the CLI prints it as one line, no Python file:line prefix
    from realm_ms.sysid.cli import _show_data_warnings

    _show_data_warnings()
    load_dir(off)
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("warning: ")]
    assert len(lines) == 2 and "drift" in lines[0] and "DataWarning" not in err


def test_encoder_bias_sign():
    """q_servo = q_logged + bias: at rest a positive bias puts the logged angle *below* the command."""
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.simulator import ReplaySimulator

    sim = ReplaySimulator()
    q0 = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]])
    hold = np.repeat(q0[:, None], 240, 1)
    ref = sim.rollout(q0, np.zeros_like(q0), hold, [])[0, -1]
    biased = sim.rollout(q0, np.zeros_like(q0), hold, [make_effect("encoder_bias", {"bias7": 0.005, "bias1": -0.004})])[0, -1]
    assert biased[6] - ref[6] == pytest.approx(-0.005, abs=5e-4)
    assert biased[0] - ref[0] == pytest.approx(0.004, abs=5e-4)


def test_torque_logs_without_q_cmd_load_for_torque_space(tmp_path):
    """npz with t, q, tau (no q_cmd) and a LeRobot dataset with an effort feature and no action."""
    from realm_ms.sysid.data_io import load_dir, read_lerobot

    t = np.arange(1200) / 1000.0
    q = POSE[None].repeat(1200, 0)
    (tmp_path / "npz").mkdir()
    np.savez(tmp_path / "npz" / "a.npz", t=t, q=q, tau=np.zeros((1200, 7)))
    (tr,) = load_dir(tmp_path / "npz")
    assert tr.q_cmd is None and tr.tau.shape == (1200, 7)

    pytest.importorskip("lerobot")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    feats = {"observation.state": {"dtype": "float32", "shape": (7,), "names": None},
             "observation.effort": {"dtype": "float32", "shape": (7,), "names": None}}
    ds = LeRobotDataset.create(repo_id="local/torque_log", fps=100, features=feats, root=tmp_path / "ds", use_videos=False)
    for i in range(150):
        ds.add_frame({"observation.state": (POSE + 0.001 * i).astype(np.float32),
                      "observation.effort": np.full(7, 0.5, np.float32), "task": "log"})
    ds.save_episode()
    ds.finalize()
    (tr,) = read_lerobot(tmp_path / "ds")
    assert tr.q_cmd is None and tr.tau.shape == (150, 7) and np.allclose(tr.tau, 0.5)
    assert len(load_dir(tmp_path / "ds")) == 1
