"""Seconds per control step of REALM-PickApple-v1 with its three cameras, per shader and resolution.

    python bench/render_rate.py [--rows default@320x180,rt-fast@320x180,rt@1280x720,...]
                                [--steps 5] [--budget-s 120] [--denoiser auto] [--rt-spp N]

Each row: one env (3 cameras: exterior_1, exterior_2, wrist), one warm-up step (shader compilation,
acceleration structures; reported separately), then up to ``--steps`` timed steps or until
``--budget-s`` is spent (at least one). ``raster`` at the same size is measured in the same run, so
the ``x raster`` column is a ratio on this machine. The denoiser column is what the
process really uses (``realm_ms.rendering.resolve_denoiser``). ``--rt-spp`` caps ray-tracing samples
(marked in the table). Writes outputs/bench/render_rate.json.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
import warnings
from pathlib import Path

DEFAULT_ROWS = "default@320x180,rt-fast@320x180,rt@320x180,default@1280x720,rt-fast@1280x720,rt@1280x720"


def measure(shader: str, w: int, h: int, steps: int, budget_s: float, denoiser: str) -> dict:
    import gymnasium as gym
    import torch

    import realm_ms  # noqa: F401

    env = gym.make("REALM-PickApple-v1", obs_mode="rgb", shader=shader, denoiser=denoiser, camera_width=w, camera_height=h,
                   control_mode="droid_joint_pos")
    u = env.unwrapped
    env.reset(seed=0)
    hold = torch.cat([u.agent.arm_qpos, torch.zeros(u.num_envs, 1, device=u.device)], dim=1)
    t = time.perf_counter()
    env.step(hold)
    warm = time.perf_counter() - t
    times = []
    t_end = time.perf_counter() + budget_s
    while len(times) < steps and (not times or time.perf_counter() < t_end):
        t = time.perf_counter()
        env.step(hold)
        times.append(time.perf_counter() - t)
    env.close()
    return dict(shader=shader, size=f"{w}x{h}", cameras=3, warmup_s=round(warm, 3), steps=len(times),
                s_per_step=round(sum(times) / len(times), 4))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rows", default=DEFAULT_ROWS, help="comma-separated SHADER@WxH")
    p.add_argument("--steps", type=int, default=5)
    p.add_argument("--budget-s", type=float, default=120.0, help="timed seconds per row (after one step)")
    p.add_argument("--denoiser", default="auto")
    p.add_argument("--rt-spp", type=int, default=None, help="cap ray-tracing samples per pixel")
    p.add_argument("--out", type=Path, default=Path("outputs/bench/render_rate.json"))
    args = p.parse_args()

    from realm_ms.rendering import resolve_denoiser, rt_samples_per_pixel
    from realm_ms.validate import output_arg

    output_arg(p, args.out, example="render_rate.json")

    warnings.filterwarnings("ignore", message=".*(env.unwrapped|precision lowered).*")
    den = resolve_denoiser(args.denoiser)
    rows = []
    spp = rt_samples_per_pixel(args.rt_spp) if args.rt_spp else contextlib.nullcontext()
    raster = {}
    with spp:
        for spec in args.rows.split(","):
            shader, size = spec.split("@")
            w, h = (int(v) for v in size.split("x"))
            r = measure(shader, w, h, args.steps, args.budget_s, args.denoiser)
            r["denoiser"] = den if shader.startswith("rt") else "-"
            r["rt_spp_cap"] = args.rt_spp if shader.startswith("rt") else None
            if shader == "default":
                raster[r["size"]] = r["s_per_step"]
            r["x_raster"] = round(r["s_per_step"] / raster[r["size"]], 1) if r["size"] in raster else None
            rows.append(r)
            print(f"{shader:8s} {r['size']:>9s}  {r['s_per_step']:9.3f} s/step  (warm-up {r['warmup_s']:.1f} s, {r['steps']} steps)"
                  f"  denoiser {r['denoiser']}{'  spp<=' + str(args.rt_spp) if r['rt_spp_cap'] else ''}"
                  f"{'  x' + str(r['x_raster']) + ' raster' if r['x_raster'] else ''}", flush=True)
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
