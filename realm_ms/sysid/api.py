"""Python API with the same verbs as ``realm sysid``.

    from realm_ms.sysid import api
    api.synth("coulomb_friction:fc=0.3", "data/", seed=0)
    d = api.diagnose("data/")                      # dict, the documented JSON
    f = api.fit("data/", add="coulomb_friction", out="MODEL.yaml")
    api.report("data/", model="MODEL.yaml", out="report.html")

Every function takes DATA as a path (npz directory or LeRobot v3.0 dataset) or as
(train, heldout) lists of :class:`~realm_ms.sysid.timeseries.Trajectory`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from realm_ms.sysid.timeseries import MIN_SAMPLES, DataError, Trajectory
from realm_ms.validate import InputError, check_device, check_int, check_non_negative, check_positive

#: shortest synthetic trajectory the other verbs accept: 1 s burn-in plus at least 1 s scored
MIN_SYNTH_DURATION_S = 2.0


def _read_options(command: str | None):
    """``--command MODE[:SPACE]``: how a DROID log's command becomes joint targets (``droid_formats.py``)."""
    from realm_ms.sysid.droid_formats import ReadOptions

    return ReadOptions.parse(command)


def _split(data, heldout=None, seed: int = 0, heldout_fraction: float = 0.3,
           command: str | None = None) -> tuple[list[Trajectory], list[Trajectory]]:
    if isinstance(data, tuple):
        return data
    from realm_ms.sysid.data_io import load_split

    return load_split(data, heldout, seed, heldout_fraction, _read_options(command))


def _space(trajs: list[Trajectory], space: str | None) -> str:
    """``position`` (replay of q_cmd under the DROID controller) or ``torque`` (inverse-dynamics
    residual of a torque log). Default: torque when the data has no q_cmd, else position."""
    space = space or "auto"
    if space not in ("auto", "position", "torque"):
        raise InputError(f"space (--space): unknown space {space!r}; use position, torque or auto")
    no_cmd = [t.name for t in trajs if t.q_cmd is None]
    no_tau = [t.name for t in trajs if t.tau is None]
    if space == "auto":
        space = "torque" if no_cmd else "position"
    if space == "position" and no_cmd:
        raise DataError(f"{no_cmd[0]}: no q_cmd (commanded targets); the position-space replay needs them. "
                        + ("It has tau: use --space torque (the inverse-dynamics residual)" if not no_tau else
                           "Add q_cmd, or tau for torque-space work"))
    if space == "torque" and no_tau:
        raise DataError(f"{no_tau[0]}: no tau (measured joint torque, N·m); torque space needs it "
                        + ("(or use --space position: the data has q_cmd)" if not no_cmd else "in every trajectory"))
    return space


def _checked_space(trajs: list[Trajectory], space: str | None) -> str:
    """``_space``, for the verbs that reach a verdict or fit: data with nothing to identify is refused."""
    from realm_ms.sysid.timeseries import check_identifiable

    space = _space(trajs, space)
    check_identifiable(trajs, space)
    return space


def _model(model):
    from realm_ms.agents.robot_model import RobotModel

    return RobotModel.load(model)


def _evaluator(model, workers=None, device=None, progress: bool = True):
    import sys

    if workers is not None:
        workers = check_int(workers, "workers (--workers)", minimum=1)
    if device is not None:
        check_device(device)

    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.simulator import SimConfig

    ev = Evaluator.auto(SimConfig.from_model(model), workers, device)
    ev.progress = progress and sys.stderr.isatty()
    return ev


def effects() -> list[dict[str, Any]]:
    """The effect library: name, summary, signature and parameters with units, bounds, off-values."""
    from realm_ms.agents.effects import EFFECTS, make_effect

    out = []
    for name, cls in EFFECTS.items():
        fx = make_effect(name)
        out.append({
            "name": name, "summary": cls.summary, "signature": cls.signature,
            "kind": "build-time" if cls.build_time else "torque-path",
            "params": [{"name": s.name, "unit": s.unit, "per_joint": s.per_joint, "nominal": s.nominal,
                        "bounds": [s.lo, s.hi], "off": s.off, "scale": s.scale, "fitted_by_default": s.fit_by_default,
                        "doc": s.doc} for s in fx.specs],
        })
    return out


def excite(out: str | Path, n: int = 10, seed: int = 0, **config) -> list[Path]:
    from realm_ms.sysid.excite import ExciteConfig, write_excitation

    check_int(n, "n (--n)", minimum=1)
    check_int(seed, "seed (--seed)", minimum=0)
    return write_excitation(out, n, seed, ExciteConfig(**config))


def synth(hidden: str, out: str | Path, seed: int = 0, noise_rad: float = 2e-4, rate_hz: float = 15.0,
          workers: int | None = 1, dry_run: bool = False, **config) -> dict:
    """``dry_run``: only the argument checks (``synth_droid`` shares them)."""
    check_int(seed, "seed (--seed)", minimum=0)
    check_non_negative(noise_rad, "noise_rad (--noise)", "rad")
    rate = check_positive(rate_hz, "rate_hz (--rate)", "Hz")
    control = check_positive(config.get("control_hz", 15.0), "control_hz (--control-hz)", "Hz")
    if rate < control:
        raise InputError(f"rate_hz (--rate): {rate:g} Hz is below the control rate {control:g} Hz")
    for key in ("n_train", "n_heldout"):
        if key in config:
            check_int(config[key], f"{key} (--{key.replace('_', '-')})", minimum=1)
    duration = check_positive(config.get("duration_s", 10.0), "duration_s (--duration)", "s")
    if duration < MIN_SYNTH_DURATION_S or duration * rate + 1 < MIN_SAMPLES:
        raise InputError(f"duration_s (--duration): {duration:g} s is too short; every trajectory needs >= "
                         f"{MIN_SYNTH_DURATION_S:g} s (1 s burn-in + scored time) and >= {MIN_SAMPLES} samples "
                         f"(at {rate:g} Hz: >= {max(MIN_SYNTH_DURATION_S, (MIN_SAMPLES - 1) / rate):.3g} s)")
    if dry_run:
        return {}
    from realm_ms.sysid.synth import SynthConfig, synth as _synth  # after the checks: fail fast

    return _synth(hidden, out, SynthConfig(seed=seed, noise_rad=noise_rad, rate_hz=rate_hz, **config))


def synth_droid(hidden: str, out: str | Path, action_space: str = "cartesian_position", formats=("npz",),
                log_joint_target: bool = False, seed: int = 0, noise_rad: float = 2e-4, rate_hz: float = 15.0,
                workers: int | None = 1, **config) -> dict:
    """DROID-format episodes with hidden effects (``synth.synth_droid``): same checks as ``synth``."""
    control = config.get("control_hz", 15.0)
    if rate_hz != control:
        raise InputError(f"rate_hz (--rate): DROID logs one sample per command; use --rate = --control-hz ({control:g} Hz)")
    if config.get("engine", "physx") not in ("physx", "mujoco"):
        raise InputError("engine (--engine): DROID-format data comes from the physx or mujoco engine")
    synth("none", out, seed, noise_rad, rate_hz, workers, dry_run=True, **config)  # the shared argument checks
    from realm_ms.sysid.synth import SynthConfig, synth_droid as _synth_droid

    return _synth_droid(hidden, out, SynthConfig(seed=seed, noise_rad=noise_rad, rate_hz=rate_hz, **config), action_space,
                        tuple(formats), log_joint_target)


def compare(data, model=None, heldout=None, workers=None, device=None, segment_s: float = 8.0,
            space: str | None = None, command: str | None = None) -> dict:
    """Replay DATA (all trajectories; plus ``heldout`` if given) with the model."""
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.fit import compare as _compare

    check_positive(segment_s, "segment_s (--segment)", "s")
    m = _model(model)
    opts = _read_options(command)
    trajs = data if isinstance(data, list) else load_dir(data, options=opts)
    if heldout is not None:
        trajs = trajs + load_dir(heldout, options=opts)
    if _space(trajs, space) == "torque":
        from realm_ms.sysid.torque import verbs

        return verbs.compare(trajs, m)
    out = _compare(trajs, m, segment_s=segment_s, evaluator=_evaluator(m, workers, device))
    out["unit"] = "rad"
    return out


def diagnose(data, model=None, heldout=None, seed: int = 0, workers=None, device=None, log=print,
             space: str | None = None, command: str | None = None, **config) -> dict:
    from realm_ms.sysid.diagnose import DiagnoseConfig, diagnose as _diagnose

    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    if _checked_space(train + held, space) == "torque":
        from realm_ms.sysid.torque import verbs

        cands = config.pop("candidates", None)
        out = verbs.diagnose(train, held, m, cands, DiagnoseConfig(**config), log=log)
        out["split"] = {"train": [t.name for t in train], "heldout": [t.name for t in held], "seed": seed}
        return out
    d = _diagnose(train, held, m, DiagnoseConfig(**config), _evaluator(m, workers, device), log=log)
    out = d.to_json()
    out["split"] = {"train": [t.name for t in train], "heldout": [t.name for t in held], "seed": seed}
    return out


def fit(data, add: str, out: str | Path | None = None, model=None, heldout=None, seed: int = 0, workers=None,
        device=None, progress: bool = True, log=print, space: str | None = None, command: str | None = None,
        **config) -> dict:
    from datetime import datetime, timezone

    from realm_ms.sysid.fit import FitConfig, fit as _fit
    from realm_ms.validate import check_output_file

    if config.get("popsize") is not None:
        check_int(config["popsize"], "popsize (--popsize)", minimum=2)  # CMA-ES needs 2 to rank
    if "generations" in config:
        check_int(config["generations"], "generations (--generations)", minimum=1)
    if "noise_stop" in config:
        check_non_negative(config["noise_stop"], "noise_stop (--noise-stop)")
    if out is not None:
        check_output_file(out, "out (--out)")  # before the fit, not after it
    if config.get("checkpoint"):
        check_output_file(config["checkpoint"], "checkpoint (--checkpoint)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    if _checked_space(train + held, space) == "torque":
        from realm_ms.sysid.torque import verbs

        j = verbs.fit(train, held, add, m, refit=config.get("refit", True), log=log)
        j["_model"].provenance.update({"data": str(data) if not isinstance(data, tuple) else "in-memory",
                                       "space": "torque", "fitted": j["effects"], **_versions()})
        if out is not None:
            j["_model"].save(out)
        j.pop("_terms", None)
        j["split"] = {"train": [t.name for t in train], "heldout": [t.name for t in held], "seed": seed}
        return j
    res = _fit(train, held, m, FitConfig(add=add, seed=seed, **config), _evaluator(m, workers, device), progress, log)
    res.model.provenance.update({
        "data": str(data) if not isinstance(data, tuple) else "in-memory",
        "train": [t.name for t in train], "heldout": [t.name for t in held],
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "fitted": res.effects, "heldout_rmse_rad": res.after["heldout_rmse_rad"],
        **_versions(),
    })
    if out is not None:
        res.model.save(out)
    j = res.to_json()
    j["split"] = {"train": [t.name for t in train], "heldout": [t.name for t in held], "seed": seed}
    j["_model"] = res.model
    return j


def auto(data, out: str | Path | None = None, model=None, heldout=None, seed: int = 0, workers=None, device=None,
         progress: bool = True, log=print, space: str | None = None, command: str | None = None, **config) -> dict:
    """diagnose -> fit the top suspect -> re-diagnose ... until the floor (``sysid/auto.py``)."""
    from datetime import datetime, timezone

    from realm_ms.sysid.auto import AutoConfig, auto as _auto
    from realm_ms.validate import check_output_file

    for key in ("generations", "max_steps"):
        if key in config:
            check_int(config[key], f"{key} (--{key.replace('_', '-')})", minimum=1)
    if out is not None:
        check_output_file(out, "out (--out)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    if _checked_space(train + held, space) == "torque":
        from realm_ms.sysid.torque import verbs

        res = verbs.auto(train, held, m, AutoConfig(seed=seed, **config), log)
    else:
        res = _auto(train, held, m, AutoConfig(seed=seed, **config), _evaluator(m, workers, device), progress, log)
    fitted = res["_model"]
    fitted.provenance.update({
        "data": str(data) if not isinstance(data, tuple) else "in-memory",
        "train": [t.name for t in train], "heldout": [t.name for t in held],
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "fitted": [s["effect"] for s in res["steps"]], "heldout_rmse_rad": res["final"]["heldout_rmse"],
        **_versions(),
    })
    if out is not None:
        fitted.save(out)
    res["split"] = {"train": [t.name for t in train], "heldout": [t.name for t in held], "seed": seed}
    return res


def report(data, model=None, out: str | Path = "report.html", heldout=None, seed: int = 0, diagnosis=None,
           fit_result=None, workers=None, device=None, waterfall: bool = True, log=print, auto_result=None,
           command: str | None = None) -> Path:
    from realm_ms.sysid.report import build_report
    from realm_ms.validate import check_output_file

    check_output_file(out, "out (--out)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    if _checked_space(train + held, None) == "torque":  # no q_cmd: the inverse-dynamics residual, in N·m
        from realm_ms.sysid.report.torque_report import build_torque_report

        auto_result = _load_json(auto_result, ("nominal_heldout_rmse", "steps", "final"), "auto --json")
        return build_torque_report(train, held, m if model is not None else None, Path(out), str(data), auto_result)
    diagnosis = _load_json(diagnosis, ("baseline", "suspects"), "diagnose --json")
    fit_result = _load_json(fit_result, ("history", "before", "after"), "fit --json")
    auto_result = _load_json(auto_result, ("nominal_heldout_rmse", "steps", "final"), "auto --json")
    return build_report(train, held, m, Path(out), _evaluator(m, workers, device), diagnosis=diagnosis,
                        fit_result=fit_result, waterfall=waterfall, data_name=str(data), log=log, auto=auto_result)


def align(data, model=None, out: str | Path = "align.html", command: str | None = None, waterfall: bool = True,
          log=print) -> dict:
    """The alignment report of DROID episodes (any format ``load_dir`` reads): closed-loop replay
    under the nominal robot, the model's waterfall and the model; per-lab and per-episode flange
    error, lag, response; HTML at ``out`` (``report/align_report.py``). Episodes that fail to read
    or validate are left out and listed. Labs come from ``index.json`` (``file`` -> ``lab``) in DATA
    or its parent, else from the name's last ``_`` part."""
    from realm_ms.sysid.alignment import read_droid_episodes
    from realm_ms.sysid.report.align_report import build_align_report
    from realm_ms.validate import check_output_file

    check_output_file(out, "out (--out)")
    episodes, skipped = read_droid_episodes(data, command)
    m = _model(model) if model is not None else None
    name = "nominal" if model is None else Path(str(model)).name
    return build_align_report(episodes, m, name, Path(out), str(data), skipped, waterfall, log)


def _load_json(obj, keys: tuple[str, ...], what: str):
    if not isinstance(obj, (str, Path)):
        return obj
    p = Path(obj)
    if not p.is_file():
        raise InputError(f"{p} not found" + (" (it is a directory)" if p.is_dir() else ""))
    try:
        data = json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: not valid JSON ({e})") from None
    missing = [k for k in keys if not isinstance(data, dict) or k not in data]
    if missing:
        raise InputError(f"{p}: not a `{what}` output (missing {', '.join(missing)})")
    return data


def _versions() -> dict:
    out = {}
    for mod in ("realm_ms", "sapien", "mani_skill", "torch"):
        try:
            out[f"{mod}_version"] = str(__import__(mod).__version__)
        except Exception:  # noqa: BLE001
            pass
    return out


__all__ = ["effects", "excite", "synth", "compare", "diagnose", "fit", "auto", "report", "DataError"]
