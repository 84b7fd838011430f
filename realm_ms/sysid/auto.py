"""``realm sysid auto``: diagnose -> fit the top suspect -> re-diagnose from the fitted model -> ...

One loop for both spaces (``space.py``; the space diagnoses, fits a suspect and names its unit).
Each round ranks the effects still missing from the current model (``diagnose``, screening
with the model's own parameters re-tuned), fits the best suspect jointly with everything already
kept (``fit`` with refit, started at the screened values) -- and each look-alike the diagnosis could
not tell from it (``contenders``, until one reaches the floor), keeping the one that fits best, or
one with fewer parameters that fits as well within noise (``_simplest``) --
and **keeps the step only when the held-out RMSE falls by more than noise allows**: by at least
``min_gain`` of its current value and by at least ``min_floor_drop`` x the judging floor (a fit that
only absorbed noise on the train split does not lower the held-out error that much). A rejected suspect is not tried again; the
next one is. Once a later step is kept, each look-alike an earlier step fitted beside the effect it
kept is fitted again in that effect's place, jointly with the rest (``_recontest``): it
takes the place (a swap step) when better by the keep bar, and a pair within the bar is reported
as confounded. The loop stops at the floor (held-out RMSE <= ``found_factor`` x the judging floor),
when no suspect helps, or after ``max_steps`` kept steps / ``max_fits`` fits.

Verdict: ``at_floor`` (the final model is within ``found_factor`` x the judging floor),
``partially_explained`` (steps were kept but error above the floor remains), ``unexplained``
(nothing in the library lowered the error and it is above the floor). The judging floor is
``diagnose.judging_floor`` (noise floor and the replay's own error on a matching plant).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.gripper import gripper_json
from realm_ms.sysid.diagnose import DiagnoseConfig, Suspect, judging_floor, times_floor, unscreened, unscreened_note

#: velocity grid of the reported friction curve: +-0.05 ... 1.5 rad/s
FRICTION_QD = np.concatenate([-np.linspace(1.5, 0.05, 30), np.linspace(0.05, 1.5, 30)])


@dataclass
class AutoConfig:
    max_steps: int = 4  # kept effects at most
    # fits at most (kept + rejected) that replay the data (``Space.fit_replays``: torque space's are
    # the screening's own least squares, free): a step fits up to four contenders, and on
    # DROID-format data (a delay and softer gains) two steps and the delay's re-contest take 7
    max_fits: int = 8
    generations: int = 10  # CMA-ES generations per fit (the linearised start does most of the work)
    # CMA-ES stops once its best train loss improved by < 0.2 % over this many generations (``fit``
    # waits 6): auto runs up to ``max_fits`` fits, and each generation replays the search data once
    patience: int = 3
    popsize: int | None = None
    min_gain: float = 0.05  # relative held-out RMSE fall a step must bring
    min_floor_drop: float = 0.1  # ... and absolute, in units of the judging floor
    # an unscreened look-alike (LuGre: its bristle costs as much per replay as all screened laws
    # together) is fitted only when a screened contender's fit ends within this factor of the
    # judging floor: far above it a look-alike is not what stands between the model and the floor,
    # and its fit would be most of the run (2 real DROID episodes: smooth friction at 16x the floor,
    # then LuGre fitted and rejected at 28x, 31 % of the run's CPU)
    unscreened_within: float = 3.0
    # seconds of train data the screening and the fits replay (whole trajectories, ``Space.searching``;
    # None or 0: all): every probe and CMA-ES candidate replays all of it, while the held-out error
    # that ranks suspects, keeps steps and judges the verdict is always on the whole held-out split
    search_s: float | None = 45.0
    seed: int = 0
    diagnose: DiagnoseConfig = field(default_factory=DiagnoseConfig)


@dataclass
class AutoStep:
    effect: str
    params: dict[str, float]
    heldout_rmse: float
    kept: bool
    verdict_before: str
    replaces: str = ""  # a swap: the earlier kept look-alike this effect took the place of

    def to_json(self) -> dict:
        out = {"effect": self.effect, "params": self.params, "heldout_rmse": self.heldout_rmse}
        if self.replaces:
            out["replaces"] = self.replaces
        return out


def step_label(step: dict) -> str:
    """A kept step as the message, the CLI and the report's waterfall name it: "+latency", or
    "latency for target_filter" for a swap (``AutoStep.to_json()``)."""
    return f"{step['effect']} for {step['replaces']}" if step.get("replaces") else f"+{step['effect']}"


def contenders(cands: list, screened, tried: set[str], library=None, near: float = 0.0) -> list:
    """The top suspect, then the screened suspects the diagnosis could not tell from it: those its
    screening named confounded (``confounded_with``), its documented look-alikes (``CONFOUNDS``)
    that the screening found helping, and any it put within ``near`` of the top's held-out error.
    The screening ranks them on a short re-tune, so each is fitted in full and the data decide (on
    MuJoCo's ``frictionloss`` the screening ranks Coulomb first without naming smooth friction
    beside it, and the full fits give smooth friction 0.47 mrad against Coulomb's 0.53). Last, the
    top suspect's look-alikes the screening leaves out (not in ``screened``: LuGre friction, too
    costly to screen) but the space can model (``library``, default every effect), from their
    typical values. The caller stops at the first contender that reaches the floor (but for a
    near one with fewer parameters, ``_simplest``)."""
    from realm_ms.agents.effects import confounded_with

    top = cands[0]
    alike = set(top.confounded_with) | set(confounded_with(top.effect))
    out = [top] + [c for c in cands[1:] if bare_effect(c.effect) in alike or _near(c, top, near)]
    for name in confounded_with(top.effect):
        if (name not in screened and name not in tried and all(c.effect != name for c in out)
                and (library is None or name in library)):
            out.append(Suspect(name, 0.0, float("nan"), float("nan"), {},
                               f"a look-alike of {top.effect} that diagnose does not screen"))
    return out


def _near(sus, top, near: float) -> bool:
    """The screening put ``sus`` within ``near`` of the top suspect's held-out error (NaN: not screened)."""
    return bool(sus.heldout_rmse_after - top.heldout_rmse_after < near)


def n_free(effect: str) -> int:
    """Free parameters of an effect spec ("viscous_damping": 7, "lugre_friction": 18)."""
    from realm_ms.sysid.effect_spec import parse_effects

    return sum(len(fx.free_params) for fx in parse_effects(effect))


def _simplest(fitted: list, cfg: "AutoConfig", floor: float) -> list:
    """The step's fits, the one to keep first: the best held-out error, unless a contender with fewer
    free parameters ends within a step's bar of it (LuGre's σ₂ is a viscous damper: on a damped
    plant it fits a hair better than ``viscous_damping`` with 11 parameters more, and a superset that
    wins by less than noise allows is not what the data show); then the others, best first."""
    fitted = sorted(fitted, key=lambda x: x[0])
    best = fitted[0]
    simpler = [x for x in fitted if n_free(x[1].effect) < n_free(best[1].effect)
               and x[0] - best[0] < _bar_of(cfg, x[0], floor)]
    pick = min(simpler, key=lambda x: (n_free(x[1].effect), x[0])) if simpler else best
    return [pick] + [x for x in fitted if x is not pick]


def _bar_of(cfg: AutoConfig, current: float, floor: float) -> float:
    """How much lower a step must bring the held-out error to be kept: more than noise allows."""
    return max(cfg.min_gain * current, cfg.min_floor_drop * floor)


def _rounded(params: dict) -> dict[str, float]:
    return {k: round(float(v), 9) for k, v in params.items()}


def _added(steps: list[AutoStep]) -> int:
    """Effects the kept steps added (a swap adds none)."""
    return len([s for s in steps if s.kept and not s.replaces])


def bare_effect(effect: str) -> str:
    """The effect's name in a model, from a step's spec ("link_mass:fit_com=true" -> "link_mass")."""
    return effect.split(":")[0]


def _recontest(space, model: RobotModel, current: float, floor: float, pending: dict, steps: list[AutoStep],
               confounded: list[dict], cfg: AutoConfig, fits: int, verdict: str, screened, log):
    """Each earlier kept effect against the look-alikes its step fitted beside it, now that a later
    step is kept: each look-alike is fitted in its place, jointly with everything else kept
    (a target filter imitates "slow + late" better than a pure delay while softer gains are still
    unmodelled, and loses once they are). It takes the place (a swap step) when it lowers the
    held-out error by a step's bar, and the next look-alike is fitted in the new holder's place (on
    DROID-format data the target ramp takes the filter's place, and the delay the ramp's); within
    that bar of it the pair is confounded and said so. Each look-alike is contested once (none once
    the model is at the floor); every fit that replays the data counts against ``max_fits``, and a
    look-alike the diagnosis does not screen (LuGre: as costly as the other fits together) only within ``unscreened_within``
    x the floor: farther off it waits for the next kept step (on MuJoCo's LuGre plant the screened
    friction laws end at 4.1-4.5x the floor, and viscous damping, kept next, brings the model within
    it). Returns (model, current, fits)."""
    for effect in list(pending):
        holder, waiting = effect, []  # the look-alike holding the place: the kept effect, or the last swap
        for sus in pending.pop(effect):
            if current <= cfg.diagnose.found_factor * floor:
                break  # at the floor: no look-alike can do visibly better
            if bare_effect(sus.effect) not in screened and current > cfg.unscreened_within * floor:
                waiting.append(sus)
                continue
            if fits >= cfg.max_fits:
                log(f"auto: {sus.effect} not contested against {holder}: {cfg.max_fits} fits spent")
                continue
            fits += space.fit_replays
            base = _without(space, model, holder, sus.effect)
            f = space.fit_suspect(base, sus, cfg, log=lambda *a: None)
            after, bar = f.heldout_after, _bar_of(cfg, current, floor)
            swap = current - after >= bar
            # what it takes the place of: the holder, and a kept effect it contains
            place = " and ".join([holder] + [n for n in model.names if n != bare_effect(holder) and n not in base.names])
            steps.append(AutoStep(sus.effect, _rounded(f.params) if swap else {}, after, swap, verdict, place))
            if swap:
                log(f"auto: {sus.effect} for {place}: held-out {current:.3e} -> {after:.3e} {space.unit} "
                    "(swapped: the look-alike fits better with the rest refitted)")
                model, current, holder = f.model, after, sus.effect
                continue
            tie = abs(after - current) < bar
            if tie:
                confounded.append({"effects": [holder, sus.effect], "heldout_rmse": [current, after]})
            log(f"auto: {sus.effect} for {holder}: held-out {current:.3e} -> {after:.3e} {space.unit} "
                + ("(confounded: within what noise allows)" if tie else f"({holder} stays)"))
        if waiting:
            pending.setdefault(holder, []).extend(waiting)
            log(f"auto: {', '.join(s.effect for s in waiting)} not yet contested against {holder}: not screened, "
                f"and {current / floor:.1f}x the floor is above {cfg.unscreened_within:g}x")
    return model, current, fits


def _without(space, model: RobotModel, *effects: str) -> RobotModel:
    """The model a suspect (the last of ``effects``) is fitted onto: less the others (the kept effect
    it is contested against) and, where the fit replays the data, less what the suspect contains
    (``Effect.contains``). A kept viscous damper beside a LuGre fit is a second copy of its σ₂, and
    the replayed fit starts in a worse basin (MuJoCo's LuGre plant, seed 0: LuGre in Coulomb's place
    beside the kept damper ends at 0.58 mrad, alone at 0.28); torque space's least squares, which
    fitted the suspect jointly with the model in its screening, keeps the model whole."""
    from realm_ms.agents.effects import effect_class

    out = model.copy()
    drop = {bare_effect(e) for e in effects[:-1]}
    if space.fit_replays:
        drop |= set(effect_class(bare_effect(effects[-1])).contains)
    out.effects = [fx for fx in out.effects if fx.name not in drop]
    return out


def _start_spec(effect: str, params: dict[str, float]) -> str:
    """``EFFECT:key=value,...`` starting the fit at the screened values (the bare name if those do
    not parse, e.g. a value rounded onto a bound)."""
    from realm_ms.sysid.effect_spec import parse_effects

    spec = effect + (":" + ",".join(f"{k}={v:.9g}" for k, v in params.items()) if params else "")
    try:
        parse_effects(spec)
    except ValueError:
        return effect
    return spec


def friction_curve(model: RobotModel, qd: np.ndarray = FRICTION_QD) -> dict:
    """Steady sliding friction of the model's friction effects: {qd: [...], tau: [[7] per qd]} [N·m].

    ``tau`` is the torque the joint must be driven with to keep sliding at ``qd`` (same sign as qd,
    as in Gaz et al. 2019), i.e. minus the effect's torque on the joint."""
    import torch

    from realm_ms.agents.effects.implicit_torque import ImplicitJointTorque

    v = torch.as_tensor(np.repeat(qd[:, None], 7, 1), dtype=torch.float32)
    tau = torch.zeros_like(v)
    for fx in model.effects:
        if isinstance(fx, ImplicitJointTorque):
            with torch.inference_mode():
                tau += fx.sliding_friction(v).to(tau.dtype)
    return {"qd": [round(float(x), 6) for x in qd], "tau": [[round(float(x), 6) for x in row] for row in tau.numpy()]}


@dataclass
class AutoResult:
    """What ``auto`` found: the kept steps, the final error and verdict, and the final model."""

    unit: str
    nominal_heldout_rmse: float
    steps: list[AutoStep]  # kept, in order
    rejected: list[AutoStep]
    heldout_rmse: float
    noise_floor: float
    judging_floor: float
    found_factor: float
    verdict: str  # at_floor | partially_explained | unexplained
    message: str
    model: RobotModel
    details: dict = field(default_factory=dict)  # the space's own (``Space.details``)
    split: dict | None = None  # the train/held-out split the API used (``api._split_block``)
    # kept effects a look-alike fits as well in place of: [{"effects": [kept, look-alike], "heldout_rmse": [2]}]
    confounded: list[dict] = field(default_factory=list)
    flange: object = None  # alignment.FlangeComparison: held-out flange mm, lag and b, start -> final model
    gripper: object = None  # the gripper row (``sysid/gripper.GripperCheck``), set by the API when the data has one

    def to_json(self) -> dict:
        out = {"unit": self.unit, "nominal_heldout_rmse": self.nominal_heldout_rmse,
               "steps": [s.to_json() for s in self.steps],
               "final": {"heldout_rmse": self.heldout_rmse, "noise_floor": self.noise_floor, "verdict": self.verdict,
                         "confounded": self.confounded},
               "friction_curve": friction_curve(self.model),
               "details": {"judging_floor": self.judging_floor, "found_factor": self.found_factor, **self.details,
                           "rejected": [{k: v for k, v in s.to_json().items() if k != "params"} for s in self.rejected],
                           "at_bounds": self.model.params_at_bounds(), "message": self.message}}
        if self.split is not None:
            out["split"] = self.split
        if self.flange is not None:
            out["flange"] = self.flange.to_json()
        return out | gripper_json(self.gripper)


def auto(space, model: RobotModel | None = None, config: AutoConfig | None = None, progress: bool = True,
         log=print) -> AutoResult:
    """The loop over a space (``space.py``: position or torque)."""
    cfg = config or AutoConfig()
    dcfg = cfg.diagnose
    unit = space.unit
    model = (model or RobotModel()).copy()
    start = model.copy()
    quiet = lambda *a: None  # noqa: E731
    bar = _bar(progress, cfg.max_fits)
    full, space = space, space.searching(cfg.search_s)
    if space is not full and len(space.train) < len(full.train):
        log(f"auto: screening and fitting on {len(space.train)} of {len(full.train)} train trajectories "
            f"({sum(t.duration for t in space.train):.0f} of {sum(t.duration for t in full.train):.0f} s, "
            f"search budget {cfg.search_s:g} s); every held-out error is on all {len(space.heldout)} held-out trajectories")
    d = space.diagnose(model, dcfg, log=quiet)
    nominal = float(d.baseline_heldout_rmse)
    noise = float(d.noise_floor)
    current = nominal
    floor = judging_floor(noise, space.replay_floor(dcfg))
    log(f"auto: nominal held-out RMSE {nominal:.3e} {unit}, judging floor {floor:.2e} {unit} ({d.verdict})")
    if d.saturated_fraction:
        log(f"auto: {d.saturated_fraction:.1%} of the held-out samples lie in torque-saturated bursts: simulated, not scored")
    steps: list[AutoStep] = []
    tried: set[str] = set()
    screened = space.screened(dcfg)
    fits = 0
    pending: dict[str, list[Suspect]] = {}  # kept effect -> its step's look-alikes, to contest after the next kept step
    confounded: list[dict] = []
    while (_added(steps) < cfg.max_steps and fits < cfg.max_fits
           and current > dcfg.found_factor * floor):
        cands = [s for s in d.suspects if s.score >= dcfg.min_improvement and s.effect not in tried]
        if not cands:
            log("auto: no remaining suspect helps")
            break
        fitted, deferred = [], []
        top = cands[0]
        near = _bar_of(cfg, top.heldout_rmse_after, floor)
        reached = None  # free parameters of the first contender that reached the floor
        todo = contenders(cands, screened, tried, space.library(), near)
        for sus in todo[: cfg.max_fits - fits] if space.fit_replays else todo:
            if reached is not None and not (n_free(sus.effect) < reached and _near(sus, top, near)):
                continue  # at the floor: only a simpler near-tie could still be preferred
            best = min((a for a, _, _ in fitted), default=None)
            if bare_effect(sus.effect) not in screened and best is not None and best > cfg.unscreened_within * floor:
                log(f"auto: not fitting {sus.effect} yet (a look-alike diagnose does not screen): the best screened "
                    f"contender ends at {best / floor:.1f}x the floor, above {cfg.unscreened_within:g}x; it is "
                    "contested in the kept effect's place once a later step brings the model within that")
                deferred.append(sus)
                continue
            tried.add(sus.effect)
            fits += space.fit_replays
            bar.set_description(f"auto: fitting {sus.effect}")
            f = space.fit_suspect(_without(space, model, sus.effect), sus, cfg, log=quiet)
            bar.update(1)
            fitted.append((f.heldout_after, sus, f))
            if reached is None and f.heldout_after <= dcfg.found_factor * floor:
                reached = n_free(sus.effect)
        fitted = _simplest(fitted, cfg, floor)
        if len(fitted) > 1:
            for after, sus, _ in fitted[1:]:
                steps.append(AutoStep(sus.effect, {}, after, False, d.verdict))
                better = ("which fits better" if after >= fitted[0][0] else
                          "which fits as well within noise with fewer parameters")
                log(f"auto: + {sus.effect}: held-out {current:.3e} -> {after:.3e} {unit} (a look-alike of "
                    f"{fitted[0][1].effect}, {better})")
        after, sus, f = fitted[0]
        kept = current - after >= _bar_of(cfg, current, floor)
        steps.append(AutoStep(sus.effect, _rounded(f.params), after, kept, d.verdict))
        log(f"auto: + {sus.effect}: held-out {current:.3e} -> {after:.3e} {unit} "
            + ("(kept)" if kept else "(rejected: within what noise allows)"))
        if not kept:
            continue
        model, current, fits = _recontest(space, f.model, after, floor, pending, steps, confounded, cfg, fits,
                                          d.verdict, screened, log)
        # this step's look-alikes were fitted before the effects still missing are modelled, which
        # can rank them either way (DROID-format data, a delay and softer gains: the delay fitted
        # alone ends 50 % above the target filter, and 10x below it once the gains are in): each is
        # contested again once a later step is kept. First a look-alike the step could not afford to
        # fit, then the others, best first: those lost to the kept effect on data already (LuGre's
        # plant: Coulomb kept, Stribeck and smooth friction lost; with viscous damping kept next,
        # only LuGre reaches the floor in Coulomb's place)
        if len(fitted) > 1 or deferred:
            pending[sus.effect] = deferred + [s for _, s, _ in fitted[1:]]
        if current <= dcfg.found_factor * floor or _added(steps) >= cfg.max_steps:
            break
        bar.set_description("auto: diagnosing")
        # the effects the last diagnosis had to re-screen from typical strengths (their parameters do
        # nothing at their off-values on this data) get that start in its first batches this time
        dcfg = replace(dcfg, typical_starts=tuple(dict.fromkeys(dcfg.typical_starts + tuple(d.rescreened))))
        d = space.diagnose(model, dcfg, log=quiet)
        noise = min(noise, float(d.noise_floor))  # the estimate is inflated by model error: keep the lowest
        floor = judging_floor(noise, space.replay_floor(dcfg))
    bar.close()
    kept = [s for s in steps if s.kept]
    if current <= dcfg.found_factor * floor:
        verdict = "at_floor"
    elif kept:
        verdict = "partially_explained"
    else:
        verdict = "unexplained"
    details, note = space.details(d, model)
    details["searched_train"] = [t.name for t in space.train]
    confounded = [c for c in confounded if bare_effect(c["effects"][0]) in model.names]
    msg = _message(verdict, nominal, current, floor, kept, model.params_at_bounds(),
                   unscreened(screened, tried | set(model.names), space.library()), dcfg.found_factor, unit)
    msg += confounded_note(confounded, unit)
    if note and verdict != "at_floor":
        msg += "; " + note
    log(msg)
    flange = full.flange(start, model)
    return AutoResult(unit, nominal, kept, [s for s in steps if not s.kept], current, noise, floor, dcfg.found_factor,
                      verdict, msg, model, details, confounded=confounded, flange=flange)


def confounded_note(confounded: list[dict], unit: str = "rad") -> str:
    """A clause naming each kept effect and the look-alike that fits as well in its place, else ''."""
    return "".join(f"; {a} or {b}: the data cannot tell them apart (held-out {ha:.2e} vs {hb:.2e} {unit}, each "
                   f"fitted with the rest), {a} kept" for c in confounded for (a, b), (ha, hb) in [(c["effects"], c["heldout_rmse"])])


def bounds_note(at_bounds: dict[str, str]) -> str:
    """A clause naming fitted parameters pressed against a bound, else ''."""
    if not at_bounds:
        return ""
    names = ", ".join(f"{k} ({side})" for k, side in list(at_bounds.items())[:8])
    more = f" and {len(at_bounds) - 8} more" if len(at_bounds) > 8 else ""
    return (f"; at their bounds: {names}{more}: the effect is stretched to explain something else, "
            "so read these values with care")


def _message(verdict: str, nominal: float, final: float, floor: float, kept: list[AutoStep],
             at_bounds: dict[str, str] | None = None, left_out: list[str] = (), found_factor: float = 1.5,
             unit: str = "rad") -> str:
    chain = " -> ".join([f"nominal {nominal:.2e}"] + [f"{step_label(s.to_json())} {s.heldout_rmse:.2e}" for s in kept]) + f" {unit}"
    if verdict == "at_floor":
        return (f"at the floor ({final:.2e} <= {found_factor:g}x {floor:.2e} {unit}): {chain}"
                + bounds_note(at_bounds or {}))
    left_out = list(left_out)
    outside = "an effect outside the library" if not left_out else "an effect not screened or outside the library"
    if verdict == "partially_explained":
        share = 1 - max(final**2 - floor**2, 0) / max(nominal**2 - floor**2, 1e-30)
        return (f"partially explained ({100 * share:.0f}% of the model error): {chain}; residual {final:.2e} {unit} "
                f"left ({times_floor(final, floor, unit)}): {outside}, or a plant/controller mismatch"
                + unscreened_note(left_out) + bounds_note(at_bounds or {}))
    return (f"unexplained: no screened effect lowers the held-out RMSE {nominal:.2e} {unit} "
            f"({times_floor(nominal, floor, unit)})" + unscreened_note(left_out))


class _NoBar:
    def set_description(self, *_):
        pass

    def update(self, *_):
        pass

    def close(self):
        pass


def _bar(progress: bool, total: int):
    import sys

    if not progress or not sys.stderr.isatty():
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(total=total, desc="auto", unit="fit", leave=False)
