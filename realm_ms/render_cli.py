"""``realm render sheet``: what a policy sees, at a glance: every task x shader x camera in one image.

    realm render sheet --out sheet.png                       # all 11 tasks, default + rt-fast + rt
    realm render sheet --out s.png --tasks REALM-PickApple-v1 --shaders default --size 320x180
    realm render sheet --out s.png --rt-spp 4                # cheaper ray tracing (CPU previews)

Rows are tasks (reset with ``--seed``), columns are shader x {exterior_1, exterior_2, wrist}; each
tile is labelled. The sheet is rewritten after every task, so a long run can be watched.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from realm_ms.rendering import CAMERA_UIDS as CAMERAS


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must be WIDTHxHEIGHT (e.g. 160x90), got {text!r}") from None
    if not (16 <= w <= 4096 and 16 <= h <= 4096):
        raise argparse.ArgumentTypeError(f"size {w}x{h} out of range (16..4096 pixels per side)")
    return w, h


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    from realm_ms.validate import integer

    p = subparsers.add_parser("render", help="render contact sheets of the tasks' cameras", description=__doc__,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="render_cmd", metavar="VERB")
    p.set_defaults(func=lambda a: (p.print_help(), 2)[1], needs_envs=False)
    s = sub.add_parser("sheet", help="every task x shader x camera in one PNG")
    s.add_argument("--out", type=Path, required=True, metavar="PNG", help="output image (.png)")
    s.add_argument("--tasks", nargs="+", default=None, metavar="ENV_ID", help="tasks (default: all REALM tasks)")
    s.add_argument("--shaders", nargs="+", default=["default", "rt-fast", "rt"], metavar="SHADER",
                   help="shaders: default | rt-fast | rt-med | rt | minimal (default: default rt-fast rt)")
    s.add_argument("--denoiser", default="auto", help="ray-tracing denoiser: auto | optix | oidn | none (default auto)")
    s.add_argument("--size", type=_size, default=(160, 90), metavar="WxH", help="tile size in pixels (default 160x90)")
    s.add_argument("--seed", type=integer(0), default=0, help="episode seed of every task (default 0)")
    s.add_argument("--rt-spp", type=integer(1), default=None, metavar="N",
                   help="cap ray-tracing samples per pixel (default: the shader's own; 4 is a quick CPU preview)")
    s.set_defaults(func=run_sheet, needs_envs=True)


def run_sheet(args) -> int:
    from realm_ms.errors import UserError
    from realm_ms.rendering import DENOISERS, SHADERS
    from realm_ms.tasks import TASKS

    tasks = args.tasks or sorted(TASKS)
    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise UserError(f"unknown task(s) {', '.join(unknown)}; known: {', '.join(sorted(TASKS))}")
    bad = [s for s in args.shaders if s not in SHADERS]
    if bad:
        raise UserError(f"unknown shader(s) {', '.join(bad)}; choose from {', '.join(SHADERS)}")
    if args.denoiser not in DENOISERS:
        raise UserError(f"unknown denoiser {args.denoiser!r}; choose from {', '.join(DENOISERS)}")
    if args.out.suffix.lower() != ".png":
        raise UserError(f"--out must be a .png file, got {args.out}")
    from realm_ms.validate import check_output_file

    check_output_file(args.out, "--out")  # before minutes of rendering
    try:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_bytes(b"")  # really writable (the sheet is rewritten after every task)
    except OSError as e:
        raise UserError(f"--out: cannot write {args.out} ({e.strerror})") from None
    render_sheet(tasks, args.shaders, args.out, size=args.size, seed=args.seed, denoiser=args.denoiser, rt_spp=args.rt_spp)
    print(f"wrote {args.out} ({len(tasks)} tasks x {len(args.shaders)} shaders x {len(CAMERAS)} cameras)")
    return 0


def render_frames(task: str, shader: str, size=(160, 90), seed: int = 0, denoiser: str = "auto") -> dict:
    """{camera: HxWx3 uint8} of ``task`` right after ``reset(seed)``."""
    import gymnasium as gym

    env = gym.make(task, obs_mode="rgb", shader=shader, denoiser=denoiser, camera_width=size[0], camera_height=size[1])
    try:
        obs, _ = env.reset(seed=seed)
        return {c: obs["sensor_data"][c]["rgb"][0].cpu().numpy() for c in CAMERAS}
    finally:
        env.close()


def render_sheet(tasks, shaders, out: Path, size=(160, 90), seed: int = 0, denoiser: str = "auto", rt_spp: int | None = None):
    """Render the sheet (see module doc); returns the PIL image."""
    import contextlib
    import warnings

    from PIL import Image, ImageDraw
    from tqdm import tqdm

    from realm_ms.rendering import DenoiserUnavailable, rt_samples_per_pixel

    w, h = size
    label_w, head_h = 150, 16
    cols = [(s, c) for s in shaders for c in CAMERAS]
    sheet = Image.new("RGB", (label_w + w * len(cols), head_h + h * len(tasks)), (24, 24, 24))
    draw = ImageDraw.Draw(sheet)
    for j, (s, c) in enumerate(cols):
        draw.text((label_w + j * w + 3, 2), f"{s} {c.replace('exterior_', 'ext')}", fill=(230, 230, 230))
    spp = rt_samples_per_pixel(rt_spp) if rt_spp else contextlib.nullcontext()
    with spp, warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*(env.unwrapped|precision lowered).*")
        bar = tqdm(total=len(tasks) * len(shaders), desc="render sheet", unit="env")
        for i, task in enumerate(tasks):
            draw.text((4, head_h + i * h + h // 2 - 6), task.replace("REALM-", "").replace("-v1", ""), fill=(230, 230, 230))
            for k, s in enumerate(shaders):
                try:
                    frames = render_frames(task, s, size, seed, denoiser)
                except DenoiserUnavailable as e:
                    from realm_ms.errors import UserError

                    raise UserError(str(e)) from None
                for m, c in enumerate(CAMERAS):
                    sheet.paste(Image.fromarray(frames[c][..., :3]), (label_w + (k * len(CAMERAS) + m) * w, head_h + i * h))
                bar.update(1)
            sheet.save(out)  # incremental: the sheet so far
        bar.close()
    return sheet
