"""``realm perturbations``: list the 16 perturbation settings; draw a contact sheet of a task under each.

    realm perturbations list [--json]
    realm perturbations sheet --task REALM-PickApple-v1 --out sheet.png [--seed 0] [--width 320 --height 180]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("perturbations", help="REALM's perturbations: list them, render a contact sheet")
    sub = p.add_subparsers(dest="perturbations_command", metavar="ACTION")
    ls = sub.add_parser("list", help="the 16 perturbation settings with what they change and their ranges")
    ls.add_argument("--json", action="store_true", help="machine-readable output")
    ls.set_defaults(func=_list)
    sh = sub.add_parser("sheet", help="one image per perturbation (exterior + wrist camera) for a task")
    sh.add_argument("--task", action="append", required=True, help="env id (repeat for several; 'all' for every task)")
    from realm_ms.rendering import SHADERS  # the one shader table
    from realm_ms.validate import integer, seed

    sh.add_argument("--out", required=True, help="PNG (or JPEG) path (with several tasks: one file per task, the id appended)")
    sh.add_argument("--seed", type=seed(), default=0, help="seed of the perturbation draws, an integer in [0, 2**32) (default 0)")
    sh.add_argument("--width", type=integer(16, 4096), default=320, help="image width per tile in pixels, 16-4096 (default 320)")
    sh.add_argument("--height", type=integer(16, 4096), default=180, help="image height per tile in pixels, 16-4096 (default 180)")
    sh.add_argument("--shader", default="default", choices=SHADERS,
                    help="default (raster) | rt | rt-med | rt-fast | minimal (default: default)")
    sh.set_defaults(func=_sheet)
    p.set_defaults(func=lambda a: (p.print_help(), 2)[1])


def _rows() -> list[dict]:
    from realm_ms.perturbations import all_perturbations

    return [p.describe() for p in all_perturbations()]


def _list(args) -> int:
    rows = _rows()
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    import shutil
    import textwrap

    # the "changes" and "ranges" columns wrap to the terminal (never cut): 27 columns of id/name/when
    width = max(100, shutil.get_terminal_size((120, 24)).columns)
    wc = (width - 28) // 2
    print(f"{'id':>2s}  {'name':9s} {'when':12s} {'changes':{wc}s} ranges")
    for r in rows:
        changes = textwrap.wrap(r["acts_on"], wc, break_on_hyphens=False) or [""]
        ranges = textwrap.wrap(str(r["ranges"]), width - 28 - wc, break_on_hyphens=False) or [""]
        for k in range(max(len(changes), len(ranges))):
            head = f"{r['id']:2d}  {r['name']:9s} {r['when']:12s}" if k == 0 else " " * 26
            c = changes[k] if k < len(changes) else ""
            g = ranges[k] if k < len(ranges) else ""
            print(f"{head} {c:{wc}s} {g}".rstrip())
    return 0


def _sheet(args) -> int:
    from realm_ms.errors import UserError

    import realm_ms

    realm_ms.register_envs()
    from realm_ms.tasks import TASKS

    from realm_ms.validate import check_output_path

    tasks = sorted(TASKS) if "all" in args.task else list(dict.fromkeys(args.task))  # a task given twice is one sheet
    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise UserError(f"unknown task {unknown[0]!r}; known: {', '.join(sorted(TASKS))}")
    out = Path(args.out)
    check_output_path(out, "--out", "file", example="sheet.png")
    if out.suffix.lower() not in (".png", ".jpg", ".jpeg"):
        raise UserError(f"--out {out}: the sheet is an image; give a .png (or .jpg) path")
    paths = [out if len(tasks) == 1 else out.with_name(f"{out.stem}_{task}{out.suffix}") for task in tasks]
    for path in paths:  # all of them before the first (slow) render
        check_output_path(path, "--out", "file", example="sheet.png")
    out.parent.mkdir(parents=True, exist_ok=True)
    for task, path in zip(tasks, paths):
        # a user catalog too small for a perturbation raises common.CatalogTooSmall (an InputError): one line
        contact_sheet(task, path, seed=args.seed, size=(args.width, args.height), shader=args.shader)
        print(f"wrote {path}")
    return 0


def contact_sheet(task: str, path: Path, seed: int = 0, size=(320, 180), shader: str = "default") -> None:
    """A 4 x 4 grid: each tile is the exterior_1 and wrist images of one perturbation (same seed)."""
    import gymnasium as gym
    import numpy as np
    from PIL import Image, ImageDraw
    from tqdm import tqdm

    from realm_ms.perturbations import all_perturbations

    w, h = size
    env = gym.make(task, obs_mode="rgb", camera_width=w, camera_height=h, shader=shader)
    label_h = 34
    cols = 4
    perts = all_perturbations()
    sheet = Image.new("RGB", (cols * 2 * w, (len(perts) + cols - 1) // cols * (h + label_h)), "white")
    draw = ImageDraw.Draw(sheet)
    try:
        for k, p in enumerate(tqdm(perts, desc=task, leave=False)):
            obs, info = env.reset(seed=seed, options={"perturbation": p.name})
            ext = obs["sensor_data"]["exterior_1"]["rgb"][0].cpu().numpy()
            wrist = obs["sensor_data"]["wrist"]["rgb"][0].cpu().numpy()
            tile = np.concatenate([ext, wrist], axis=1).astype(np.uint8)
            x, y = (k % cols) * 2 * w, (k // cols) * (h + label_h)
            sheet.paste(Image.fromarray(tile), (x, y + label_h))
            draw.text((x + 4, y + 2), f"{p.pid} {p.name}", fill="black")
            draw.text((x + 4, y + 17), info["perturbation"]["instruction"][0][: 2 * w // 6], fill=(60, 60, 160))
    finally:
        env.close()
    sheet.save(path)
