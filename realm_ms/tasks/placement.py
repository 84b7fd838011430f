"""Seeded collision-free placement of objects on the table (rejection sampling on footprint discs).

Each env draws from its own RNG (ManiSkill's ``_batched_episode_rng``), so layouts are identical
on CPU and GPU and for any ``num_envs``. Footprints are discs of the object's xy bounding radius;
REALM uses axis-aligned rectangles with 0.05 m separation, discs are yaw-invariant and stricter.
"""

from __future__ import annotations

import numpy as np

MAX_TRIES = 2000


class PlacementError(RuntimeError):
    pass


def sample_placements(
    rngs: list,
    radii: list[float],
    regions: list[tuple[float, float, float, float]],
    yaw_ranges: list[tuple[float, float]],
    min_separation: float = 0.05,
    obstacles: list[tuple[float, float, float]] = (),
    reach: list[float | None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Returns xy (B, K, 2) and yaw (B, K). Objects are placed largest first, clear of each other
    and of ``obstacles`` (x, y, radius): fixtures that stay where they are. ``reach[i]`` (m, None:
    anywhere in its region) keeps object i's centre that close to the robot base at the origin."""
    reach = list(reach) if reach is not None else [None] * len(radii)
    b, k = len(rngs), len(radii)
    xy = np.zeros((b, k, 2))
    yaw = np.zeros((b, k))
    order = np.argsort(-np.asarray(radii), kind="stable")
    for e, rng in enumerate(rngs):
        for restart in range(MAX_RESTARTS + 1):
            # greedy placement can corner itself (a large object in the middle); start the layout over
            if _place_env(rng, e, xy, yaw, order, radii, regions, yaw_ranges, min_separation, obstacles, reach, last=restart == MAX_RESTARTS):
                break
    return xy, yaw


MAX_RESTARTS = 20


def _place_env(rng, e, xy, yaw, order, radii, regions, yaw_ranges, min_separation, obstacles, reach, last: bool) -> bool:
    placed: list[int] = []
    fixed = [(np.array([x, y]), r) for x, y, r in obstacles]
    tries = MAX_TRIES if last else MAX_TRIES // 10
    for i in order:
        x0, x1, y0, y1 = regions[i]
        r = radii[i]
        lo = np.array([x0 + r, y0 + r])
        hi = np.array([max(x1 - r, x0 + r), max(y1 - r, y0 + r)])
        for _ in range(tries):
            p = lo + (hi - lo) * rng.uniform(0, 1, size=2)
            if reach[i] is not None and np.linalg.norm(p) > reach[i]:
                continue
            if all(np.linalg.norm(p - xy[e, j]) >= r + radii[j] + min_separation for j in placed) and all(
                np.linalg.norm(p - c) >= r + rc + min_separation for c, rc in fixed
            ):
                break
        else:
            if not last:
                return False
            raise PlacementError(
                f"could not place object {i} (radius {r:.3f} m) without collision in region {regions[i]}"
                + (f" within {reach[i]} m of the robot" if reach[i] is not None else "")
                + f" after {MAX_RESTARTS} restarts; enlarge the spawn region or use fewer/smaller objects"
            )
        xy[e, i] = p
        placed.append(i)
        yaw[e, i] = rng.uniform(*yaw_ranges[i])
    return True
