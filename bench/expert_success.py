"""Scripted-expert success table: every REALM task x N seeds (default 20), CPU sim, state obs.

    .venv/bin/python bench/expert_success.py [--seeds 20] [--tasks REALM-PickApple-v1 ...] [--out outputs/expert_success.json]

Writes after every episode (so a rerun resumes where it stopped) and prints
``task | success rate | mean progression | mean steps | stalled stages``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections import Counter
from pathlib import Path

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")


def summarize(episodes: dict) -> list[dict]:
    rows = []
    for task, eps in sorted(episodes.items()):
        vals = list(eps.values())
        if not vals:
            continue
        n = len(vals)
        rows.append(dict(
            task=task,
            episodes=n,
            success_rate=sum(e["progression"] >= 1.0 for e in vals) / n,
            mean_progression=sum(e["progression"] for e in vals) / n,
            mean_steps=sum(e["steps"] for e in vals) / n,
            stalled=dict(Counter(e["stalled_stage"] for e in vals if e["stalled_stage"] != "DONE")),
        ))
    return rows


def format_table(rows: list[dict]) -> str:
    lines = [f"{'task':32s} {'n':>3s} {'success':>8s} {'progr.':>7s} {'steps':>7s}  stalled at"]
    for r in rows:
        lines.append(f"{r['task']:32s} {r['episodes']:3d} {r['success_rate']:8.2f} {r['mean_progression']:7.3f} {r['mean_steps']:7.1f}  {r['stalled'] or ''}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--tasks", nargs="*", default=None)
    ap.add_argument("--out", default="outputs/expert_success.json")
    args = ap.parse_args(argv)

    import gymnasium as gym

    import realm_ms  # noqa: F401
    from realm_ms.expert import make_expert, run_episode
    from realm_ms.tasks import TASKS

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    data = json.loads(out.read_text()) if out.exists() else {}
    episodes: dict = data.get("episodes", {})
    tasks = args.tasks or sorted(TASKS)
    for task in tasks:
        done = episodes.setdefault(task, {})
        todo = [s for s in range(args.seeds) if str(s) not in done]
        if not todo:
            continue
        env = gym.make(task, obs_mode="state")
        env.reset(seed=todo[0])
        expert = make_expert(env)
        for s in todo:
            t = time.time()
            res = run_episode(env, s, expert=expert)
            res["wall_s"] = round(time.time() - t, 2)
            done[str(s)] = res
            data = dict(episodes=episodes, table=summarize(episodes))
            tmp = out.with_suffix(".tmp")
            tmp.write_text(json.dumps(data, indent=1))
            tmp.replace(out)
            print(f"{task} seed {s}: progression {res['progression']:.2f} steps {res['steps']} ({res['wall_s']} s) {res['log'] or ''}", flush=True)
        env.close()
    rows = summarize({t: episodes[t] for t in tasks if t in episodes})
    print(format_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
