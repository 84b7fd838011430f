"""Effect library: names, parameter declarations, spec parsing, and each effect in the simulator."""

import numpy as np
import pytest
import torch

from realm_ms.agents.effects import CONFOUNDS, EFFECTS, make_effect
from realm_ms.sysid.effect_spec import parse_effects

NAMES = ["coulomb_friction", "viscous_damping", "stribeck_friction", "smooth_friction", "lugre_friction", "armature",
         "payload", "gravity_comp_error", "latency", "target_filter", "target_interpolation",
         "gain_mismatch", "torque_limit", "backlash", "encoder_bias", "link_mass", "gripper_response"]
ARM = [n for n in NAMES if EFFECTS[n].acts_on == "arm"]
UNITS = {"N·m", "N·m·s/rad", "kg·m²", "kg", "m", "s", "rad", "rad/s", "N·m/s", "N·m/rad", "1"}


def test_registry_has_exactly_the_issue_names():
    assert list(EFFECTS) == NAMES
    for a, b in CONFOUNDS:
        assert a in EFFECTS and b in EFFECTS


@pytest.mark.parametrize("name", NAMES)
def test_declared_parameters(name):
    fx = make_effect(name)
    assert fx.specs and fx.free_params
    for s in fx.specs:
        assert s.unit in UNITS, (name, s.name, s.unit)
        assert s.lo < s.hi and s.lo <= s.nominal <= s.hi and s.lo <= s.off <= s.hi
        assert s.scale in ("lin", "log") and s.doc
    assert fx.is_off()
    assert fx.summary and fx.signature


def test_set_values_by_joint_and_errors():
    fx = make_effect("coulomb_friction", {"fc": 0.2, "fc4": 0.5})
    v = fx.values()
    assert v["fc1"] == pytest.approx(0.2) and v["fc4"] == pytest.approx(0.5)
    with pytest.raises(KeyError, match="no parameter"):
        fx.set_values({"friction": 1})
    with pytest.raises(ValueError, match="outside its bounds"):
        fx.set_values({"fc": 99})


def test_spec_parsing():
    fx = parse_effects("coulomb_friction:fc=0.3,asymmetric=true,fc_asym2=0.1,latency:delay=0.01")
    assert [f.name for f in fx] == ["coulomb_friction", "latency"]
    assert fx[0].config.asymmetric is True
    assert fx[0].values()["fc_asym2"] == pytest.approx(0.1)
    assert "coulomb_friction.fc_asym1" in [p.key for p in fx[0].free_params]
    assert fx[1].values()["delay"] == pytest.approx(0.01)
    assert parse_effects("none") == []
    nominal = parse_effects("armature", default_values="nominal")[0]
    assert nominal.values()["ia3"] == pytest.approx(0.2)
    with pytest.raises(ValueError, match="unknown effect"):
        parse_effects("friction")


# ---------------------------------------------------------------------------- in the simulator
@pytest.fixture(scope="module")
def sim():
    from realm_ms.sysid.simulator import ReplaySimulator

    return ReplaySimulator()


@pytest.fixture(scope="module")
def commands():
    from realm_ms.sysid.excite import ExciteConfig, excite

    # 2 s of the 3 s excitation (a rollout costs per physics tick, the lugre and smooth friction steps most)
    cmds = excite(3, seed=1, config=ExciteConfig(duration_s=3.0))
    steps = 240
    k = np.minimum((np.arange(steps) / 120 * 15 + 1e-9).astype(int), cmds[0].shape[0] - 1)
    cmd = np.stack([c[k] for c in cmds])
    return cmd[:, 0].copy(), cmd


def _roll(sim, commands, effects):
    q0, cmd = commands
    return sim.rollout(q0, np.zeros_like(q0), cmd, effects)


@pytest.fixture(scope="module")
def nominal(sim, commands):
    return _roll(sim, commands, [])


@pytest.mark.parametrize("name", ARM)
def test_off_is_nominal_and_nominal_strength_changes_motion(sim, commands, nominal, name):
    off = _roll(sim, commands, [make_effect(name)])
    # float32 PhysX; the step-exact law divides position errors by h^2, so ULP-level differences
    # (re-applied build properties) grow to ~2e-6 rad over 10 s
    np.testing.assert_allclose(off, nominal, atol=1e-5)
    on = parse_effects(name, default_values="nominal")
    moved = _roll(sim, commands, on)
    assert np.all(np.isfinite(moved))
    assert np.abs(moved - nominal).max() > 5e-4, f"{name} at its typical strength leaves no trace"
    # build-time effects are reset between rollouts
    np.testing.assert_allclose(_roll(sim, commands, []), nominal, atol=1e-5)


def test_batched_rows_equal_single_runs(sim, commands):
    """A batch where an effect is active on some envs only (screening) equals separate runs."""
    q0, cmd = commands
    fx = make_effect("coulomb_friction")
    theta = np.zeros((3, len(fx.params)))
    theta[1, :7] = 0.4
    fx.set_theta(theta)
    g = make_effect("gravity_comp_error")
    gt = np.zeros((3, 1))
    gt[2] = 0.2
    g.set_theta(gt)
    batched = sim.rollout(q0, np.zeros_like(q0), cmd, [fx, g])
    single1 = sim.rollout(q0[1:2], np.zeros((1, 7)), cmd[1:2], [make_effect("coulomb_friction", {"fc": 0.4})])
    single2 = sim.rollout(q0[2:3], np.zeros((1, 7)), cmd[2:3], [make_effect("gravity_comp_error", {"scale": 0.2})])
    np.testing.assert_allclose(batched[1], single1[0], atol=1e-6)
    np.testing.assert_allclose(batched[2], single2[0], atol=1e-6)


def test_latency_is_continuous_below_one_physics_step(sim, commands, nominal):
    a = _roll(sim, commands, [make_effect("latency", {"delay": 0.002})])
    b = _roll(sim, commands, [make_effect("latency", {"delay": 0.004})])
    da, db = np.abs(a - nominal).max(), np.abs(b - nominal).max()
    assert 0 < da < db < 3 * da  # sub-step delays (dt = 8.3 ms) act, proportionally


def test_payload_sags_and_gravity_comp_keeps_nominal_model(sim, commands, nominal):
    q0, cmd = commands
    hold = np.repeat(q0[:, None], cmd.shape[1], 1)
    ref = sim.rollout(q0, np.zeros_like(q0), hold, [])
    sag = sim.rollout(q0, np.zeros_like(q0), hold, [make_effect("payload", {"mass": 1.0})])
    # at rest the payload pulls joints 2/4 away from the target; the nominal robot holds it
    assert np.abs(ref[:, -1] - q0).max() < 1e-3
    assert np.abs(sag[:, -1, [1, 3]] - q0[:, [1, 3]]).max() > 2e-3


@pytest.mark.parametrize("integrator", ["exact", "explicit", "implicit_damping"])
def test_benchmark_stage_interface(integrator):
    """Effects are ActuationStages the benchmark's DroidArmDriver runs unchanged, with every
    integrator (the explicit ones give the friction steps no within-step plant: their per-joint
    fallback runs)."""
    from realm_ms.agents.actuation import ActuationModel
    from realm_ms.agents.control import DroidArmDriver, DroidControlConfig
    from realm_ms.sysid.simulator import ReplaySimulator

    model = ReplaySimulator.__new__(ReplaySimulator)  # only for the ArmModel path
    from realm_ms.agents.arm_model import ArmModel
    from realm_ms.sysid.locked_urdf import BASE_LINK, TIP_LINK, source_urdf_path

    arm = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    stages = [make_effect(n) for n in NAMES]
    for s in stages:
        s.set_values({p.local_key: p.spec.nominal for p in s.free_params})
    drv = DroidArmDriver(arm, DroidControlConfig(joint_physics="none", integrator=integrator), 2, "cpu",
                         ActuationModel(stages))
    q = torch.tensor([[0.0, -0.6, 0.0, -2.4, 0.0, 1.9, 0.0]] * 2)
    drv.reset(q)
    drv.set_target(q + 0.1)
    for _ in range(3):
        tau = drv.torque(q, torch.zeros_like(q), 1 / 120)
    assert tau.shape == (2, 7) and torch.isfinite(tau).all()
    del model


def test_gravity_comp_error_holds_the_static_offset_the_law_predicts(sim):
    """At rest, an over-compensation s*g(q) is held by the law's joint stiffness alone:
    Kp (q - q*) = s g(q), Kp = diag(Kq) + J^T Kx J. The step-exact integration must keep its velocity
    correction where only an actuator stage (not the law's torque limit) changed the torque; when it
    did not, the offset came out about twice this."""
    import torch

    from realm_ms.agents.control import GAIN_PRESETS, BatchedGains, DroidControlConfig, resolve

    q0 = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]])
    steps, scale = 600, 0.2
    hold = np.repeat(q0[:, None], steps, 1)
    q = sim.rollout(q0, np.zeros_like(q0), hold, [make_effect("gravity_comp_error", {"scale": scale})])[0, -1]
    model = sim.model
    qt = torch.as_tensor(q, dtype=model.dtype)[None]
    gains = BatchedGains.from_gains(resolve(DroidControlConfig().gains, GAIN_PRESETS, "gain"), 1, "cpu", torch.float64)
    jac = model.jacobian(qt).to(torch.float64)
    kp = torch.diag_embed(gains.kq) + jac.transpose(-1, -2) @ (gains.kx[..., None] * jac)
    g = model.gravity_torque(qt).to(torch.float64)
    expected = torch.linalg.solve(kp, scale * g[..., None])[0, :, 0].numpy()
    offset = q - q0[0]
    big = np.abs(expected) > 2e-3  # joints the error visibly moves (2, 4 at this pose)
    assert big.any()
    np.testing.assert_allclose(offset[big], expected[big], rtol=0.15)


def test_symmetric_coulomb_shortcut_equals_the_asymmetric_law():
    """With fc_asym zero on every row the level skips the direction blend (it runs at every law
    tick); rows without asymmetry must get the same torque, bit for bit, as when another row's
    asymmetry forces the full law, and an asymmetric row must differ by direction."""
    from types import SimpleNamespace

    fx = make_effect("coulomb_friction")
    n = len(fx.params)
    th = np.zeros((3, n))
    th[:, :7] = 0.3
    v = torch.tensor([[0.2, -0.2, 0.0, 1e-3, -1e-3, 0.5, -0.5]] * 3)
    inertia, state = torch.full((3, 7), 0.05), SimpleNamespace(dt=1 / 120)
    fx.set_theta(th)
    sym = fx.friction_torque(v, inertia, state, None)
    th[2, 7:] = 0.1  # asymmetric on the last row only: the full law for all
    fx.set_theta(th)
    full = fx.friction_torque(v, inertia, state, None)
    assert torch.equal(sym[:2], full[:2])
    assert torch.equal(sym[:, [2]], torch.zeros(3, 1))  # at rest: no torque
    assert (full[2, [0, 5]].abs() > sym[2, [0, 5]].abs()).all() and (full[2, [1, 6]].abs() < sym[2, [1, 6]].abs()).all()


def test_target_interpolation_ramps_to_each_new_target():
    """Linear: equal steps, the target reached after ``duration``; min-jerk: the quintic, slow at both
    ends; a target arriving mid-ramp starts a new ramp from the point reached; 0 steps at once."""
    from types import SimpleNamespace

    state = SimpleNamespace(dt=0.01)

    def ramp(values, config, targets):
        fx = make_effect("target_interpolation", values, config)
        fx.reset(1, "cpu", None, torch.zeros(1, 7))
        return [float(fx.command(torch.full((1, 7), t), state)[0, 0]) for t in targets]

    assert ramp({"duration": 0.05}, {}, [1.0] * 6) == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0, 1.0])
    s = np.array([0.2, 0.4, 0.6, 0.8, 1.0])
    assert ramp({"duration": 0.05}, {"min_jerk": True}, [1.0] * 5) == pytest.approx(s ** 3 * (10 - 15 * s + 6 * s ** 2), abs=1e-6)
    # 0.4 reached when the target moves to 2: the next ramp runs from 0.4 to 2 in 5 steps
    assert ramp({"duration": 0.05}, {}, [1.0, 1.0, 2.0, 2.0]) == pytest.approx([0.2, 0.4, 0.72, 1.04])
    assert ramp({"duration": 0.0}, {}, [1.0, 3.0]) == pytest.approx([1.0, 3.0])
