"""Residual features: lag estimate, noise floor."""

import numpy as np

from realm_ms.sysid.replay import SegmentSet
from realm_ms.sysid.signatures import estimate_lag, noise_floor
from realm_ms.sysid.timeseries import Trajectory


def test_lag_recovers_a_sub_sample_delay():
    dt = 1 / 15
    t = np.arange(600) * dt
    f = lambda x: np.sin(1.3 * x) + 0.5 * np.sin(2.9 * x + 1)  # noqa: E731
    assert abs(estimate_lag(f(t - 0.02), f(t), dt) - 0.02) < 0.004
    assert abs(estimate_lag(f(t), f(t), dt)) < 1e-6


def test_noise_floor_of_white_noise_on_smooth_motion():
    rng = np.random.default_rng(0)
    t = np.arange(400) / 15.0
    q = np.array([0, -0.6, 0, -2.4, 0, 1.9, 0]) + 0.1 * np.sin(0.5 * t)[:, None]
    noisy = q + rng.normal(0, 3e-4, q.shape)
    ss = SegmentSet.build([Trajectory("a", t, noisy, q)], 120.0)
    res = np.where(ss.mask[..., None], ss.meas - q[ss.sample_idx.clip(0)], np.nan)
    sigma, per_joint = noise_floor(ss, res)
    assert abs(sigma - 3e-4) < 0.4e-4 and per_joint.shape == (7,)


def test_evidence_never_divides_by_a_zero_rms():
    """A joint with residual only in holds (move_rms 0) used to read "hold/move rms 300000000.00"."""
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.signatures import Features, evidence

    z = np.zeros(7)
    rms = np.full(7, 3e-4)
    f = Features(z, z, np.full(7, 0.5), z, z, z, z, z, rms, z, z)
    text = evidence(make_effect("armature"), {}, f)
    assert "hold/move rms n/a" in text
    f = Features(z, z, z, z, z, z, np.full(7, 1e-4), rms, rms, rms, z)
    assert "mean/rms 0.33" in evidence(make_effect("encoder_bias"), {}, f)
