"""Optimisers over effect parameters, in normalised coordinates u in [0, 1] (lin/log per parameter).

* ``linearized_step``: batched secant (finite-difference) sensitivities of the simulated trajectory,
  one Levenberg-Marquardt solve per group of parameters, a 2-point line search -- used by the
  diagnosis to screen every candidate effect in a few batched rollouts and to start the fit.
* ``cma_fit``: CMA-ES (the ``cmaes`` package) with the population evaluated as one batch,
  progress bar, per-generation history and an optional resumable checkpoint.
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from realm_ms.agents.effects import Effect, make_effect
from realm_ms.agents.effects.parameter import Param, ParamSet
from realm_ms.atomic import write_bytes
from realm_ms.sysid.replay import SegmentSet, score


@dataclass
class Group:
    """A set of effects fitted together (one candidate explanation), with its free parameters."""

    effects: list[Effect]
    params: ParamSet
    u: np.ndarray  # current point in unit coordinates

    @classmethod
    def of(cls, effects: list[Effect], params: list[Param] | None = None) -> "Group":
        ps = ParamSet.of(params if params is not None else [p for fx in effects for p in fx.free_params])
        x = np.array([fx.values()[p.local_key] for p in ps for fx in effects if fx.name == p.effect])
        return cls(effects, ps, ps.to_unit(x))

    def theta_rows(self, us: np.ndarray) -> dict[str, np.ndarray]:
        """Effect name -> theta (R, n) for R points ``us`` (R, P) in unit coordinates."""
        xs = self.params.from_unit(us)
        out = {}
        for fx in self.effects:
            base = fx.theta[0].cpu().numpy().astype(np.float64)
            rows = np.repeat(base[None], len(us), 0)
            for k, p in enumerate(self.params):
                if p.effect == fx.name:
                    rows[:, fx.params.index(p)] = xs[:, k]
            out[fx.name] = rows
        return out

    def apply(self, u: np.ndarray) -> None:
        """Set the effects' values to point ``u``."""
        self.u = np.clip(np.asarray(u, dtype=float), 0, 1)
        for name, rows in self.theta_rows(self.u[None]).items():
            fx = next(f for f in self.effects if f.name == name)
            fx.set_theta(rows)

    def values(self) -> dict[str, float]:
        return self.params.as_dict(self.params.from_unit(self.u))


def copy_effect(fx: Effect) -> Effect:
    """An independent effect with ``fx``'s values and configuration."""
    return make_effect(fx.name, fx.values(), fx.config_dict())


def typical_start(group: Group, keys: set[str]) -> Group:
    """A copy of ``group`` with the parameters in ``keys`` at their typical (nominal) strengths and
    the others where ``group`` has them: the second start of a linearised fit, for effects whose
    off-values are a poor place to linearise (a payload of zero mass has no centre of mass to
    probe; a stick-slip law has local minima)."""
    alt = Group.of([copy_effect(fx) for fx in group.effects])
    u_nom = alt.params.to_unit(alt.params.nominal())
    alt.apply(np.array([u_nom[i] if p.key in keys else group.u[i] for i, p in enumerate(alt.params)]))
    return alt


def batch_effects(base: list[Effect], rows: list[dict[str, np.ndarray]], all_names: list[str], configs: dict) -> list[Effect]:
    """Stack per-candidate theta rows into batched effect instances (one per effect name).
    ``rows[c][name]`` is the (1, n) theta of effect ``name`` in candidate c; missing = off."""
    out = []
    for fx in base:
        out.append(fx)  # base model effects: shared across candidates (theta with 1 row)
    for name in all_names:
        proto = make_effect(name, None, configs.get(name, {}))
        off = proto.theta[0].cpu().numpy().astype(np.float64)
        th = np.stack([r[name][0] if name in r else off for r in rows])
        proto.set_theta(th)
        out.append(proto)
    return out


@dataclass
class GroupScores:
    """One group's R points evaluated on one segment set."""

    mse: np.ndarray  # (R,) mean over scored samples and joints, rad^2
    per_joint_mse: np.ndarray  # (R, 7)
    sim: np.ndarray  # (R, N, L, 7) simulated q at the data samples

    def row(self, i: int) -> "GroupScores":
        """Point ``i`` alone (still a batch of one)."""
        return GroupScores(self.mse[i:i + 1], self.per_joint_mse[i:i + 1], self.sim[i:i + 1])

    @property
    def rmse(self) -> float:
        """RMSE of the first (usually the only) point."""
        return float(np.sqrt(self.mse[0]))

    @property
    def per_joint_rmse(self) -> list[float]:
        return [float(x) for x in np.sqrt(self.per_joint_mse[0])]


def evaluate_groups(evaluator, segsets: list[SegmentSet], base: list[Effect], groups: list[Group],
                    points: list[np.ndarray]) -> list[list[GroupScores]]:
    """Evaluate, for each group g, the points ``points[g]`` (R_g, P_g) on every segset; all in one
    batch. Returns ``out[s][g]``: the scores of group g's R_g points on segset s."""
    rows: list[dict[str, np.ndarray]] = []
    owner: list[tuple[int, int]] = []
    names: list[str] = []
    configs: dict = {}
    base_names = {fx.name for fx in base}
    for gi, (g, pts) in enumerate(zip(groups, points)):
        th = g.theta_rows(np.atleast_2d(pts))
        for fx in g.effects:
            if fx.name not in names and fx.name not in base_names:
                names.append(fx.name)
                configs[fx.name] = fx.config_dict()
        for r in range(len(np.atleast_2d(pts))):
            rows.append({k: v[r:r + 1] for k, v in th.items()})
            owner.append((gi, r))
    n_cand = len(rows)
    results = []
    # every set in one rollout (train and held-out alike): its cost is mostly per physics step
    sims = SegmentSet.split(segsets, evaluator.simulate(SegmentSet.stack(segsets), batch_effects(base, rows, names, configs),
                                                        n_cand), n_cand)
    for ss, sim in zip(segsets, sims):
        sc = score(ss, sim, n_cand)
        sim = sim.reshape(n_cand, ss.n, *sim.shape[1:])
        per_group = []
        for gi in range(len(groups)):
            idx = [c for c, (g, _) in enumerate(owner) if g == gi]
            per_group.append(GroupScores(sc.mse[idx], sc.per_joint_mse[idx], sim[idx]))
        results.append(per_group)
    return results


@dataclass
class LinearStep:
    """One group's linearised step (``linearized_step``)."""

    mse_before: float  # train MSE at the group's point before the step
    mse_after: float  # ... after it (= before when no step lowered it)
    improved: bool
    # at the chosen point, on ``ss`` and then each of ``also`` (None when not improved)
    scores: list[GroupScores] | None
    insensitive: list[int]  # parameters whose probe did not change the simulation

    @property
    def also(self) -> list[GroupScores]:
        """The scores on the ``also`` sets (the held-out set first)."""
        return self.scores[1:] if self.scores else []


#: a probe whose rollout moves no sample by more than this saw nothing (float32 rollouts differ by
#: ~1e-6 rad when only their batch neighbours change; measurement noise is >= 1e-4 rad)
PROBE_RESOLUTION_RAD = 1e-5


def probe_steps(ps: ParamSet, u: np.ndarray, first: bool) -> np.ndarray:
    """Secant step per parameter: towards the nominal strength (from off) on the first iteration,
    30 % of that afterwards; never zero, always inside [0, 1]."""
    u_nom, u_off = ps.to_unit(ps.nominal()), ps.to_unit(ps.off())
    h = (u_nom - u_off) * (1.0 if first else 0.3)
    h = np.where(np.abs(h) < 0.02, 0.05, h)
    h = np.where((u + h > 1) | (u + h < 0), -h, h)
    return h


def probe_blocks(ps: ParamSet, block: bool) -> list[list[int]]:
    """Which parameters are perturbed together in one probe rollout. ``block``: the 7 joints of a
    per-joint parameter share one probe and each joint's column is read from that joint's residual
    only (block-diagonal sensitivities; cross-joint coupling is recovered by the next, full iteration
    and by the fit) -- 7x fewer rollouts for screening."""
    if not block:
        return [[i] for i in range(len(ps))]
    groups: dict[tuple, list[int]] = {}
    for i, p in enumerate(ps):
        key = (p.effect, p.spec.name) if p.joint is not None else (p.effect, p.spec.name, i)
        groups.setdefault(key, []).append(i)
    return list(groups.values())


def linearized_step(evaluator, ss: SegmentSet, base: list[Effect], groups: list[Group], first: bool,
                    damping: float = 1e-3, block: bool = False, also: list[SegmentSet] | None = None) -> list[LinearStep]:
    """One Gauss-Newton/LM iteration for every group independently (other groups off), batched:
    one probe rollout per parameter (or per block, see ``probe_blocks``) for the secant
    sensitivities, then the full and the half step evaluated on ``ss`` (+ ``also``) in one batch.
    Each group moves to the better step if it lowers the loss on ``ss``. Returns a ``LinearStep``
    per group."""
    pts, plans = [], []
    for g in groups:
        h = probe_steps(g.params, g.u, first)
        blocks = probe_blocks(g.params, block)
        probes = [g.u.copy()]
        for b in blocks:
            u = g.u.copy()
            u[b] += h[b]
            probes.append(u)
        pts.append(np.vstack(probes))
        plans.append((h, blocks))
    res = evaluate_groups(evaluator, [ss], base, groups, pts)[0]
    mask = ss.mask
    cand, insensitive, mse0 = [], [], []
    for g, (h, blocks), sc in zip(groups, plans, res):
        sim = sc.sim
        y0 = sim[0][mask]  # (M, 7)
        r = (ss.meas[mask] - y0).ravel()
        cols = np.zeros((y0.size, len(h)))
        for bi, b in enumerate(blocks):
            dy = sim[bi + 1][mask] - y0
            for k in b:
                j = g.params.params[k].joint
                if len(b) > 1 and j is not None:
                    d = np.zeros_like(dy)
                    d[:, j] = dy[:, j]
                    cols[:, k] = d.ravel() / h[k]
                else:
                    cols[:, k] = dy.ravel() / h[k]
        ok = np.isfinite(cols).all(axis=0) & (np.abs(cols).sum(axis=0) > 0)
        # a probe that moves no sample by more than float32 noise found nothing to linearise
        moved = np.where(np.isfinite(cols), np.abs(cols), np.inf).max(axis=0, initial=0.0) * np.abs(h)
        insensitive.append([int(k) for k in np.nonzero(moved < PROBE_RESOLUTION_RAD)[0]])
        delta = np.zeros(len(h))
        if ok.any() and np.isfinite(r).all():
            Jo = cols[:, ok]
            jtj = Jo.T @ Jo
            d = np.diag(jtj).copy()
            reg = damping * np.diag(d) + 1e-9 * max(d.max(), 1e-30) * np.eye(len(d))
            try:
                delta[ok] = np.linalg.solve(jtj + reg, Jo.T @ r)
            except np.linalg.LinAlgError:
                delta[ok] = np.linalg.lstsq(jtj + reg, Jo.T @ r, rcond=None)[0]
        cand.append(np.vstack([g.u, np.clip(g.u + delta, 0, 1), np.clip(g.u + 0.5 * delta, 0, 1)]))
        mse0.append(float(sc.mse[0]))
    sets = [ss] + list(also or [])
    res2 = evaluate_groups(evaluator, sets, base, groups, [c[1:] for c in cand])
    out = []
    for gi, (g, c, before) in enumerate(zip(groups, cand, mse0)):
        mse = res2[0][gi].mse
        best = int(np.argmin(mse))
        improved = bool(mse[best] < before)
        if improved:
            g.apply(c[1 + best])
        scores = [s[gi].row(best) for s in res2] if improved else None
        out.append(LinearStep(before, float(min(mse[best], before)), improved, scores, insensitive[gi]))
    return out


def confidence_intervals(evaluator, ss: SegmentSet, base: list[Effect], group: Group, z: float = 1.96) -> dict:
    """Gauss-Newton uncertainty at the fitted values: a forward-difference Jacobian of the simulated
    positions w.r.t. each parameter (one batch of k + 1 rollouts), Sigma_u = s^2 (J^T J)^-1 with
    s^2 = RSS / (N - k), inflated by (1 + rho) / (1 - rho) for the residual's lag-1 autocorrelation
    rho (trajectory residuals are far from white), mapped to physical units through each
    parameter's scale. Returns {key: {"std": ..., "ci95": [lo, hi]}}; a direction the data cannot
    see (singular J^T J) gets an infinite interval, clipped to the bounds."""
    k = len(group.params)
    if k == 0:
        return {}
    u0 = group.u.copy()
    h = np.where(u0 + 0.01 > 1.0, -0.01, 0.01)
    pts = np.vstack([u0] + [u0 + np.eye(k)[i] * h[i] for i in range(k)])
    (res,) = evaluate_groups(evaluator, [ss], base, [group], [pts])
    sim = res[0].sim
    group.apply(u0)
    mask = ss.mask
    y0 = sim[0][mask]
    r = ss.meas[mask] - y0
    jac = np.stack([(sim[i + 1][mask] - y0).ravel() / h[i] for i in range(k)], axis=1)
    n = r.size
    rss = float(np.nansum(r**2))
    rr = r - np.nanmean(r, axis=0)
    rho = float(np.clip(np.nansum(rr[1:] * rr[:-1]) / max(np.nansum(rr**2), 1e-300), 0.0, 0.99))
    s2 = rss / max(n - k, 1) * (1 + rho) / (1 - rho)
    jtj = jac.T @ jac
    try:
        cov = s2 * np.linalg.pinv(jtj, rcond=1e-10, hermitian=True)
        std_u = np.sqrt(np.clip(np.diag(cov), 0, None))
        std_u[np.diag(jtj) <= 1e-300] = np.inf
    except np.linalg.LinAlgError:
        std_u = np.full(k, np.inf)
    out = {}
    for i, p in enumerate(group.params):
        lo_u, hi_u = u0[i] - z * std_u[i], u0[i] + z * std_u[i]
        v, lo, hi = (float(p.from_unit(x)) for x in (u0[i], lo_u if np.isfinite(lo_u) else 0.0, hi_u if np.isfinite(hi_u) else 1.0))
        out[p.key] = {"std": float((hi - lo) / (2 * z)) if np.isfinite(std_u[i]) else float("inf"), "ci95": [lo, hi]}
    return out


# ---------------------------------------------------------------------------- CMA-ES
@dataclass
class CmaResult:
    u: np.ndarray
    loss: float
    history: list[dict] = field(default_factory=list)
    generations: int = 0
    # why it stopped: "max_generations", "patience", "cmaes" (its own criteria) or "target"
    stop: str = "max_generations"


def cma_fit(loss_fn: Callable[[np.ndarray], np.ndarray], u0: np.ndarray, sigma0: float = 0.05, seed: int = 0,
            max_generations: int = 40, popsize: int | None = None, patience: int = 8, tol: float = 1e-3,
            checkpoint: str | Path | None = None, progress: bool = True, initial_loss: float | None = None,
            target_loss: float | None = None) -> CmaResult:
    """Minimise ``loss_fn`` (batched: (C, P) unit points -> (C,) losses) with CMA-ES in [0, 1]^P.

    Stops after ``max_generations``, when the best loss improved by less than ``tol`` (relative) over
    ``patience`` generations, when CMA-ES says so, or once the best loss (``initial_loss`` included:
    then before the first generation) is at or below ``target_loss``. With ``checkpoint``, the optimiser state is
    written after every generation and a rerun resumes from it."""
    from cmaes import CMA

    dim = len(u0)
    ckpt = Path(checkpoint) if checkpoint else None
    state = None
    if ckpt and ckpt.exists():
        try:
            state = pickle.loads(ckpt.read_bytes())
            if len(state["best_u"]) != dim:
                state = None
        except Exception:  # noqa: BLE001 - a corrupt checkpoint is ignored, not fatal
            state = None
    if state is None:
        bounds = np.array([[0.0, 1.0]] * dim)
        # cmaes needs dim >= 2; a 1-D problem gets a dummy coordinate that does nothing
        opt = CMA(mean=np.r_[np.clip(u0, 0, 1), 0.5] if dim == 1 else np.clip(u0, 0, 1), sigma=sigma0,
                  bounds=np.vstack([bounds, [[0, 1]]]) if dim == 1 else bounds, seed=seed,
                  population_size=popsize)
        state = {"opt": opt, "history": [], "best_u": np.clip(u0, 0, 1), "best_loss": initial_loss if initial_loss is not None else np.inf}
    opt, history = state["opt"], state["history"]
    def at_target() -> bool:
        return target_loss is not None and state["best_loss"] <= target_loss

    bar = None
    if progress and not at_target():
        from tqdm.auto import tqdm

        bar = tqdm(total=max_generations, initial=len(history), desc="CMA-ES", unit="gen", leave=False)
    stop = "max_generations"
    try:
        while len(history) < max_generations:
            if at_target():
                stop = "target"
                break
            xs = np.array([opt.ask() for _ in range(opt.population_size)])
            us = xs[:, :dim]
            losses = np.asarray(loss_fn(us), dtype=float)
            losses = np.where(np.isfinite(losses), losses, 1e6)
            opt.tell([(x, float(v)) for x, v in zip(xs, losses)])
            i = int(np.argmin(losses))
            if losses[i] < state["best_loss"]:
                state["best_loss"], state["best_u"] = float(losses[i]), us[i].copy()
            history.append({"generation": len(history) + 1, "best_loss": float(np.sqrt(state["best_loss"])),
                            "median_loss": float(np.sqrt(np.median(losses)))})
            if bar:
                bar.update(1)
                bar.set_postfix(best_rmse=f"{history[-1]['best_loss']:.2e} rad")
            if ckpt:
                write_bytes(ckpt, pickle.dumps(state))
            if len(history) > patience:
                old = history[-1 - patience]["best_loss"]
                if old - history[-1]["best_loss"] <= tol * old:
                    stop = "patience"
                    break
            if opt.should_stop():
                stop = "cmaes"
                break
    finally:
        if bar:
            bar.close()
    return CmaResult(state["best_u"], float(state["best_loss"]), history, len(history), stop)
