"""DROID's action spaces: each conversion against DROID's own formulas (robot_ik_solver.py,
transformations.py, FrankaRobot.create_action_dict), the IK's behaviour, the env wiring, the expert."""

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation as R

from realm_ms.agents import droid_action_spaces as das
from realm_ms.agents.droid_action_spaces import DroidIK, make_action_space, parse_action_space_flag

RNG = np.random.default_rng(0)
RESET_Q = np.array([0, -np.pi / 5, 0, -4 * np.pi / 5, 0, 3 * np.pi / 5, 0.0])


# ---- DROID's code, transcribed one vector at a time (droid/robot_ik/robot_ik_solver.py) ----------
def droid_joint_velocity_to_delta(joint_velocity):
    relative_max_joint_vel = np.array([0.2] * 7) / 0.2
    max_joint_vel_norm = (np.abs(joint_velocity) / relative_max_joint_vel).max()
    if max_joint_vel_norm > 1:
        joint_velocity = joint_velocity / max_joint_vel_norm
    return joint_velocity * 0.2


def droid_cartesian_velocity_to_delta(v):
    lin, rot = v[:3], v[3:6]
    if np.linalg.norm(lin) > 1:
        lin = lin / np.linalg.norm(lin)
    if np.linalg.norm(rot) > 1:
        rot = rot / np.linalg.norm(rot)
    return np.concatenate([lin * 0.075, rot * 0.15])


def droid_gripper_velocity_to_delta(v):
    n = np.linalg.norm(v)
    if n > 1:
        v = v / n
    return v * 0.25


def droid_add_poses(delta, source):  # droid/misc/transformations.py
    rot = R.from_euler("xyz", delta[3:6]) * R.from_euler("xyz", source[3:6])
    return np.concatenate([np.array(delta[:3]) + np.array(source[:3]), rot.as_euler("xyz")])


def droid_pose_diff(target, source):
    rot = R.from_euler("xyz", target[3:6]) * R.from_euler("xyz", source[3:6]).inv()
    return np.concatenate([np.array(target[:3]) - np.array(source[:3]), rot.as_euler("xyz")])


def _random_q(n):
    lo, hi = das.Q_LIMITS[:, 0] + 0.5, das.Q_LIMITS[:, 1] - 0.5
    return RESET_Q + RNG.uniform(-0.4, 0.4, (n, 7)).clip(lo - RESET_Q, hi - RESET_Q)


# ---- formulas ------------------------------------------------------------------------------------
def test_joint_velocity_rescales_the_whole_vector_like_droid():
    v = RNG.uniform(-3, 3, (200, 7))
    v[:50] *= 0.3  # some rows already inside [-1, 1]
    ours = das.joint_velocity_to_delta(v)
    ref = np.stack([droid_joint_velocity_to_delta(x) for x in v])
    assert np.allclose(ours, ref, atol=1e-12)
    assert np.abs(ours).max() <= 0.2 + 1e-12
    big = np.abs(v).max(1) > 1  # direction kept: parallel to v
    cos = (ours[big] * v[big]).sum(1) / np.linalg.norm(ours[big], axis=1) / np.linalg.norm(v[big], axis=1)
    assert np.allclose(cos, 1.0)


def test_cartesian_velocity_rescales_linear_and_angular_norms_separately():
    v = RNG.uniform(-2, 2, (200, 6))
    ours = das.cartesian_velocity_to_delta(v)
    assert np.allclose(ours, np.stack([droid_cartesian_velocity_to_delta(x) for x in v]), atol=1e-12)
    assert np.linalg.norm(ours[:, :3], axis=1).max() <= 0.075 + 1e-12
    assert np.linalg.norm(ours[:, 3:], axis=1).max() <= 0.15 + 1e-12


def test_gripper_spaces_follow_create_action_dict():
    g = RNG.uniform(0, 1, 100)
    v = RNG.uniform(-3, 3, 100)
    sp = make_action_space("joint_velocity", "velocity")
    out = sp.to_joint_target(np.concatenate([np.zeros((100, 7)), v[:, None]], 1), np.tile(RESET_Q, (100, 1)), g)
    ref = np.clip(g + np.array([droid_gripper_velocity_to_delta(x) for x in v]), 0, 1)
    assert np.allclose(out[:, 7], ref)
    pos = make_action_space("joint_velocity", "position")
    out = pos.to_joint_target(np.concatenate([np.zeros((100, 7)), v[:, None]], 1), np.tile(RESET_Q, (100, 1)), g)
    assert np.allclose(out[:, 7], np.clip(v, 0, 1))


def test_droid_default_gripper_space_and_names():
    assert make_action_space("joint_velocity").gripper == "velocity"
    assert make_action_space("cartesian_velocity").gripper == "velocity"
    assert make_action_space("cartesian_position").gripper == "position"
    assert make_action_space("joint_position").gripper == "position"
    assert parse_action_space_flag("joint_velocity:position") == {"action_space": "joint_velocity", "gripper_action_space": "position"}
    assert parse_action_space_flag("joint_position") == {} and parse_action_space_flag(None) == {}
    with pytest.raises(ValueError, match="known: joint_position"):
        parse_action_space_flag("eef_delta")
    with pytest.raises(ValueError, match="gripper_action_space"):
        parse_action_space_flag("joint_velocity:torque")


def test_pose_algebra_matches_droid_transformations():
    src = np.concatenate([RNG.uniform(-1, 1, (50, 3)), RNG.uniform(-np.pi, np.pi, (50, 3))], 1)
    dlt = np.concatenate([RNG.uniform(-0.1, 0.1, (50, 3)), RNG.uniform(-0.3, 0.3, (50, 3))], 1)
    added = das.add_poses(dlt, src)
    assert np.allclose(added, np.stack([droid_add_poses(d, s) for d, s in zip(dlt, src)]))
    diff = das.pose_diff(added, src)
    assert np.allclose(diff, np.stack([droid_pose_diff(a, s) for a, s in zip(added, src)]))
    assert np.allclose(diff, dlt, atol=1e-9)  # pose_diff inverts add_poses


def test_joint_velocity_target_and_inverse():
    q = _random_q(30)
    v = RNG.uniform(-1.5, 1.5, (30, 7))
    sp = make_action_space("joint_velocity", "position")
    t = sp.to_joint_target(np.concatenate([v, np.ones((30, 1))], 1), q, np.zeros(30))
    assert np.allclose(t[:, :7], q + np.stack([droid_joint_velocity_to_delta(x) for x in v]))
    back = sp.from_joint_target(t, q, np.zeros(30))
    assert np.allclose(sp.to_joint_target(back, q, np.zeros(30)), t)


# ---- IK --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def ik():
    return DroidIK()


def test_ik_step_realises_small_cartesian_deltas(ik):
    q = _random_q(20)
    delta = np.concatenate([RNG.uniform(-0.01, 0.01, (20, 3)), RNG.uniform(-0.02, 0.02, (20, 3))], 1)
    dq = ik.cartesian_delta_to_joint_delta(delta, q)
    assert np.abs(dq).max() <= 0.2 + 1e-9  # DROID's joint_velocity_limits
    jac = ik.jacobian(q)
    realised = np.einsum("bij,bj->bi", jac, dq)
    # damped (1e-2) least squares: the realised twist follows the command to a few per cent
    assert np.abs(realised - delta).max() < 0.1 * np.abs(delta).max()


def test_cartesian_position_round_trip_reaches_the_pose(ik):
    """Tracking each joint target exactly, a reachable pose (<= one step away) is reached within
    1 mm / 0.01 rad after a few control steps: DROID's IK is one linearised step per action."""
    sp = make_action_space("cartesian_position")
    q0 = _random_q(10)
    q_goal = q0 + RNG.uniform(-0.1, 0.1, q0.shape)  # a pose that a joint config reaches
    goal = ik.pose(q_goal)
    q = q0.copy()
    for _ in range(8):
        q = sp.to_joint_target(np.concatenate([goal, np.zeros((10, 1))], 1), q, np.zeros(10), ik)[:, :7]
    err = das.pose_diff(goal, ik.pose(q))
    assert np.linalg.norm(err[:, :3], axis=1).max() < 1e-3
    assert np.linalg.norm(err[:, 3:], axis=1).max() < 1e-2


def test_cartesian_velocity_moves_at_most_droids_step(ik):
    sp = make_action_space("cartesian_velocity", "position")
    q = _random_q(10)
    v = np.concatenate([RNG.uniform(-5, 5, (10, 6)), np.zeros((10, 1))], 1)  # far beyond the unit ball
    t = sp.to_joint_target(v, q, np.zeros(10), ik)
    moved = ik.pose(t[:, :7])[:, :3] - ik.pose(q)[:, :3]
    assert np.linalg.norm(moved, axis=1).max() < 0.075 * 1.1
    assert np.abs(t[:, :7] - q).max() <= 0.2 + 1e-9


def test_joint_limit_margin_and_nullspace(ik):
    q = RESET_Q.copy()
    # 5 mrad outside the 0.3 rad margin: the limit constraint (integrated over dt = 1/15, as DROID
    # configures it) allows 0.95 * 0.005 * 15 rad toward it, below the 0.2 velocity limit
    q[0] = das.Q_LIMITS[0, 1] - 0.305
    lo, hi = ik.bounds(q)
    assert hi[0] == pytest.approx(0.95 * 0.005 * 15) and lo[0] == -0.2
    # deep inside the margin: no motion further toward the limit, free to move away from it
    # (dm_robotics sets the bound toward the limit to 0, never a push away; the arm is never stuck)
    q[0] = das.Q_LIMITS[0, 1] - 0.1
    lo, hi = ik.bounds(q)
    assert hi[0] == 0 and lo[0] == -0.2
    dq = ik.cartesian_delta_to_joint_delta(np.full((1, 6), 0.01), q[None])[0]
    assert dq[0] <= 1e-12 and np.abs(dq).max() > 1e-4
    # zero command: only self-motion toward q = 0 (nullspace_gain), the flange stays put; the bias
    # is clipped to the joint bounds first (dm_robotics' mapper), so the step is toward the clipped bias
    q = _random_q(5)
    dq = ik.cartesian_delta_to_joint_delta(np.zeros((5, 6)), q)
    assert np.abs(dq).max() > 1e-3
    assert np.abs(np.einsum("bij,bj->bi", ik.jacobian(q), dq)).max() < 1e-6
    bias = np.stack([np.clip(das.NULLSPACE_GAIN * -qi * das.CONTROL_HZ, *ik.bounds(qi)) for qi in q])
    assert np.all(np.einsum("bj,bj->b", dq, bias) > 0)


# ---- env wiring --------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def envs():
    import gymnasium as gym

    import realm_ms  # noqa: F401

    made = {}
    for sp in ("joint_position", "joint_velocity", "cartesian_position"):
        made[sp] = gym.make("REALM-PickApple-v1", obs_mode="state", action_space=sp)
        made[sp].reset(seed=0)
    yield made
    for e in made.values():
        e.close()


def test_env_action_space_bounds(envs):
    assert envs["joint_position"].unwrapped.droid_actions is None  # the droid_joint_pos path, untouched
    assert envs["joint_position"].action_space.shape == (8,)
    jv = envs["joint_velocity"].action_space
    assert jv.shape == (8,) and np.all(jv.low == -1) and np.all(jv.high == 1)  # DROID default: gripper velocity
    cp = envs["cartesian_position"].action_space
    assert cp.shape == (7,) and cp.low[-1] == 0 and cp.high[-1] == 1
    assert envs["joint_velocity"].unwrapped.config.to_dict()["action_space"] == "joint_velocity"


def test_env_converts_before_the_controller(envs):
    u = envs["joint_velocity"].unwrapped
    q = u.agent.arm_qpos[0].double().numpy()
    g = float(u.agent.gripper_position[0])
    v = np.array([2.0, -1.0, 0.5, 0, 0, 0, 0, 4.0], np.float32)  # beyond [-1, 1]: rescaled, not clipped
    t = u._checked_action(torch.as_tensor(v))[0].double().numpy()
    assert np.allclose(t[:7], q + droid_joint_velocity_to_delta(v[:7].astype(np.float64)), atol=1e-5)
    assert t[7] == pytest.approx(min(1.0, g + 0.25), abs=1e-5)
    with pytest.raises(ValueError, match="shape"):
        u._checked_action(torch.zeros(7))


def test_bad_action_space_is_a_clear_error():
    import gymnasium as gym

    import realm_ms  # noqa: F401

    with pytest.raises(ValueError, match="unknown action_space 'delta'"):
        gym.make("REALM-PickApple-v1", obs_mode="state", action_space="delta")


def test_expert_drives_cartesian_position(envs):
    """The expert converted to absolute flange poses still picks the apple (the full table per
    space: bench/expert_success.py --action-space)."""
    from realm_ms.expert.core import run_episode

    res = run_episode(envs["cartesian_position"], seed=0, max_steps=200)
    assert res["success"], res


def test_eval_flag_reaches_the_env_keywords_with_clear_errors():
    from realm_ms.errors import UserError
    from realm_ms.eval.policies import make_policy, policy_action_space

    zero = make_policy("zero")
    assert policy_action_space(zero, {"action_space": "cartesian_velocity:position"}) == {
        "action_space": "cartesian_velocity", "gripper_action_space": "position"}
    assert policy_action_space(zero, {}) == {}
    with pytest.raises(UserError, match="--action-space: unknown action_space 'nope'"):
        policy_action_space(zero, {"action_space": "nope"})


@pytest.mark.parametrize("kw", [dict(action_space="joint_velocity", control_mode="pd_joint_delta_pos"),
                                dict(action_space="cartesian_position", control_mode="pd_ee_delta_pose"),
                                dict(gripper_action_space="velocity", control_mode="pd_joint_pos")])
def test_droid_spaces_need_the_droid_controller(kw):
    """A zero joint velocity under pd_joint_delta_pos used to move the arm 3 cm: refused before the scene is built."""
    import gymnasium as gym

    import realm_ms  # noqa: F401
    from realm_ms.tasks import RealmEnvConfig

    with pytest.raises(ValueError, match=r"is DROID's and needs control_mode='droid_joint_pos' \(got 'pd_"):
        gym.make("REALM-PickApple-v1", obs_mode="state", **kw)
    with pytest.raises(ValueError, match="needs control_mode='droid_joint_pos'"):
        RealmEnvConfig(task="REALM-PickApple-v1", **kw)
    RealmEnvConfig(task="REALM-PickApple-v1", control_mode=kw["control_mode"])  # joint_position: ManiSkill's modes stay open


def _joint_path(env, chunk) -> float:
    u = env.unwrapped
    q0 = u.agent.arm_qpos[0].double().numpy().copy()
    path, q = 0.0, q0
    for a in chunk:
        env.step(torch.as_tensor(a))
        q1 = u.agent.arm_qpos[0].double().numpy()
        path, q = path + float(np.abs(q1 - q).sum()), q1.copy()
    return path


@pytest.mark.parametrize("space", ["joint_velocity", "cartesian_position"])
def test_baselines_act_in_the_env_space(envs, space):
    """`realm eval --policy zero --action-space joint_velocity:position` used to read the absolute
    targets as velocities (0.74 rad of joint path in 8 steps): the baselines emit the env's space."""
    from realm_ms.eval.policies import PolicyInput, make_policy

    env = envs[space]
    env.reset(seed=0)
    sp = env.unwrapped.droid_action_space
    lo, hi = sp.bounds()

    def chunk(name, **kw):
        state = env.unwrapped.agent.droid_state().double().numpy().astype(np.float32)
        out = make_policy(name, action_space=f"{sp.action_space}:{sp.gripper}", **kw).act(PolicyInput(state, ["x"]))
        assert out.actions.shape == (1, 8, sp.dim)
        assert np.all(out.actions >= lo - 1e-6) and np.all(out.actions <= hi + 1e-6)
        return out.actions[0]

    zero = chunk("zero")
    if space == "joint_velocity":
        assert np.all(zero == 0)  # zero motion: zero velocities, gripper velocity 0
    assert _joint_path(env, zero) < 0.03  # the bug: 0.74 rad
    env.reset(seed=0)
    q0 = env.unwrapped.agent.arm_qpos[0].double().numpy().copy()
    walk = chunk("random", seed=3)
    ref = make_policy("random", seed=3).act(PolicyInput(np.concatenate([q0, [0.0]])[None].astype(np.float32), ["x"])).actions[0]
    _joint_path(env, walk)  # the same random walk of targets, asked for in this space
    q8 = env.unwrapped.agent.arm_qpos[0].double().numpy()
    assert np.abs(q8 - ref[-1, :7]).max() < 0.06, (q8, ref[-1, :7])
    with pytest.raises(ValueError, match="--action-space: unknown action_space 'joint_vel'"):
        make_policy("zero", action_space="joint_vel")


def test_a_finite_huge_action_is_outside_the_space_not_nan(envs):
    """1e39 is finite: it used to be refused as "NaN or Inf" (it overflows float32)."""
    import warnings

    u = envs["joint_position"].unwrapped
    a = np.array([1e39, -0.6, 0.0, -2.4, 0.0, 1.9, 0.0, 0.0])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t = u._checked_action(a)
    assert float(t.reshape(-1)[0]) == pytest.approx(2.8973, abs=1e-4) and t.dtype == torch.float32
    assert any("outside the action space" in str(w.message) for w in caught) or "0" in u._action_warned
    v = envs["joint_velocity"].unwrapped
    q = v.agent.arm_qpos[0].double().numpy()
    t = v._checked_action(np.array([1e39, 0, 0, 0, 0, 0, 0, 0.0]))[0].double().numpy()
    assert t[0] == pytest.approx(min(q[0] + 0.2, 2.8973), abs=1e-5) and np.allclose(t[1:7], q[1:7], atol=1e-5)
    with pytest.raises(ValueError, match="NaN or Inf"):
        u._checked_action(np.array([np.inf, 0, 0, 0, 0, 0, 0, 0.0]))
