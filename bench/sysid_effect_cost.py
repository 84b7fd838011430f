"""What each effect adds to a replay rollout's time per physics step, on one core (as a worker
process runs): the figures behind the ``step_cost`` hints with which ``Evaluator`` spreads a
screening batch's effects over its workers.

    python bench/sysid_effect_cost.py [--arms 16] [--steps 360] [--repeat 3] [--out FILE.json]

For each registered effect: rollouts of ``--arms`` and of 4x as many arms with the effect on every
arm (its nominal values, a little spread) against the same rollouts with no effect, best of
``--repeat``. The extra time is split into a part per physics step and a part per arm the effect is
on (the two numbers ``Effect.step_cost`` declares, printed beside them); the no-effect rollouts
give what one more arm costs (``engine.ARM_STEP_COST``).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def _batch(arms: int, steps: int, rng: np.random.Generator):
    q_ref = np.array([0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8])
    t = np.floor(np.arange(steps) / 120.0 * 15) / 15  # 15 Hz targets held over 120 Hz physics steps
    q0 = q_ref + 0.01 * rng.standard_normal((arms, 7))
    cmd = q_ref + 0.4 * np.sin(2 * np.pi * 0.4 * t[None, :, None] + rng.uniform(0, 6, (arms, 1, 7)))
    return q0, np.zeros((arms, 7)), cmd


def _effect_on_all(name: str, arms: int, rng: np.random.Generator):
    import torch

    from realm_ms.agents.effects import make_effect

    fx = make_effect(name)
    off = np.array([p.spec.off for p in fx.params])
    nominal = np.array([p.spec.nominal for p in fx.params])
    theta = np.where(nominal != off, nominal * (1 + 0.1 * rng.standard_normal((arms, len(off)))), off)
    fx.set_theta(torch.as_tensor(theta, dtype=torch.float32))
    return fx


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", type=int, default=16)
    ap.add_argument("--steps", type=int, default=360)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()

    import torch

    torch.set_num_threads(1)
    from realm_ms.agents.effects import EFFECTS
    from realm_ms.sysid.engine import ARM_STEP_COST
    from realm_ms.sysid.simulator import ReplaySimulator

    sim = ReplaySimulator()
    rng = np.random.default_rng(0)
    q0, qd0, cmd = _batch(args.arms, args.steps, rng)
    q4, qd4, cmd4 = _batch(4 * args.arms, args.steps, rng)

    def best(effects, batch=None) -> float:
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            sim.rollout(*(batch or (q0, qd0, cmd)), effects)
            times.append(time.perf_counter() - t0)
        return 1000 * min(times) / args.steps

    big = (q4, qd4, cmd4)
    best([])  # warm-up: the scene and the law's first calls
    base = [best([]), best([], big)]
    measured = {}
    for name in EFFECTS.names():
        measured[name] = [best([_effect_on_all(name, n, rng)], b) for n, b in ((args.arms, None), (4 * args.arms, big))]
    base = [min(base[0], best([])), min(base[1], best([], big))]  # before and after: the noise is one-sided
    arm = (base[1] - base[0]) / (3 * args.arms)
    print(f"{args.arms} and {4 * args.arms} arms, {args.steps} physics steps, best of {args.repeat}, one thread")
    print(f"no effect: {base[0]:.2f} and {base[1]:.2f} ms/step; one more arm {arm:.3f} ms/step (ARM_STEP_COST {ARM_STEP_COST})")
    print(f"{'effect':20s} {'ms/step':>8s} {'x4 arms':>8s} {'per step':>9s} {'per arm':>8s}   hint")
    rows = {"no_effect_ms_per_step": base, "arm_ms_per_step": arm, "effects": {}}
    for name, (ms, ms4) in measured.items():
        extra, extra4 = ms - base[0], ms4 - base[1]
        per_arm = (extra4 - extra) / (3 * args.arms)
        per_step = extra - per_arm * args.arms
        hint = EFFECTS.get(name).step_cost
        rows["effects"][name] = {"ms_per_step": [ms, ms4], "extra_per_step": per_step, "extra_per_arm": per_arm,
                                 "step_cost_hint": list(hint)}
        print(f"{name:20s} {ms:8.2f} {ms4:8.2f} {per_step:9.2f} {per_arm:8.3f}   {hint}")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
