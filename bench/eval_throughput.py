"""`realm eval` throughput: env-steps/s with the zero policy for 1, 2, 4, ... worker processes, three
raster cameras at 320x180, next to ManiSkill's PickCube-v1 in the same scheme, in one run.

Scheme: N spawned worker processes, each stepping one CPU-physics env with rendering; the main
process sends an 8-action chunk per round and gets the observation back (REALM: through shared
memory via ``realm_ms.eval.backends.processes.ProcessBackend``; PickCube: the same loop over a pipe, its one
camera set to 320x180 and the same shader). Both capture images only at a chunk's last step, the
one the policy sees. Measured in steady state: a warm-up round per worker
(spawn, imports, env build) is excluded. Efficiency = steps/s(N) / (N * steps/s(1)).

    python bench/eval_throughput.py [--workers 1,2,4] [--seconds 30] [--task REALM-PickApple-v1]

Prints a table and writes outputs/bench/eval_throughput.json. On a machine with fewer cores than
workers the efficiency is bounded by the cores (this says how many it saw).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
CHUNK = 8


def _pickcube_worker(conn, width: int, height: int) -> None:
    import gymnasium as gym
    import mani_skill.envs  # noqa: F401
    import numpy as np
    import torch

    torch.set_num_threads(1)
    env = gym.make("PickCube-v1", obs_mode="rgb", control_mode="pd_joint_pos",
                   sensor_configs=dict(width=width, height=height, shader_pack="default"))
    obs, _ = env.reset(seed=0)
    hold = env.unwrapped.agent.robot.get_qpos()[:, :8].clone()
    # the same capture scheme as `realm eval`: only a chunk's last step renders (RealmEnv.capture_sensors)
    u, capture, last = env.unwrapped, [True], {}
    full = u._get_obs_sensor_data

    def sensor_data(*args, **kwargs):
        if capture[0] or "d" not in last:
            last["d"] = full(*args, **kwargs)
        return last["d"]

    u._get_obs_sensor_data = sensor_data
    conn.send("ready")
    while True:
        cmd = conn.recv()
        if cmd is None:
            break
        for i in range(CHUNK):
            capture[0] = i == CHUNK - 1
            obs, _, term, trunc, _ = env.step(hold)
        if bool(trunc[0]) or bool(term[0]):
            env.reset()
        img = obs["sensor_data"]["base_camera"]["rgb"][0].cpu().numpy()  # cuda tensors where SAPIEN renders on a GPU
        conn.send((CHUNK, np.ascontiguousarray(img)))
    env.close()


def bench_pickcube(n: int, seconds: float, width: int, height: int) -> float:
    ctx = mp.get_context("spawn")
    pipes, procs = [], []
    for _ in range(n):
        a, b = ctx.Pipe()
        p = ctx.Process(target=_pickcube_worker, args=(b, width, height), daemon=True)
        p.start()
        pipes.append(a)
        procs.append(p)
    for c, p in zip(pipes, procs):
        if not c.poll(300):  # a dead or stuck worker must not hang the bench
            raise RuntimeError(f"PickCube worker {p.pid} did not start (exit code {p.exitcode})")
        assert c.recv() == "ready"
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for c in pipes:
            c.send(1)
        for c in pipes:
            if not c.poll(120):
                raise RuntimeError("a PickCube worker stopped answering")
            k, _ = c.recv()
            steps += k
    rate = steps / (time.perf_counter() - t0)
    for c in pipes:
        c.send(None)
    for p in procs:
        p.join(timeout=30)
    return rate


def bench_realm(n: int, seconds: float, task: str, width: int, height: int) -> float:
    import numpy as np

    from realm_ms.eval.policies import ObsRequest, make_policy
    from realm_ms.eval.policies.policy import PolicyInput
    from realm_ms.eval.protocol import EpisodeKey
    from realm_ms.eval.runner import RunConfig
    from realm_ms.eval.backends.processes import ProcessBackend

    policy = make_policy("zero")
    cfg = RunConfig(policy="zero", max_steps=10**6, obs=ObsRequest(("exterior_1", "exterior_2", "wrist"), width, height), quality=False)
    be = ProcessBackend(cfg, n)
    try:
        obs = be.start({s: EpisodeKey(task, "Default", s) for s in range(n)})  # warm-up: spawn, imports, env build

        def round_():
            batch = PolicyInput(state=np.stack([obs[s]["state"] for s in range(n)]), instructions=[""] * n,
                                images={c: np.stack([obs[s]["images"][c] for s in range(n)]) for c in obs[0]["images"]})
            acts = policy.act(batch).actions
            res = be.step({s: acts[s] for s in range(n)})
            for s, (o, _) in res.items():
                obs[s] = o
            return CHUNK * n

        round_()
        steps, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            steps += round_()
        return steps / (time.perf_counter() - t0)
    finally:
        be.close()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", default="1,2,4")
    ap.add_argument("--seconds", type=float, default=30.0, help="measurement time per configuration")
    ap.add_argument("--task", default="REALM-PickApple-v1")
    ap.add_argument("--size", default="320x180")
    ap.add_argument("--out", default="outputs/bench/eval_throughput.json")
    args = ap.parse_args(argv)
    from realm_ms.validate import output_arg

    output_arg(ap, args.out, example="eval_throughput.json")
    w, h = (int(v) for v in args.size.split("x"))
    ns = [int(v) for v in args.workers.split(",")]
    cores = os.cpu_count()
    rows = []
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for n in ns:
        realm = bench_realm(n, args.seconds, args.task, w, h)
        print(f"workers {n}: {args.task} {realm:.1f} env-steps/s (3 cams)", flush=True)
        cube = bench_pickcube(n, args.seconds, w, h)
        print(f"workers {n}: PickCube-v1 {cube:.1f} env-steps/s (1 cam)", flush=True)
        rows.append(dict(workers=n, realm_steps_s=realm, pickcube_steps_s=cube))
        out.write_text(json.dumps(dict(cores=cores, size=[w, h], task=args.task, rows=rows, partial=True), indent=2))
    base_r, base_c = rows[0]["realm_steps_s"] / ns[0], rows[0]["pickcube_steps_s"] / ns[0]
    print(f"\n{cores} CPU cores seen; {w}x{h} raster cameras; zero policy; chunks of {CHUNK}")
    print(f"{'workers':>7s} {'REALM st/s':>11s} {'eff.':>6s} {'PickCube st/s':>14s} {'eff.':>6s} {'REALM/PickCube':>15s}")
    for r in rows:
        r["realm_efficiency"] = r["realm_steps_s"] / (r["workers"] * base_r)
        r["pickcube_efficiency"] = r["pickcube_steps_s"] / (r["workers"] * base_c)
        print(f"{r['workers']:7d} {r['realm_steps_s']:11.1f} {r['realm_efficiency']:6.2f} {r['pickcube_steps_s']:14.1f} "
              f"{r['pickcube_efficiency']:6.2f} {r['realm_steps_s'] / r['pickcube_steps_s']:15.2f}")
    out.write_text(json.dumps(dict(cores=cores, size=[w, h], task=args.task, rows=rows), indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
