"""How closely the replay simulator's PhysX plant reproduces the independent 1 kHz MuJoCo reference
(`realm_ms/sysid/reference_mujoco.py`: the same URDF and impedance law, written without realm-ms's
driver) on excitation commands, per integrator and control-model rate.

    python bench/mujoco_agreement.py [--seeds 0-9] [--duration 10] [--out outputs/bench/mujoco_agreement.json]

Two tables (RMS per joint, mrad, compared every 25 ms on both time grids):

1. integrators: `excite` seed 0, 2 trajectories x ``--duration`` s from rest, pooled, under each
   integrator / ``model_rate`` at 120 Hz (and the explicit law at 960 Hz, 8x the steps);
2. the default plant (exact law, ``model_rate="path"``, 120 Hz) on one trajectory of each of
   ``--seeds``: the worst joint of each log and the worst over all of them.

The MuJoCo runs are the baseline; the figures are the distance to it.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

# (label, integrator, model_rate, physics_hz)
ROWS = [
    ("implicit_damping", "implicit_damping", None, 120.0),
    ('exact, model_rate="control"', "exact", "control", 120.0),
    ('exact, model_rate="physics"', "exact", "physics", 120.0),
    ('exact, model_rate="path" (default)', "exact", "path", 120.0),
    ("explicit at 960 Hz", "explicit", None, 960.0),
]


def replay(sim, cmd15: np.ndarray, hz: float, duration: float) -> np.ndarray:
    """Commands (E, T, 7) at 15 Hz held at ``hz``, from rest at the first command: (E, steps + 1, 7)."""
    from realm_ms.sysid.replay import held_commands

    t = np.arange(cmd15.shape[1]) / 15.0
    steps = int(round(duration * hz))
    cmd = np.stack([held_commands(t, c, steps, 1.0 / hz) for c in cmd15])
    return sim.rollout(cmd15[:, 0], np.zeros((len(cmd15), 7)), cmd, [])


def rms_40hz(q: np.ndarray, hz: float, ref: np.ndarray, duration: float) -> np.ndarray:
    """Per-joint RMS over the arms, on the 25 ms grid both rates hit: (7,) rad."""
    t = np.arange(1, int(duration * 40)) / 40.0
    err = q[:, np.round(t * hz).astype(int)] - ref[:, np.round(t * 1000).astype(int)]
    return np.sqrt((err**2).mean(axis=(0, 1)))


def physx(cmd15: np.ndarray, duration: float, integrator: str, model_rate: str | None, hz: float) -> np.ndarray:
    from realm_ms.sysid.simulator import ReplaySimulator, SimConfig

    return replay(ReplaySimulator(SimConfig(physics_hz=hz, model_rate=model_rate, integrator=integrator)), cmd15, hz,
                  duration)


def seeds_arg(s: str) -> list[int]:
    if "-" in s:
        a, b = s.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(x) for x in s.split(",")]


def main() -> int:
    from realm_ms.sysid.excite import ExciteConfig, excite
    from realm_ms.sysid.reference_mujoco import MujocoReference

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0-9", help="excitation seeds of table 2 (0-9 or 0,3,5)")
    ap.add_argument("--duration", type=float, default=10.0, help="seconds per trajectory")
    ap.add_argument("--out", default="outputs/bench/mujoco_agreement.json")
    a = ap.parse_args()
    cfg = ExciteConfig(duration_s=a.duration, control_hz=15.0)
    t0 = time.perf_counter()

    cmd = np.stack(excite(2, 0, cfg))
    ref = replay(MujocoReference(), cmd, 1000.0, a.duration)
    table1 = {}
    print(f"integrators: excite seed 0, 2 trajectories x {a.duration:g} s; RMS per joint J1..J7 [mrad] "
          "against the 1 kHz MuJoCo reference")
    for label, integrator, model_rate, hz in ROWS:
        r = 1e3 * rms_40hz(physx(cmd, a.duration, integrator, model_rate, hz), hz, ref, a.duration)
        table1[label] = r.tolist()
        print(f"| {label} | {', '.join(f'{x:.2f}' for x in r)} |", flush=True)

    table2 = {}
    print(f"default plant on one {a.duration:g} s log per seed: worst joint [mrad]")
    for seed in seeds_arg(a.seeds):
        c = np.stack(excite(1, seed, cfg))
        ref = replay(MujocoReference(), c, 1000.0, a.duration)
        r = 1e3 * rms_40hz(physx(c, a.duration, "exact", "path", 120.0), 120.0, ref, a.duration)
        table2[seed] = r.tolist()
        print(f"  seed {seed}: max {r.max():.2f} (J{int(r.argmax()) + 1}); {', '.join(f'{x:.2f}' for x in r)}", flush=True)
    worst = max(table2, key=lambda s: max(table2[s]))
    w = np.asarray(table2[worst])
    wall = time.perf_counter() - t0
    print(f"worst over {len(table2)} logs: {w.max():.2f} mrad (seed {worst}, J{int(w.argmax()) + 1}); {wall:.0f} s wall")
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"duration_s": a.duration, "integrators_mrad": table1, "default_by_seed_mrad": table2,
                               "worst_mrad": float(w.max()), "worst_seed": worst, "wall_s": wall}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
