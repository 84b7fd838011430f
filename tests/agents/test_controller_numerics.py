"""The DROID arm driver's numerics: the robot model's mass matrix, the plant inertia the
step-exact integrator predicts with, and the integrator switch."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from realm_ms.agents.arm_model import ArmModel
from realm_ms.agents.control import DroidArmDriver, DroidControlConfig
from realm_ms.sysid.locked_urdf import BASE_LINK, TIP_LINK, source_urdf_path

HOME = [0.0, -np.pi / 5, 0.0, -4 * np.pi / 5, 0.0, 3 * np.pi / 5, 0.0]


@pytest.fixture(scope="module")
def model64():
    return ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK, dtype=torch.float64)


def test_crba_mass_matrix_equals_unit_acceleration_rnea(model64):
    q = torch.as_tensor(np.random.default_rng(0).uniform(-2, 2, (6, 7)))
    assert torch.allclose(model64.mass_matrix(q), model64.mass_matrix_rnea(q), atol=1e-12)


def test_mass_matrix_equals_mujoco(model64):
    mujoco = pytest.importorskip("mujoco")
    from realm_ms.sysid.reference_mujoco import build_model

    m = build_model()
    d = mujoco.MjData(m)
    q = np.asarray(HOME) + 0.3
    d.qpos[:] = q
    mujoco.mj_forward(m, d)
    full = np.zeros((7, 7))
    mujoco.mj_fullM(m, d, full)
    assert np.abs(model64.mass_matrix(torch.as_tensor(q)[None])[0].numpy() - full).max() < 1e-9


def test_the_robot_model_is_one_code_on_both_namespaces(model64):
    """``ArmModel.numpy()`` is the same model on float64 numpy: every term agrees with torch's."""
    npm = model64.numpy()
    rng = np.random.default_rng(2)
    q, qd, qdd = (rng.uniform(-2, 2, (4, 7)) for _ in range(3))
    t = torch.as_tensor
    calls = {"link_frames": (q,), "fk": (q,), "jacobian": (q,), "rnea": (q, qd, qdd), "gravity_torque": (q,),
             "coriolis_torque": (q, qd), "mass_matrix": (q,), "mass_matrix_rnea": (q,)}
    for name, args in calls.items():
        a, b = getattr(model64, name)(*map(t, args)), getattr(npm, name)(*args)
        assert isinstance(a, torch.Tensor) and isinstance(b, np.ndarray), name
        assert np.abs(a.numpy() - b).max() < 1e-12, name
    assert np.abs(npm.gravity_torque(q)).max() > 1.0  # not trivially zero


@pytest.mark.parametrize("effect", ["payload:mass=0.8", "armature:ia=0.1"])
def test_build_time_effects_tell_the_driver_the_plant_inertia_they_add(model64, effect):
    """``plant_inertia`` of a build-time effect equals the change of MuJoCo's mass matrix when the
    same effect is built into the MuJoCo model (an independent implementation of the plant)."""
    mujoco = pytest.importorskip("mujoco")
    from realm_ms.agents.actuation import ControlState
    from realm_ms.sysid.effect_spec import parse_effects
    from realm_ms.sysid.reference_mujoco import MujocoReference

    fx = parse_effects(effect, default_values="nominal")[0]
    q = np.asarray(HOME) + 0.2
    ref = MujocoReference()
    m, target = ref._model(0)

    def mass():
        d = mujoco.MjData(m)
        d.qpos[:] = q
        mujoco.mj_forward(m, d)
        full = np.zeros((7, 7))
        mujoco.mj_fullM(m, d, full)
        return full

    target.reset()
    nominal = mass()
    fx.build_target(target, 0)
    added = mass() - nominal
    target.reset()
    qt = torch.as_tensor(q, dtype=torch.float32)[None]
    state = ControlState(q=qt, qd=torch.zeros_like(qt), q_target=qt, dt=1 / 120, model=model64.to(dtype=torch.float32),
                         time=torch.zeros(1))
    predicted = fx.plant_inertia(state)[0].double().numpy()
    model64.to(dtype=torch.float64)
    assert np.abs(predicted - added).max() < 1e-5 + 1e-4 * np.abs(added).max(), (predicted, added)


def test_integrator_switch():
    assert DroidControlConfig().integrator == "exact"
    with pytest.raises(ValueError, match="integrator"):
        DroidControlConfig(integrator="rk4")


def test_implicit_damping_drive_carries_the_laws_damping_diagonal(model64):
    """With ``integrator="implicit_damping"`` the drive carries Kd's diagonal at the reference pose
    (or the configured values) and the explicit torque pre-compensates it: torque + drive = the law."""
    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    cfg = DroidControlConfig(joint_physics="none", integrator="implicit_damping")
    drv = DroidArmDriver(model, cfg, 1)
    q = torch.tensor([list(cfg.reference_qpos)], dtype=torch.float32)
    jac = model.jacobian(q)
    kd = torch.diag_embed(drv.gains.kqd) + jac.transpose(1, 2) @ (drv.gains.kxd[..., None] * jac)
    assert torch.allclose(drv.drive_damping, torch.diagonal(kd[0]), rtol=1e-5)
    assert (drv.drive_damping > 0).all()
    explicit = DroidArmDriver(model, DroidControlConfig(joint_physics="none", integrator="explicit"), 1)
    qd = torch.full_like(q, 0.1)
    for d in (drv, explicit):
        d.reset(q)
        d.set_target(q + 0.01)
    assert torch.allclose(drv.torque(q, qd, 1 / 120) - drv.drive_damping * qd, explicit.torque(q, qd, 1 / 120), atol=1e-4)
    fixed = DroidArmDriver(model, DroidControlConfig(integrator="implicit_damping", drive_damping=(1.0,) * 7), 1)
    assert torch.all(fixed.drive_damping == 1.0)


def test_exact_step_holds_a_pose_and_reaches_a_target(model64):
    """No implicit drive damping is needed: the exact step is stable on the light wrist at 120 Hz."""
    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    drv = DroidArmDriver(model, DroidControlConfig(joint_physics="none"), 1)
    assert torch.all(drv.drive_damping == 0)
    q = torch.tensor([HOME], dtype=torch.float32)
    drv.reset(q)
    drv.set_target(q)
    tau = drv.torque(q, torch.zeros_like(q), 1 / 120)
    gravity = model.gravity_torque(q)
    assert torch.allclose(tau, gravity, atol=1e-3)  # at rest on target: gravity compensation only


@pytest.mark.parametrize("model_rate", ["path", "physics", "control"])
def test_numpy_fast_path_equals_batched_torch_law(model_rate):
    """The CPU few-env numpy path computes the same torques as the batched torch path."""
    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    q0 = torch.tensor([HOME], dtype=torch.float32)
    rng = np.random.default_rng(0)
    targets = [q0 + torch.tensor(rng.normal(0, 0.4 if i == 3 else 0.05, (1, 7)), dtype=torch.float32) for i in range(6)]
    outs = []
    for numpy_path in (True, False):
        drv = DroidArmDriver(model, DroidControlConfig(joint_physics="realm", model_rate=model_rate), 1)
        drv.allow_numpy = numpy_path
        assert drv.numpy_path() is numpy_path
        drv.reset(q0)
        res = []
        for k in range(48):
            if k % 8 == 0:
                drv.set_target(targets[k // 8])
            res.append(drv.torque(q0 + 0.002 * k, torch.full_like(q0, 0.1 * np.sin(k)), 1 / 120))
        outs.append(torch.cat(res))
    assert torch.allclose(outs[0], outs[1], atol=5e-3, rtol=1e-4), (outs[0] - outs[1]).abs().max()


def test_path_rate_matches_the_mujoco_reference_on_both_paths():
    """model_rate="path" (terms taken along the predicted path, one batched evaluation per action)
    replays the 1 kHz MuJoCo reference within 1 mrad RMS per joint on the CPU numpy path and on
    batched torch, as close as terms taken every step, with one plan per action in free motion."""
    pytest.importorskip("mujoco")
    from realm_ms.sysid.excite import ExciteConfig, excite
    from realm_ms.sysid.reference_mujoco import MujocoReference
    from realm_ms.sysid.replay import held_commands
    from realm_ms.sysid.simulator import ReplaySimulator, SimConfig

    duration, hz = 4.0, 120.0
    cmd15 = excite(1, 0, ExciteConfig(duration_s=duration, control_hz=15.0))[0]

    def replay(sim, rate):
        cmd = held_commands(np.arange(len(cmd15)) / 15.0, cmd15, int(round(duration * rate)), 1.0 / rate)[None]
        return sim.rollout(cmd15[:1], np.zeros((1, 7)), cmd, [])[0]

    ref = replay(MujocoReference(), 1000.0)
    t = np.arange(1, int(duration * 40)) / 40.0
    rms, plans = {}, {}
    for model_rate, numpy_path in (("path", True), ("path", False), ("physics", True)):
        sim = ReplaySimulator(SimConfig(physics_hz=hz))
        make, drivers = sim._driver, []

        def driver(n, act, model_rate=model_rate, numpy_path=numpy_path):
            d = make(n, act)
            d = DroidArmDriver(d.model, dataclasses.replace(d.config, model_rate=model_rate), n, "cpu", act)
            d.allow_numpy = numpy_path
            assert d.numpy_path() is numpy_path
            drivers.append(d)
            return d

        sim._driver = driver
        q = replay(sim, hz)
        err = q[np.round(t * hz).astype(int)] - ref[np.round(t * 1000).astype(int)]
        rms[model_rate, numpy_path] = np.sqrt((err**2).mean(0))
        last = drivers[-1]
        plans[model_rate, numpy_path] = (last.folded if numpy_path else last).rate.plans if model_rate == "path" else 0
    for key, r in rms.items():
        assert r.max() <= 1e-3, (key, r)
    assert np.abs(rms["path", True] - rms["physics", True]).max() < 1e-4, rms
    assert np.abs(rms["path", True] - rms["path", False]).max() < 2e-5, rms  # float64 numpy vs float32 torch
    actions = len(cmd15)
    for numpy_path in (True, False):  # a plan per action; re-plans off the path (here: torque saturation) are rare
        assert actions - 1 <= plans["path", numpy_path] <= 1.2 * actions, (plans, actions)


def test_path_plans_agree_across_backends_with_partial_replans():
    """Several envs, targets changing in some rows only and one arm pushed off its path: the batched
    torch plan and the numpy plan re-plan the same rows and give the same torques."""
    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    npm = model.numpy()
    b, dt = 3, 1 / 120
    q0 = np.repeat(np.array([HOME]), b, 0)
    outs = []
    for numpy_path in (True, False):
        drv = DroidArmDriver(model, DroidControlConfig(joint_physics="realm"), b)
        drv.allow_numpy = numpy_path
        drv.reset(torch.as_tensor(q0, dtype=torch.float32))
        arm = np.diag(drv.armature.double().numpy())
        q, qd, res = q0.copy(), np.zeros_like(q0), []
        target = q0.copy()
        for k in range(48):
            if k % 8 == 0:
                target[k // 8 % b] += 0.05  # one row's target changes per action
                drv.set_target(torch.as_tensor(target, dtype=torch.float32))
            tau = drv.torque(torch.as_tensor(q, dtype=torch.float32), torch.as_tensor(qd, dtype=torch.float32), dt).double().numpy()
            links = npm.links(npm.link_frames(q))
            bias, mass = npm.bias_at(links, qd), npm.mass_at(links)
            qd = qd + dt * np.linalg.solve(mass + arm, (tau - bias)[..., None])[..., 0]
            if k == 20:
                qd[1] += 0.5  # a push: row 1 leaves its predicted path
            q = q + dt * qd
            res.append(tau)
        outs.append(np.stack(res))
        plans = (drv.folded if numpy_path else drv).rate.plans
        assert plans > 48 // 8, plans  # partial re-plans happened
    assert np.abs(outs[0] - outs[1]).max() < 5e-3, np.abs(outs[0] - outs[1]).max()


@pytest.mark.parametrize("numpy_path", [True, False])
def test_an_arm_that_does_not_move_as_predicted_gets_at_most_the_motor_limit(numpy_path):
    """The exact step's torque may exceed the motor limit only while PhysX follows its prediction
    (free motion); an arm held in place (contact) after a large target step gets the clipped torque,
    as a real motor would give it, on both the numpy and the torch path."""
    from realm_ms.agents.control import FRANKA_EFFORT_LIMITS

    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    q0 = torch.tensor([HOME], dtype=torch.float32)
    drv = DroidArmDriver(model, DroidControlConfig(joint_physics="none"), 1)
    drv.allow_numpy = numpy_path
    drv.reset(q0)
    drv.set_target(q0 + 0.6)
    limits = torch.tensor(FRANKA_EFFORT_LIMITS)
    peak = torch.zeros(7)
    for _ in range(16):
        peak = torch.maximum(peak, drv.torque(q0, torch.zeros_like(q0), 1 / 120)[0].abs())
    assert (peak <= limits + 1e-3).all(), peak
    assert (peak >= limits - 1e-3).any(), "the step should saturate the motor"


def test_the_law_is_one_code_on_both_backends(model64):
    """``control/law.py`` is written once against an array backend: on float64 torch and on numpy
    it gives the same stiffness, damping, feed-forward, transition, gravity Jacobian and path plan."""
    from realm_ms.agents.control import law
    from realm_ms.agents.control.backend import NumpyBackend, TorchBackend
    from realm_ms.agents.control.presets import GAIN_PRESETS, BatchedGains

    cfg = DroidControlConfig()
    rng = np.random.default_rng(1)
    q, qd = np.asarray(HOME)[None] + rng.normal(0, 0.2, (3, 7)), rng.normal(0, 0.5, (3, 7))
    q_t, ext = q + rng.normal(0, 0.05, (3, 7)), rng.normal(0, 0.3, (3, 7))
    g64 = BatchedGains.from_gains(GAIN_PRESETS["polymetis"], 3, "cpu", torch.float64)
    out = {}
    for be, conv, gains in ((TorchBackend(model64), torch.as_tensor, g64),
                            (NumpyBackend(model64), np.asarray, g64.map(lambda g: g.numpy()))):
        arm = be.diag(conv(np.full(7, 0.1)))
        terms = law.terms_at(be, cfg, conv(q), conv(qd), gains, arm, None, 1 / 120)
        plan = law.plan_path(be, cfg, conv(q), conv(qd), conv(q_t), gains, arm, None, conv(ext), 1 / 120, 4)
        out[be.name] = {**{f"terms.{k}": v for k, v in terms.items()}, **{f"plan.{k}": v for k, v in plan.items()},
                        "dg": law.gravity_jacobian(be, cfg, conv(q))}
    assert out["torch"].keys() == out["numpy"].keys()
    for key, t in out["torch"].items():
        assert np.allclose(np.asarray(t), out["numpy"][key], rtol=1e-9, atol=1e-9), key
    assert np.abs(out["numpy"]["terms.phi"]).max() > 0.5 and np.abs(out["numpy"]["dg"]).max() > 1.0  # not trivially zero


def test_a_target_that_moves_at_every_step_gets_one_step_plans_exact_at_the_measured_state():
    """A command filter moves the tracked target at every physics step, so every plan is replaced
    after its first step: the plans are then one step long, and a plan's first step is the law at
    the measured state (model_rate="physics"). A target held for each action gets 8-step plans."""
    model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
    npm = model.numpy()
    b, dt = 3, 1 / 120
    q0 = np.repeat(np.array([HOME]), b, 0)

    def run(rate: str, target):
        drv = DroidArmDriver(model, DroidControlConfig(model_rate=rate), b)
        drv.allow_numpy = False
        drv.reset(torch.as_tensor(q0, dtype=torch.float32))
        arm = np.diag(drv.armature.double().numpy())
        q, qd, res, horizons = q0.copy(), np.zeros_like(q0), [], []
        for k in range(24):
            drv.set_target(torch.as_tensor(target(k), dtype=torch.float32))
            tau = drv.torque(torch.as_tensor(q, dtype=torch.float32), torch.as_tensor(qd, dtype=torch.float32), dt).double().numpy()
            links = npm.links(npm.link_frames(q))
            qd = qd + dt * np.linalg.solve(npm.mass_at(links) + arm, (tau - npm.bias_at(links, qd))[..., None])[..., 0]
            q = q + dt * qd
            res.append(tau)
            horizons.append(getattr(drv.rate, "horizon", None))
        return np.stack(res), horizons

    filtered = lambda k: q0 + 0.1 * (1 - np.exp(-k / 10))  # noqa: E731
    (path, horizons), (physics, _) = run("path", filtered), run("physics", filtered)
    assert horizons[0] == 8 and set(horizons[2:]) == {1}, horizons
    np.testing.assert_allclose(path, physics, rtol=1e-4, atol=1e-3)
    _, horizons = run("path", lambda k: q0 + 0.02 * (k // 8 + 1))  # held for each 8-step action
    assert set(horizons) == {8}, horizons
