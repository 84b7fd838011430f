"""realm_ms.agents.effects.parameter: units, bounds, normalised coordinates."""

import numpy as np
import pytest

from realm_ms.agents.effects.parameter import ParamSet, ParamSpec, format_value


def test_lin_and_log_round_trip():
    lin = ParamSpec("b", "N·m·s/rad", 0.5, 0.0, 10.0).expand("viscous_damping")
    log = ParamSpec("vs", "rad/s", 0.05, 0.005, 0.5, 0.05, per_joint=False, scale="log").expand("stribeck_friction")
    ps = ParamSet.of(lin + log)
    x = np.array([0.0, 1.0, 2.5, 5.0, 7.5, 9.0, 10.0, 0.05])
    u = ps.to_unit(x)
    assert np.all((u >= 0) & (u <= 1))
    assert u[-1] == pytest.approx(0.5)  # geometric middle of [0.005, 0.5]
    np.testing.assert_allclose(ps.from_unit(u), x, rtol=1e-12, atol=1e-12)
    # out-of-bounds values are clipped, never extrapolated
    assert ps.from_unit(np.full(8, 2.0))[0] == 10.0


def test_keys_units_and_bounds():
    ps = ParamSet.of(ParamSpec("fc", "N·m", 0.3, 0.0, 3.0).expand("coulomb_friction"))
    assert ps.keys[0] == "coulomb_friction.fc1" and ps.keys[-1] == "coulomb_friction.fc7"
    lo, hi = ps.bounds()
    assert lo.tolist() == [0.0] * 7 and hi.tolist() == [3.0] * 7
    assert ps.params[3].unit == "N·m" and ps.params[3].joint == 3


def test_invalid_specs_are_refused():
    with pytest.raises(ValueError):
        ParamSpec("x", "1", 1.0, 2.0, 1.0)
    with pytest.raises(ValueError):
        ParamSpec("x", "1", 1.0, 0.0, 1.0, scale="log")


def test_format_value():
    assert format_value(0.0123, "s") == "12.3 ms"
    assert format_value(0.0021, "rad") == "2.1 mrad"
    assert format_value(0.31, "N·m") == "0.31 N·m"


def test_a_fit_pressed_against_a_bound_is_flagged_but_an_effect_left_off_is_not():
    from realm_ms.agents.effects import make_effect
    from realm_ms.agents.robot_model import RobotModel

    spec = ParamSpec("s", "1", 0.1, -0.9, 2.0, 0.0)
    assert spec.at_bound(-0.9) == "lower" and spec.at_bound(2.0) == "upper"
    assert spec.at_bound(-0.89) is None and spec.at_bound(0.5) is None and spec.at_bound(0.0) is None
    fc = ParamSpec("fc", "N·m", 0.3, 0.0, 3.0, 0.0)
    assert fc.at_bound(0.0) is None  # off-value on the bound: the effect is off on that joint, not stretched
    m = RobotModel([make_effect("link_mass", {"s2": -0.9, "s4": 0.3}, {"fit_com": True}),
                    make_effect("coulomb_friction", {"fc": 0.0, "fc7": 3.0})])
    assert m.params_at_bounds() == {"link_mass.s2": "lower", "coulomb_friction.fc7": "upper"}
