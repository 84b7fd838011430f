"""Physically consistent inertial parameters (``realm_ms/agents/effects/inertial.py``): the
parametrisations of ``link_mass`` and ``payload`` stay physical everywhere in bounds, and the
body regressor is the arm's inverse dynamics (and MuJoCo's)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from realm_ms.agents.effects import inertial, make_effect
from realm_ms.agents.effects.link_mass import corrected
from realm_ms.agents.effects.payload import payload_pi


def _arm():
    from realm_ms.sysid.torque.residual import torque_arm

    return torque_arm()


def _uniform(fx, n: int, rng) -> np.ndarray:
    lo = np.array([p.spec.lo for p in fx.params])
    hi = np.array([p.spec.hi for p in fx.params])
    u = rng.uniform(size=(n, len(lo)))
    u[: n // 4] = np.round(u[: n // 4])  # corners of the box too
    return lo + u * (hi - lo)


def test_link_coordinates_are_physical_everywhere_in_bounds():
    """Random points (and box corners) of all 70 link coordinates: positive mass, symmetric
    positive-definite inertia, triangle inequalities, on every link; the off-point is the URDF."""
    arm = _arm()
    fx = make_effect("link_mass", None, {"fit_com": True, "fit_inertia": True})
    assert len(fx.free_params) == 70
    x = _uniform(fx, 400, np.random.default_rng(0))
    fx.set_theta(x)
    v = fx.coords().to(torch.float64)  # (B, 7, 10)
    for k in range(7):
        m, c, i = corrected(arm.masses[k], arm.coms[k], arm.inertias[k], v[:, k])
        ok = inertial.is_physical(m, i)
        assert bool(ok.all()), (k, x[~ok.numpy()][:2])
        s = torch.linalg.eigvalsh(inertial.second_moment(i))
        assert float(s.min()) > 0  # strictly inside: a real mass distribution with volume
    m, c, i = corrected(arm.masses[3], arm.coms[3], arm.inertias[3], torch.zeros(10, dtype=torch.float64))
    assert float(m) == pytest.approx(float(arm.masses[3]))
    np.testing.assert_allclose(i.numpy(), arm.inertias[3].numpy(), atol=1e-12)


def test_the_raw_standard_parameters_would_not_be_physical():
    """Why the coordinates: uniform points of the standard parameters' own box around a link are
    mostly no rigid body (the triangle inequalities fail), so fitting them directly is not safe."""
    arm = _arm()
    pi0 = inertial.standard(arm.masses[3], arm.coms[3], arm.inertias[3])
    rng = np.random.default_rng(1)
    bad = 0
    for _ in range(200):
        pi = pi0 * torch.as_tensor(1 + rng.uniform(-0.5, 0.5, 10))
        m, h, io = pi[0], pi[1:4], torch.zeros(3, 3, dtype=torch.float64)
        for n, (a, b) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
            io[a, b] = io[b, a] = pi[4 + n]
        c = h / m
        ic = io - m * (c.dot(c) * torch.eye(3, dtype=torch.float64) - torch.outer(c, c))
        bad += not bool(inertial.is_physical(m, ic))
    assert bad > 50


def test_payload_is_physical_everywhere_in_bounds():
    fx = make_effect("payload", None, {"fit_inertia": True})
    assert {"gyr_x", "gyr_y", "gyr_z"} <= {p.local_key for p in fx.free_params}
    x = _uniform(fx, 300, np.random.default_rng(2))
    x[:, 0] = np.maximum(x[:, 0], 1e-3)  # mass 0 is "no payload"
    fx.set_theta(x)
    t = torch.as_tensor(x, dtype=torch.float64)
    gyr = t[:, 4:7]
    sigma = torch.diag_embed(t[:, :1] * gyr**2)
    i = inertial.inertia_of(sigma)
    tri = torch.linalg.eigvalsh(inertial.second_moment(i)).amin(-1)
    assert bool((tri >= -1e-15).all()) and bool((torch.linalg.eigvalsh(i).amin(-1) >= 0).all())
    # the standard parameters it adds to body 7 are those of the same body moved rigidly
    arm = _arm()
    pi = payload_pi(t[:, 0], t[:, 1:4], gyr, arm.tip_offset.to(torch.float64))
    assert torch.allclose(pi[:, 0], t[:, 0])


def test_regressor_is_the_arm_inverse_dynamics_and_mass_matrix():
    """Y_k pi_k equals ArmModel.rnea with only link k massive; the body mass matrix equals the
    unit-acceleration RNEA's."""
    arm = _arm()
    g = torch.Generator().manual_seed(0)
    q, qd, qdd = (torch.randn(16, 7, dtype=torch.float64, generator=g) for _ in range(3))
    masses, inertias = arm.masses.clone(), arm.inertias.clone()
    for k in range(7):
        keep = torch.zeros_like(masses)
        keep[k] = 1.0
        arm.masses, arm.inertias = masses * keep, inertias * keep[:, None, None]
        try:
            ref, m_ref = arm.rnea(q, qd, qdd), arm.mass_matrix_rnea(q)
        finally:
            arm.masses, arm.inertias = masses, inertias
        pi = inertial.standard(masses[k], arm.coms[k], inertias[k])
        y = inertial.regressor(arm, q, qd, qdd, k)
        np.testing.assert_allclose((y @ pi).numpy(), ref.numpy(), atol=1e-10)
        np.testing.assert_allclose(inertial.body_mass_matrix(arm, q, k, pi[None]).numpy(), m_ref.numpy(), atol=1e-10)


def test_link_term_matches_mujoco_for_any_mass_com_and_shape():
    """The torque-space link term against MuJoCo's inverse dynamics of the locked arm whose link
    4 and 6 inertials were replaced through the MuJoCo build target (mass, CoM and a sheared,
    stretched inertia): the regressor, the coordinates and the build target's principal-axes
    conversion agree."""
    pytest.importorskip("mujoco")
    from realm_ms.sysid.locked_urdf import flange_offset_in_link7
    from realm_ms.sysid.reference_mujoco import MujocoBuildTarget, MujocoConfig, build_model, inverse_dynamics
    from realm_ms.sysid.torque.terms import Samples, link_mass

    values = {"s4": 0.3, "dcx4": 0.04, "dcy4": -0.03, "dcz4": 0.01, "ax4": 0.4, "ay4": -0.3, "az4": 0.2,
              "shxy4": 0.3, "shxz4": -0.2, "shyz4": 0.4, "s6": -0.4, "dcz6": 0.05, "shxy6": -0.5}
    fx = make_effect("link_mass", values, {"fit_com": True, "fit_inertia": True})
    cfg = MujocoConfig()
    nominal, changed = build_model(cfg), build_model(cfg)
    tgt = MujocoBuildTarget(changed, flange_offset_in_link7())
    fx.build_target(tgt, 0)
    arm = _arm()
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = np.array([0, -0.6, 0, -2.4, 0, 1.9, 0]) + rng.normal(0, 0.3, 7)
        qd, qdd = rng.normal(0, 0.5, 7), rng.normal(0, 3, 7)
        tau = [inverse_dynamics(m, q, qd, qdd) for m in (changed, nominal)]
        t = lambda x: torch.as_tensor(x)[None]  # noqa: E731
        ours = link_mass(values, Samples(t(q), t(qd), t(qdd), arm), fx.config)
        np.testing.assert_allclose(ours.numpy()[0], tau[0] - tau[1], atol=2e-3)
    tgt.reset()
    np.testing.assert_allclose(changed.body_mass, nominal.body_mass)
