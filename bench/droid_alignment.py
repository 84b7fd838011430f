"""Closed-loop replay of real DROID episodes: flange error, lag and first-order response b, sim beside real.

    python bench/droid_alignment.py DATA_DIR [--model MODEL.yaml|droid-aligned] [--split heldout|heldin|all]
        [--max-steps N] [--per-lab N] [--episodes N] [--per-episode] [--json OUT.json] [--write-npz DIR]
        [--grid 'target_filter.tau=0.06,0.08;coulomb_friction.fc=0,0.6' [--leave-one-lab-out]]

DATA_DIR: DROID episodes in any format ``realm sysid`` reads (``../shared/droid_real``: ``index.json`` +
``episodes/*.npz`` with ``t``, ``q`` and ``cartesian_position_cmd``), read by
``realm_ms.sysid.alignment.read_droid_episodes`` (episodes that fail to read or validate are set
aside with a warning). The split is ``realm_ms.sysid.alignment.heldout_split``.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from realm_ms.errors import UserError


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data")
    ap.add_argument("--model", default=None, help="robot model file or name (default: the nominal robot)")
    ap.add_argument("--split", choices=("heldout", "heldin", "all"), default="all")
    ap.add_argument("--max-steps", type=int, default=0, help="only episodes of at most N steps (0 = all): short batches replay fast")
    ap.add_argument("--per-lab", type=int, default=0, help="first N episodes of each lab of the split, by name (0 = all)")
    ap.add_argument("--episodes", type=int, default=0, help="then the first N of those, labs in alphabetical order (0 = all)")
    ap.add_argument("--per-episode", action="store_true")
    ap.add_argument("--grid", default=None, metavar="SPEC",
                    help="search candidates on top of --model: 'effect.param=v1,v2;effect.param=...' (every combination, "
                         "one batch); prints each candidate's overall row, best flange error last")
    ap.add_argument("--leave-one-lab-out", action="store_true",
                    help="with --grid: for each lab, the candidate best on the other labs' episodes and this lab's "
                         "flange error under it (what a lab outside the data should expect)")
    ap.add_argument("--json", default=None)
    ap.add_argument("--write-npz", default=None, metavar="DIR",
                    help="write the selected episodes as the workbench's npz (q_cmd rebuilt from the measured state) instead of replaying them")
    args = ap.parse_args(argv)
    from realm_ms.sysid import alignment
    from realm_ms.sysid.cli import _show_data_warnings

    _show_data_warnings()
    try:
        eps, _ = alignment.read_droid_episodes(args.data)
        held_in, held_out = alignment.heldout_split(eps, alignment.read_labs(alignment.episodes_dir(args.data)))
        eps = {"all": eps, "heldin": held_in, "heldout": held_out}[args.split]
        if args.max_steps:
            eps = [e for e in eps if e.steps <= args.max_steps]
        if args.per_lab:
            eps = [e for lab in sorted({e.lab for e in eps}) for e in sorted((x for x in eps if x.lab == lab), key=lambda x: x.name)[: args.per_lab]]
        if args.episodes:
            eps = eps[: args.episodes]
        if args.write_npz:
            alignment.write_workbench_npz(eps, args.write_npz)
            print(f"wrote {len(eps)} workbench npz files to {args.write_npz}")
            return 0
        if args.grid:
            grid = {k.strip(): [float(x) for x in v.split(",")] for k, v in (item.split("=") for item in args.grid.split(";"))}
            found = sorted(alignment.align_grid(eps, args.model, grid), key=lambda cr: -cr[1].overall.flange_mm)
            for values, res in found:
                r = res.overall
                print(f"{values}: flange {r.flange_mm:.2f} mm, lag {r.lag_sim:.1f} (real {r.lag_real:.1f}), "
                      f"b {r.b_sim:.3f} (real {r.b_real:.3f})")
                if args.per_episode:
                    print("  " + ", ".join(f"{e.name} {e.flange_mm:.1f}" for e in res.episodes))
            if args.leave_one_lab_out:
                rows = alignment.leave_one_lab_out(found)
                for lab, values, mm in rows:
                    print(f"leave {lab} out: {values} chosen on the other labs; {lab}: flange {mm:.2f} mm")
                print(f"leave-one-lab-out: median over labs {np.median([mm for _, _, mm in rows]):.2f} mm")
            if args.json:
                with open(args.json, "w") as f:
                    json.dump([{"values": v, **res.to_dict()} for v, res in found], f, indent=1)
            return 0
        res = alignment.align(eps, args.model, args.model or "nominal")
    except (UserError, ValueError, KeyError, FileNotFoundError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(res.table(args.per_episode))
    print(f"{len(eps)} episodes ({args.split}), {res.seconds:.0f} s")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res.to_dict(), f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
