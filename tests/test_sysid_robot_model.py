"""MODEL.yaml: round trip, errors, and the benchmark entry point."""

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
