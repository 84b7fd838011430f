"""The payload effect with its centre of mass (position space, PhysX replay)."""

from __future__ import annotations

import numpy as np

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
    theta = np.array([[0.8, 0.0, 0.0, 0.15], [0.8, 0.12, 0.0, 0.0]])
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
