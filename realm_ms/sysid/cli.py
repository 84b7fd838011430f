"""``realm sysid {effects,excite,synth,compare,diagnose,fit,report}``.

Registered by ``realm_ms/cli.py`` through ``add_parser(subparsers)``; heavy imports stay inside
the handlers. Bad input raises ``realm_ms.cli.UserError`` (one clear message, no traceback).
"""

from __future__ import annotations

import argparse
import json
import sys
from contextlib import contextmanager
from pathlib import Path


def _user_error(msg: str):
    from realm_ms.cli import UserError

    return UserError(msg)


@contextmanager
def _user_input(what: str = ""):
    """Turn errors caused by user input (data, specs, model files) into UserError."""
    from realm_ms.sysid.timeseries import DataError

    try:
        yield
    except DataError as e:
        raise _user_error(str(e)) from None
    except FileNotFoundError as e:
        raise _user_error(f"{what}{e}") from None
    except (ValueError, KeyError) as e:
        raise _user_error(f"{what}{str(e).strip(chr(34))}") from None


def _write_json(path: str | None, data: dict) -> None:
    if not path:
        return
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    clean = {k: v for k, v in data.items() if not k.startswith("_")}
    tmp = p.with_suffix(p.suffix + ".tmp")
    tmp.write_text(json.dumps(clean, indent=2, default=float))
    tmp.replace(p)
    print(f"wrote {p}", file=sys.stderr)


def _common(p: argparse.ArgumentParser, heldout: bool = True) -> None:
    p.add_argument("--model", help="robot model (MODEL.yaml) to start from; default: the nominal DROID robot")
    if heldout:
        p.add_argument("--heldout", help="held-out data directory; default: split DATA by trajectory (seeded)")
        p.add_argument("--seed", type=int, default=0, help="seed of the train/held-out split (default 0)")
    p.add_argument("--workers", type=int, default=None, help="CPU worker processes (default: REALM_SYSID_WORKERS or min(2, cores))")
    p.add_argument("--device", choices=["cpu", "cuda"], default=None, help="simulation device (default: cuda if available)")


def _check_data(path: str) -> None:
    if not Path(path).exists():
        raise _user_error(f"DATA {path!r} does not exist (an npz directory or a LeRobot v3.0 dataset)")


# ---------------------------------------------------------------------------- handlers
def _effects(args) -> int:
    from realm_ms.sysid import api

    lib = api.effects()
    if args.json:
        print(json.dumps(lib, indent=2))
        return 0
    for e in lib:
        print(f"{e['name']}  ({e['kind']}) - {e['summary']}")
        print(f"    signature: {e['signature']}")
        for p in e["params"]:
            where = "per joint" if p["per_joint"] else "shared"
            print(f"    {p['name']:<16} [{p['unit']}] {where}, bounds [{p['bounds'][0]:g}, {p['bounds'][1]:g}], "
                  f"off {p['off']:g}, typical {p['nominal']:g}, {p['scale']}" + ("" if p["fitted_by_default"] else ", fitted on request"))
    return 0


def _excite(args) -> int:
    from realm_ms.sysid import api

    if args.n < 1 or args.duration <= 1:
        raise _user_error("--n must be >= 1 and --duration > 1 s")
    paths = api.excite(args.out, n=args.n, seed=args.seed, duration_s=args.duration, control_hz=args.control_hz,
                       max_velocity=args.max_velocity)
    print(f"wrote {len(paths)} command trajectories ({args.duration:g} s at {args.control_hz:g} Hz) to {args.out}")
    return 0


def _synth(args) -> int:
    from realm_ms.sysid import api

    if args.noise < 0 or args.rate <= 0:
        raise _user_error("--noise must be >= 0 rad and --rate > 0 Hz")
    if args.rate < args.control_hz:
        raise _user_error(f"--rate {args.rate:g} Hz is below the control rate {args.control_hz:g} Hz")
    with _user_input("--hidden: "):
        info = api.synth(args.hidden, args.out, seed=args.seed, noise_rad=args.noise, rate_hz=args.rate,
                         n_train=args.n_train, n_heldout=args.n_heldout, duration_s=args.duration,
                         control_hz=args.control_hz)
    print(f"wrote {args.n_train} train + {args.n_heldout} held-out trajectories to {args.out} "
          f"(hidden: {info['hidden']}; truth in truth.yaml)")
    return 0


def _compare(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    with _user_input():
        c = api.compare(args.data, args.model, None, args.workers, args.device, args.segment)
    names = [f"J{i}" for i in range(1, 8)]
    print(f"replay of {len(c['trajectories'])} trajectories: RMSE {c['rmse_rad']:.3e} rad, noise floor ≈ {c['noise_floor_rad']:.2e} rad")
    print("joint      " + " ".join(f"{n:>9}" for n in names))
    print("RMSE [rad] " + " ".join(f"{v:9.2e}" for v in c["per_joint_rmse_rad"]))
    print("max  [rad] " + " ".join(f"{v:9.2e}" for v in c["per_joint_max_abs_error_rad"]))
    worst = sorted(c["trajectories"], key=lambda t: -(t["rmse_rad"] or 0))[:3]
    print("worst trajectories: " + ", ".join(f"{t['name']} ({t['rmse_rad']:.2e} rad)" for t in worst))
    _write_json(args.json, c)
    return 0


def _diagnose(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    kw = {}
    if args.candidates:
        kw["candidates"] = tuple(s.strip() for s in args.candidates.split(",") if s.strip())
    with _user_input():
        d = api.diagnose(args.data, args.model, args.heldout, args.seed, args.workers, args.device,
                         log=lambda m: print(m, file=sys.stderr), **kw)
    b = d["baseline"]
    print(f"baseline held-out RMSE {b['heldout_rmse_rad']:.3e} rad, noise floor ≈ {b['noise_floor_rad']:.2e} rad")
    print(d["message"])
    for i, s in enumerate(d["suspects"][: args.top], 1):
        print(f"{i:2d}. {s['effect']:<20} score {s['score']:+.2f}  held-out RMSE after {s['heldout_rmse_after_rad']:.2e} rad")
        print(f"    {s['evidence']}")
    _write_json(args.json, d)
    return 0


def _fit(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    with _user_input():
        f = api.fit(args.data, args.add, args.out, args.model, args.heldout, args.seed, args.workers, args.device,
                    progress=not args.no_progress, log=lambda m: print(m, file=sys.stderr),
                    generations=args.generations, popsize=args.popsize, checkpoint=args.checkpoint,
                    refit=not args.no_refit)
    names = [f"J{i}" for i in range(1, 8)]
    print(f"fitted {', '.join(f['effects'])} -> {args.out}")
    for k, v in f["params"].items():
        print(f"  {k:<32} {v:.5g} {f['units'][k]}   bounds {f['bounds'][k]}")
    print("                     " + " ".join(f"{n:>9}" for n in names) + "      all")
    for when in ("before", "after"):
        m = f[when]
        print(f"{when:<6} held-out [rad] " + " ".join(f"{v:9.2e}" for v in m["per_joint_heldout_rmse_rad"])
              + f"  {m['heldout_rmse_rad']:9.2e}   (train {m['train_rmse_rad']:.2e})")
    _write_json(args.json, f)
    return 0


def _report(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    with _user_input():
        p = api.report(args.data, args.model, args.out, args.heldout, args.seed, args.diagnosis, args.fit,
                       args.workers, args.device, waterfall=not args.no_waterfall, log=lambda m: print(m, file=sys.stderr))
    print(f"wrote {p}")
    return 0


# ---------------------------------------------------------------------------- parser
def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser("sysid", help="system identification: compare, diagnose, fit, report",
                              description="System identification of the DROID Panda against measured trajectories.")
    sub = p.add_subparsers(dest="verb", metavar="VERB")
    p.set_defaults(func=lambda a: (p.print_help(), 2)[1])

    s = sub.add_parser("effects", help="list the effect library with parameters and units")
    s.add_argument("--json", action="store_true", help="machine-readable output")
    s.set_defaults(func=_effects)

    s = sub.add_parser("excite", help="write identification command trajectories (15 Hz joint targets)")
    s.add_argument("--out", required=True)
    s.add_argument("--n", type=int, default=10)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--duration", type=float, default=10.0, help="seconds per trajectory")
    s.add_argument("--control-hz", type=float, default=15.0)
    s.add_argument("--max-velocity", type=float, default=1.0, help="rad/s")
    s.set_defaults(func=_excite)

    s = sub.add_parser("synth", help="measured-like data with a hidden effect, from the simulator")
    s.add_argument("--hidden", required=True, help="EFFECT[:param=value,...][,EFFECT...] or none")
    s.add_argument("--out", required=True)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--noise", type=float, default=2e-4, help="sensor noise std [rad] (default 2e-4)")
    s.add_argument("--rate", type=float, default=15.0, help="logging rate [Hz] (default 15)")
    s.add_argument("--control-hz", type=float, default=15.0)
    s.add_argument("--n-train", type=int, default=7)
    s.add_argument("--n-heldout", type=int, default=3)
    s.add_argument("--duration", type=float, default=10.0)
    s.set_defaults(func=_synth)

    s = sub.add_parser("compare", help="replay DATA in simulation: per-joint error and noise floor")
    s.add_argument("data")
    _common(s, heldout=False)
    s.add_argument("--segment", type=float, default=8.0, help="multiple-shooting segment length [s]")
    s.add_argument("--json")
    s.set_defaults(func=_compare)

    s = sub.add_parser("diagnose", help="rank the missing effects by held-out improvement")
    s.add_argument("data")
    _common(s)
    s.add_argument("--candidates", help="comma-separated effect names (default: all)")
    s.add_argument("--top", type=int, default=5)
    s.add_argument("--json")
    s.set_defaults(func=_diagnose)

    s = sub.add_parser("fit", help="add effects and fit their parameters with CMA-ES")
    s.add_argument("data")
    s.add_argument("--add", required=True, help="EFFECT[:param=start,...][,EFFECT...]")
    s.add_argument("--out", required=True, help="MODEL.yaml to write")
    _common(s)
    s.add_argument("--generations", type=int, default=30)
    s.add_argument("--popsize", type=int, default=None)
    s.add_argument("--checkpoint", help="resumable optimiser state (pickle) written every generation")
    s.add_argument("--no-refit", action="store_true", help="keep the --model's own parameters fixed (default: refit them jointly)")
    s.add_argument("--no-progress", action="store_true")
    s.add_argument("--json")
    s.set_defaults(func=_fit)

    s = sub.add_parser("report", help="one self-contained HTML page: where the model fails, suspects, fit")
    s.add_argument("data")
    s.add_argument("--out", required=True)
    _common(s)
    s.add_argument("--diagnosis", help="diagnose --json output to include (else computed)")
    s.add_argument("--fit", help="fit --json output to include (history, before/after)")
    s.add_argument("--no-waterfall", action="store_true", help="skip the effect-by-effect held-out waterfall")
    s.set_defaults(func=_report)
    return p
