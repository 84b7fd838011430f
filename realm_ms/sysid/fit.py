"""Add effects to a robot model and fit their parameters.

1. start: values given on the command line (``coulomb_friction:fc=0.2``) or the effect's off-values;
2. linearised Gauss-Newton start (``optimize.linearized_step``, all chosen parameters jointly,
   iterated while each iteration still cuts the train RMSE by ``gn_gain``, at most
   ``gn_iterations``) -- cheap, and CMA-ES then polishes from a good mean;
3. CMA-ES in normalised coordinates (``cmaes``), the population of each generation simulated as one
   batch (one candidate per env on GPU, worker processes on CPU); progress bar; history;
4. before/after RMSE per joint on train and held-out data, and 95 % confidence intervals of the
   fitted parameters from the Jacobian at the optimum (``optimize.confidence_intervals``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.errors import InputError
from realm_ms.sysid.alignment import FlangeComparison, replay_flange
from realm_ms.sysid.optimize import Group, GroupScores, cma_fit, confidence_intervals, evaluate_groups, linearized_step, typical_start
from realm_ms.sysid.replay import SegmentSet
from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.effect_spec import parse_effects
from realm_ms.sysid.gripper import gripper_json, gripper_lines
from realm_ms.sysid.signatures import noise_floor, noise_floor_of
from realm_ms.sysid.timeseries import Trajectory


@dataclass
class FitConfig:
    add: str = ""
    generations: int = 30
    popsize: int | None = None
    sigma0: float = 0.04
    seed: int = 0
    patience: int = 6
    tol: float = 2e-3
    # the linearised start iterates (at least twice) while an iteration cuts the train RMSE by gn_gain:
    # a delay and softer gains sit in a narrow valley that CMA-ES's few points do not walk down
    # (with 2 fixed iterations a joint-velocity DROID fit stopped at 3.0 mrad held-out, the truth 0.38)
    gn_iterations: int = 6
    gn_gain: float = 0.25
    segment_s: float = 8.0
    burn_in_s: float = 1.0
    refit: bool = True  # also refit the parameters of effects already in the model (jointly)
    multistart: bool = True  # linearised start from the given values and from typical strengths
    checkpoint: str | None = None
    uncertainty: bool = True  # 95 % intervals of the fitted values (one more batch of k + 1 rollouts)
    # CMA-ES stops (or does not start) once the train RMSE is within this factor of the measurement
    # noise, estimated from the residual at the linearised start (0: never): what is left is noise
    noise_stop: float = 1.05


@dataclass
class FitResult:
    model: RobotModel
    effects: list[str]
    params: dict[str, float]
    before: dict
    after: dict
    history: list[dict] = field(default_factory=list)
    gn_history: list[dict] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)
    bounds: dict[str, list[float]] = field(default_factory=dict)
    # Gauss-Newton 95 % intervals at the fit (``optimize.confidence_intervals``): {key: {std, ci95}}
    uncertainty: dict[str, dict] = field(default_factory=dict)
    # why CMA-ES stopped (``optimize.CmaResult.stop``; "target": at the measurement noise) and that
    # noise (rad, estimated at the linearised start; None where no start improved on the given values)
    cma_stop: str = ""
    noise_rmse: float | None = None
    split: dict | None = None  # the train/held-out split the API used (``api._split_block``)
    flange: FlangeComparison | None = None  # held-out flange mm, lag and b, before and after
    unit = "rad"

    @property
    def heldout_after(self) -> float:
        return float(self.after["heldout_rmse_rad"])

    def to_json(self) -> dict:
        out = {"unit": self.unit, "effects": self.effects, "params": self.params, "before": self.before,
               "after": self.after, "history": self.history, "cma_stop": self.cma_stop, "noise_rmse_rad": self.noise_rmse,
               "units": self.units, "bounds": self.bounds, "uncertainty": self.uncertainty,
               "linearized_start": self.gn_history, "at_bounds": self.model.params_at_bounds()}
        if self.split is not None:
            out["split"] = self.split
        if self.flange is not None:
            out["flange"] = self.flange.to_json()
        return out

    def lines(self) -> list[str]:
        """The terminal summary: fitted values with units and bounds, per-joint held-out RMSE, flange."""
        out = [f"  {k:<32} {v:.5g} {self.units[k]}   bounds {self.bounds[k]}" for k, v in self.params.items()]
        out.append("                     " + " ".join(f"{f'J{i}':>9}" for i in range(1, 8)) + "      all")
        for when, m in (("before", self.before), ("after", self.after)):
            out.append(f"{when:<6} held-out [rad] " + " ".join(f"{v:9.2e}" for v in m["per_joint_heldout_rmse_rad"])
                       + f"  {m['heldout_rmse_rad']:9.2e}   (train {m['train_rmse_rad']:.2e})")
        if self.flange is not None:
            out.append("held-out " + self.flange.line())
        return out + at_bounds_lines(self.model.params_at_bounds())


def at_bounds_lines(at_bounds: dict[str, str]) -> list[str]:
    """A fit's parameters pressed against a bound, as a terminal line (none if there are none)."""
    if not at_bounds:
        return []
    return ["at a bound (the effect is stretched to explain something else): "
            + ", ".join(f"{k} ({side})" for k, side in at_bounds.items())]


@dataclass
class CompareResult:
    """``compare``: the replay of every trajectory with one model (rad)."""

    rmse: float
    per_joint_rmse: list[float]
    per_joint_max_abs_error: list[float]
    noise_floor: float
    noise_floor_per_joint: list[float]
    saturated_fraction: float
    interaction_fraction: float
    trajectories: list[dict]  # {name, rmse_rad, max_abs_error_rad, masked}
    error_over_time: list[tuple[str, float, float]]  # (trajectory, t, RMS over joints) per scored sample
    flange: FlangeComparison | None = None  # flange mm, lag and b beside the real arm's, per trajectory and lab
    gripper: object = None  # the gripper row (``sysid/gripper.GripperCheck``), set by the API when the data has one
    unit = "rad"

    def to_json(self) -> dict:
        return {"unit": self.unit, "rmse_rad": self.rmse, "per_joint_rmse_rad": self.per_joint_rmse,
                "per_joint_max_abs_error_rad": self.per_joint_max_abs_error, "noise_floor_rad": self.noise_floor,
                "saturated_fraction": self.saturated_fraction, "interaction_fraction": self.interaction_fraction,
                "noise_floor_per_joint_rad": self.noise_floor_per_joint, "trajectories": self.trajectories,
                "error_over_time": self.error_over_time, "flange": self.flange.to_json() if self.flange else None} \
            | gripper_json(self.gripper)

    def lines(self) -> list[str]:
        """The terminal summary: per-joint RMSE and max error, masked samples, worst trajectories."""
        out = [f"replay of {len(self.trajectories)} trajectories: RMSE {self.rmse:.3e} rad, noise floor ≈ {self.noise_floor:.2e} rad",
               "joint      " + " ".join(f"{f'J{i}':>9}" for i in range(1, 8)),
               "RMSE [rad] " + " ".join(f"{v:9.2e}" for v in self.per_joint_rmse),
               "max  [rad] " + " ".join(f"{v:9.2e}" for v in self.per_joint_max_abs_error)]
        if self.interaction_fraction:
            out.append(f"grasps and stalls against the scene (not modelled by an arm-only replay) and near-singular IK "
                       f"targets: {self.interaction_fraction:.1%} of the scored samples simulated but not scored; per trajectory: "
                       + ", ".join(f"{t['name']} {t['masked']['masked']:.0%}"
                                   + (f" (singular {t['masked']['singular']:.0%})" if t["masked"].get("singular") else "")
                                   for t in self.trajectories if t.get("masked") and t["masked"]["masked"] > 0))
        worst = sorted(self.trajectories, key=lambda t: -(t["rmse_rad"] or 0))[:3]
        out.append("worst trajectories: " + ", ".join(f"{t['name']} ({t['rmse_rad']:.2e} rad)" for t in worst))
        if self.flange is not None:
            out.append(self.flange.line())
        return out + gripper_lines(self.gripper)


def _metrics(tr: GroupScores, he: GroupScores) -> dict:
    return {"train_rmse_rad": tr.rmse, "heldout_rmse_rad": he.rmse, "per_joint_heldout_rmse_rad": he.per_joint_rmse,
            "per_joint_train_rmse_rad": tr.per_joint_rmse}


def fit(train: list[Trajectory], heldout: list[Trajectory], model: RobotModel | None = None,
        config: FitConfig | None = None, evaluator=None, progress: bool = True, log=print) -> FitResult:
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.simulator import SimConfig

    cfg = config or FitConfig()
    model = (model or RobotModel()).copy()
    added = parse_effects(cfg.add)
    clash = [fx.name for fx in added if fx.name in model.names]
    if clash:
        raise InputError(f"{', '.join(clash)} already in the model (its parameters are refitted anyway); drop it from --add")
    fitted = added + ([fx for fx in model.effects] if cfg.refit else [])
    if not added:
        raise InputError("nothing to fit: give effects with --add (see `realm sysid effects`)")
    fixed = [fx for fx in model.effects if fx not in fitted]
    ev = evaluator or Evaluator.auto(SimConfig.from_model(model))
    tr_ss = SegmentSet.build(train, model.physics_hz, cfg.segment_s, cfg.burn_in_s, gains=model.gains)
    he_ss = SegmentSet.build(heldout, model.physics_hz, cfg.segment_s, cfg.burn_in_s, gains=model.gains)
    base_fixed = sorted(fixed, key=lambda fx: fx.order)

    # before: the model as given
    before_group = Group.of([])
    (b_tr,), (b_he,) = evaluate_groups(ev, [tr_ss, he_ss], sorted(model.effects, key=lambda f: f.order), [before_group], [np.zeros((1, 0))])
    before = _metrics(b_tr, b_he)
    log(f"before: train RMSE {before['train_rmse_rad']:.3e} rad, held-out {before['heldout_rmse_rad']:.3e} rad")

    group = Group.of(fitted)
    # multi-start linearised fit: from the given values (off unless set on the command line) and
    # from the parameters' typical strengths, both in one batch; the better one seeds CMA-ES.
    # Stick-slip effects (stiction) have local minima that one start can fall into.
    starts = [group]
    if cfg.multistart:
        starts.append(typical_start(group, {p.key for fx in added for p in fx.free_params}))
    gn_hist = []
    mse = [np.inf] * len(starts)
    sims = [None] * len(starts)  # the train simulation at each start's current point
    for it in range(cfg.gn_iterations):
        # first iteration as the diagnosis screens (block probes: robust for stick-slip effects),
        # then full-Jacobian iterations
        rs = linearized_step(ev, tr_ss, base_fixed, starts, first=(it == 0), block=(it == 0))
        mse = [r.mse_after for r in rs]
        sims = [r.scores[0].sim[0] if r.improved else sim for r, sim in zip(rs, sims)]
        best = int(np.argmin(mse))
        gn_hist.append({"iteration": it + 1, "train_rmse_rad": float(np.sqrt(mse[best]))})
        log(f"linearised start {it + 1}: train RMSE {np.sqrt(rs[0].mse_before):.3e} -> "
            + ", ".join(f"{np.sqrt(m):.3e}" for m in mse) + " rad" + (" (starts: given, typical)" if len(starts) > 1 else ""))
        if it >= 1 and gn_hist[-1]["train_rmse_rad"] > (1 - cfg.gn_gain) * gn_hist[-2]["train_rmse_rad"]:
            break
    if starts[int(np.argmin(mse))] is not group:
        group.apply(starts[int(np.argmin(mse))].u)

    def loss(us: np.ndarray) -> np.ndarray:
        (res,) = evaluate_groups(ev, [tr_ss], base_fixed, [group], [us])
        return res[0].mse

    start_loss = gn_hist[-1]["train_rmse_rad"] ** 2 if gn_hist else None
    sim = sims[int(np.argmin(mse))] if gn_hist else None
    noise = noise_floor_of(tr_ss, sim)[0] if sim is not None else None
    target = (cfg.noise_stop * noise) ** 2 if noise and cfg.noise_stop > 0 else None
    res = cma_fit(loss, group.u.copy(), sigma0=cfg.sigma0, seed=cfg.seed, max_generations=cfg.generations,
                  popsize=cfg.popsize, patience=cfg.patience, tol=cfg.tol, checkpoint=cfg.checkpoint,
                  progress=progress, initial_loss=start_loss, target_loss=target)
    group.apply(res.u)
    if res.stop == "target":
        log(f"CMA-ES: {'stopped after ' + str(res.generations) + ' generations' if res.history else 'not run'}: "
            f"train RMSE {np.sqrt(res.loss):.3e} rad is within {cfg.noise_stop:g}x the measurement noise "
            f"{noise:.3e} rad, so what is left is noise")
    elif res.history:
        log(f"CMA-ES: {res.generations} generations, best train RMSE {res.history[-1]['best_loss']:.3e} rad")

    (a_tr,), (a_he,) = evaluate_groups(ev, [tr_ss, he_ss], base_fixed, [group], [group.u[None]])
    after = _metrics(a_tr, a_he)
    uncertainty = confidence_intervals(ev, tr_ss, base_fixed, group) if cfg.uncertainty else {}
    log(f"after: train RMSE {after['train_rmse_rad']:.3e} rad, held-out {after['heldout_rmse_rad']:.3e} rad")
    out_model = RobotModel(sorted(base_fixed + fitted, key=lambda f: f.order), model.gains, model.joint_physics,
                           model.physics_hz, dict(model.provenance))
    params = {p.key: float(v) for p, v in zip(group.params, group.params.from_unit(group.u))}
    units = {p.key: p.unit for p in group.params}
    bounds = {p.key: [p.spec.lo, p.spec.hi] for p in group.params}
    flange = replay_flange(he_ss, [("before", b_he.sim[0]), ("after", a_he.sim[0])])
    return FitResult(out_model, [fx.name for fx in fitted], params, before, after, res.history, gn_hist, units, bounds,
                     uncertainty, res.stop, noise, flange=flange)


def compare(data: list[Trajectory], model: RobotModel | None = None, segment_s: float = 8.0, burn_in_s: float = 1.0,
            evaluator=None) -> CompareResult:
    """Replay ``data`` with ``model``: per-joint RMSE / max error, error over time, noise floor."""
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.simulator import SimConfig

    model = model or RobotModel()
    ev = evaluator or Evaluator.auto(SimConfig.from_model(model))
    ss = SegmentSet.build(data, model.physics_hz, segment_s, burn_in_s, gains=model.gains)
    (r,) = evaluate_groups(ev, [ss], sorted(model.effects, key=lambda f: f.order), [Group.of([])], [np.zeros((1, 0))])
    sim = r[0].sim[0]
    res = np.where(ss.mask[..., None], ss.meas - sim, np.nan)
    floor, floor_j = noise_floor(ss, res)
    per_traj = []
    for ti, tr in enumerate(data):
        rows = [i for i, s in enumerate(ss.segments) if s.traj == ti]
        rr = res[rows][ss.mask[rows]]
        per_traj.append({"name": tr.name, "rmse_rad": float(np.sqrt(np.mean(rr**2))) if rr.size else None,
                         "max_abs_error_rad": float(np.max(np.abs(rr))) if rr.size else None,
                         "masked": tr.meta.get("interaction")})
    # error over time: RMS over joints per scored sample, with its trajectory time
    over_time = []
    for i, s in enumerate(ss.segments):
        m = ss.mask[i]
        t = data[s.traj].t[s.start:s.stop][m[: s.stop - s.start]]
        e = np.sqrt(np.mean(res[i][m] ** 2, axis=1))
        over_time += [(data[s.traj].name, float(a), float(b)) for a, b in zip(t, e)]
    allres = res[ss.mask]
    return CompareResult(float(np.sqrt(np.mean(allres**2))), [float(x) for x in np.sqrt(np.mean(allres**2, axis=0))],
                         [float(x) for x in np.max(np.abs(allres), axis=0)], floor, [float(x) for x in floor_j],
                         ss.saturated_fraction, ss.interaction_fraction, per_traj, over_time,
                         replay_flange(ss, [("model" if model.effects else "nominal", sim)]))
