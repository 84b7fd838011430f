"""The workbench verbs in torque space (``compare``, ``diagnose``, ``fit``, ``auto``), same JSON
shapes as in position space with ``unit: "N·m"`` and ``_nm`` keys. See ``space.py``."""

from __future__ import annotations

import numpy as np

from realm_ms.agents.effects import EFFECTS
from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.diagnose import DiagnoseConfig, Suspect, judge_verdict, unscreened
from realm_ms.sysid.timeseries import Trajectory
from realm_ms.sysid.torque.space import UNIT, Term, TorqueSet, fit_terms, residual_bands, rmse, torque_arm
from realm_ms.sysid.torque.spectrum import high_frequency_note
from realm_ms.sysid.torque.terms import TERMS, TRACKING_ONLY

MAX_FIT_SAMPLES = 6000  # train samples the least squares sees (evenly thinned); held-out uses all
#: configured variants screened beside the library candidates: a link's CoM moves the torque in ways
#: no mass scale can (a regressor product per evaluation, so 28 parameters screen in seconds)
SCREENED_VARIANTS = ("link_mass:fit_com=true",)


def _sets(train, held):
    arm = torque_arm()
    return TorqueSet.build(train, arm, max_samples=MAX_FIT_SAMPLES), TorqueSet.build(held, arm)


def _floor(ts: TorqueSet) -> float:
    return float(np.sqrt(np.mean(ts.noise**2)))


def terms_of(model: RobotModel | None, log=print) -> list[Term]:
    """The model's torque-space terms (tracking effects are skipped with a note)."""
    out = []
    if model is None:
        return out
    for fx in model.effects:
        if fx.name in TRACKING_ONLY:
            log(f"note: {fx.name} is a tracking effect (needs q_cmd); it is ignored in torque space")
            continue
        out.append(Term.make(fx.name, fx.values(), fx.config_dict()))
    extra = (model.provenance.get("torque_space") or {}) if model.provenance else {}
    for name, values in extra.items():
        out.append(Term.make(name, values))
    return out


def model_of(terms: list[Term], base: RobotModel | None = None) -> RobotModel:
    """A MODEL.yaml for the terms: library effects as effects, torque-space-only terms (link_mass)
    under ``provenance.torque_space`` (the replay has no such stage)."""
    from realm_ms.agents.effects import EFFECTS, make_effect

    base = (base or RobotModel()).copy()
    keep = [fx for fx in base.effects if fx.name in TRACKING_ONLY]
    fx = [make_effect(t.name, t.values, t.config_dict()) for t in terms if t.name in EFFECTS]
    extra = {t.name: dict(t.values) for t in terms if t.name not in EFFECTS}
    prov = dict(base.provenance)
    prov.pop("torque_space", None)
    if extra:
        prov["torque_space"] = extra
    return RobotModel(sorted(keep + fx, key=lambda f: f.order), base.gains, base.joint_physics, base.physics_hz, prov)


def _config_names(name: str) -> set[str]:
    from dataclasses import fields

    return {f.name for f in fields(EFFECTS.get(name).Config)} if name in EFFECTS else set()


def _copy(terms: list[Term]) -> list[Term]:
    return [Term.make(t.name, dict(t.values), t.config_dict()) for t in terms]


def compare(trajs: list[Trajectory], model: RobotModel | None = None) -> dict:
    ts = TorqueSet.build(trajs, torque_arm())
    terms = terms_of(model, log=lambda *a: None)
    total, per = rmse(ts, terms)
    return {"unit": UNIT, "rmse_nm": total, "per_joint_rmse_nm": [float(x) for x in per],
            "noise_floor_nm": _floor(ts), "noise_floor_per_joint_nm": [float(x) for x in ts.noise],
            "samples": len(ts.tau), "residual_bands": residual_bands(ts, terms)}


def diagnose(train, held, model=None, candidates=None, config: DiagnoseConfig | None = None, log=print,
             sets=None) -> dict:
    cfg = config or DiagnoseConfig()
    tr, he = sets or _sets(train, held)
    base_terms = terms_of(model, log)
    present = {t.name for t in base_terms}
    if candidates is None:  # the config's library candidates + the torque-space-only terms + those
        # position space screens only on request (link_mass: cheap here, a regressor fit)
        candidates = [n for n in TERMS if n in cfg.candidates or n not in EFFECTS or not EFFECTS.get(n).screened]
        candidates += list(SCREENED_VARIANTS)
    names = [n for n in candidates if _base(n) not in present and _base(n) not in TRACKING_ONLY]
    base_tr, _ = rmse(tr, base_terms)
    base_he, per_he = rmse(he, base_terms)
    floor = _floor(he)
    log(f"torque space: baseline held-out RMSE {base_he:.3e} {UNIT}, noise floor ≈ {floor:.2e} {UNIT}")
    suspects = []
    for n in names:
        terms = _copy(base_terms) + parse_terms(n)
        after_tr = fit_terms(tr, terms)
        after_he, _ = rmse(he, terms)
        new = terms[-1]
        retuned = {f"{t.name}.{k}": round(v, 9) for t in terms[:-1] for k, v in t.values.items()}
        sc = (base_he - after_he) / base_he if base_he > 0 else 0.0
        sp = Suspect(n, sc, after_he, after_tr, {k: round(v, 9) for k, v in new.values.items()},
                     f"{n}: inverse-dynamics residual fitted by least squares")
        sp.retuned_model_params = retuned
        suspects.append(sp)
    suspects.sort(key=lambda s: -s.score)
    left_out = unscreened({_base(n) for n in names}, present, [n for n in TERMS if n not in TRACKING_ONLY])
    verdict, msg, judge = judge_verdict(base_he, floor, suspects, cfg, unit=UNIT, left_out=left_out)
    return {"unit": UNIT, "verdict": verdict, "message": msg, "missing_effect_found": verdict == "found",
            "unexplained": verdict == "unexplained",
            "baseline": {"heldout_rmse_nm": base_he, "train_rmse_nm": base_tr, "noise_floor_nm": floor,
                         "judging_floor_nm": judge, "per_joint_heldout_rmse_nm": [float(x) for x in per_he],
                         "noise_floor_per_joint_nm": [float(x) for x in he.noise]},
            "suspects": [{"effect": s.effect, "score": round(float(s.score), 6), "explains": round(s.explains, 4),
                          "heldout_rmse_after_nm": float(s.heldout_rmse_after_rad), "params": s.params,
                          "evidence": s.evidence, "train_rmse_after_nm": float(s.train_rmse_after_rad),
                          "retuned_model_params": s.retuned_model_params} for s in suspects]}


def parse_terms(spec: str) -> list[Term]:
    """Terms of an ``--add``-style spec, e.g. ``link_mass:link=4,fit_com=true,s4=0.1``: the effect's
    config keys set its config, the others start its free parameters."""
    from realm_ms.sysid.effect_spec import _value, split_specs

    out = []
    for name, kv in split_specs(spec):
        cfg_names = _config_names(name)
        t = Term.make(name, config={k: _value(v, k) for k, v in kv.items() if k in cfg_names})
        kv = {k: v for k, v in kv.items() if k not in cfg_names}
        unknown = [k for k in kv if k not in t.values]
        if unknown:
            raise ValueError(f"{name}: unknown or fixed parameter(s) {unknown} in torque space; free: {list(t.values)}")
        t.values.update({k: float(v) for k, v in kv.items()})
        out.append(t)
    return out


def _base(spec: str) -> str:
    """Effect name of a candidate spec (``link_mass:fit_com=true`` -> ``link_mass``)."""
    return spec.split(":", 1)[0]


def fit(train, held, add: str, model=None, refit: bool = True, log=print, sets=None) -> dict:
    tr, he = sets or _sets(train, held)
    base_terms = terms_of(model, log)
    added = parse_terms(add)
    clash = [t.name for t in added if t.name in {b.name for b in base_terms}]
    if clash:
        raise ValueError(f"{', '.join(clash)} already in the model; drop it from --add")
    if not added:
        raise ValueError("nothing to fit: give effects with --add")
    before_tr, _ = rmse(tr, base_terms)
    before_he, before_j = rmse(he, base_terms)
    fitted = (base_terms if refit else []) + added
    fit_terms(tr, fitted)
    terms = (base_terms if refit else _copy(base_terms)) + added
    after_tr, _ = rmse(tr, terms)
    after_he, after_j = rmse(he, terms)
    log(f"torque space: held-out RMSE {before_he:.3e} -> {after_he:.3e} {UNIT}")
    params = {f"{t.name}.{k}": float(v) for t in fitted for k, v in t.values.items()}
    out = {"unit": UNIT, "effects": [t.name for t in fitted], "params": params,
           "before": {"train_rmse_nm": before_tr, "heldout_rmse_nm": before_he,
                      "per_joint_heldout_rmse_nm": [float(x) for x in before_j]},
           "after": {"train_rmse_nm": after_tr, "heldout_rmse_nm": after_he,
                     "per_joint_heldout_rmse_nm": [float(x) for x in after_j]},
           "noise_floor_nm": _floor(he), "residual_bands": residual_bands(he, terms), "_terms": terms}
    out["_model"] = model_of(terms, model)
    out["at_bounds"] = out["_model"].params_at_bounds()
    return out


def auto(train, held, model=None, config=None, log=print) -> dict:
    """diagnose -> fit -> re-diagnose in torque space (rules of ``sysid/auto.py``)."""
    from realm_ms.sysid.auto import AutoConfig, AutoStep, _message, friction_curve

    cfg = config or AutoConfig()
    dcfg = cfg.diagnose
    sets = _sets(train, held)
    quiet = lambda *a: None  # noqa: E731
    d = diagnose(train, held, model, config=dcfg, log=quiet, sets=sets)
    nominal = current = d["baseline"]["heldout_rmse_nm"]
    floor = d["baseline"]["judging_floor_nm"]
    noise = d["baseline"]["noise_floor_nm"]
    terms = terms_of(model, quiet)
    steps, rejected, tried = [], [], set()
    while len(steps) < cfg.max_steps and current > dcfg.found_factor * floor:
        cands = [s for s in d["suspects"] if s["score"] >= dcfg.min_improvement and s["effect"] not in tried]
        if not cands:
            break
        s = cands[0]
        tried.add(s["effect"])
        # the diagnosis already fitted it jointly with the model's terms: take those values
        new = parse_terms(s["effect"])[0]
        new.values.update({k: v for k, v in s["params"].items() if k in new.values})
        trial = _copy(terms) + [new]
        for t in trial[:-1]:
            t.values.update({k.split(".", 1)[1]: v for k, v in s["retuned_model_params"].items()
                             if k.split(".", 1)[0] == t.name})
        after = rmse(sets[1], trial)[0]
        keep = current - after >= max(cfg.min_gain * current, cfg.min_floor_drop * floor)
        log(f"auto (torque space): + {s['effect']}: {current:.3e} -> {after:.3e} {UNIT}" + ("" if keep else " (rejected)"))
        if not keep:
            rejected.append({"effect": s["effect"], "heldout_rmse": after})
            continue
        terms, current = trial, after
        steps.append({"effect": s["effect"], "params": {f"{t.name}.{k}": round(v, 9) for t in terms
                                                         for k, v in t.values.items()}, "heldout_rmse": after})
        if current <= dcfg.found_factor * floor or len(steps) >= cfg.max_steps:
            break  # done: a re-diagnosis (the costly joint refits) would go unused, as in sysid/auto.py
        d = diagnose(train, held, model_of(terms, model), config=dcfg, log=quiet, sets=sets)
    verdict = "at_floor" if current <= dcfg.found_factor * floor else ("partially_explained" if steps else "unexplained")
    final_model = model_of(terms, model)
    kept = [AutoStep(s["effect"], s["params"], s["heldout_rmse"], True, "") for s in steps]
    bands = residual_bands(sets[1], terms)
    at_bounds = final_model.params_at_bounds()
    msg = _message(verdict, nominal, current, floor, kept, at_bounds).replace(" rad", f" {UNIT}")
    note = high_frequency_note(bands) if verdict != "at_floor" else ""
    if note:
        msg += "; " + note
    return {"unit": UNIT, "nominal_heldout_rmse": nominal, "steps": steps,
            "final": {"heldout_rmse": current, "noise_floor": noise, "verdict": verdict},
            "friction_curve": friction_curve(final_model),
            "details": {"judging_floor": floor, "found_factor": dcfg.found_factor, "rejected": rejected,
                        "message": msg, "space": "torque", "residual_bands": bands, "at_bounds": at_bounds},
            "_model": final_model}
