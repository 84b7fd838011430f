"""MODEL.yaml: round trip, errors, and the benchmark entry point."""

import numpy as np
import pytest

from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.robot_model import RobotModel, load_actuation_model
from realm_ms.sysid.effect_spec import parse_effects


def test_round_trip(tmp_path):
    m = RobotModel(parse_effects("coulomb_friction:fc=0.25,latency:delay=0.012,armature:ia2=0.3"),
                   provenance={"data": "x"})
    m.save(tmp_path / "M.yaml")
    back = RobotModel.load(tmp_path / "M.yaml")
    assert back.names == m.names
    assert back.params() == pytest.approx(m.params())
    text = (tmp_path / "M.yaml").read_text()
    assert "N·m" in text and "gains: polymetis" in text and "joint_physics: none" in text


def test_load_actuation_model_orders_stages(tmp_path):
    RobotModel(parse_effects("coulomb_friction:fc=0.2,encoder_bias:bias=0.001,latency:delay=0.01")).save(tmp_path / "M.yaml")
    act = load_actuation_model(tmp_path / "M.yaml")
    assert isinstance(act, ActuationModel)
    assert [s.name for s in act.stages] == ["encoder_bias", "latency", "coulomb_friction"]
    assert load_actuation_model({"effects": ["latency"]}).stages[0].name == "latency"


def test_bad_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        RobotModel.load(tmp_path / "nope.yaml")
    (tmp_path / "b.yaml").write_text("effects: [{name: friction}]")
    with pytest.raises(ValueError, match="unknown effect"):
        RobotModel.load(tmp_path / "b.yaml")
    (tmp_path / "c.yaml").write_text("effects: [{name: latency, params: {delay: 5}}]")
    with pytest.raises(ValueError, match="outside its bounds"):
        RobotModel.load(tmp_path / "c.yaml")


def _model(tmp_path, text):
    (tmp_path / "m.yaml").write_text(text)
    return RobotModel.load(tmp_path / "m.yaml")


@pytest.mark.parametrize("text, msg", [
    ("physics_hz: 1500000", r"physics_hz: 1\.5e\+06 Hz is outside the supported 60-2000 Hz"),  # a multiple of 15: used to hang
    ("physics_hz: 45", r"physics_hz: 45 Hz is outside"),
    ("effects: [latency, latency]", r"effects\[1\]: effect 'latency' given twice \(also effects\[0\]\)"),
    ("effects: [{name: coulomb_friction, params: {fc: 300}, units: {fc: furlong}}]", r"units\.fc: 'furlong' is not N·m"),
    ("effects: [{name: coulomb_friction, units: {fz: N·m}}]", r"units\.fz: effect 'coulomb_friction' has no parameter 'fz'"),
    ("effects: [{name: coulomb_friction, units: N·m}]", r"units: expected a mapping"),
    ("effects: [{name: coulomb_friction, params: {fc: [0.1, 0.2, 0.3]}}]", r"fc: expected one number or a list of 7 \(one per joint\), got a list of 3"),
    ("effects: [{name: coulomb_friction, params: {fc3: [0.1, 0.2]}}]", r"fc3: expected a number, got a list of 2"),
    ("effects: [{name: coulomb_friction, params: {fc: abc}}]", r"fc: expected one number or a list of 7"),
    # a misspelt key would otherwise load the nominal robot (or the effect's defaults) silently
    ("effect: [latency]", r"unknown key 'effect' \(did you mean 'effects'\?\); a robot model has"),
    ("effects: [{name: latency, param: {delay: 0.1}}]", r"effects\[0\]: unknown key 'param' \(did you mean 'params'\?\); an effect has"),
])
def test_model_files_refused_with_one_line(tmp_path, text, msg):
    with pytest.raises(ValueError, match=msg) as e:
        _model(tmp_path, text)
    assert "\n" not in str(e.value)


def test_units_are_converted(tmp_path):
    m = _model(tmp_path, "effects: [{name: coulomb_friction, params: {fc: 300, fc2: [250]}, units: {fc: mN·m}},"
                         " {name: encoder_bias, params: {bias: 0.5}, units: {bias: deg}}]")
    p = m.params()
    assert p["coulomb_friction.fc1"] == pytest.approx(0.3) and p["coulomb_friction.fc2"] == pytest.approx(0.25)
    assert p["encoder_bias.bias1"] == pytest.approx(np.deg2rad(0.5))
    # the file the model writes back is in the declared units again (and loads to the same values)
    m.save(tmp_path / "back.yaml")
    assert RobotModel.load(tmp_path / "back.yaml").params() == pytest.approx(p)


@pytest.mark.parametrize("add", ["coulomb_friction:direction_velocity=-0.01", "coulomb_friction:asymmetric=2.5",
                                 "backlash:torque_width=-1", "latency,latency"])
def test_fit_refuses_what_its_loader_would(tmp_path, capsys, add):
    """`fit --add` settings go through the loader's checks before any work: no MODEL.yaml is written."""
    from realm_ms.cli import main

    t = np.arange(60) / 15.0
    q = np.array([0.0, -0.6, 0.0, -2.4, 0.0, 1.9, 0.0])[None].repeat(len(t), 0)
    (tmp_path / "d").mkdir()
    np.savez(tmp_path / "d" / "traj_0.npz", t=t, q=q, q_cmd=q)
    code = main(["sysid", "fit", str(tmp_path / "d"), "--add", add, "--out", str(tmp_path / "m.yaml")])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and not (tmp_path / "m.yaml").exists()
    with pytest.raises(ValueError) as e:  # the loader refuses the same settings
        parse_effects(add)
    assert str(e.value).splitlines()[-1] in err


def test_every_effect_round_trips_and_save_refuses_a_bad_model(tmp_path):
    from realm_ms.agents.effects import EFFECTS

    m = RobotModel(parse_effects(",".join(EFFECTS)))
    m.save(tmp_path / "all.yaml")
    assert RobotModel.load(tmp_path / "all.yaml").names == m.names
    bad = RobotModel(parse_effects("coulomb_friction"))
    object.__setattr__(bad.effects[0].config, "direction_velocity", -1.0)  # changed after validation
    with pytest.raises(ValueError, match="direction_velocity: must be > 0"):
        bad.save(tmp_path / "bad.yaml")
    assert not (tmp_path / "bad.yaml").exists()
