"""The payload effect with its centre of mass and rotational inertia (position space on the PhysX
replay; torque space on MuJoCo-native logs with an off-axis payload body)."""

from __future__ import annotations

import numpy as np
import pytest

from realm_ms.agents.effects import make_effect


def test_payload_centre_of_mass_moves_the_sag_and_batches():
    from realm_ms.sysid.simulator import ReplaySimulator

    sim = ReplaySimulator()
    q0 = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]] * 2)
    hold = np.repeat(q0[:, None], 240, 1)
    axial = sim.rollout(q0[:1], np.zeros((1, 7)), hold[:1], [make_effect("payload", {"mass": 0.8})])[0, -1]
    side = sim.rollout(q0[:1], np.zeros((1, 7)), hold[:1],
                       [make_effect("payload", {"mass": 0.8, "com_x": 0.12, "com_z": 0.0})])[0, -1]
    # an off-axis centre of mass loads the wrist differently: joints 5-7 move, not just 2 and 4
    assert np.abs(side - axial)[4:].max() > 5e-4
    # two rows with different centres of mass in one batch equal the single runs
    fx = make_effect("payload")
    theta = np.array([[0.8, 0.0, 0.0, 0.15, 0.0, 0.0, 0.0], [0.8, 0.12, 0.0, 0.0, 0.0, 0.0, 0.0]])
    fx.set_theta(theta)
    both = sim.rollout(q0, np.zeros((2, 7)), hold, [fx])[:, -1]
    np.testing.assert_allclose(both[0], axial, atol=1e-5)
    np.testing.assert_allclose(both[1], side, atol=1e-5)


def test_payload_without_com_values_keeps_the_configured_offset():
    fx = make_effect("payload", {"mass": 0.5})
    v = fx.values()
    np.testing.assert_allclose([v["com_x"], v["com_y"], v["com_z"]], [0.0, 0.0, 0.15], atol=1e-7)
    fixed = make_effect("payload", None, {"fit_com": False})
    assert [p.local_key for p in fixed.free_params] == ["mass"]


def test_payload_inertia_is_off_by_default_and_freed_by_fit_inertia():
    assert {p.local_key for p in make_effect("payload").free_params} == {"mass", "com_x", "com_y", "com_z"}
    fx = make_effect("payload", None, {"fit_inertia": True})
    assert {"gyr_x", "gyr_y", "gyr_z"} <= {p.local_key for p in fx.free_params}


def test_payload_inertia_in_the_replay_slows_the_wrist():
    """A payload with rotational inertia (gyr 0.1 m) is built into the PhysX flange link and known
    to the driver's prediction: the wrist lags a step target more than with the point mass."""
    from realm_ms.sysid.simulator import ReplaySimulator

    sim = ReplaySimulator()
    q0 = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]])
    target = q0.copy()
    target[0, 6] += 0.2
    step = np.repeat(target[:, None], 12, 1)
    point = sim.rollout(q0, np.zeros((1, 7)), step, [make_effect("payload", {"mass": 0.8, "com_z": 0.05})])[0]
    spread = sim.rollout(q0, np.zeros((1, 7)), step, [make_effect(
        "payload", {"mass": 0.8, "com_z": 0.05, "gyr_x": 0.1, "gyr_y": 0.1}, {"fit_inertia": True})])[0]
    assert (spread[6, 6] - q0[0, 6]) < (point[6, 6] - q0[0, 6]) - 1e-3


def test_payload_term_with_inertia_matches_a_mujoco_payload_body():
    """The torque-space payload term (mass, CoM and gyration) against MuJoCo's inverse dynamics of
    the native plant with a payload body whose inertia is 0.002 kg·m² about each axis."""
    pytest.importorskip("mujoco")
    import torch

    from realm_ms.sysid.reference_mujoco import MujocoConfig, inverse_dynamics
    from realm_ms.sysid.reference_native import NativeEffects, build_native_model
    from realm_ms.sysid.torque.residual import torque_arm
    from realm_ms.sysid.torque.terms import Samples, payload

    fx = NativeEffects(payload_mass=0.8, payload_com=(0.12, -0.03, 0.05), payload_inertia=0.002)
    with_p, nominal = build_native_model(fx, MujocoConfig()), build_native_model(NativeEffects(), MujocoConfig())
    gyr = float(np.sqrt(0.002 / 2 / 0.8))  # I = m (gyr² + gyr²) about each axis
    values = {"mass": 0.8, "com_x": 0.12, "com_y": -0.03, "com_z": 0.05, "gyr_x": gyr, "gyr_y": gyr, "gyr_z": gyr}
    cfg = make_effect("payload").config
    rng = np.random.default_rng(0)
    arm = torque_arm()
    for _ in range(3):
        q = np.array([0, -0.6, 0, -2.4, 0, 1.9, 0]) + rng.normal(0, 0.3, 7)
        qd, qdd = rng.normal(0, 1.0, 7), rng.normal(0, 20, 7)
        tau = [inverse_dynamics(m, q, qd, qdd) for m in (with_p, nominal)]
        t = lambda x: torch.as_tensor(x)[None]  # noqa: E731
        s = Samples(t(q), t(qd), t(qdd), arm)
        np.testing.assert_allclose(payload(values, s, cfg).numpy()[0], tau[0] - tau[1], atol=2e-3)
        point = {k: v for k, v in values.items() if not k.startswith("gyr")}
        assert np.abs(payload(point, Samples(t(q), t(qd), t(qdd), arm), cfg).numpy()[0] - (tau[0] - tau[1])).max() > 5e-3


def test_off_axis_payload_fits_to_the_floor_in_torque_space(tmp_path):
    """0.8 kg, 12 cm out from the flange axis (MuJoCo payload body with its own inertia): the fit
    finds mass and centre of mass and reaches 2x the noise floor; with ``fit_inertia`` the
    gyration comes back too."""
    pytest.importorskip("mujoco")
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.reference_native import synth_native
    from realm_ms.sysid.fit import FitConfig
    from realm_ms.sysid.torque.space import TorqueSpace

    synth_native("payload_com", tmp_path, seed=0, n_train=2, n_heldout=1, duration_s=4.0, with_cmd=False)
    train, held = load_split(tmp_path)
    quiet = lambda *a: None  # noqa: E731
    f = TorqueSpace(train, held).fit(config=FitConfig(add="payload"), log=quiet).to_json()
    p = f["params"]
    assert f["after"]["heldout_rmse_nm"] <= 2 * f["noise_floor_nm"], f["after"]
    assert p["payload.mass"] == pytest.approx(0.8, rel=0.05)
    np.testing.assert_allclose([p["payload.com_x"], p["payload.com_y"], p["payload.com_z"]], [0.12, 0.0, 0.05], atol=0.01)
    fi = TorqueSpace(train, held).fit(config=FitConfig(add="payload:fit_inertia=true"), log=quiet).to_json()
    gyr = [fi["params"][f"payload.gyr_{a}"] for a in "xyz"]
    np.testing.assert_allclose(gyr, np.sqrt(0.002 / 2 / 0.8), rtol=0.2)
    assert fi["after"]["heldout_rmse_nm"] <= f["after"]["heldout_rmse_nm"]
