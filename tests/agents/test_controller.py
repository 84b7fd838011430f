"""The Polymetis hybrid impedance controller inside REALM-PickApple-v1 (CPU sim)."""

import gymnasium as gym
import numpy as np
import pytest
import torch

import realm_ms  # noqa: F401
from realm_ms.agents.actuation import ActuationStage
from realm_ms.agents.control import FRANKA_EFFORT_LIMITS

STEP = torch.tensor([0.3, -0.3, 0.3, 0.3, 0.3, -0.3, 0.3])


def make(**kw):
    return gym.make("REALM-PickApple-v1", obs_mode="state", **kw)


def run(env, target_arm, steps, gripper=0.0):
    u = env.unwrapped
    a = torch.cat([target_arm, torch.tensor([gripper])])
    traj, torques = [], []
    arm = u.agent.arm_controller
    for _ in range(steps):
        env.step(a)
        traj.append(u.agent.arm_qpos[0].clone())
        torques.append(arm.driver.motor_torque[0].clone())
    return torch.stack(traj), torch.stack(torques)


@pytest.fixture(scope="module")
def env():
    e = make()
    yield e
    e.close()


def test_hold_pose_10s_drifts_less_than_1mrad(env):
    env.reset(seed=0)
    q0 = env.unwrapped.agent.arm_qpos[0].clone()
    traj, _ = run(env, q0, 150)  # 10 s at 15 Hz
    drift = (traj - q0).abs().max(dim=0).values
    assert (drift < 1e-3).all(), f"drift per joint (rad): {drift}"


def _check_step_response(env):
    env.reset(seed=0)
    q0 = env.unwrapped.agent.arm_qpos[0].clone()
    target = q0 + STEP
    traj, torques = run(env, target, 45)  # 3 s
    err = (traj - target).abs()
    late, mid = err[30:].max(dim=0).values, err[15:30].max(dim=0).values
    assert (late <= mid + 1e-4).all(), f"oscillation grows: 1-2 s {mid}, 2-3 s {late}"
    assert (err[-1] < 5e-3).all(), f"not settled after 3 s: {err[-1]}"
    overshoot = ((traj - q0) / STEP).max(dim=0).values - 1
    assert (overshoot < 0.5).all(), f"overshoot fraction {overshoot}"
    return torques


def test_step_settles_without_growing_oscillation(env):
    _check_step_response(env)


def test_torques_respect_franka_limits(env):
    env.reset(seed=0)
    q0 = env.unwrapped.agent.arm_qpos[0].clone()
    _, torques = run(env, q0 + 1.2 * STEP.sign(), 20)  # large step: saturates
    limits = torch.tensor(FRANKA_EFFORT_LIMITS)
    peak = torques.abs().max(dim=0).values
    assert (peak <= limits + 1e-4).all(), peak
    assert (peak[4:] > 0.99 * limits[4:]).any(), "the large step should saturate a wrist joint"


def test_stable_at_480hz():
    e = make(sim_config=dict(sim_freq=480, control_freq=15))
    try:
        assert e.unwrapped.agent.arm_controller._sim_steps == 32
        e.reset(seed=0)
        q0 = e.unwrapped.agent.arm_qpos[0].clone()
        traj, _ = run(e, q0, 45)
        assert ((traj - q0).abs().max() < 1e-3)
        _check_step_response(e)
    finally:
        e.close()


class ConstantTorque(ActuationStage):
    def __init__(self, tau):
        self.tau = tau

    def plant_torque(self, state):
        return self.tau.expand_as(state.q)


def test_actuation_stage_offset_matches_impedance_law(env):
    """A constant external torque tau must leave a static error K_p(q)^-1 tau: the stage hook and
    the Cartesian+joint stiffness of the law, checked together."""
    u = env.unwrapped
    env.reset(seed=0)
    arm = u.agent.arm_controller
    tau = torch.tensor([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5])
    arm.actuation.stages = [ConstantTorque(tau)]
    try:
        q0 = u.agent.arm_qpos[0].clone()
        traj, _ = run(env, q0, 30)
        offset = traj[-1] - q0
        g = arm.driver.gains
        jac = arm.driver.model.jacobian(q0[None])
        jt = jac.transpose(1, 2)
        kp = torch.diag_embed(g.kq) + jt @ (g.kx[..., None] * jac)
        predicted = torch.linalg.solve(kp[0], tau)
        assert torch.allclose(offset, predicted, atol=0.15 * predicted.abs().max()), (offset, predicted)
    finally:
        arm.actuation.stages = []


def test_explicit_damping_alone_is_unstable_at_120hz():
    """Why the diagonal damping rides on PhysX's implicit drive: the purely explicit law blows up."""
    e = make(droid_control=dict(integrator="explicit"))
    e.reset(seed=0)
    q0 = e.unwrapped.agent.arm_qpos[0].clone()
    traj, _ = run(e, q0 + STEP, 45)
    assert (traj - (q0 + STEP)).abs()[-15:].max() > 0.05
    e.close()


def test_control_rate_model_refresh_stays_close_to_exact_law():
    """model_rate="control" (J, C, g refreshed at 15 Hz, gravity first order) tracks the exact law
    to a few mrad on smooth DROID-like motion (0.6 rad/s); on instantaneous 0.3 rad steps the gap is ~2.5e-2 rad."""
    trajs = []
    for rate in ("physics", "control"):
        e = make(droid_control=dict(model_rate=rate))
        e.reset(seed=0)
        u = e.unwrapped
        q0 = u.agent.arm_qpos[0].clone()
        traj = []
        for k in range(45):
            target = q0 + STEP * torch.sin(torch.tensor(k / 15 * 2.0))  # 3 s of smooth motion
            e.step(torch.cat([target, torch.zeros(1)]))
            traj.append(u.agent.arm_qpos[0].clone())
        trajs.append(torch.stack(traj))
        e.close()
    assert (trajs[0] - trajs[1]).abs().max() < 6e-3  # measured 4.8e-3 rad


def test_gain_presets_change_the_loop():
    from realm_ms.agents.control import GAIN_PRESETS

    e = make(droid_control=dict(gains="realm"))
    g = e.unwrapped.agent.arm_controller.driver.gains
    assert g.kq[0, 3].item() == GAIN_PRESETS["realm"].kq[3] == 35
    assert g.kx[0, 0].item() == 400
    e.close()
    with pytest.raises(ValueError, match="unknown gain preset"):
        make(droid_control=dict(gains="nope"))


def test_per_joint_settings_of_the_wrong_length_are_one_line():
    """`droid_control={"effort_limits": [87, 87, 87]}` used to end in numpy's broadcast message."""
    import pytest

    from realm_ms.agents.control import DroidControlConfig, ImpedanceGains
    from realm_ms.tasks import RealmEnvConfig

    with pytest.raises(ValueError, match=r"droid_control\.effort_limits: expected 7 finite numbers \(one per joint\), got 3"):
        RealmEnvConfig.from_kwargs(None, {"droid_control": {"effort_limits": [87, 87, 87]}})
    with pytest.raises(ValueError, match=r"droid_control\.reference_qpos: expected 7"):
        DroidControlConfig(reference_qpos=(0.0, 0.0))
    with pytest.raises(ValueError, match=r"gains\.kx: expected 6 finite numbers \(one per axis\), got 7"):
        ImpedanceGains((40,) * 7, (4,) * 7, (750,) * 7, (37,) * 6)
    with pytest.raises(ValueError, match=r"droid_control\.drive_damping: expected a list of 7 numbers"):
        DroidControlConfig(drive_damping=[1, 2, "x"])
    assert DroidControlConfig(effort_limits=[87.0] * 7).effort_limits == [87.0] * 7


def test_custom_gains_and_joint_physics_as_mappings():
    """A mapping for `gains` / `joint_physics` names the fields it lacks; a scalar field stays a scalar."""
    import pytest

    from realm_ms.tasks.config import _control_fields

    jp = _control_fields({"joint_physics": {"friction": [0.1] * 7, "armature": [0.0] * 7, "friction_velocity": 0.05}})
    assert jp["joint_physics"].friction_velocity == 0.05 and jp["joint_physics"].friction == (0.1,) * 7
    with pytest.raises(ValueError, match=r"droid_control\.joint_physics: expected the fields friction, armature "
                                         r"\(optional: friction_velocity\), got \['friction'\]"):
        _control_fields({"joint_physics": {"friction": [0.1] * 7}})
