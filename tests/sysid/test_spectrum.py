"""Torque residuals by frequency band (``realm_ms/sysid/torque/spectrum.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from realm_ms.sysid.torque.spectrum import band_names, band_rms, high_frequency_note, summary


def _signal(freqs_amps, n=4000, dt=1e-3, offset=0.0):
    t = np.arange(n) * dt
    return offset + sum(a * np.sin(2 * np.pi * f * t) for f, a in freqs_amps)


def test_each_sine_lands_in_its_band_and_the_bands_add_up():
    dt = 1e-3
    r = np.zeros((4000, 7))
    r[:, 0] = _signal([(1.0, 0.5)], offset=0.2)  # slow, with a mean: both in the lowest band
    r[:, 1] = _signal([(5.0, 0.3)])  # the motion band
    r[:, 2] = _signal([(40.0, 0.4)])  # fast
    r[:, 3] = _signal([(1.0, 0.1), (40.0, 0.3)])
    b = band_rms(r, [4000], dt)
    assert b.shape == (3, 7)
    np.testing.assert_allclose(b[:, 0], [np.sqrt(0.2**2 + 0.5**2 / 2), 0, 0], atol=1e-6)
    np.testing.assert_allclose(b[:, 1], [0, 0.3 / np.sqrt(2), 0], atol=1e-6)
    np.testing.assert_allclose(b[:, 2], [0, 0, 0.4 / np.sqrt(2)], atol=1e-6)
    np.testing.assert_allclose(b[:, 3], [0.1 / np.sqrt(2), 0, 0.3 / np.sqrt(2)], atol=1e-6)
    np.testing.assert_allclose((b**2).sum(0), (r**2).mean(0), rtol=1e-9)  # orthogonal bands


def test_trajectories_are_transformed_one_by_one():
    """Two back-to-back trajectories: the jump between them is no high-frequency content."""
    a = np.tile(_signal([(1.0, 0.5)], n=3000)[:, None], (1, 7)) + 1.0
    b = np.tile(_signal([(1.0, 0.5)], n=2000)[:, None], (1, 7)) - 1.0
    r = np.concatenate([a, b])
    split = band_rms(r, [3000, 2000], 1e-3)
    joined = band_rms(r, [5000], 1e-3)
    assert split[2].max() < 1e-9 < joined[2].max()
    np.testing.assert_allclose((split**2).sum(0), (r**2).mean(0))
    with pytest.raises(ValueError, match="lengths add up"):
        band_rms(r, [3000], 1e-3)


def test_summary_and_the_high_frequency_note():
    r = np.zeros((4000, 7))
    r[:, :] = _signal([(30.0, 0.4), (1.0, 0.1)])[:, None]
    s = summary(band_rms(r, [4000], 1e-3))
    assert s["bands"] == band_names() == ["0-2 Hz", "2-10 Hz", ">10 Hz"]
    assert abs(sum(s["share"]) - 1) < 1e-9 and s["share"][2] > 0.9
    note = high_frequency_note(s)
    assert "above 10 Hz" in note and "no effect in the library" in note and "7.07e-02 N·m" in note
    r[:, :] = _signal([(1.0, 0.4), (30.0, 0.1)])[:, None]
    assert high_frequency_note(summary(band_rms(r, [4000], 1e-3))) == ""
