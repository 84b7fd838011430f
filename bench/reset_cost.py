"""Reset cost with perturbations on CPU: median / p90 seconds per ``env.reset`` (one env, 320x180 rgb).

    .venv/bin/python bench/reset_cost.py [--task REALM-PickApple-v1] [--n 20] [--obs-mode rgb] [--only V-AUG ...] [--out outputs/reset_cost.json]

Rows: the plain env (baseline, no perturbation argument), Default, the episode-level factors
(V-LIGHT, B-HOBJ, VB-POSE, S-LANG; no reconfiguration) and the scene-changing ones (V-SC, V-VIEW,
SB-NOUN, SB-VRB, VB-MOBJ, VSB-NOBJ; ManiSkill reconfiguration every reset). Each reset uses a new
seed, so every draw is fresh (procedural meshes are generated once and cached on disk: the first
few resets of an unseen object pay for it, as on a fresh machine). REALM: 5.4 s reset + 7.4 s warm-up.
Targets: median < 1 s without reconfiguration, < 3 s with it.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")

ROWS = [None, "Default", "V-LIGHT", "B-HOBJ", "VB-POSE", "S-LANG", "V-AUG", "V-SC", "V-VIEW", "SB-NOUN", "SB-VRB", "VB-MOBJ", "VSB-NOBJ"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="REALM-PickApple-v1")
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--obs-mode", default="rgb")
    ap.add_argument("--only", nargs="*", default=None, help="perturbation rows to run (the plain baseline always runs)")
    ap.add_argument("--out", default="outputs/reset_cost.json")
    args = ap.parse_args(argv)
    from realm_ms.validate import output_arg

    output_arg(ap, args.out, example="reset_cost.json")

    import gymnasium as gym
    from tqdm import tqdm

    import realm_ms  # noqa: F401

    results = []
    rows = ROWS if not args.only else [None] + [r for r in ROWS[1:] if r in args.only]
    for name in rows:
        kw = dict(obs_mode=args.obs_mode)
        if name is not None:
            kw["perturbation"] = name
        env = gym.make(args.task, **kw)
        env.reset(seed=0)  # warm (first build)
        times, reconf = [], False
        for s in tqdm(range(1, args.n + 1), desc=name or "plain", leave=False):
            t = time.perf_counter()
            _, info = env.reset(seed=s)
            times.append(time.perf_counter() - t)
            reconf = bool(info.get("reconfigure", False))
        env.close()
        times.sort()
        results.append(dict(perturbation=name or "(plain env)", reconfigure=reconf, n=len(times), median_s=statistics.median(times),
                            p90_s=times[int(0.9 * (len(times) - 1))]))
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(dict(task=args.task, obs_mode=args.obs_mode, rows=results), indent=1))
    base = results[0]["median_s"]
    print(f"task {args.task}, obs_mode {args.obs_mode}, {args.n} resets each, CPU")
    print(f"{'perturbation':14s} {'reconfig':>8s} {'median s':>9s} {'p90 s':>7s} {'x plain':>8s}")
    for r in results:
        print(f"{r['perturbation']:14s} {str(r['reconfigure']):>8s} {r['median_s']:9.3f} {r['p90_s']:7.3f} {r['median_s'] / base:8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
