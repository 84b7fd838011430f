"""Seeded collision-free placement."""

import numpy as np
import pytest

from realm_ms.tasks.placement import PlacementError, sample_placements


def _rngs(n, seed=0):
    return [np.random.RandomState(seed + i) for i in range(n)]


def test_objects_keep_clear_of_each_other_fixtures_and_region():
    radii = [0.08, 0.05, 0.04, 0.03]
    region = (0.35, 0.75, -0.30, 0.30)
    obstacles = [(0.55, 0.0, 0.10)]
    xy, yaw = sample_placements(_rngs(20), radii, [region] * 4, [(-np.pi, np.pi)] * 4, 0.03, obstacles)
    for e in range(20):
        for i, r in enumerate(radii):
            assert region[0] + r - 1e-9 <= xy[e, i, 0] <= region[1] - r + 1e-9
            assert region[2] + r - 1e-9 <= xy[e, i, 1] <= region[3] - r + 1e-9
            assert np.linalg.norm(xy[e, i] - [0.55, 0.0]) >= r + 0.10 + 0.03 - 1e-9
            for j in range(i):
                assert np.linalg.norm(xy[e, i] - xy[e, j]) >= r + radii[j] + 0.03 - 1e-9
    assert np.abs(yaw).max() <= np.pi


def test_same_seed_same_layout_and_different_seeds_differ():
    args = ([0.05, 0.04], [(0.35, 0.75, -0.3, 0.3)] * 2, [(-np.pi, np.pi)] * 2)
    a, _ = sample_placements(_rngs(3), *args)
    b, _ = sample_placements(_rngs(3), *args)
    c, _ = sample_placements(_rngs(3, seed=10), *args)
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).max() > 1e-3


def test_impossible_layout_is_a_clear_error():
    with pytest.raises(PlacementError, match="enlarge the spawn region"):
        sample_placements(_rngs(1), [0.2, 0.2], [(0.4, 0.6, -0.1, 0.1)] * 2, [(0, 0)] * 2)


def test_reach_keeps_an_object_near_the_robot():
    """An object given a reach spawns within it of the base (the corners of REALM's regions are out
    of the arm's top-down reach); the others still use the whole region."""
    region = (0.30, 0.82, -0.40, 0.40)
    xy, _ = sample_placements(_rngs(200), [0.03, 0.03], [region] * 2, [(0, 0)] * 2, 0.01, reach=[0.78, None])
    d = np.linalg.norm(xy, axis=-1)
    assert d[:, 0].max() <= 0.78
    assert d[:, 1].max() > 0.78  # the unrestricted one does reach the corners
    with pytest.raises(PlacementError, match="within 0.2 m of the robot"):
        sample_placements(_rngs(1), [0.03], [region], [(0, 0)], reach=[0.2])
