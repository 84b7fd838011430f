"""`realm demo`: the scripted expert on REALM tasks, with a video per task and a progression table.

Writes to ``outputs/demo/``: ``<env_id>.mp4`` (human-view camera above the two exterior cameras and
the wrist camera, 15 fps), ``summary.json`` (per task: progression, success, stage -> control step
at which it latched, stalled stage) and ``summary.md`` (the same as a table). Tasks already in
``summary.json`` are skipped unless ``--force``, so an interrupted demo resumes.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

DEFAULT_OUT = Path("outputs/demo")


def add_parser(sub) -> None:
    p = sub.add_parser("demo", help="run the scripted expert on REALM tasks; write videos + a progression table")
    p.add_argument("--tasks", default="all", help="comma-separated env ids, or 'all' (default)")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output directory (default {DEFAULT_OUT})")
    p.add_argument("--seed", type=int, default=0, help="episode seed, integer (default 0)")
    from realm_ms.rendering import SHADERS  # the one shader table

    p.add_argument("--shader", default="default", choices=SHADERS,
                   help="default (raster) | rt | rt-med | rt-fast | minimal (default: default)")
    p.add_argument("--max-steps", type=int, default=300, help="control steps per episode (REALM: 800)")
    p.add_argument("--no-video", action="store_true", help="skip the mp4 per task (faster)")
    p.add_argument("--force", action="store_true", help="re-run tasks already in summary.json")
    p.set_defaults(func=run)


def _tile(render_frame, sensor_frames):
    import cv2
    import numpy as np

    top = render_frame
    w = top.shape[1]
    cams = [cv2.resize(f, (w // len(sensor_frames), int(w // len(sensor_frames) * f.shape[0] / f.shape[1]))) for f in sensor_frames]
    h = min(c.shape[0] for c in cams)
    row = np.concatenate([c[:h] for c in cams], axis=1)
    row = np.pad(row, ((0, 0), (0, w - row.shape[1]), (0, 0)))
    return np.concatenate([top, row], axis=0)


def run_task(env_id: str, out: Path, seed: int, shader: str, max_steps: int, video: bool) -> dict:
    import gymnasium as gym
    import imageio.v2 as imageio

    import realm_ms  # noqa: F401
    from realm_ms.expert import make_expert

    env = gym.make(
        env_id,
        obs_mode="rgb" if video else "state",
        render_mode="rgb_array" if video else None,
        shader=shader,
        max_episode_steps=max_steps,
    )
    u = env.unwrapped
    obs, info = env.reset(seed=seed)
    expert = make_expert(env)
    stages = list(u.tracker.stages)
    latched: dict[str, int | None] = {s.value: None for s in stages}
    frames = []
    t0 = time.perf_counter()
    steps = 0
    for steps in range(1, max_steps + 1):
        obs, _, term, trunc, info = env.step(expert.act(obs))
        for s in stages:
            if latched[s.value] is None and bool(info[f"stage_{s.value.lower()}"][0]):
                latched[s.value] = steps
        if video:
            cams = [obs["sensor_data"][c]["rgb"][0].cpu().numpy() for c in ("exterior_1", "exterior_2", "wrist")]
            frames.append(_tile(env.render()[0].cpu().numpy(), cams))
        if bool(term[0]) or bool(trunc[0]):
            break
    result = {
        "env_id": env_id,
        "instruction": u.instruction,
        "skill": u.task_spec.skill,
        "seed": seed,
        "progression": float(info["progression"][0]),
        "success": bool(info["success"][0]),
        "stalled_stage": u.stalled_stage()[0],
        "stages_latched_at_step": latched,
        "steps": steps,
        "wall_s": round(time.perf_counter() - t0, 2),
    }
    if video:
        path = out / f"{env_id}.mp4"
        imageio.mimwrite(path, frames, fps=15, macro_block_size=8)
        result["video"] = str(path)
    env.close()
    return result


def _write_markdown(summary: dict, path: Path) -> None:
    lines = ["| task | skill | progression | success | stalled at | steps | stages (step latched) |", "|---|---|---|---|---|---|---|"]
    for r in summary.values():
        st = ", ".join(f"{k}@{v}" if v is not None else f"{k}:-" for k, v in r["stages_latched_at_step"].items())
        lines.append(f"| {r['env_id']} | {r['skill']} | {r['progression']:.2f} | {r['success']} | {r['stalled_stage']} | {r['steps']} | {st} |")
    path.write_text("\n".join(lines) + "\n")


def run(args) -> int:
    from rich.progress import track

    from realm_ms.cli import UserError
    from realm_ms.tasks import TASKS

    env_ids = sorted(TASKS) if args.tasks == "all" else [t.strip() for t in args.tasks.split(",") if t.strip()]
    unknown = [t for t in env_ids if t not in TASKS]
    if unknown:
        raise UserError(f"unknown task(s) {unknown}; available: {sorted(TASKS)}")
    args.out.mkdir(parents=True, exist_ok=True)
    summary_path = args.out / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.exists() and not args.force else {}
    todo = [t for t in env_ids if t not in summary]
    for env_id in track(todo, description="demo episodes"):
        summary[env_id] = run_task(env_id, args.out, args.seed, args.shader, args.max_steps, not args.no_video)
        summary_path.write_text(json.dumps(summary, indent=2))  # incremental: an interrupted demo resumes
        r = summary[env_id]
        print(f"{env_id}: progression {r['progression']:.2f} success {r['success']} ({r['steps']} steps, {r['wall_s']} s)")
    _write_markdown({k: summary[k] for k in env_ids}, args.out / "summary.md")
    print((args.out / "summary.md").read_text())
    print(f"videos and summary in {args.out}/")
    return 0
