"""The gripper's strokes, real beside simulated: speed, duration, where a grasp stops them.

    python bench/gripper_response.py DATA_DIR [--model MODEL.yaml|droid-aligned] [--json OUT.json]

DATA_DIR: DROID episodes in any format ``realm sysid`` reads (``../shared/droid_real``), read with
``realm_ms.sysid.alignment.read_droid_episodes``. The real strokes are ``sysid.gripper.strokes`` of the
measured gripper. The simulated ones come from a REALM env (``REALM-PickApple-v1``, one env, CPU
physics, the arm held at its reset pose, nothing in the fingers), answering step requests open ->
closed -> open of each stroke size seen in the data (0.25, 0.5, 0.75, 1), sampled at 15 Hz exactly
as the real ones, under the nominal robot and under ``--model``; then the workbench's gripper row
(``sysid.gripper.check_gripper``) for the nominal robot and ``--model``.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")

SIZES = (0.25, 0.5, 0.75, 1.0)
HOLD = 25  # control steps each request is held (1.7 s: the slowest stroke ends well within it)


def stroke_table(ss) -> dict:
    """Per direction: count, median speed (p10-p90), peak speed, duration, where closing strokes stop."""
    out = {}
    for d in ("close", "open"):
        s = [x for x in ss if x.direction == d]
        if not s:
            continue
        sp = np.array([x.speed for x in s])
        out[d] = {"n": len(s), "speed": float(np.median(sp)), "speed_p10": float(np.percentile(sp, 10)),
                  "speed_p90": float(np.percentile(sp, 90)), "peak": float(np.median([x.peak for x in s])),
                  "full_stroke_s": float(np.median([x.duration / max(abs(x.end - x.begin), 1e-9) for x in s])),
                  "end_median": float(np.median([x.end for x in s]))}
    return out


def sim_strokes(model) -> tuple[list, float]:
    import gymnasium as gym
    import torch

    import realm_ms  # noqa: F401  (registers the envs)
    from realm_ms.sysid.gripper import strokes

    env = gym.make("REALM-PickApple-v1", obs_mode="state", num_envs=1, robot_model=model)
    env.reset(seed=0)
    agent = env.unwrapped.agent
    q = agent.arm_qpos[0].cpu().numpy()
    cmds = [0.0] * 5
    for size in SIZES:
        cmds += [size] * HOLD + [0.0] * HOLD
    t0 = time.perf_counter()
    g = [float(agent.gripper_position[0])]
    with torch.no_grad():
        for c in cmds:
            env.step(np.concatenate([q, [c]]).astype(np.float32))
            g.append(float(agent.gripper_position[0]))
    wall = time.perf_counter() - t0
    env.close()
    t = np.arange(len(g)) / 15.0
    return strokes(np.array(g), t, "sim"), wall / len(cmds)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data")
    ap.add_argument("--model", default=None, help="robot model file or name to measure beside the nominal robot")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    from realm_ms.agents.robot_model import load_robot_model
    from realm_ms.sysid import alignment
    from realm_ms.sysid.cli import _show_data_warnings
    from realm_ms.sysid.gripper import check_gripper, strokes

    _show_data_warnings()
    eps, _ = alignment.read_droid_episodes(args.data)
    trajs = [e.traj for e in eps]
    real = [s for tr in trajs if tr.gripper is not None for s in strokes(tr.gripper, tr.t, tr.name)]
    rows = {"real": stroke_table(real)}
    runs = [("nominal", None)] + ([(args.model, args.model)] if args.model else [])
    step_ms = {}
    for label, model in runs:
        ss, per_step = sim_strokes(model)
        rows[f"sim {label}"] = stroke_table(ss)
        step_ms[label] = 1e3 * per_step
    print(f"{len(eps)} episodes, {len(real)} real strokes; units of the 0 (open) .. 1 (closed) stroke")
    print(f"{'':<22} {'dir':<5} {'n':>4} {'speed/s':>8} {'p10-p90':>11} {'peak/s':>7} {'full s':>7} {'ends':>6}")
    for label, table in rows.items():
        for d, r in table.items():
            print(f"{label[:22]:<22} {d:<5} {r['n']:>4} {r['speed']:>8.2f} {r['speed_p10']:>5.2f}-{r['speed_p90']:<5.2f} "
                  f"{r['peak']:>7.2f} {r['full_stroke_s']:>7.2f} {r['end_median']:>6.3f}")
    labs = {}
    for e in eps:
        if e.traj.gripper is not None:
            labs.setdefault(e.lab, []).extend(x.speed for x in strokes(e.traj.gripper, e.traj.t, e.name))
    print("real per lab, median stroke speed /s (strokes): " + ", ".join(
        f"{lab} {np.median(v):.2f} ({len(v)})" for lab, v in sorted(labs.items()) if v))
    for label, _ in runs:
        ratio = {d: rows[f"sim {label}"][d]["speed"] / rows["real"][d]["speed"] for d in rows["real"]}
        print(f"sim {label}: speed / real " + ", ".join(f"{d} {v:.2f}×" for d, v in ratio.items())
              + f" ({step_ms[label]:.1f} ms per env step)")
    checks = {}
    for label, model in runs:
        c = check_gripper(trajs, load_robot_model(model) if model else None)
        checks[label] = c.to_json()
        print(f"workbench, {label}: {c.line()}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"tables": rows, "labs": {k: float(np.median(v)) for k, v in labs.items() if v}, "checks": checks,
                       "env_step_ms": step_ms}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
