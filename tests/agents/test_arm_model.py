"""The robot's own model (batched RNEA/FK/Jacobian) against PhysX's articulation."""

import numpy as np
import pytest
import sapien
import torch

from realm_ms.agents.arm_model import ArmModel
from realm_ms.agents.urdf import panda_droid_urdf_path


@pytest.fixture(scope="module")
def setup():
    urdf = str(panda_droid_urdf_path())
    scene = sapien.Scene()
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    robot = loader.load(urdf)
    names = [j.name for j in robot.get_active_joints()]
    arm = [names.index(f"panda_joint{i}") for i in range(1, 8)]
    model = ArmModel.from_urdf(urdf, "panda_link0", "panda_link8", dtype=torch.float64)
    return robot, arm, model, scene  # keep the scene alive


def _random_state(robot, arm, rng):
    q = np.zeros(robot.dof)
    lo, hi = robot.get_qlimits()[arm].T
    q[arm] = lo + (hi - lo) * rng.uniform(0.1, 0.9, 7)
    qd = np.zeros(robot.dof)
    qd[arm] = rng.uniform(-1.5, 1.5, 7)
    robot.set_qpos(q)
    robot.set_qvel(qd)
    return q, qd


def test_gravity_and_coriolis_match_physx(setup):
    robot, arm, model, _ = setup
    rng = np.random.default_rng(0)
    for _ in range(5):
        q, qd = _random_state(robot, arm, rng)
        # SAPIEN returns the generalized force that balances gravity / Coriolis, i.e. g(q) and C(q, qd) qd
        g_px = robot.compute_passive_force(gravity=True, coriolis_and_centrifugal=False)[arm]
        c_px = robot.compute_passive_force(gravity=False, coriolis_and_centrifugal=True)[arm]
        qt, qdt = torch.tensor(q[arm])[None], torch.tensor(qd[arm])[None]
        np.testing.assert_allclose(model.gravity_torque(qt)[0].numpy(), g_px, atol=2e-3)
        np.testing.assert_allclose(model.coriolis_torque(qt, qdt)[0].numpy(), c_px, atol=2e-3)


def test_batched_equals_single(setup):
    _, _, model, _ = setup
    q = torch.rand(4, 7, dtype=torch.float64)
    qd = torch.rand(4, 7, dtype=torch.float64)
    batched = model.bias_torque(q, qd)
    single = torch.cat([model.bias_torque(q[i : i + 1], qd[i : i + 1]) for i in range(4)])
    torch.testing.assert_close(batched, single)


def test_fk_matches_physx_link_pose(setup):
    robot, arm, model, _ = setup
    rng = np.random.default_rng(1)
    pin = robot.create_pinocchio_model()
    link = [l.name for l in robot.get_links()].index("panda_link8")
    for _ in range(3):
        q, _ = _random_state(robot, arm, rng)
        pin.compute_forward_kinematics(q)
        pose = pin.get_link_pose(link)
        t = model.fk(torch.tensor(q[arm])[None])[0].numpy()
        np.testing.assert_allclose(t[:3, 3], pose.p, atol=1e-5)
        np.testing.assert_allclose(t[:3, :3], pose.to_transformation_matrix()[:3, :3], atol=1e-5)


def test_jacobian_is_derivative_of_fk(setup):
    _, _, model, _ = setup
    q = torch.tensor([[0.1, -0.5, 0.2, -2.0, 0.3, 1.6, 0.4]], dtype=torch.float64)
    jac = model.jacobian(q)[0]
    eps = 1e-6
    for i in range(7):
        dq = torch.zeros_like(q)
        dq[0, i] = eps
        dp = (model.fk(q + dq)[0, :3, 3] - model.fk(q - dq)[0, :3, 3]) / (2 * eps)
        torch.testing.assert_close(jac[:3, i], dp, atol=1e-6, rtol=1e-5)


def test_mass_matrix_is_spd_and_consistent_with_rnea(setup):
    _, _, model, _ = setup
    q = torch.tensor([[0.3, -0.2, 0.1, -1.8, 0.2, 1.4, -0.3]], dtype=torch.float64)
    m = model.mass_matrix(q)[0]
    torch.testing.assert_close(m, m.T)
    assert torch.linalg.eigvalsh(m).min() > 0
    qdd = torch.tensor([[0.5, -1.0, 0.3, 0.2, -0.7, 1.1, 0.9]], dtype=torch.float64)
    tau = model.rnea(q, torch.zeros_like(q), qdd, gravity=False)[0]
    torch.testing.assert_close(tau, m @ qdd[0])
