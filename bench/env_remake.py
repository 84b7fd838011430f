"""Seconds to make and reset an rgb env after another env in the same process was closed: with the
renderer SAPIEN frees when its last scene goes (the baseline, rebuilt each time), against the renderer
``realm_ms.rendering.keep_renderer`` keeps for the process. A new renderer recomputes its BRDF lookup
table on its first picture, which on lavapipe is most of an env's start-up; evaluation workers and
tests that make env after env in one process pay it each time without the kept renderer.

    python bench/env_remake.py [--task REALM-PickApple-v1] [--size 64x48] [--repeats 3]

Prints the median of each and their ratio.
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings

import gymnasium as gym

import realm_ms  # noqa: F401
from realm_ms import rendering


def make_reset_close(task: str, w: int, h: int) -> float:
    t = time.perf_counter()
    env = gym.make(task, obs_mode="rgb", camera_width=w, camera_height=h)
    env.reset(seed=0)
    dt = time.perf_counter() - t
    env.close()
    return dt


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="REALM-PickApple-v1")
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    w, h = (int(x) for x in a.size.split("x"))
    warnings.simplefilter("ignore")
    first = make_reset_close(a.task, w, h)  # imports, asset caches, the first renderer
    released, kept = [], []
    for _ in range(a.repeats):
        rendering._KEPT.clear()  # the baseline: nothing holds the renderer once the env is closed
        released.append(make_reset_close(a.task, w, h))
        kept.append(make_reset_close(a.task, w, h))  # made while the previous env's renderer is kept
    r, k = statistics.median(released), statistics.median(kept)
    print(f"{a.task} rgb {a.size}: first env in the process {first:.2f} s")
    print(f"next env, renderer released: {r:.2f} s (median of {a.repeats})")
    print(f"next env, renderer kept:     {k:.2f} s (median of {a.repeats})")
    print(f"released / kept = {r / k:.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
