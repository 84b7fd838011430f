"""Torque space: the inverse-dynamics residual of torque logs from the MuJoCo-native reference
(MuJoCo's own frictionloss / payload body, the independent law, a torque sensor), no q_cmd."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from realm_ms.cli import main  # noqa: E402


def _synth(root, variant, noise=True, n=(2, 1), duration=4.0):
    from realm_ms.sysid.reference_native import synth_native

    kw = {} if noise else dict(noise_rad=0.0, noise_nm=0.0, noise_qd=0.0)
    synth_native(variant, root, seed=0, n_train=n[0], n_heldout=n[1], duration_s=duration, with_cmd=False, **kw)
    return root


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    return _synth(tmp_path_factory.mktemp("tq") / "clean", "none", noise=False, n=(1, 1))


@pytest.fixture(scope="module")
def null(tmp_path_factory):
    return _synth(tmp_path_factory.mktemp("tq") / "null", "none")


@pytest.fixture(scope="module")
def friction(tmp_path_factory):
    return _synth(tmp_path_factory.mktemp("tq") / "fl", "frictionloss")


def test_consistent_smoothing_leaves_no_residual_on_clean_data(clean):
    """Same SG kernel on torque and acceleration: the nominal plant's residual is tiny; smoothing
    only the acceleration (not the torque) leaves the law's fast torque changes in it."""
    import torch
    from scipy.signal import savgol_filter

    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.torque.residual import TorqueSet, rmse, torque_arm

    trajs = load_dir(clean / "heldout")
    arm = torque_arm()
    ts = TorqueSet.build(trajs, arm)
    total, per = rmse(ts, [])
    assert per.max() < 0.08, per  # N·m (M varies within the 51 ms window)
    tr = trajs[0]
    w = 51
    a = savgol_filter(tr.qd, w, 3, deriv=1, delta=1e-3, axis=0)
    T = lambda x: torch.as_tensor(x[100:-100])  # noqa: E731
    naive = tr.tau[100:-100] - arm.rnea(T(tr.q), T(tr.qd), T(a)).numpy()
    assert np.sqrt(np.mean(naive**2)) > 5 * total


def test_noise_floor_matches_the_null_residual_and_null_is_at_floor(null):
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = load_split(null)
    d = TorqueSpace(train, held).diagnose(candidates=("coulomb_friction", "payload", "armature"), log=lambda *a: None).to_json()
    b = d["baseline"]
    assert 0.7 < b["heldout_rmse_nm"] / b["noise_floor_nm"] < 1.4, b
    assert d["verdict"] == "no_missing_effect" and "no missing effect" in d["message"], d["message"]


def test_frictionloss_is_found_and_fitted_near_the_floor(friction):
    """MuJoCo's frictionloss (a constraint, exact stiction) is not our smooth law: Coulomb ranks
    first, its level comes back within 15 %, and the fit ends within 2x the floor."""
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = load_split(friction)
    d = TorqueSpace(train, held).diagnose(candidates=("coulomb_friction", "viscous_damping", "armature", "payload"),
                                          log=lambda *a: None).to_json()
    assert d["suspects"][0]["effect"] == "coulomb_friction", [s["effect"] for s in d["suspects"]]
    fc = [d["suspects"][0]["params"][f"fc{j}"] for j in range(1, 8)]
    np.testing.assert_allclose(fc, 0.3, rtol=0.15)
    assert d["suspects"][0]["heldout_rmse_after_nm"] <= 2 * d["baseline"]["judging_floor_nm"]


def test_narrowed_candidates_name_what_was_left_out(friction):
    """Screening without the friction laws leaves the friction residual: the verdict names the
    library terms not screened (never "no effect in the library"), tracking-only effects excluded."""
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = load_split(friction)
    d = TorqueSpace(train, held).diagnose(candidates=("payload", "armature"), log=lambda *a: None).to_json()
    assert d["verdict"] in ("partially_explained", "unexplained"), d["message"]
    note = d["message"].split("not screened here: ", 1)[1]
    assert "coulomb_friction" in note and "link_mass" in note and "latency" not in note and "payload" not in note
    assert "in the library" not in d["message"]


def test_cli_torque_space_and_tracking_effects_need_q_cmd(friction, tmp_path, capsys):
    import json

    code = main(["sysid", "fit", str(friction), "--add", "coulomb_friction", "--out", str(tmp_path / "m.yaml"),
                 "--json", str(tmp_path / "f.json")])
    out = capsys.readouterr()
    assert code == 0, out.err
    f = json.loads((tmp_path / "f.json").read_text())
    assert f["unit"] == "N·m" and f["after"]["heldout_rmse_nm"] < 0.6 * f["before"]["heldout_rmse_nm"]
    # no flange figures in torque space, and the reason, in the JSON and the printed summary
    assert set(f["flange"]) == {"skipped"} and "no commanded target" in f["flange"]["skipped"]
    assert "flange: not measured (torque space" in out.out
    from realm_ms.agents.robot_model import RobotModel

    assert RobotModel.load(tmp_path / "m.yaml").names == ["coulomb_friction"]
    code = main(["sysid", "fit", str(friction), "--add", "latency", "--out", str(tmp_path / "m2.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and "needs `q_cmd`" in err and "Traceback" not in err
    code = main(["sysid", "report", str(friction), "--out", str(tmp_path / "r.html")])
    capsys.readouterr()
    html = (tmp_path / "r.html").read_text()
    assert code == 0 and "Torque residual overlays" in html and "Residual left by frequency band" in html
    code = main(["sysid", "compare", str(friction), "--space", "position"])
    err = capsys.readouterr().err
    assert code == 2 and "--space torque" in err


def test_native_effect_spec_parsing():
    from realm_ms.sysid.reference_native import VARIANTS, NativeEffects

    fx = NativeEffects.parse("frictionloss=0.3,damping4=0.5,payload_mass=0.8,payload_com_x=0.12,link_scale4=0.3")
    assert fx.frictionloss == (0.3,) * 7 and fx.damping[3] == 0.5 and fx.damping[0] == 0.0
    assert fx.payload_com == (0.12, 0.0, 0.0) and fx.link_scale[3] == 0.3
    for spec in VARIANTS.values():
        NativeEffects.parse(spec)
    with pytest.raises(ValueError, match="unknown native effect"):
        NativeEffects.parse("warp=1")


def test_payload_term_matches_a_mujoco_payload_body():
    """The torque-space payload term (point mass at its centre of mass) against MuJoCo's own
    inverse dynamics of the native plant with a payload body, at random states."""
    import torch

    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.reference_mujoco import MujocoConfig, inverse_dynamics
    from realm_ms.sysid.reference_native import NativeEffects, build_native_model
    from realm_ms.sysid.torque.residual import torque_arm
    from realm_ms.sysid.torque.terms import Samples, payload

    fx = NativeEffects(payload_mass=0.8, payload_com=(0.12, -0.03, 0.05))
    with_p, nominal = build_native_model(fx, MujocoConfig()), build_native_model(NativeEffects(), MujocoConfig())
    rng = np.random.default_rng(0)
    arm = torque_arm()
    cfg = make_effect("payload").config
    for _ in range(3):
        q = np.array([0, -0.6, 0, -2.4, 0, 1.9, 0]) + rng.normal(0, 0.3, 7)
        qd, qdd = rng.normal(0, 0.5, 7), rng.normal(0, 3, 7)
        tau = [inverse_dynamics(m, q, qd, qdd) for m in (with_p, nominal)]
        t = lambda x: torch.as_tensor(x)[None]  # noqa: E731
        ours = payload({"mass": 0.8, "com_x": 0.12, "com_y": -0.03, "com_z": 0.05}, Samples(t(q), t(qd), t(qdd), arm), cfg)
        np.testing.assert_allclose(ours.numpy()[0], tau[0] - tau[1], atol=2e-3)


def test_one_long_torque_log_enters_as_one_file(tmp_path, capsys):
    """A robot's single recording (one .npz, t/q/qd/tau, no q_cmd) goes straight into the workbench:
    cut into time blocks, some held out, and MuJoCo's frictionloss is still the first suspect."""
    import json

    root = _synth(tmp_path / "one", "frictionloss", n=(1, 1), duration=21.0)
    (log,) = sorted((root / "train").glob("*.npz"))
    code = main(["sysid", "diagnose", str(log), "--candidates", "coulomb_friction,armature,payload",
                 "--json", str(tmp_path / "d.json")])
    assert code == 0, capsys.readouterr().err
    d = json.loads((tmp_path / "d.json").read_text())
    assert d["unit"] == "N·m" and len(d["split"]["train"]) == 1 and len(d["split"]["heldout"]) == 1
    assert all(n.startswith(log.stem + "[") for n in d["split"]["train"] + d["split"]["heldout"])
    assert d["suspects"][0]["effect"] == "coulomb_friction"


def test_vibration_left_after_the_fit_is_named_by_its_band(tmp_path, capsys):
    """A 25 Hz torque oscillation (0.8 N·m) on joints 2 and 4, a structural mode the rigid-body
    library has no effect for, on top of MuJoCo's frictionloss: `auto` still fits the friction, does
    not call the rest found, and says the residual left lies above 10 Hz; `compare` prints the bands."""
    import json

    root = _synth(tmp_path / "vib", "frictionloss", n=(2, 1), duration=4.0)
    for f in sorted(root.glob("*/*.npz")):
        d = dict(np.load(f))
        d["tau"][:, [1, 3]] += 0.8 * np.sin(2 * np.pi * 25.0 * d["t"])[:, None]
        np.savez(f, **d)
    code = main(["sysid", "auto", str(root), "--max-steps", "1", "--out", str(tmp_path / "m.yaml"),
                 "--json", str(tmp_path / "a.json")])
    assert code == 0, capsys.readouterr().err
    a = json.loads((tmp_path / "a.json").read_text())
    assert a["steps"] and a["steps"][0]["effect"] in ("coulomb_friction", "smooth_friction", "stribeck_friction")
    assert a["final"]["verdict"] == "partially_explained", a["details"]["message"]
    bands = a["details"]["residual_bands"]
    assert bands["share"][-1] > 0.7 and "above 10 Hz" in a["details"]["message"]
    capsys.readouterr()
    assert main(["sysid", "compare", str(root / "heldout"), "--model", str(tmp_path / "m.yaml")]) == 0
    out = capsys.readouterr().out
    assert "by band" in out and ">10 Hz" in out
