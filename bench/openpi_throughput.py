"""Policy-server throughput (openpi and RoboArena): env-steps/s with 1, 4, 8 stand-in servers against the sequential client.

    .venv/bin/python bench/openpi_throughput.py [--protocols openpi roboarena] [--slots 8] [--rounds 5] [--sleep 0.1]
        [--servers 1 4 8] [--replan-every 8] [--env REALM-PickApple-v1 --max-steps 48]

Each stand-in is an ``OpenPIServer(serial=True)`` or ``RoboArenaServer(serial=True)`` (one request at
a time, as both projects' servers) whose model sleeps ``--sleep`` s per request. One round = one
``act`` on ``--slots`` rows (openpi pi0 requests: two 320x180 views resized to 224x224, joints,
gripper, prompt; RoboArena: the same views at its default 224x224, plus the Cartesian pose; each
slot keeps to its server's connection), which the runner
then executes ``--replan-every`` env steps each; env-steps/s = slots x replan_every x rounds / wall.
This measures the serving layer alone (the policy-bound regime the concurrency is for); with
``--env`` it also runs ``realm eval`` episodes on real envs against each setting (batched
backend: one env of ``--slots`` sub-envs on CPU physics, 64x36 cameras, joint_velocity space),
where the env's own stepping cost on this machine is included.

Rows: ``sequential`` = one connection, one request at a time (the client before concurrency);
``N servers`` = the concurrent client over N servers, one connection each. Ratios are against the
sequential client; linear = min(N, slots).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def synthetic_batch(n: int):
    from realm_ms.eval.policies import PolicyInput

    rng = np.random.default_rng(0)
    state = np.tile(np.array([0.0, -0.63, 0.0, -2.51, 0.0, 1.88, 0.0, 0.0], np.float32), (n, 1))
    return PolicyInput(state=state, instructions=["pick up the apple"] * n, slots=list(range(n)),
                       images={c: rng.integers(0, 255, (n, 180, 320, 3), dtype=np.uint8) for c in ("exterior_1", "wrist")})


def serve_rate(protocol: str, addresses: list[str], sequential: bool, slots: int, rounds: int, replan: int) -> float:
    from realm_ms.eval.policies import make_policy

    pol = make_policy(f"{protocol}:{','.join(addresses)}", openpi_max_in_flight=1 if sequential else None, action_space="joint_velocity:position")
    batch = synthetic_batch(slots)
    pol.reset(list(range(slots)))
    pol.act(batch)  # connect + warm up
    t = time.perf_counter()
    for _ in range(rounds):
        out = pol.act(batch)
        assert out.errors is None, out.errors
    wall = time.perf_counter() - t
    pol.close()
    return slots * replan * rounds / wall


def env_rate(protocol: str, addresses: list[str], sequential: bool, task: str, slots: int, max_steps: int, replan: int) -> float:
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS
    from realm_ms.eval.records import read_records

    proto = PRESETS["realm"].with_overrides(episodes=slots, seed=0, max_steps=max_steps, replan_every=replan)
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        evaluate(f"{protocol}:{','.join(addresses)}", [task], ["Default"], proto, Path(d), workers=slots, backend="batched",
                 camera_size=(64, 36), quality=False, progress=False, quiet=True,
                 policy_options=dict(action_space="joint_velocity:position", openpi_max_in_flight=1 if sequential else None),
                 env_kwargs=dict(action_space="joint_velocity", gripper_action_space="position"))
        wall = time.perf_counter() - t
        steps = sum(int(r.get("steps", 0)) for r in read_records(Path(d) / "records.jsonl"))
    return steps / wall


def bench_protocol(protocol: str, args) -> None:
    from realm_ms.eval.policies.openpi_server import OpenPIServer, sleep_infer
    from realm_ms.eval.policies.roboarena_server import RoboArenaServer

    infer = partial(sleep_infer, seconds=args.sleep)  # {"actions": (10, 8)}: both protocols' answer

    def server():
        if protocol == "openpi":
            return OpenPIServer(infer, serial=True)
        return RoboArenaServer(infer, dict(action_space="joint_velocity"), serial=True)

    servers = [server().start() for _ in range(max(args.servers))]
    try:
        addr = [s.address for s in servers]
        rows = [("sequential", addr[:1], True)] + [(f"{n} server{'s' if n > 1 else ''}", addr[:n], False) for n in args.servers]
        print(f"\n{protocol} throughput: {args.slots} slots x {args.replan_every} steps per round, stand-in {args.sleep * 1000:.0f} ms/request, "
              f"{args.rounds} rounds")
        print(f"{'client':<14} {'env-steps/s':>12} {'x sequential':>13} {'linear':>7} {'of linear':>10}")
        base = None
        for name, a, seq in rows:
            r = serve_rate(protocol, a, seq, args.slots, args.rounds, args.replan_every)
            base = base or r
            lin = 1 if seq else min(len(a), args.slots)
            print(f"{name:<14} {r:12.1f} {r / base:13.2f} {lin:7d} {r / base / lin:10.2f}")
        if args.env:
            print(f"\nreal envs ({args.env}, batched backend, {args.slots} episodes x {args.max_steps} steps, joint_velocity):")
            base = None
            for name, a, seq in rows:
                r = env_rate(protocol, a, seq, args.env, args.slots, args.max_steps, args.replan_every)
                base = base or r
                print(f"{name:<14} {r:12.1f} {r / base:13.2f}")
    finally:
        for s in servers:
            s.stop()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--protocols", nargs="+", choices=("openpi", "roboarena"), default=["openpi", "roboarena"])
    ap.add_argument("--slots", type=int, default=8, help="episode slots asking for actions each round")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--sleep", type=float, default=0.1, help="stand-in inference time per request (s)")
    ap.add_argument("--servers", type=int, nargs="+", default=[1, 4, 8])
    ap.add_argument("--replan-every", type=int, default=8)
    ap.add_argument("--env", default=None, help="also run realm eval episodes of this task on real envs")
    ap.add_argument("--max-steps", type=int, default=48, help="episode length with --env")
    args = ap.parse_args(argv)

    for protocol in args.protocols:
        bench_protocol(protocol, args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
