"""``realm sysid {effects,excite,synth,compare,diagnose,fit,auto,report,align}``.

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
    from realm_ms.errors import UserError

    return UserError(msg)


@contextmanager
def _flag(flag: str):
    """A user error raised while reading FLAG's value names the flag; anything else (a bug) is
    left to traceback."""
    from realm_ms.errors import UserError

    try:
        yield
    except UserError as e:
        raise _user_error(f"{flag}: {e}") from None


def _check_model(args) -> None:
    """Load --model once up front: a bad file fails in a second, not after the data is read."""
    if getattr(args, "model", None):
        from realm_ms.agents.robot_model import RobotModel

        with _flag("--model"):
            try:
                RobotModel.load(args.model)
            except FileNotFoundError as e:  # the API's type for a missing file; here it is the user's
                raise _user_error(str(e)) from None


def _write_json(path: str | None, data: dict) -> None:
    if not path:
        return
    from realm_ms.atomic import write_json

    p = Path(path)
    write_json(p, data, indent=2, default=float)
    print(f"wrote {p}", file=sys.stderr)


def _show_data_warnings() -> None:
    """Data warnings (``timeseries.DataWarning``) as one line on stderr, without Python's file:line."""
    import warnings

    from realm_ms.sysid.timeseries import DataWarning

    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, DataWarning):
            print(f"warning: {' '.join(str(message).split())}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    warnings.simplefilter("always", DataWarning)


def _check_data(path: str) -> None:
    _show_data_warnings()
    if not Path(path).exists():
        raise _user_error(f"DATA {path!r} does not exist (an npz directory or a LeRobot v3.0 dataset)")


def _check_outputs(args, files: tuple[str, ...] = (), dirs: tuple[str, ...] = ()) -> None:
    """Output paths are checked before the (long) work, so a run never fails at its end."""
    from realm_ms.validate import check_output_dir, check_output_file

    for flag in files:
        value = getattr(args, flag.lstrip("-").replace("-", "_"), None)
        if value:
            check_output_file(value, flag)
    for flag in dirs:
        value = getattr(args, flag.lstrip("-").replace("-", "_"), None)
        if value:
            check_output_dir(value, flag)


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

    if args.duration <= 1:
        raise _user_error(f"--duration must be > 1 s, got {args.duration:g}")
    _check_outputs(args, dirs=("--out",))
    paths = api.excite(args.out, n=args.n, seed=args.seed, duration_s=args.duration, control_hz=args.control_hz,
                       max_velocity=args.max_velocity)
    print(f"wrote {len(paths)} command trajectories ({args.duration:g} s at {args.control_hz:g} Hz) to {args.out}")
    return 0


def _joined(specs: list[str] | str, flag: str) -> str:
    """Repeated ``--add``/``--hidden`` flags accumulate: ``--add A --add B`` means ``--add A,B``
    (argparse's default would silently keep only the last one)."""
    if isinstance(specs, str):
        return specs
    parts = [s.strip() for s in specs if s.strip()]
    if len(parts) > 1 and any(p.lower() == "none" for p in parts):
        raise _user_error(f"{flag} none cannot be combined with other {flag} effects")
    return ",".join(parts)


def _synth(args) -> int:
    from realm_ms.sysid import api

    from realm_ms.sysid.effect_spec import parse_effects

    args.hidden = _joined(args.hidden, "--hidden")
    if args.engine == "mujoco-native":
        return _synth_native(args)
    if args.rate < args.control_hz:
        raise _user_error(f"--rate {args.rate:g} Hz is below the control rate --control-hz {args.control_hz:g} Hz")
    _check_outputs(args, dirs=("--out",))
    with _flag("--hidden"):
        parse_effects(args.hidden, default_values="nominal")
    common = dict(seed=args.seed, noise_rad=args.noise, rate_hz=args.rate, n_train=args.n_train,
                  n_heldout=args.n_heldout, duration_s=args.duration, control_hz=args.control_hz, engine=args.engine)
    if args.droid_space:
        info = api.synth_droid(args.hidden, args.out, args.droid_space, args.format or ["npz"],
                               log_joint_target=args.log_joint_target, **common)
    else:
        info = api.synth(args.hidden, args.out, **common)
    where = f"{args.out}/<format>/" if args.droid_space else f"{args.out}"
    print(f"wrote {args.n_train} train + {args.n_heldout} held-out trajectories to {where} "
          f"(hidden: {info['hidden']}; truth in truth.yaml)")
    return 0


def _synth_native(args) -> int:
    from realm_ms.sysid.reference_native import VARIANTS, NativeEffects, synth_native

    _check_outputs(args, dirs=("--out",))
    with _flag("--hidden"):
        NativeEffects.parse(VARIANTS.get(args.hidden, args.hidden))
    rate = 1000.0 if args.torque_only and args.rate == 15.0 else args.rate
    info = synth_native(args.hidden, args.out, seed=args.seed, n_train=args.n_train, n_heldout=args.n_heldout,
                        duration_s=args.duration, rate_hz=rate, noise_rad=args.noise, noise_nm=args.noise_torque,
                        control_hz=args.control_hz, with_cmd=not args.torque_only)
    print(f"wrote {args.n_train} train + {args.n_heldout} held-out trajectories to {args.out} at {rate:g} Hz "
          f"(MuJoCo-native: {info['effects'] or 'none'}; t, q, qd, tau" + ("" if args.torque_only else ", q_cmd") + ")")
    return 0


def _compare(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    _check_outputs(args, files=("--json",))
    _check_model(args)
    c = api.compare(args.data, args.model, None, args.workers, args.device, args.segment, space=args.space,
                    command=args.command)
    print("\n".join(c.lines()))
    _write_json(args.json, c.to_json())
    return 0


def _diagnose(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    kw = {}
    if args.candidates:
        kw["candidates"] = tuple(s.strip() for s in args.candidates.split(",") if s.strip())
        with _flag("--candidates"):
            from realm_ms.agents.effects import effect_class

            for name in kw["candidates"]:
                effect_class(name)
    _check_outputs(args, files=("--json",))
    _check_model(args)
    res = api.diagnose(args.data, args.model, args.heldout, args.seed, args.workers, args.device,
                       log=lambda m: print(m, file=sys.stderr), space=args.space, command=args.command, **kw)
    d = res.to_json()
    from realm_ms.sysid.diagnose import UNIT_KEYS

    b, u = d["baseline"], d["unit"]
    sfx = UNIT_KEYS[u]
    print(f"baseline held-out RMSE {b[f'heldout_rmse_{sfx}']:.3e} {u}, noise floor ≈ {b[f'noise_floor_{sfx}']:.2e} {u}")
    print(d["message"])
    print("held-out " + res.flange.line())
    for i, s in enumerate(d["suspects"][: args.top], 1):
        print(f"{i:2d}. {s['effect']:<20} score {s['score']:+.2f}  held-out RMSE after {s[f'heldout_rmse_after_{sfx}']:.2e} {u}")
        print(f"    {s['evidence']}")
    if "gripper" in d:
        print(d["gripper"]["line"])
    _write_json(args.json, d)
    return 0


def _fit(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    _check_outputs(args, files=("--out", "--json", "--checkpoint"))
    _check_model(args)
    args.add = _joined(args.add, "--add")
    with _flag("--add"):
        from realm_ms.sysid.effect_spec import parse_effects

        parse_effects(args.add)
    f = api.fit(args.data, args.add, args.out, args.model, args.heldout, args.seed, args.workers, args.device,
                progress=not args.no_progress, log=lambda m: print(m, file=sys.stderr),
                generations=args.generations, popsize=args.popsize, checkpoint=args.checkpoint,
                noise_stop=args.noise_stop, refit=not args.no_refit, space=args.space,
                command=args.command)
    print(f"fitted {', '.join(f.effects)} -> {args.out}")
    print("\n".join(f.lines()))
    _write_json(args.json, f.to_json())
    return 0


def _auto(args) -> int:
    from realm_ms.sysid import api
    from realm_ms.sysid.auto import step_label

    _check_data(args.data)
    _check_outputs(args, files=("--out", "--json"))
    _check_model(args)
    res = api.auto(args.data, args.out, args.model, args.heldout, args.seed, args.workers, args.device,
                   progress=not args.no_progress, log=lambda m: print(m, file=sys.stderr),
                   generations=args.generations, max_steps=args.max_steps, space=args.space,
                   command=args.command, search_s=args.search_s)
    a = res.to_json()
    f = a["final"]
    u = a["unit"]
    print(f"nominal held-out RMSE {a['nominal_heldout_rmse']:.3e} {u}")
    for s in a["steps"]:
        print(f"  {step_label(s):<40} -> {s['heldout_rmse']:.3e} {u}")
    print(f"final {f['heldout_rmse']:.3e} {u}, noise floor {f['noise_floor']:.2e} {u}: {f['verdict']}")
    print(a["details"]["message"])
    print("held-out " + res.flange.line())
    if "gripper" in a:
        print(a["gripper"]["line"] + ("" if a["gripper"]["verdict"] == "matches" else " -> gripper_response added to the model"))
    if args.out:
        print(f"model -> {args.out}")
    _write_json(args.json, a)
    return 0


def _report(args) -> int:
    from realm_ms.sysid import api

    _check_data(args.data)
    _check_outputs(args, files=("--out",))
    _check_model(args)
    p = api.report(args.data, args.model, args.out, args.heldout, args.seed, args.diagnosis, args.fit,
                   args.workers, args.device, waterfall=not args.no_waterfall, log=lambda m: print(m, file=sys.stderr),
                   auto_result=args.auto, command=args.command)
    print(f"wrote {p}")
    return 0


def _align(args) -> int:
    import numpy as np

    from realm_ms.sysid import api

    _check_data(args.data)
    _check_outputs(args, files=("--out", "--json"))
    _check_model(args)
    a = api.align(args.data, args.model, args.out, args.command, waterfall=not args.no_waterfall,
                  log=lambda m: print(m, file=sys.stderr))
    print(f"{'robot':<40} {'flange mm':>9} {'free mm':>8} {'lag sim':>7} {'b sim':>6}   (real: lag "
          f"{a['runs'][0]['overall']['lag_real']:.1f}, b {a['runs'][0]['overall']['b_real']:.2f})")
    for r in a["runs"]:
        o = r["overall"]
        print(f"{r['label'][:40]:<40} {o['flange_mm']:>9.1f} {r['free_flange_mm']:>8.1f} {o['lag_sim']:>7.1f} {o['b_sim']:>6.2f}")
    masked = [e["masked"] for e in a["runs"][0]["episodes"]]
    print(f"grasps/stalls masked: {np.mean(masked):.0%} of steps on average; {len(a['skipped'])} episode(s) left out")
    if "gripper" in a:
        print(a["gripper"]["line"])
    _write_json(args.json, a)
    print(f"wrote {args.out}")
    return 0


# ---------------------------------------------------------------------------- parser
def _common(p: argparse.ArgumentParser, heldout: bool = True) -> None:
    from realm_ms.validate import integer

    p.add_argument("--model", metavar="MODEL.yaml",
                   help="robot model file to start from (default: the nominal DROID robot)")
    if heldout:
        p.add_argument("--heldout", metavar="DIR", help="held-out data directory (default: DATA/heldout when "
                       "DATA has train/ and heldout/, else a seeded split of DATA by trajectory)")
        p.add_argument("--seed", type=integer(0), default=0, help="seed of the train/held-out split, integer >= 0 (default 0)")
    p.add_argument("--workers", type=integer(1), default=None, metavar="N",
                   help="CPU worker processes, integer >= 1 (default: $REALM_SYSID_WORKERS or min(2, cores))")
    p.add_argument("--device", choices=["cpu", "cuda"], default=None,
                   help="simulation device (default: cuda if a GPU is available, else cpu)")
    p.add_argument("--command", metavar="MODE[:SPACE]", default=None,
                   help="how a DROID log's command becomes joint targets: logged (its joint target), rebuild "
                        "(converted at the measured state), closed_loop (converted at the simulated state inside "
                        "the replay), auto (default: logged if there, else rebuild); SPACE picks the logged "
                        "action space (e.g. rebuild:cartesian_position)")


def _space_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--space", choices=("auto", "position", "torque"), default="auto",
                   help="position: replay q_cmd under the DROID controller (rad); torque: inverse-dynamics residual "
                        "of measured tau (N·m, any controller, no q_cmd needed); auto (default): torque when the "
                        "data has no q_cmd")


def add_parser(subparsers) -> argparse.ArgumentParser:
    from realm_ms.validate import integer, non_negative, positive

    p = subparsers.add_parser("sysid", help="system identification: compare, diagnose, fit, report",
                              description="System identification of the DROID Panda against measured trajectories. "
                                          "Units: rad, s, Hz, N·m. Bad input: one-line error, exit code 2.")
    sub = p.add_subparsers(dest="verb", metavar="VERB")
    p.set_defaults(func=lambda a: (p.print_help(), 2)[1], needs_envs=False)

    s = sub.add_parser("effects", help="list the effect library with parameters and units")
    s.add_argument("--json", action="store_true", help="print the library as JSON on stdout")
    s.set_defaults(func=_effects)

    s = sub.add_parser("excite", help="write identification command trajectories (15 Hz joint targets)")
    s.add_argument("--out", required=True, metavar="DIR", help="directory for excite_XXX.npz (created)")
    s.add_argument("--n", type=integer(1), default=10, help="number of trajectories, integer >= 1 (default 10)")
    s.add_argument("--seed", type=integer(0), default=0, help="random seed, integer >= 0 (default 0)")
    s.add_argument("--duration", type=positive("s"), default=10.0, help="seconds per trajectory, > 1 s (default 10)")
    s.add_argument("--control-hz", type=positive("Hz"), default=15.0, help="command rate in Hz, > 0 (default 15, DROID)")
    s.add_argument("--max-velocity", type=positive("rad/s"), default=1.0,
                   help="joint speed cap in rad/s, > 0 (default 1.0)")
    s.set_defaults(func=_excite)

    s = sub.add_parser("synth", help="measured-like data with a hidden effect, from the simulator")
    s.add_argument("--hidden", required=True, action="append", help="EFFECT[:param=value,...][,EFFECT...] or none "
                   "(values in the units of `realm sysid effects`); repeat to hide several effects")
    s.add_argument("--out", required=True, metavar="DIR", help="output directory: train/, heldout/, truth.yaml, synth.json")
    s.add_argument("--seed", type=integer(0), default=0, help="random seed, integer >= 0 (default 0)")
    s.add_argument("--noise", type=non_negative("rad"), default=2e-4, help="sensor noise std in rad, >= 0 (default 2e-4)")
    s.add_argument("--rate", type=positive("Hz"), default=15.0, help="logging rate in Hz, >= --control-hz (default 15)")
    s.add_argument("--control-hz", type=positive("Hz"), default=15.0, help="command rate in Hz, > 0 (default 15)")
    s.add_argument("--n-train", type=integer(1), default=7, help="training trajectories, integer >= 1 (default 7)")
    s.add_argument("--n-heldout", type=integer(1), default=3, help="held-out trajectories, integer >= 1 (default 3)")
    s.add_argument("--duration", type=positive("s"), default=10.0,
                   help="seconds per trajectory, >= 2 s (default 10)")
    s.add_argument("--engine", choices=("physx", "mujoco", "mujoco-native"), default="physx",
                   help="physx: the replay simulator itself; mujoco: the independent reference (same URDF and "
                        "law at 1 kHz in MuJoCo; needs `pip install mujoco`); mujoco-native: that law on a plant "
                        "whose effects are MuJoCo's own (--hidden frictionloss=0.3,payload_mass=0.8,"
                        "payload_com_x=0.12,... or a variant name: none, frictionloss, damping, armature, payload_com, "
                        "link4_mass, springs, frictionloss+payload_com, gaz, lugre), with a joint-torque sensor (tau)")
    s.add_argument("--torque-only", action="store_true",
                   help="mujoco-native: write t, q, qd, tau without q_cmd (a torque log; default rate 1 kHz)")
    s.add_argument("--noise-torque", type=non_negative("N·m"), default=0.02,
                   help="mujoco-native: torque-sensor noise std in N·m, >= 0 (default 0.02)")
    s.add_argument("--droid-space", choices=("joint_position", "joint_velocity", "cartesian_position", "cartesian_velocity"),
                   default=None, help="DROID-format episodes commanded in this action space, closed loop through "
                   "DROID's conversion (physx/mujoco engines; 15 Hz, one sample per command)")
    s.add_argument("--format", nargs="+", choices=("npz", "json", "csv", "h5", "lerobot"), default=None,
                   help="with --droid-space: the formats to write, each under OUT/<format>/ (default npz)")
    s.add_argument("--log-joint-target", action="store_true",
                   help="with --droid-space: also log the joint target DROID sent (as its own logs do)")
    s.set_defaults(func=_synth)

    s = sub.add_parser("compare", help="replay DATA in simulation: per-joint error and noise floor")
    s.add_argument("data", metavar="DATA", help="npz directory (or synth's train/+heldout/ layout) or LeRobot v3.0 dataset")
    _common(s, heldout=False)
    s.add_argument("--segment", type=positive("s"), default=8.0,
                   help="multiple-shooting segment length in s, > 0 (default 8)")
    s.add_argument("--json", metavar="FILE", help="also write the result as JSON to FILE")
    _space_arg(s)
    s.set_defaults(func=_compare)

    s = sub.add_parser("diagnose", help="rank the missing effects by held-out improvement")
    s.add_argument("data", metavar="DATA", help="npz directory (or synth's train/+heldout/ layout) or LeRobot v3.0 dataset")
    _common(s)
    s.add_argument("--candidates", help="comma-separated effect names (default: all but link_mass in position space; see `realm sysid effects`)")
    s.add_argument("--top", type=integer(1), default=5, help="suspects to print, integer >= 1 (default 5)")
    s.add_argument("--json", metavar="FILE", help="also write the diagnosis as JSON to FILE")
    _space_arg(s)
    s.set_defaults(func=_diagnose)

    s = sub.add_parser("fit", help="add effects and fit their parameters with CMA-ES")
    s.add_argument("data", metavar="DATA", help="npz directory (or synth's train/+heldout/ layout) or LeRobot v3.0 dataset")
    s.add_argument("--add", required=True, action="append", help="EFFECT[:param=start,...][,EFFECT...] (start values "
                   "in the units of `realm sysid effects`); repeat to add several effects (--add A --add B is "
                   "--add A,B; an effect given twice is an error)")
    s.add_argument("--out", required=True, metavar="MODEL.yaml", help="robot model file to write (not a directory)")
    _common(s)
    s.add_argument("--generations", type=integer(1), default=30, help="CMA-ES generations at most, integer >= 1 (default 30)")
    s.add_argument("--popsize", type=integer(2), default=None,
                   help="CMA-ES candidates per generation, integer >= 2 (default 4 + 3 ln(parameters))")
    s.add_argument("--noise-stop", type=non_negative(), default=1.05, metavar="X",
                   help="stop CMA-ES once the train RMSE is within X times the measurement noise (estimated at the "
                   "linearised start; a start that close skips it); 0 runs every generation (default 1.05)")
    s.add_argument("--checkpoint", metavar="FILE", help="resumable optimiser state (pickle) written every generation")
    s.add_argument("--no-refit", action="store_true", help="keep the --model's own parameters fixed (default: refit them jointly)")
    s.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    s.add_argument("--json", metavar="FILE", help="also write the fit result (history, before/after) as JSON to FILE")
    _space_arg(s)
    s.set_defaults(func=_fit)

    s = sub.add_parser("report", help="one self-contained HTML page: where the model fails, suspects, fit")
    s.add_argument("data", metavar="DATA", help="npz directory (or synth's train/+heldout/ layout) or LeRobot v3.0 dataset")
    s.add_argument("--out", required=True, metavar="FILE.html", help="HTML file to write (not a directory)")
    _common(s)
    s.add_argument("--diagnosis", metavar="FILE", help="diagnose --json output to include (else computed)")
    s.add_argument("--fit", metavar="FILE", help="fit --json output to include (history, before/after)")
    s.add_argument("--no-waterfall", action="store_true", help="skip the effect-by-effect held-out waterfall")
    s.add_argument("--auto", metavar="FILE", help="auto --json output to include (its waterfall)")
    s.set_defaults(func=_report)

    s = sub.add_parser("align", help="alignment report of DROID episodes: closed-loop replay, flange error, lag and "
                                     "response per episode and lab, before and after a robot model (HTML)")
    s.add_argument("data", metavar="DATA", help="DROID episodes: a directory of .npz/.json/.csv dumps or "
                   "trajectory.h5 files in DROID's DATE/EPISODE/ folders, or a LeRobot dataset (index.json with file -> lab names the labs)")
    s.add_argument("--out", required=True, metavar="FILE.html", help="HTML file to write (not a directory)")
    s.add_argument("--model", metavar="MODEL.yaml", help="robot model to compare with the nominal robot")
    s.add_argument("--command", metavar="MODE[:SPACE]", default=None,
                   help="how commands become joint targets (default closed_loop; see `realm sysid compare --help`)")
    s.add_argument("--no-waterfall", action="store_true", help="only nominal and the model, not its effects one at a time")
    s.add_argument("--json", metavar="FILE", help="write the numbers as JSON")
    s.set_defaults(func=_align)

    s = sub.add_parser("auto", help="diagnose, fit the top suspect, re-diagnose ... until the noise floor")
    s.add_argument("data", metavar="DATA", help="npz directory (or synth's train/+heldout/ layout) or LeRobot v3.0 dataset")
    s.add_argument("--out", metavar="MODEL.yaml", help="robot model file to write (the final model)")
    _common(s)
    s.add_argument("--generations", type=integer(1), default=10,
                   help="CMA-ES generations per fit, integer >= 1 (default 10)")
    s.add_argument("--max-steps", type=integer(1), default=4, help="effects to add at most, integer >= 1 (default 4)")
    s.add_argument("--search-s", type=non_negative("s"), default=45.0, metavar="S",
                   help="seconds of train data the screening and fits replay: whole trajectories in order, at least "
                        "one (position space; every held-out error is on all held-out data); 0 = all (default 45)")
    s.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    s.add_argument("--json", metavar="FILE", help="write the steps, final verdict and friction curve as JSON to FILE")
    _space_arg(s)
    s.set_defaults(func=_auto)
    return p
