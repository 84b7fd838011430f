"""``realm assets build|stats``: the asset pipeline's command line."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    from asset_pipeline.sources import DEFAULT_SOURCES, SOURCES
    from realm_ms.validate import integer, positive

    p = subparsers.add_parser("assets", help="build and inspect the object catalog", description=__doc__)
    sub = p.add_subparsers(dest="assets_cmd", metavar="VERB")
    p.set_defaults(func=lambda a: (p.print_help(), 2)[1], needs_envs=False)

    names = [n for n in SOURCES if n != "folder"]
    b = sub.add_parser("build", help="process mesh sources into a simulation-ready catalog")
    b.add_argument("--source", action="append", default=[], metavar="SRC",
                   help=f"{' | '.join(names)} | NAME=PATH (a source's files at PATH) | a folder of meshes "
                        "(repeatable; `--all` = every installed one)")
    b.add_argument("--all", action="store_true",
                   help=f"every default source that is installed ({', '.join(DEFAULT_SOURCES)})")
    b.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="catalog directory (default: $REALM_ASSETS_DIR or ~/.cache/realm_ms/catalog)")
    b.add_argument("--workers", type=integer(1), default=max(1, (__import__("os").cpu_count() or 1)), metavar="N",
                   help="parallel worker processes, integer >= 1 (default: CPU count)")
    b.add_argument("--variants", type=integer(1), default=None, metavar="N",
                   help="procedural objects per category, integer >= 1 (default 40)")
    b.add_argument("--limit", type=integer(1), default=None, metavar="N",
                   help="at most N objects per source, integer >= 1 (smoke tests; default: all)")
    b.add_argument("--timeout", type=positive("s"), default=None, metavar="SECONDS",
                   help="per-object wall-clock limit in s, > 0 (default 240)")
    b.add_argument("--coacd-budget", type=positive("s"), default=None, metavar="SECONDS",
                   help="CoACD time budget per object in s before the convex-hull fallback, > 0 (default 60)")
    b.add_argument("--no-coacd", action="store_true", help="convex hulls instead of CoACD (fast, coarse)")
    b.add_argument("--no-thumbnails", action="store_true", help="skip the 128 px thumbnail per object")
    b.add_argument("--ray", action="store_true", help="run objects as Ray tasks")
    b.add_argument("--ray-address", default=None, metavar="HOST:PORT",
                   help="connect to an existing Ray cluster (implies --ray)")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.add_argument("--json", action="store_true", help="print the build report as JSON on stdout")
    b.set_defaults(func=_build)

    s = sub.add_parser("stats", help="counts by category/source/seen-unseen and a contact sheet")
    s.add_argument("catalog", nargs="?", type=Path, default=None, metavar="CATALOG",
                   help="catalog directory (default: $REALM_ASSETS_DIR or ~/.cache/realm_ms/catalog)")
    s.add_argument("--json", action="store_true", help="print machine-readable counts on stdout")
    s.add_argument("--sheet", type=Path, default=None, metavar="FILE.png",
                   help="contact sheet path (default: CATALOG/contact_sheet.png)")
    s.add_argument("--no-sheet", action="store_true", help="skip the contact sheet")
    s.set_defaults(func=_stats)


def _build(args: argparse.Namespace) -> int:
    from realm_ms.errors import UserError

    from asset_pipeline.build import SourceUnavailable, build_catalog, default_sources
    from asset_pipeline.config import BuildConfig
    from asset_pipeline.stages.decompose import CoacdSettings
    from realm_ms.assets.paths import default_catalog_dir

    if not args.source and not args.all:
        raise UserError("give --source SRC (repeatable) or --all")
    from realm_ms.validate import check_output_dir

    out = check_output_dir(args.out or default_catalog_dir(), "--out")
    cfg = BuildConfig(workers=args.workers, use_coacd=not args.no_coacd, thumbnails=not args.no_thumbnails)
    if args.variants is not None:
        cfg.procedural_variants = args.variants
    if args.timeout is not None:
        cfg.object_timeout_s = args.timeout
    if args.coacd_budget is not None:
        cfg.coacd = CoacdSettings(budget_s=args.coacd_budget)
    sources = list(args.source) + (default_sources() if args.all else [])
    try:
        rep = build_catalog(sources, out, cfg, ray=args.ray or bool(args.ray_address), ray_address=args.ray_address,
                            limit_per_source=args.limit, strict=not args.all, progress=not args.quiet)
    except SourceUnavailable as e:
        raise UserError(str(e)) from None
    if rep.total == 0:  # an empty folder, or every source skipped: not a success with "0 built"
        from asset_pipeline.sources.folder import MESH_EXTS

        skipped = "; ".join(f"{k}: {v}" for k, v in rep.skipped_sources.items())
        raise UserError(f"no objects found in {', '.join(map(str, sources))}; nothing was built"
                        + (f" (skipped {skipped})" if skipped else f" (a folder source needs mesh files: {' '.join(MESH_EXTS)})"))
    d = {**rep.__dict__, "objects_per_minute": round(rep.objects_per_minute, 1)}
    if args.json:
        print(json.dumps(d))
    else:
        for k, v in rep.skipped_sources.items():
            print(f"skipped source {k}: {v}")
        print(f"{rep.total} objects -> {out}: {rep.built} built, {rep.cached} cached, {rep.failed} failed "
              f"in {rep.seconds:.1f} s ({rep.objects_per_minute:.0f} built/min, {rep.workers} {rep.backend} workers)")
        if rep.failed:
            print(f"failure report: {out / 'failures.jsonl'}")
    return 0 if rep.failed == 0 or rep.built + rep.cached > 0 else 1


def _stats(args: argparse.Namespace) -> int:
    from realm_ms.errors import UserError

    from asset_pipeline.record import CATALOG_FILE, read_catalog
    from asset_pipeline.stats import catalog_stats, contact_sheet
    from realm_ms.assets.paths import ENV_CATALOG, default_catalog_dir

    root = args.catalog or default_catalog_dir()
    if args.sheet is not None and not args.no_sheet:
        from realm_ms.validate import check_output_file

        check_output_file(args.sheet, "--sheet")
    if not (root / CATALOG_FILE).exists():
        raise UserError(f"no catalog at {root} (set ${ENV_CATALOG} or run `realm assets build --all --out {root}`)")
    recs = read_catalog(root)
    st = catalog_stats(recs)
    if not args.no_sheet:
        sheet = args.sheet or root / "contact_sheet.png"
        st["contact_sheet"] = str(sheet) if contact_sheet(root, recs, sheet) else None
    if args.json:
        print(json.dumps(st))
        return 0
    print(f"catalog {root}: {st['objects']} objects, {st['categories']} categories, {st['real_mesh_objects']} from real meshes "
          f"({st['unique_real_shapes']} unique shapes), "
          f"{st['unseen_objects']} unseen ({st['unseen_categories']} categories), {st['textured_objects']} textured")
    print("by source:      " + ", ".join(f"{k} {v}" for k, v in st["by_source"].items()))
    print("decomposition:  " + ", ".join(f"{k} {v}" for k, v in st["by_decomposition"].items()))
    print("by category:")
    items = list(st["by_category"].items())
    for i in range(0, len(items), 4):
        print("  " + "".join(f"{k[:22]:22s}{v:5d}   " for k, v in items[i : i + 4]))
    if st.get("contact_sheet"):
        print(f"contact sheet: {st['contact_sheet']}")
    return 0
