"""The ``link_mass`` effect (per-link mass, centre of mass and inertia): fitted in torque space on
MuJoCo-native logs whose link 4 is heavier (and off-centre), and acting on the PhysX replay arm the
way MuJoCo's heavier link acts on the native plant (position space)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from realm_ms.agents.effects import make_effect  # noqa: E402


def _synth(root, variant):
    from realm_ms.sysid.reference_native import synth_native

    synth_native(variant, root, seed=0, n_train=2, n_heldout=1, duration_s=4.0, with_cmd=False)
    return root


@pytest.fixture(scope="module")
def link4(tmp_path_factory):
    return _synth(tmp_path_factory.mktemp("lm") / "link4", "link4_mass")


def test_link4_mass_is_ranked_first_and_fitted_to_the_floor(link4):
    """Link 4 +30 % mass and inertia (MuJoCo body_mass/body_inertia): link_mass beats the payload
    and gravity-scale explanations, s4 comes back within 0.03 and held-out within 1.5x the floor."""
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = load_split(link4)
    d = TorqueSpace(train, held).diagnose(candidates=("link_mass", "payload", "gravity_comp_error"), log=lambda *a: None).to_json()
    top = d["suspects"][0]
    assert top["effect"] == "link_mass", [(s["effect"], s["heldout_rmse_after_nm"]) for s in d["suspects"]]
    assert top["params"]["s4"] == pytest.approx(0.3, abs=0.03)
    assert top["heldout_rmse_after_nm"] <= 1.5 * d["baseline"]["judging_floor_nm"]
    assert d["verdict"] == "found"


@pytest.fixture(scope="module")
def link4_com(tmp_path_factory):
    return _synth(tmp_path_factory.mktemp("lmc") / "l4c", "link4_inertial")


def test_link_centre_of_mass_fits_with_fit_com(link4_com):
    """Link 4 heavier *and* its CoM 4 cm / -3 cm off: mass alone stays above 2x the floor, mass +
    CoM (``link_mass:link=4,fit_com=true``) reaches it and finds the shift."""
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.fit import FitConfig
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = load_split(link4_com)
    quiet = lambda *a: None  # noqa: E731
    mass_only = TorqueSpace(train, held).fit(config=FitConfig(add="link_mass:link=4"), log=quiet).to_json()
    with_com = TorqueSpace(train, held).fit(config=FitConfig(add="link_mass:link=4,fit_com=true"), log=quiet).to_json()
    floor = with_com["noise_floor_nm"]
    assert mass_only["after"]["heldout_rmse_nm"] > 2 * floor
    assert with_com["after"]["heldout_rmse_nm"] <= 2 * floor
    p = with_com["params"]
    # the plant's CoM moved by (0.04, -0.03) m; the fitted mass absorbs part of the first moment
    # (m c), so compare first moments: (1 + s) (c0 + dc) against 1.3 (c0 + shift)
    from realm_ms.sysid.torque.residual import torque_arm

    c0 = torque_arm().coms[3].numpy()
    got = (1 + p["link_mass.s4"]) * (c0 + [p["link_mass.dcx4"], p["link_mass.dcy4"], p["link_mass.dcz4"]])
    np.testing.assert_allclose(got[:2], 1.3 * (c0[:2] + [0.04, -0.03]), atol=0.01)


def test_auto_finds_a_shifted_link_centre_of_mass(link4_com):
    """Torque-space ``auto`` screens link CoMs too (``link_mass:fit_com=true``, all links): on the
    heavier, off-centre link 4 it takes that step (mass scales alone make held-out worse) and stops
    at the floor with link 4's first moment where the plant's is."""
    from realm_ms.sysid.auto import AutoConfig, auto
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.diagnose import DiagnoseConfig
    from realm_ms.sysid.torque.residual import torque_arm
    from realm_ms.sysid.torque.space import TorqueSpace

    train, held = load_split(link4_com)
    cfg = AutoConfig(diagnose=DiagnoseConfig(candidates=("payload", "gravity_comp_error")))
    a = auto(TorqueSpace(train, held), config=cfg, log=lambda *a: None).to_json()
    assert [s["effect"] for s in a["steps"]] == ["link_mass:fit_com=true"], a["steps"]
    assert a["final"]["verdict"] == "at_floor"
    p = a["steps"][0]["params"]
    c0 = torque_arm().coms[3].numpy()
    got = (1 + p["link_mass.s4"]) * (c0 + [p["link_mass.dcx4"], p["link_mass.dcy4"], p["link_mass.dcz4"]])
    np.testing.assert_allclose(got[:2], 1.3 * (c0[:2] + [0.04, -0.03]), atol=0.01)


def test_cli_fit_writes_a_library_effect(link4, tmp_path, capsys):
    from realm_ms.agents.robot_model import RobotModel
    from realm_ms.cli import main

    code = main(["sysid", "fit", str(link4), "--add", "link_mass:link=4", "--out", str(tmp_path / "m.yaml")])
    assert code == 0, capsys.readouterr().err
    m = RobotModel.load(tmp_path / "m.yaml")
    (fx,) = m.effects
    assert fx.name == "link_mass" and fx.values()["s4"] == pytest.approx(0.3, abs=0.03)
    assert [p.local_key for p in fx.free_params] == ["s4"]


def test_link_mass_in_the_replay_acts_as_mujoco_heavier_link():
    """Position space: the PhysX replay arm with link_mass s4 = 0.3 tracks a 3 s excitation like the
    MuJoCo-native plant whose link 4 is 30 % heavier (the remaining difference is the nominal
    PhysX-vs-MuJoCo one), and ``reset`` restores the link."""
    from realm_ms.sysid.excite import ExciteConfig, excite
    from realm_ms.sysid.reference_native import NativeEffects, NativeReference
    from realm_ms.sysid.simulator import ReplaySimulator

    cmds = excite(1, seed=3, config=ExciteConfig(duration_s=3.0, control_hz=15.0))[0]
    steps = np.repeat(cmds[:-1], 8, 0)  # 120 Hz physics, 15 Hz commands
    sim = ReplaySimulator()
    px = {n: sim.rollout(cmds[:1], np.zeros((1, 7)), steps[None], fx)[0]
          for n, fx in (("nominal", []), ("link4", [make_effect("link_mass", {"s4": 0.3})]))}
    k = np.minimum((np.arange(int(len(steps) / 120 * 1000)) / 1000 * 15 + 1e-9).astype(int), len(cmds) - 1)
    t_px = np.arange(len(steps) + 1) / 120.0
    mj = {}
    for n, spec in (("nominal", ""), ("link4", "link_scale4=0.3")):
        q = NativeReference(NativeEffects.parse(spec)).rollout_torque(cmds[0], cmds[k])[0]
        t = np.arange(len(q)) / 1000.0
        mj[n] = np.stack([np.interp(t_px, t, q[:, j]) for j in range(7)], 1)
    rms = lambda a, b: float(np.sqrt(np.mean((a[120:] - b[120:]) ** 2)))  # noqa: E731
    effect = rms(mj["link4"], mj["nominal"])
    plant_gap = rms(px["nominal"], mj["nominal"])
    assert effect > 3e-3  # the heavier link moves the arm by mrads
    assert rms(px["link4"], mj["link4"]) < 1.5 * plant_gap + 1e-4
    # a rollout without the effect resets the link to its URDF inertial
    sim.rollout(cmds[:1], np.zeros((1, 7)), steps[None, :8], [make_effect("link_mass", {"s4": 0.3})])
    m_changed = sim._targets[0]._link(3).get_mass()
    sim.rollout(cmds[:1], np.zeros((1, 7)), steps[None, :8], [])
    m_nominal = sim._targets[0]._link(3).get_mass()
    assert m_changed == pytest.approx(1.3 * m_nominal, rel=1e-5)
