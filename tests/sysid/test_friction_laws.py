"""Friction laws we did not write into our effects: Gaz et al.'s identified sigmoid and LuGre on
the MuJoCo-native plant, fitted in torque space; and the torque-space report."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")


def test_gaz_law_matches_the_published_table():
    """Zero at rest and the limits / values the notes derive from the paper's φ (joint 1, 4, 7)."""
    from realm_ms.sysid.reference_friction import gaz_friction

    np.testing.assert_allclose(gaz_friction(np.zeros(7)), 0.0, atol=1e-12)
    hi, lo, half = gaz_friction(np.full(7, 50.0)), gaz_friction(np.full(7, -50.0)), gaz_friction(np.full(7, 0.5))
    np.testing.assert_allclose(hi[[0, 3, 6]], [0.246, 0.575, 0.277], atol=2e-3)
    np.testing.assert_allclose(lo[[0, 3, 6]], [-0.301, -0.704, -0.288], atol=2e-3)
    np.testing.assert_allclose(half[[0, 3, 6]], [0.213, 0.514, 0.274], atol=2e-3)


def test_lugre_steady_sliding_is_stribeck_plus_viscous_and_presliding_is_a_spring():
    from realm_ms.sysid.reference_friction import LuGre

    lg = LuGre([0.3] * 7, 1.5, 0.05, 1000.0, 1.0, [0.2] * 7, dt=2.5e-4)
    v = np.array([0.01, 0.03, 0.05, 0.1, 0.3, -0.5, -1.0])
    for _ in range(4000):  # 1 s at constant velocity: the bristles settle
        f = lg.step(v)
    g = 0.3 + 0.15 * np.exp(-((v / 0.05) ** 2))
    np.testing.assert_allclose(f, g * np.sign(v) + 0.2 * v, rtol=1e-6)
    lg = LuGre([0.3] * 7, 1.5, 0.05, 1000.0, 0.0, [0.0] * 7, dt=2.5e-4)
    for _ in range(10):  # 10 steps at 1e-3 rad/s: 2.5 µrad of deflection, far below breakaway
        f = lg.step(np.full(7, 1e-3))
    np.testing.assert_allclose(f, 1000.0 * 2.5e-6, rtol=0.01)  # a spring σ0 z, z ≈ displacement


def _data(root, variant):
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.reference_native import synth_native

    synth_native(variant, root, seed=0, n_train=2, n_heldout=1, duration_s=4.0, with_cmd=False)
    return load_split(root)


@pytest.mark.parametrize("variant", ["gaz", "lugre"])
def test_other_friction_laws_fit_within_twice_the_floor_with_coulomb_and_viscous(tmp_path, variant):
    """Gaz's sigmoid (smooth, asymmetric, saturating) and LuGre (bristle dynamics) are neither of
    our laws; Coulomb + viscous in torque space still brings the held-out residual within 2x the
    noise floor (a third or less of the nominal residual)."""
    from realm_ms.sysid.fit import FitConfig
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = _data(tmp_path / variant, variant)
    f = TorqueSpace(train, held).fit(config=FitConfig(add="coulomb_friction,viscous_damping"), log=lambda *a: None).to_json()
    after, before, floor = f["after"]["heldout_rmse_nm"], f["before"]["heldout_rmse_nm"], f["noise_floor_nm"]
    assert before > 3 * floor, (before, floor)
    assert after <= 2 * floor, (after, floor)
    if variant == "lugre":  # sliding level 0.3 N·m on most joints, 0.5 on J4, 0.2 on J7; viscous 0.2
        fc = np.array([f["params"][f"coulomb_friction.fc{j}"] for j in range(1, 8)])
        assert abs(fc[3] - 0.5) < 0.12 and abs(fc[6] - 0.2) < 0.08 and np.all(np.abs(fc[[0, 1, 2]] - 0.3) < 0.1), fc


def test_report_on_torque_data_shows_per_joint_overlays_in_newton_metres(tmp_path):
    from realm_ms.cli import main
    from realm_ms.sysid.reference_native import synth_native

    root = tmp_path / "fl"
    synth_native("frictionloss", root, seed=0, n_train=1, n_heldout=1, duration_s=3.0, with_cmd=False)
    assert main(["sysid", "fit", str(root), "--add", "coulomb_friction", "--out", str(tmp_path / "m.yaml")]) == 0
    out = tmp_path / "r.html"
    assert main(["sysid", "report", str(root), "--model", str(tmp_path / "m.yaml"), "--out", str(out)]) == 0
    html = out.read_text()
    assert "Torque residual overlays" in html and "Held-out torque residual per joint [N·m]" in html
    assert html.count("<img") >= 3 and "model (coulomb_friction)" in html
    # the per-joint table: nominal row larger than the model row on every joint (friction explained)
    import re

    rows = re.findall(r"<tr><td class=\"l\">(nominal URDF|model \(coulomb_friction\))</td>(.*?)</tr>", html)
    vals = {name: [float(x) for x in re.findall(r">([0-9.]+)</td>", body)] for name, body in rows}
    nom, mod = np.array(vals["nominal URDF"]), np.array(vals["model (coulomb_friction)"])
    assert len(nom) == 8 and np.all(mod < nom), (nom, mod)


def test_a_parameter_fitted_onto_its_bound_is_accepted():
    """Parameters are stored as float32: 0.005 (Stribeck vs's lower bound) must not read as outside."""
    from realm_ms.agents.effects import make_effect

    fx = make_effect("stribeck_friction", {"vs": 0.005, "fc_ratio": 1.0})
    assert abs(fx.values()["vs"] - 0.005) < 1e-9
    with pytest.raises(ValueError, match="outside its bounds"):
        make_effect("stribeck_friction", {"vs": 0.0049})


def test_smooth_friction_is_the_gaz_law_and_its_backward_euler_step_solves_its_equation():
    """With fc = φ₁/2, vs = 2/φ₂, v0 = φ₃ the library's smooth friction is Gaz et al.'s sigmoid;
    its implicit step lands on the root of a (v - v_free) + f(v) = 0 for stiff and soft joints alike."""
    import torch

    from realm_ms.agents.effects.smooth_friction import backward_euler_velocity, friction
    from realm_ms.sysid.reference_friction import GAZ_PHI, gaz_friction

    phi = torch.as_tensor(GAZ_PHI, dtype=torch.float64)
    for v in (-1.0, -0.2, -0.01, 0.0, 0.03, 0.4, 2.0):
        ours = friction(torch.full((7,), v, dtype=torch.float64), phi[:, 0] / 2, 2 / phi[:, 1], phi[:, 2])
        np.testing.assert_allclose(ours.numpy(), gaz_friction(np.full(7, v)), atol=1e-9)
    # the friction curve `auto` reports is the same law
    from realm_ms.agents.effects import make_effect
    from realm_ms.agents.robot_model import RobotModel
    from realm_ms.sysid.auto import friction_curve

    paper = {f"{k}{j + 1}": float(x) for j, p in enumerate(GAZ_PHI) for k, x in (("fc", p[0] / 2), ("vs", 2 / p[1]), ("v0", p[2]))}
    curve = friction_curve(RobotModel([make_effect("smooth_friction", paper)]))
    np.testing.assert_allclose(curve["tau"], [gaz_friction(np.full(7, q)) for q in curve["qd"]], atol=1e-5)
    g = torch.Generator().manual_seed(0)
    n = 20000
    v_free = 2 * torch.randn(n, generator=g, dtype=torch.float64)
    a = 10 ** (4 * torch.rand(n, generator=g, dtype=torch.float64))  # I/h from 1 to 1e4
    fc = 3 * torch.rand(n, generator=g, dtype=torch.float64)
    vs = 10 ** (-2.3 + 2.3 * torch.rand(n, generator=g, dtype=torch.float64))
    v0 = 0.2 * (torch.rand(n, generator=g, dtype=torch.float64) - 0.5)
    v = backward_euler_velocity(v_free, a, fc, vs, v0)
    residual = a * (v - v_free) + friction(v, fc, vs, v0)
    assert float((residual.abs() / (a * v_free.abs() + fc)).max()) < 1e-6
    assert bool((v * v_free >= 0).all()) and bool((v.abs() <= v_free.abs() + 1e-12).all())  # friction never reverses


def test_the_true_smooth_friction_replays_a_gaz_plant_in_position_space(tmp_path):
    """MuJoCo-native plant with Gaz's friction (applied each 4 kHz substep, not realm-ms code),
    replayed by the benchmark's 120 Hz driver: the smooth friction at the paper's values comes
    within 2x the judging floor; the exact-stiction Coulomb law at the same levels does not."""
    from realm_ms.agents.effects import make_effect
    from realm_ms.agents.robot_model import RobotModel
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.diagnose import judging_floor
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.fit import compare
    from realm_ms.sysid.reference_friction import GAZ_PHI
    from realm_ms.sysid.reference_native import synth_native

    # one 3 s log, held-out only (the plant runs one log after another; a replay costs per second of
    # log): at 1 kHz its 2 s scored hold 2000 samples, and the smooth law sits at 0.7-0.8x the floor
    # with Coulomb 12x above it (seeds 1, 2; at 4 s: 0.7-0.8x and 9-16x)
    synth_native("gaz", tmp_path, seed=1, n_train=0, n_heldout=1, duration_s=3.0, with_cmd=True)
    held = load_dir(tmp_path / "heldout")
    ev = Evaluator(workers=1, device="cpu")
    smooth = {f"{k}{j + 1}": v for j, p in enumerate(GAZ_PHI) for k, v in (("fc", p[0] / 2), ("vs", 2 / p[1]), ("v0", p[2]))}
    coulomb = {f"fc{j + 1}": p[0] / 2 for j, p in enumerate(GAZ_PHI)}
    r_smooth = compare(held, RobotModel([make_effect("smooth_friction", smooth)]), evaluator=ev)
    r_coulomb = compare(held, RobotModel([make_effect("coulomb_friction", coulomb)]), evaluator=ev)
    floor = judging_floor(r_smooth.noise_floor, 2.5e-4)
    assert r_smooth.rmse <= 2 * floor, (r_smooth.rmse, floor)
    assert r_coulomb.rmse > 2 * r_smooth.rmse, (r_coulomb.rmse, r_smooth.rmse)
