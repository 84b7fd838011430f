"""Wall time of the sysid loop: diagnose + fit for one hidden effect on 10 trajectories x 10 s at
15 Hz (7 train / 3 held-out), CPU (goal < 3 min on a 2-core machine) and, where CUDA exists, with
the GPU-parallel population (speed-up recorded).

    python bench/sysid.py [--hidden coulomb_friction:fc=0.3] [--workers N] [--device cpu|cuda|both]
                          [--engine physx|mujoco] [--noise 2e-4] [--out outputs/bench_sysid.json]
    python bench/sysid.py --sweep [--engine mujoco] [--jobs N] [--noise 1e-4] [--out sweep.json]
    python bench/sysid.py --auto [--hidden ...] [--engine mujoco]   # `realm sysid auto` wall time (goal < 5 min)
    python bench/sysid.py --torque [--hidden frictionloss]             # `auto` on 10 x 10 s MuJoCo-native torque logs
    python bench/sysid.py --droid-auto [--hidden SPEC] [--size 7,3,10] [--engine physx|mujoco]

    python bench/sysid.py --native-sweep [--space torque|position] [--size 3,2,6] [--seeds 0,1,2] [--effects ...]
    python bench/sysid.py --friction-laws [--size 3,2,6] [--seeds 0,1,2]  # which friction law fits which

``--native-sweep``: ``auto`` on every MuJoCo-native variant (``reference_native.VARIANTS``), torque
or position space, one row per variant and seed to ``--out`` (JSON) and ``.md``.

``--friction-laws``: for MuJoCo-native data whose friction is MuJoCo's ``frictionloss``, Gaz et
al.'s sigmoid or LuGre, torque-space ``fit`` of each friction combination (``FRICTION_FITS``):
held-out residual / noise floor, to ``--out`` (JSON) and ``.md``.

``--auto`` times ``realm sysid auto`` (diagnose -> fit -> re-diagnose ...) on the same 10 x 10 s data;
``--torque`` does so in torque space on 1 kHz torque logs from ``synth --engine mujoco-native``.

``--droid-auto``: `auto` on DROID-format episodes (``synth_droid``: Cartesian commands, the joint
target rebuilt from the measured state, as on real DROID logs) of a robot with a hidden command delay
and softer gains, twice in one run: with the defaults, and as before the search budget, the
look-alike rule and auto's CMA-ES patience (all train data, every unscreened look-alike fitted,
patience 6; the engine's per-chunk trimming applies to both); prints both wall and CPU times and
their ratio, each run's verdict and its final error against the floor.

``--engine mujoco`` makes the data with the independent MuJoCo reference (same URDF and law, 1 kHz
controller on a converged plant) instead of the replay simulator itself: sysid on data it did not make.

``--sweep``: the hidden-effect sweep (``realm_ms/sysid/sweep.py``: 8 effects x 3 seeds + no effect,
synth + diagnose + fit each, ``--jobs`` processes, one core each; ~5 min per case on one core) to
``--out`` (JSON) and the same name with ``.md`` (markdown table).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path


def run(device: str, workers: int, data: Path, hidden: str) -> dict:
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.diagnose import diagnose
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.fit import FitConfig, fit

    train, held = load_split(data)
    ev = Evaluator(workers=workers, device=device)
    t0 = time.perf_counter()
    d = diagnose(train, held, evaluator=ev, log=lambda m: print("  " + m, file=sys.stderr))
    t1 = time.perf_counter()
    name = d.suspects[0].effect
    f = fit(train, held, config=FitConfig(add=name), evaluator=ev, progress=True, log=lambda m: print("  " + m, file=sys.stderr))
    t2 = time.perf_counter()
    prof = ev.sim.profile.summary() if ev._sim is not None else f"{workers} worker processes"
    ev.close()
    return {"device": device, "workers": workers, "diagnose_s": t1 - t0, "fit_s": t2 - t1, "total_s": t2 - t0,
            "top_suspect": name, "hidden": hidden, "heldout_before_rad": f.before["heldout_rmse_rad"],
            "heldout_after_rad": f.after["heldout_rmse_rad"], "noise_floor_rad": d.noise_floor,
            "generations": len(f.history), "params": f.params, "profile": prof}


def run_auto(args, data: Path, space: str) -> dict:
    from realm_ms.sysid import api
    from realm_ms.sysid.auto import step_label

    t0 = time.perf_counter()
    a = api.auto(str(data), workers=args.workers, device="cpu", log=lambda m: print("  " + m, file=sys.stderr),
                 space=space).to_json()
    wall = time.perf_counter() - t0
    r = {"mode": f"auto ({space} space)", "hidden": args.hidden, "wall_s": wall, "unit": a["unit"],
         "nominal": a["nominal_heldout_rmse"], "steps": [(step_label(s), s["heldout_rmse"]) for s in a["steps"]],
         "final": a["final"], "workers": args.workers, "cpu_count": os.cpu_count(), "load": os.getloadavg()}
    chain = " -> ".join([f"{r['nominal']:.3g}"] + [f"{e} {v:.3g}" for e, v in r["steps"]])
    print(f"auto ({space}): {chain} {a['unit']}; final {a['final']['verdict']} (noise floor "
          f"{a['final']['noise_floor']:.3g}); {wall:.0f} s wall, {args.workers} worker(s), load {r['load'][0]:.1f}; goal < 300 s: "
          f"{'met' if wall < 300 else 'NOT met'}")
    return r


#: the DROID-format bench's hidden robot: a command pipeline delay and softer gains
DROID_HIDDEN = "latency:delay=0.06,gain_mismatch:stiffness_error=-0.3,damping_error=0.2"


def run_droid_auto(args) -> int:
    """``auto`` on synthetic DROID-format episodes, as it runs now and as it ran before the search
    budget, the look-alike rule and the shorter CMA-ES patience, in one run (same data, same machine
    load). Each run is its own process, so its CPU time includes its worker processes'."""
    import resource
    import subprocess

    from realm_ms.sysid import api
    from realm_ms.sysid.auto import step_label

    hidden = args.hidden if args.hidden != "coulomb_friction:fc=0.3" else DROID_HIDDEN
    n_train, n_held, secs = (float(x) for x in args.size.split(","))
    # (1e9: every unscreened look-alike is fitted; the config is written into the run's code as a repr)
    modes = {"now": {}, "before": {"search_s": None, "unscreened_within": 1e9, "patience": 6}}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        api.synth_droid(hidden, tmp, seed=args.seed, noise_rad=args.noise, engine=args.engine, n_train=int(n_train),
                        n_heldout=int(n_held), duration_s=secs)
        for mode, config in modes.items():
            code = ("import json, sys; from realm_ms.sysid import api\n"
                    f"a = api.auto({str(Path(tmp) / 'npz')!r}, workers={args.workers}, device='cpu', progress=False, "
                    f"log=lambda m: print('  ' + m, file=sys.stderr), **{config!r}).to_json()\n"
                    "print(json.dumps(a, default=float))")
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", code], check=True, stdout=subprocess.PIPE, text=True).stdout
            wall = time.perf_counter() - t0
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
            a = json.loads(out.strip().splitlines()[-1])
            f = a["final"]
            r = {"mode": mode, "config": config, "wall_s": wall, "cpu_s": cpu, "load": os.getloadavg()[0],
                 "verdict": f["verdict"], "nominal_rad": a["nominal_heldout_rmse"], "final_rad": f["heldout_rmse"],
                 "floor_rad": a["details"]["judging_floor"], "steps": [(step_label(s), s["heldout_rmse"]) for s in a["steps"]],
                 "searched_train": a["details"]["searched_train"]}
            rows.append(r)
            chain = " -> ".join([f"{r['nominal_rad']:.3g}"] + [f"{e} {v:.3g}" for e, v in r["steps"]])
            print(f"{mode:>6}: {wall:6.0f} s wall, {cpu:6.0f} s CPU (load {r['load']:.1f}): {chain} rad; "
                  f"{r['verdict']} at {r['final_rad'] / r['floor_rad']:.1f}x the floor {r['floor_rad']:.2e} rad", flush=True)
    ratio = rows[1]["wall_s"] / rows[0]["wall_s"]
    print(f"hidden {hidden}, {args.size} (train, held-out, s), {args.engine}, {args.workers} worker(s): "
          f"before / now = {ratio:.2f}x wall, {rows[1]['cpu_s'] / rows[0]['cpu_s']:.2f}x CPU")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"hidden": hidden, "size": args.size, "engine": args.engine, "runs": rows,
                               "wall_ratio": ratio}, indent=2, default=float))
    return 0


def run_native_sweep(args) -> int:
    """`auto` on every MuJoCo-native variant (reference_native.VARIANTS), in ``args.space``: torque
    logs (t, q, qd, tau) or position logs with the 15 Hz command (q_cmd), both at 1 kHz. Each
    finished case is written at once."""
    from realm_ms.sysid import api
    from realm_ms.sysid.auto import step_label
    from realm_ms.sysid.reference_native import VARIANTS, synth_native

    n_train, n_held, dur = (int(x) for x in args.size.split(","))
    position = args.space == "position"
    unit = "mrad" if position else "N·m"
    scale = 1e3 if position else 1.0
    rows = []
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    quiet = lambda m: print("  " + m, file=sys.stderr)  # noqa: E731
    for seed in (int(x) for x in args.seeds.split(",")):
        for name in (args.effects.split(",") if args.effects else VARIANTS):
            t0 = time.perf_counter()
            with tempfile.TemporaryDirectory() as tmp:
                synth_native(name, Path(tmp), seed=seed, n_train=n_train, n_heldout=n_held, duration_s=float(dur),
                             with_cmd=position)
                a = api.auto(tmp, workers=args.workers, device="cpu", log=quiet, space=args.space).to_json()
            f = a["final"]
            floor = a["details"]["judging_floor"]
            row = {"space": args.space, "variant": name, "spec": VARIANTS[name], "seed": seed,
                   "nominal": a["nominal_heldout_rmse"], "steps": [(step_label(x), x["heldout_rmse"]) for x in a["steps"]],
                   "final": f["heldout_rmse"], "floor": floor, "ratio": f["heldout_rmse"] / floor, "verdict": f["verdict"],
                   "params": a["steps"][-1]["params"] if a["steps"] else {}, "wall_s": time.perf_counter() - t0}
            rows.append(row)
            print(f"{name} seed {seed}: {scale * row['nominal']:.3f} -> "
                  + " -> ".join(f"{e} {scale * v:.3f}" for e, v in row["steps"])
                  + f" {unit}; {row['ratio']:.2f}x floor {scale * floor:.3f}: {row['verdict']} ({row['wall_s']:.0f} s)",
                  flush=True)
            lines = [f"| native variant | seed | nominal [{unit}] | auto steps (held-out after) | final / floor | verdict | wall |",
                     "|---|---|---|---|---|---|---|"]
            for r in rows:
                st = ", ".join(f"{e} ({scale * v:.3f})" for e, v in r["steps"]) or "-"
                lines.append(f"| {r['variant']} | {r['seed']} | {scale * r['nominal']:.3f} | {st} | {scale * r['final']:.3f} / "
                             f"{scale * r['floor']:.3f} = {r['ratio']:.2f}x | {r['verdict']} | {r['wall_s']:.0f} s |")
            out.write_text(json.dumps(rows, indent=2, default=float))
            out.with_suffix(".md").write_text("\n".join(lines) + f"\n\n{args.space} space, {n_train}+{n_held} "
                                              f"trajectories x {dur} s at 1 kHz\n")
    return 0


FRICTION_LAWS = ("frictionloss", "gaz", "lugre")
FRICTION_FITS = ("coulomb_friction", "coulomb_friction,viscous_damping", "stribeck_friction,viscous_damping",
                 "smooth_friction,viscous_damping", "lugre_friction")


def run_friction_laws(args) -> int:
    """Torque-space fits of every friction combination on every plant friction law."""
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.fit import FitConfig
    from realm_ms.sysid.reference_native import synth_native
    from realm_ms.sysid.torque.space import TorqueSpace

    n_train, n_held, dur = (int(x) for x in args.size.split(","))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows = []
    for seed in (int(x) for x in args.seeds.split(",")):
        for law in (args.effects.split(",") if args.effects else FRICTION_LAWS):
            with tempfile.TemporaryDirectory() as tmp:
                synth_native(law, Path(tmp), seed=seed, n_train=n_train, n_heldout=n_held, duration_s=float(dur),
                             with_cmd=False)
                train, held = load_split(Path(tmp))
            space = TorqueSpace(train, held)  # its sample sets are built once, for every fit
            for add in FRICTION_FITS:
                t0 = time.perf_counter()
                f = space.fit(config=FitConfig(add=add), log=lambda *a: None).to_json()
                floor = f["noise_floor_nm"]
                row = {"law": law, "seed": seed, "fit": add, "nominal": f["before"]["heldout_rmse_nm"],
                       "after": f["after"]["heldout_rmse_nm"], "floor": floor,
                       "ratio": f["after"]["heldout_rmse_nm"] / floor, "params": f["params"],
                       "wall_s": time.perf_counter() - t0}
                rows.append(row)
                print(f"{law} seed {seed} + {add}: {row['nominal']:.3f} -> {row['after']:.3f} N·m = "
                      f"{row['ratio']:.2f}x floor {floor:.3f} ({row['wall_s']:.0f} s)", flush=True)
            lines = ["| plant friction | seed | fit | nominal [N·m] | after [N·m] | after / floor |", "|---|---|---|---|---|---|"]
            lines += [f"| {r['law']} | {r['seed']} | {r['fit']} | {r['nominal']:.3f} | {r['after']:.3f} | "
                      f"{r['ratio']:.2f}x |" for r in rows]
            out.write_text(json.dumps(rows, indent=2, default=float))
            out.with_suffix(".md").write_text("\n".join(lines) + f"\n\n{n_train}+{n_held} trajectories x {dur} s at 1 kHz\n")
    return 0


def run_sweep(args) -> int:
    from realm_ms.sysid.sweep import SWEEP_EFFECTS, CaseResult, judge, markdown, sweep

    t0 = time.perf_counter()
    effects = tuple(args.effects.split(",")) if args.effects else SWEEP_EFFECTS
    seeds = tuple(int(s) for s in args.seeds.split(","))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    finished: list[dict] = []
    if out.exists() and not args.fresh:  # resume: the cases an earlier run of the same sweep finished
        old = json.loads(out.read_text())
        same = old.get("summary", {}).get("engine") == args.engine and old["summary"].get("noise_rad") == args.noise
        if not same:
            raise SystemExit(f"{out} holds a sweep with other settings ({old.get('summary')}); pass --fresh to overwrite it "
                             "or choose another --out")
        fields = set(CaseResult.__dataclass_fields__)
        finished = [{k: v for k, v in r.items() if k in fields} for r in old["rows"]
                    if r["effect"] in (*effects, "none") and r["seed"] in seeds]
        print(f"resuming {out}: {len(finished)} case(s) done", file=sys.stderr)
    earlier = [CaseResult(**r) for r in finished]

    def write(rows, failed, complete: bool) -> str:
        wall = time.perf_counter() - t0
        table = markdown(rows)
        summary = {"engine": args.engine, "noise_rad": args.noise, "jobs": args.jobs or os.cpu_count(), "wall_s": wall,
                   "complete": complete, "passed": sum(bool(r.passed) for r in rows), "cases": len(rows) + len(failed),
                   "failed_to_run": failed}
        out.write_text(json.dumps({"summary": summary, "rows": [r.__dict__ for r in rows]}, indent=2, default=float))
        out.with_suffix(".md").write_text(f"{table}\n\n{summary['passed']}/{summary['cases']} pass; {wall:.0f} s wall, "
                                          f"{summary['jobs']} jobs, engine {args.engine}, noise {args.noise} rad"
                                          f"{'' if complete else ' (INCOMPLETE: cut off)'}\n")
        return table

    def done(r: dict) -> None:  # each finished case is written at once: a run cut off keeps what it did
        print(f"[{time.perf_counter() - t0:6.0f} s] {r['effect']} seed {r['seed']}: "
              + (r["error"] if "error" in r else f"ranked {r['ranked']}, after {r['heldout_after_rad']}"),
              file=sys.stderr, flush=True)
        finished.append(r)
        write(judge([CaseResult(**x) for x in finished if "error" not in x]), [x for x in finished if "error" in x], False)

    rows, failed = sweep(effects, seeds, args.engine, args.noise, args.jobs, on_row=done, done=earlier)
    table = write(rows, failed, True)
    print(table)
    print(f"{sum(bool(r.passed) for r in rows)}/{len(rows) + len(failed)} pass in {time.perf_counter() - t0:.0f} s; "
          f"failed to run: {failed}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hidden", default="coulomb_friction:fc=0.3")
    ap.add_argument("--workers", type=int, default=None,
                    help="CPU worker processes (default: what `realm sysid` uses, $REALM_SYSID_WORKERS or min(2, "
                         "cores); the sweeps run $REALM_SYSID_WORKERS or one per case, --jobs cases side by side)")
    ap.add_argument("--device", choices=["cpu", "cuda", "both"], default="both")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--engine", choices=["physx", "mujoco"], default="physx", help="what makes the data")
    ap.add_argument("--noise", type=float, default=2e-4, help="sensor noise std, rad")
    ap.add_argument("--out", default="outputs/bench_sysid.json", help="results JSON file (not a folder)")
    ap.add_argument("--sweep", action="store_true", help="the hidden-effect sweep (8 effects x 3 seeds + none)")
    ap.add_argument("--jobs", type=int, default=None, help="--sweep: parallel cases (default: all cores)")
    ap.add_argument("--seeds", default="0,1,2", help="--sweep: comma-separated seeds")
    ap.add_argument("--effects", default=None, help="--sweep: comma-separated effects (default: the 8 of the sweep)")
    ap.add_argument("--fresh", action="store_true", help="--sweep: ignore the cases an earlier run left in --out")
    ap.add_argument("--auto", action="store_true", help="time `realm sysid auto` (position space)")
    ap.add_argument("--torque", action="store_true", help="time `auto` in torque space on MuJoCo-native torque logs")
    ap.add_argument("--native-sweep", action="store_true", help="`auto` on every MuJoCo-native variant (--space)")
    ap.add_argument("--space", choices=["torque", "position"], default="torque",
                    help="--native-sweep: torque logs, or position logs with the 15 Hz command")
    ap.add_argument("--size", default="7,3,10", help="--native-sweep, --friction-laws: train,heldout,seconds per trajectory")
    ap.add_argument("--droid-auto", action="store_true",
                    help="`auto` on DROID-format episodes with a hidden delay and softer gains, now and as before")
    ap.add_argument("--friction-laws", action="store_true",
                    help="torque-space fits of friction combinations on frictionloss / Gaz / LuGre plants")
    args = ap.parse_args()
    if args.workers is None:  # the timings measure what a user's `realm sysid` runs; a sweep case gets one core
        from realm_ms.sysid.engine import default_workers

        sweeping = args.sweep or args.native_sweep or args.friction_laws
        args.workers = int(os.environ.get("REALM_SYSID_WORKERS", 1)) if sweeping else default_workers()
    from realm_ms.validate import output_arg

    output_arg(ap, args.out, example="bench_sysid.json")  # before hours of fitting, not when writing
    if args.friction_laws:
        return run_friction_laws(args)
    if args.droid_auto:
        return run_droid_auto(args)
    if args.sweep:
        return run_sweep(args)
    if args.native_sweep:
        return run_native_sweep(args)
    if args.auto or args.torque:
        with tempfile.TemporaryDirectory() as tmp:
            data = Path(tmp) / "data"
            if args.torque:
                from realm_ms.sysid.reference_native import synth_native

                hidden = args.hidden if args.hidden != ap.get_default("hidden") else "frictionloss"
                args.hidden = hidden
                synth_native(hidden, data, seed=args.seed, n_train=7, n_heldout=3, duration_s=10.0, with_cmd=False)
            else:
                from realm_ms.sysid.synth import SynthConfig, synth

                synth(args.hidden, data, SynthConfig(seed=args.seed, n_train=7, n_heldout=3, duration_s=10.0,
                                                     rate_hz=15.0, noise_rad=args.noise, engine=args.engine))
            r = run_auto(args, data, "torque" if args.torque else "position")
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(r, indent=2, default=float))
        return 0
    import torch

    from realm_ms.sysid.synth import SynthConfig, synth

    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "data"
        synth(args.hidden, data, SynthConfig(seed=args.seed, n_train=7, n_heldout=3, duration_s=10.0, rate_hz=15.0,
                                             noise_rad=args.noise, engine=args.engine))
        devices = ["cpu", "cuda"] if args.device == "both" else [args.device]
        devices = [d for d in devices if d == "cpu" or torch.cuda.is_available()]
        results = [dict(run(d, args.workers, data, args.hidden), engine=args.engine) for d in devices]
    cpu = next((r for r in results if r["device"] == "cpu"), None)
    for r in results:
        print(f"data from {r['engine']}; {r['device']:>4} (workers={r['workers']}): diagnose {r['diagnose_s']:.1f} s + fit {r['fit_s']:.1f} s = "
              f"{r['total_s']:.1f} s; top suspect {r['top_suspect']}; held-out {r['heldout_before_rad']:.2e} -> "
              f"{r['heldout_after_rad']:.2e} rad (noise floor {r['noise_floor_rad']:.2e}); {r['profile']}")
        if cpu and r["device"] == "cuda":
            r["speedup_vs_cpu"] = cpu["total_s"] / r["total_s"]
            print(f"GPU speed-up vs CPU: {r['speedup_vs_cpu']:.2f}x")
    if cpu:
        print(f"goal < 180 s on CPU: {'met' if cpu['total_s'] < 180 else 'NOT met'} ({cpu['total_s']:.0f} s)")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
