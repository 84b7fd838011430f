"""Python API with the same verbs as ``realm sysid``.

    from realm_ms.sysid import api
    api.synth("coulomb_friction:fc=0.3", "data/", seed=0)
    d = api.diagnose("data/")                      # a Diagnosis; d.to_json() is the documented JSON
    f = api.fit("data/", add="coulomb_friction", out="MODEL.yaml")  # f.model is the fitted model
    api.report("data/", model="MODEL.yaml", out="report.html")

Every function takes DATA as a path (npz directory or LeRobot v3.0 dataset) or as
(train, heldout) lists of :class:`~realm_ms.sysid.timeseries.Trajectory`. ``space`` (``--space``)
is picked once per call (``_make_space``); the verbs return the space's typed results.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from realm_ms.sysid.timeseries import MIN_SAMPLES, DataError, Trajectory
from realm_ms.validate import InputError, check_int, check_non_negative, check_positive

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


def _make_space(train, held, space: str | None, model, workers=None, device=None, progress: bool = True,
                identify: bool = True):
    """The one place a space is picked and built, for ``--space`` (``position``: replay of q_cmd under
    the DROID controller; ``torque``: inverse-dynamics residual of a torque log; default ``auto``: the
    first space in ``SPACES`` the data has what it needs for, i.e. torque when the data has no q_cmd),
    checked against the data. ``identify``: also refuse data with nothing to identify (the verbs
    that reach a verdict or fit)."""
    from realm_ms.sysid.space import SPACES
    from realm_ms.sysid.timeseries import check_identifiable

    trajs = train + held
    space = space or "auto"
    if space != "auto" and space not in SPACES:
        raise InputError(f"space (--space): unknown space {space!r}; use {', '.join(SPACES)} or auto")
    cls = SPACES[space] if space in SPACES else next((c for c in SPACES.values() if c.suits(trajs)), list(SPACES.values())[-1])
    cls.check(trajs)
    if identify:
        check_identifiable(trajs)
        cls.check_identifiable(trajs)
    return cls.build(train, held, model, workers, device, progress)


def _split_block(train, held, seed: int) -> dict:
    return {"train": [t.name for t in train], "heldout": [t.name for t in held], "seed": seed}


def _provenance(data, space, train, held, fitted: list[str], heldout_rmse: float) -> dict:
    """What a saved MODEL.yaml records about the fit that made it."""
    from datetime import datetime, timezone

    from realm_ms.sysid.diagnose import UNIT_KEYS

    return {"data": str(data) if not isinstance(data, tuple) else "in-memory", "space": space.name,
            "train": [t.name for t in train], "heldout": [t.name for t in held],
            "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "fitted": fitted, f"heldout_rmse_{UNIT_KEYS[space.unit]}": heldout_rmse, **_versions()}


def _model(model):
    from realm_ms.agents.robot_model import RobotModel

    return RobotModel.load(model)


def _arm(model):
    """The model the arm's space replays: the gripper's effects left out (the gripper row judges them)."""
    arm = model.copy()
    arm.effects = arm.arm_effects
    return arm


def effects() -> list[dict[str, Any]]:
    """The effect library: name, summary, signature and parameters with units, bounds, off-values."""
    from realm_ms.agents.effects import EFFECTS, make_effect

    out = []
    for name, cls in EFFECTS.items():
        fx = make_effect(name)
        out.append({
            "name": name, "summary": cls.summary, "signature": cls.signature,
            "kind": "gripper" if cls.acts_on == "gripper" else ("build-time" if cls.build_time else "torque-path"),
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
            space: str | None = None, command: str | None = None):
    """Replay DATA (all trajectories; plus ``heldout`` if given) with the model: a ``CompareResult``
    (position space, ``fit.py``) or ``TorqueCompare`` (``torque/space.py``); ``.to_json()`` is the JSON."""
    from realm_ms.sysid.data_io import load_dir

    check_positive(segment_s, "segment_s (--segment)", "s")
    m = _model(model)
    opts = _read_options(command)
    trajs = data if isinstance(data, list) else load_dir(data, options=opts)
    if heldout is not None:
        trajs = trajs + load_dir(heldout, options=opts)
    arm = _arm(m)
    with _make_space(trajs, [], space, arm, workers, device, identify=False) as sp:
        res = sp.compare(arm, segment_s=segment_s)
    res.gripper = _gripper(trajs, m)
    return res


def diagnose(data, model=None, heldout=None, seed: int = 0, workers=None, device=None, log=print,
             space: str | None = None, command: str | None = None, candidates=None, **config):
    """The ranked suspects: a ``diagnose.Diagnosis`` (``.to_json()`` is the documented JSON)."""
    from realm_ms.sysid.diagnose import DiagnoseConfig

    _arm_only(candidates or (), "candidates (--candidates)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    arm = _arm(m)
    with _make_space(train, held, space, arm, workers, device) as sp:
        d = sp.diagnose(arm, DiagnoseConfig(**config), log=log, candidates=candidates)
    d.split = _split_block(train, held, seed)
    d.gripper = _gripper(train + held, m)
    return d


def fit(data, add: str, out: str | Path | None = None, model=None, heldout=None, seed: int = 0, workers=None,
        device=None, progress: bool = True, log=print, space: str | None = None, command: str | None = None,
        **config):
    """Add effects and fit: a ``fit.FitResult`` (position) or ``TorqueFit``; ``.model`` is saved at ``out``."""
    from realm_ms.sysid.effect_spec import parse_effects
    from realm_ms.sysid.fit import FitConfig
    from realm_ms.validate import check_output_file

    if config.get("popsize") is not None:
        check_int(config["popsize"], "popsize (--popsize)", minimum=2)  # CMA-ES needs 2 to rank
    if "generations" in config:
        check_int(config["generations"], "generations (--generations)", minimum=1)
    if "noise_stop" in config:
        check_non_negative(config["noise_stop"], "noise_stop (--noise-stop)")
    _arm_only([fx.name for fx in parse_effects(add)], "add (--add)")
    if out is not None:
        check_output_file(out, "out (--out)")  # before the fit, not after it
    if config.get("checkpoint"):
        check_output_file(config["checkpoint"], "checkpoint (--checkpoint)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    arm = _arm(m)
    with _make_space(train, held, space, arm, workers, device, progress) as sp:
        res = sp.fit(arm, FitConfig(add=add, seed=seed, **config), log=log)
    res.model.effects += m.gripper_effects  # kept as given
    res.model.provenance.update(_provenance(data, sp, train, held, res.effects, res.heldout_after))
    if out is not None:
        res.model.save(out)
    res.split = _split_block(train, held, seed)
    return res


def auto(data, out: str | Path | None = None, model=None, heldout=None, seed: int = 0, workers=None, device=None,
         progress: bool = True, log=print, space: str | None = None, command: str | None = None, **config):
    """diagnose -> fit the top suspect -> re-diagnose ... until the floor (``sysid/auto.py``): an ``AutoResult``."""
    from realm_ms.sysid.auto import AutoConfig, auto as _auto, bare_effect
    from realm_ms.validate import check_output_file

    for key in ("generations", "max_steps"):
        if key in config:
            check_int(config[key], f"{key} (--{key.replace('_', '-')})", minimum=1)
    if config.get("search_s") is not None:
        check_non_negative(config["search_s"], "search_s (--search-s)", "s")
    if out is not None:
        check_output_file(out, "out (--out)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    arm = _arm(m)
    with _make_space(train, held, space, arm, workers, device, progress) as sp:
        res = _auto(sp, arm, AutoConfig(seed=seed, **config), progress, log)
    fitted = [s.effect for s in res.steps if bare_effect(s.effect) in res.model.names]  # not swapped out
    res.gripper = _gripper(train + held, m)
    gripper = m.gripper_effects
    if res.gripper is not None and not res.gripper.matches:  # the gripper channel's step: its fitted effect
        gripper = [e for e in gripper if e.name != "gripper_response"] + [res.gripper.effect()]
        fitted.append("gripper_response")
    res.model.effects += gripper
    res.model.provenance.update(_provenance(data, sp, train, held, fitted, res.heldout_rmse))
    if out is not None:
        res.model.save(out)
    res.split = _split_block(train, held, seed)
    return res


def report(data, model=None, out: str | Path = "report.html", heldout=None, seed: int = 0, diagnosis=None,
           fit_result=None, workers=None, device=None, waterfall: bool = True, log=print, auto_result=None,
           command: str | None = None, space: str | None = None) -> Path:
    from realm_ms.validate import check_output_file

    check_output_file(out, "out (--out)")
    train, held = _split(data, heldout, seed, command=command)
    m = _model(model)
    arm = _arm(m)
    with _make_space(train, held, space, arm, workers, device) as sp:
        return sp.report(arm if model is not None else None, Path(out), str(data), log=log, waterfall=waterfall,
                         diagnosis=_load_json(diagnosis, ("baseline", "suspects"), "diagnose --json"),
                         fit_result=_load_json(fit_result, ("history", "before", "after"), "fit --json"),
                         auto=_load_json(auto_result, ("nominal_heldout_rmse", "steps", "final"), "auto --json"))


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
    res = build_align_report(episodes, m, name, Path(out), str(data), skipped, waterfall, log)
    from realm_ms.sysid.gripper import gripper_json

    return res | gripper_json(_gripper([e.traj for e in episodes if e.traj is not None], m))


def _arm_only(names, where: str) -> None:
    """InputError for an effect on the gripper among the arm replay's effects."""
    from realm_ms.agents.effects import effect_class

    gripper = [n for n in names if effect_class(n).acts_on != "arm"]
    if gripper:
        raise InputError(f"{where}: {', '.join(gripper)} acts on the gripper, which the arm replay does not simulate; "
                         "the gripper row of `realm sysid compare`, `diagnose` and `align` judges it and "
                         "`realm sysid auto` adds it to the model it writes")


def _gripper(trajs: list[Trajectory], model):
    """The gripper row (``sysid/gripper.py``) when the data has a gripper channel, else None."""
    from realm_ms.sysid.gripper import check_gripper

    return check_gripper(trajs, model) if any(t.gripper is not None for t in trajs) else None


def _load_json(obj, keys: tuple[str, ...], what: str):
    """A verb's JSON: from a file, from its typed result (``.to_json()``), or as given (a dict or None)."""
    if hasattr(obj, "to_json"):
        return obj.to_json()
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
