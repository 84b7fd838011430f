"""The hidden-effect sweep: does sysid find and fit one hidden effect in data it did not make?

For every (effect, seed): ``synth`` data with that one effect hidden at its typical strength
(``realm sysid effects``), by default from the independent MuJoCo reference; ``diagnose``; ``fit``
the hidden effect. ``effect="none"`` rows (no hidden effect) give the seed's error floor: what the
nominal model leaves on foreign data (the remaining plant difference) or the noise floor, whichever
is larger. Cases are independent, so ``sweep`` runs them in parallel processes (one core each).

Criteria (``judge``): the hidden effect (or its documented confound partner) is ranked first, and
the held-out RMSE after the fit is <= 1.5x the seed's floor; with no hidden effect the verdict is
"no missing effect" and not "unexplained".
"""

from __future__ import annotations

import os
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

SWEEP_EFFECTS = ("coulomb_friction", "viscous_damping", "payload", "latency", "gravity_comp_error", "gain_mismatch",
                 "encoder_bias", "armature")
FLOOR_FACTOR = 1.5


@dataclass
class CaseResult:
    effect: str
    seed: int
    engine: str
    noise_rad: float
    verdict: str
    missing_effect_found: bool
    unexplained: bool
    ranked: list[str]
    noise_floor_rad: float
    baseline_heldout_rmse_rad: float
    heldout_before_rad: float | None = None
    heldout_after_rad: float | None = None
    per_joint_after_rad: list[float] = field(default_factory=list)
    params: dict[str, float] = field(default_factory=dict)
    truth: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0
    # filled by ``judge``
    floor_rad: float | None = None
    ranked_first: bool | None = None
    passed: bool | None = None
    # diagnose's verdict code: no_missing_effect | found | partially_explained | unexplained
    verdict_code: str = ""


def run_case(effect: str, seed: int, engine: str = "mujoco", noise_rad: float = 1e-4, workdir: str | None = None,
             evaluator=None) -> CaseResult:
    """synth + diagnose (+ fit of the hidden effect) for one case, on CPU in this process."""
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.diagnose import diagnose
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.fit import FitConfig, fit
    from realm_ms.sysid.synth import SynthConfig, synth

    t0 = time.perf_counter()
    quiet = lambda *a: None  # noqa: E731
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        info = synth(effect, Path(tmp) / "data", SynthConfig(seed=seed, noise_rad=noise_rad, engine=engine))
        train, held = load_split(Path(tmp) / "data")
    ev = evaluator or Evaluator(workers=1, device="cpu")
    try:
        d = diagnose(train, held, evaluator=ev, log=quiet)
        row = CaseResult(effect, seed, engine, noise_rad, d.message, bool(d.missing_effect_found), bool(d.unexplained),
                         [s.effect for s in d.suspects[:3]], float(d.noise_floor), float(d.baseline_heldout_rmse),
                         truth={k: float(v) for k, v in info["truth"].items()} if isinstance(info["truth"], dict) else {},
                         verdict_code=d.verdict)
        if effect != "none":
            f = fit(train, held, config=FitConfig(add=effect), evaluator=ev, progress=False, log=quiet)
            row.heldout_before_rad = float(f.before["heldout_rmse_rad"])
            row.heldout_after_rad = float(f.after["heldout_rmse_rad"])
            row.per_joint_after_rad = [float(x) for x in f.after["per_joint_heldout_rmse_rad"]]
            row.params = {k: float(v) for k, v in f.params.items()}
    finally:
        if evaluator is None:
            ev.close()
    row.seconds = time.perf_counter() - t0
    return row


def judge(rows: list[CaseResult]) -> list[CaseResult]:
    """Fill ``floor_rad``, ``ranked_first`` and ``passed`` (see the module docstring)."""
    from realm_ms.agents.effects import confounded_with

    null = {r.seed: r.baseline_heldout_rmse_rad for r in rows if r.effect == "none"}
    for r in rows:
        r.floor_rad = max(r.noise_floor_rad, null.get(r.seed, 0.0))
        if r.effect == "none":
            r.ranked_first = None
            r.passed = not r.missing_effect_found and not r.unexplained and r.verdict_code in ("", "no_missing_effect")
        else:
            # the diagnosis names an effect when it is "found" (screened to the floor) or "partially
            # explained" (the screening's one LM step left more; the fit below must reach the floor)
            named = r.missing_effect_found or r.verdict_code == "partially_explained"
            top = r.ranked[0] if r.ranked else None
            r.ranked_first = bool(named and top is not None
                                  and (top == r.effect or top in confounded_with(r.effect)))
            r.passed = bool(r.ranked_first and r.heldout_after_rad is not None
                            and r.heldout_after_rad <= FLOOR_FACTOR * r.floor_rad)
    return rows


def _case(args) -> dict:
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    import torch

    torch.set_num_threads(1)
    effect, seed, engine, noise = args
    try:
        return asdict(run_case(effect, seed, engine, noise))
    except Exception as e:  # one failing case must not lose the others' results
        return {"effect": effect, "seed": seed, "error": f"{type(e).__name__}: {e}"}


def sweep_cases(effects, seeds, engine: str, noise_rad: float, done: list[CaseResult] = ()) -> list[tuple]:
    """(effect, seed, engine, noise) still to run: the null cases first (they set the floors), then
    seed by seed, so a run cut off short has every effect on the first seeds rather than every seed
    of the first effects; cases in ``done`` are left out."""
    have = {(r.effect, r.seed) for r in done}
    cases = [("none", s) for s in seeds] + [(e, s) for s in seeds for e in effects]
    return [(e, s, engine, noise_rad) for e, s in cases if (e, s) not in have]


def sweep(effects=SWEEP_EFFECTS, seeds=(0, 1, 2), engine: str = "mujoco", noise_rad: float = 1e-4,
          jobs: int | None = None, on_row=None, done: list[CaseResult] = ()) -> tuple[list[CaseResult], list[dict]]:
    """All (effect, seed) cases plus the null case per seed, ``jobs`` processes (default: all cores).
    ``done``: rows of an earlier, cut-off run of the same sweep; their cases are not run again.
    Returns (judged rows, ``done`` included; failed cases)."""
    import multiprocessing as mp

    cases = sweep_cases(effects, seeds, engine, noise_rad, done)
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(cases) or 1))
    rows, failed = list(done), []
    # spawn: PhysX and torch thread pools do not survive fork
    with mp.get_context("spawn").Pool(jobs, maxtasksperchild=1) as pool:
        for out in pool.imap_unordered(_case, cases):
            if "error" in out:
                failed.append(out)
            else:
                rows.append(CaseResult(**out))
            if on_row:
                on_row(out)
    order = {e: i for i, e in enumerate(list(effects) + ["none"])}
    rows.sort(key=lambda r: (order[r.effect], r.seed))
    return judge(rows), failed


def markdown(rows: list[CaseResult]) -> str:
    """The sweep as a markdown table (RMSE in mrad)."""
    mrad = lambda v: "-" if v is None else f"{1e3 * v:.2f}"  # noqa: E731
    lines = ["| hidden effect | seed | ranked first? (top 3) | held-out before | after | floor (1.5x) | pass |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        first = "n/a" if r.ranked_first is None else ("yes" if r.ranked_first else "**no**")
        verdict = f" {r.verdict_code}" if r.verdict_code else ((" \"no missing effect\"" if not r.missing_effect_found else "")
                                                                + (" unexplained" if r.unexplained else ""))
        before = r.heldout_before_rad if r.effect != "none" else r.baseline_heldout_rmse_rad
        lines.append(f"| {r.effect} | {r.seed} | {first}{verdict} ({', '.join(r.ranked)}) | {mrad(before)} | "
                     f"{mrad(r.heldout_after_rad)} | {mrad(r.floor_rad)} ({mrad(None if r.floor_rad is None else FLOOR_FACTOR * r.floor_rad)}) | "
                     f"{'yes' if r.passed else '**no**'} |")
    return "\n".join(lines)
