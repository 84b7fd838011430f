"""Workbench input handling: repeated effect flags, the encoder-bias sign, off-grid logs."""

from __future__ import annotations

import re
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


@pytest.mark.parametrize("bug", [ValueError("a bug"), KeyError("a bug")])
def test_a_bug_below_the_cli_keeps_its_traceback(bug, tmp_path, monkeypatch):
    """Only user errors become one line and exit code 2; a ValueError or KeyError from a bug in the
    workbench is not the user's input and must not be reported as if it were."""
    from realm_ms.sysid import api

    def broken(*a, **k):
        raise bug

    monkeypatch.setattr(api, "compare", broken)
    data = _write(tmp_path / "d", np.arange(40) / 15.0)
    with pytest.raises(type(bug), match="a bug"):
        main(["sysid", "compare", str(data)])


def test_a_user_error_below_the_cli_is_one_line(tmp_path, monkeypatch, capsys):
    from realm_ms.sysid import api
    from realm_ms.validate import check_positive

    monkeypatch.setattr(api, "compare", lambda *a, **k: check_positive(0, "segment (--segment)", "s"))
    data = _write(tmp_path / "d", np.arange(40) / 15.0)
    assert main(["sysid", "compare", str(data)]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == ["realm sysid compare: error: segment (--segment): must be > 0 s, got 0"]


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


def _torque_log(d, rate=1000.0, n=3, flat_joint=None):
    d.mkdir(parents=True, exist_ok=True)
    t = np.arange(int(4 * rate)) / rate
    for i in range(n):
        q = POSE + 0.2 * np.sin(2 * np.pi * 0.5 * t[:, None] + i)
        tau = np.random.default_rng(i).normal(size=(len(t), 7))
        if flat_joint is not None:
            tau[:, flat_joint] = 0.0
        np.savez(d / f"traj_{i}.npz", t=t, q=q, tau=tau)
    return d


@pytest.mark.parametrize("verb", ["diagnose", "auto", "fit"])
def test_nothing_to_identify_is_never_a_verdict(verb, tmp_path, capsys):
    """An arm that never moves, or a torque column of zeros, used to get a confident "partially
    explained by link_mass"; it is one line saying there is nothing to identify."""
    still = _write(tmp_path / "still", np.arange(300) / 15.0, control_hz=15.0, n=3)
    flat = _torque_log(tmp_path / "flat", flat_joint=2)
    extra = {"fit": ["--add", "coulomb_friction", "--out", str(tmp_path / "m.yaml")], "auto": ["--out", str(tmp_path / "m.yaml")]}
    for data, msg in ((still, "nothing to identify: the arm never moves"),
                      (flat, r"nothing to identify in torque space: tau of joint\(s\) 3 is 0 N·m throughout")):
        code = main(["sysid", verb, str(data), "--workers", "1", "--device", "cpu", *extra.get(verb, [])])
        err = capsys.readouterr().err
        assert code == 2 and "Traceback" not in err, err
        assert re.search(msg, err.strip().splitlines()[-1]), err
        assert not (tmp_path / "m.yaml").exists()


def test_torque_logs_below_100_hz_are_refused_with_the_reason(tmp_path, capsys):
    """A 15 Hz torque log used to be read like a 1 kHz one (a "> 10 Hz" band above its Nyquist limit)."""
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.timeseries import DataError, check_torque_rate

    slow = _torque_log(tmp_path / "slow", rate=15.0)
    code = main(["sysid", "compare", str(slow), "--space", "torque", "--workers", "1", "--device", "cpu"])
    err = capsys.readouterr().err
    assert code == 2 and "logged at 15 Hz; torque-space work needs >= 100 Hz" in err and "Nyquist limit is 7.5 Hz" in err
    check_torque_rate(load_dir(_torque_log(tmp_path / "ok", rate=100.0, n=1))[0])  # 100 Hz is enough
    with pytest.raises(DataError, match="logged at 50 Hz"):
        check_torque_rate(load_dir(_torque_log(tmp_path / "half", rate=50.0, n=1))[0])
