"""The space the workbench measures error in: position (this module) or torque (``torque/space.py``).

A space is bound to the data (train and held-out trajectories) and answers the verbs in its own
unit: ``compare``, ``diagnose``, ``fit``, ``report``, and, for ``auto``'s one loop (``auto.py``),
``fit_suspect`` (fit a ranked suspect onto the current model; ``fit_replays``: whether that costs a
replay of the data, counted against ``auto``'s fit budget), ``details`` (what only this space
reports), ``flange`` (the held-out flange figures of the start and final models, or why there are
none), ``screened`` / ``library`` (which effects the diagnosis ranks / could rank) and
``replay_floor`` (its own error on a plant that matches it). ``api.py`` picks the space once
(``SPACES``, ``pick``).

Position space replays ``q_cmd`` under the DROID controller (rad): DROID recordings, with their
closed-loop command and grasp/stall masks, are position-space data.
"""

from __future__ import annotations

from pathlib import Path

from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.diagnose import Diagnosis, DiagnoseConfig, diagnose
from realm_ms.sysid.fit import CompareResult, FitConfig, FitResult, compare, fit
from realm_ms.sysid.timeseries import DataError, Trajectory
from realm_ms.sysid.torque.space import TorqueSpace


class PositionSpace:
    """Position space: the multiple-shooting replay of ``q_cmd`` (rad), fitted by CMA-ES."""

    name = "position"
    unit = "rad"
    fit_replays = True  # ``fit_suspect`` replays the data (CMA-ES): counted against auto's ``max_fits``

    def __init__(self, train: list[Trajectory], heldout: list[Trajectory], evaluator, progress: bool = True):
        self.train, self.heldout, self.evaluator, self.progress = train, heldout, evaluator, progress

    @classmethod
    def build(cls, train, heldout, model: RobotModel, workers=None, device=None, progress: bool = True) -> "PositionSpace":
        """The space with a replay evaluator for ``model``'s simulation settings (``engine.Evaluator.auto``)."""
        import sys

        from realm_ms.sysid.engine import Evaluator
        from realm_ms.sysid.simulator import SimConfig
        from realm_ms.validate import check_device, check_int

        if workers is not None:
            workers = check_int(workers, "workers (--workers)", minimum=1)
        if device is not None:
            check_device(device)
        ev = Evaluator.auto(SimConfig.from_model(model), workers, device)
        ev.progress = progress and sys.stderr.isatty()
        return cls(train, heldout, ev, progress)

    def close(self) -> None:
        """Stop the replay's worker processes (a verb's last step: ``with`` the space)."""
        self.evaluator.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @staticmethod
    def replay_floor(cfg: DiagnoseConfig) -> float:
        return cfg.replay_floor_rad

    @staticmethod
    def suits(trajs: list[Trajectory]) -> bool:
        return all(t.q_cmd is not None for t in trajs)

    @staticmethod
    def check(trajs: list[Trajectory]) -> None:
        no_cmd = [t.name for t in trajs if t.q_cmd is None]
        if no_cmd:
            has_tau = all(t.tau is not None for t in trajs)
            raise DataError(f"{no_cmd[0]}: no q_cmd (commanded targets); the position-space replay needs them. "
                            + ("It has tau: use --space torque (the inverse-dynamics residual)" if has_tau else
                               "Add q_cmd, or tau for torque-space work"))

    @staticmethod
    def check_identifiable(trajs: list[Trajectory]) -> None:
        """Motion is all the replay needs (``timeseries.check_identifiable``)."""

    def library(self) -> list[str]:
        from realm_ms.agents.effects import arm_effects

        return arm_effects()  # the gripper's: the gripper row

    def screened(self, cfg: DiagnoseConfig) -> list[str]:
        return list(cfg.candidates)

    def searching(self, budget_s: float | None) -> "PositionSpace":
        """The space ``auto`` screens and fits on: the train trajectories, in order, that fit in
        ``budget_s`` seconds (at least one; None or 0: all), the held-out split whole. A replay's cost
        grows with the data it simulates, and every screening probe and CMA-ES candidate replays
        all of it; the held-out error that ranks and keeps each step stays on all held-out data."""
        return PositionSpace(within_budget(self.train, budget_s), self.heldout, self.evaluator, self.progress)

    # ------------------------------------------------------------------ verbs
    def compare(self, model: RobotModel | None = None, segment_s: float = 8.0) -> CompareResult:
        return compare(self.train + self.heldout, model, segment_s=segment_s, evaluator=self.evaluator)

    def diagnose(self, model: RobotModel | None = None, config: DiagnoseConfig | None = None, log=print,
                 candidates=None) -> Diagnosis:
        from dataclasses import replace

        cfg = config or DiagnoseConfig()
        if candidates is not None:
            cfg = replace(cfg, candidates=tuple(candidates))
        return diagnose(self.train, self.heldout, model, cfg, self.evaluator, log=log)

    def fit(self, model: RobotModel | None = None, config: FitConfig | None = None, log=print) -> FitResult:
        return fit(self.train, self.heldout, model, config, self.evaluator, self.progress, log)

    def fit_suspect(self, model: RobotModel, suspect, config, log=print) -> FitResult:
        """``auto``'s step: CMA-ES from the screened values, jointly with the model's own effects."""
        from realm_ms.sysid.auto import _start_spec

        # the loop reports values and held-out errors, not intervals: no uncertainty batch
        cfg = FitConfig(add=_start_spec(suspect.effect, suspect.params), generations=config.generations,
                        popsize=config.popsize, seed=config.seed, uncertainty=False, patience=config.patience)
        return fit(self.train, self.heldout, model, cfg, self.evaluator, progress=False, log=log)

    def details(self, diagnosis: Diagnosis, model: RobotModel) -> tuple[dict, str]:
        """``auto``'s space-specific details (held-out samples simulated but not scored) and note."""
        return {"saturated_fraction": round(float(diagnosis.saturated_fraction), 4)}, ""

    def flange(self, start: RobotModel, final: RobotModel):
        """``auto``'s flange figures: the held-out replay of its start and final models (``alignment.replay_flange``)."""
        import numpy as np

        from realm_ms.sysid.alignment import replay_flange
        from realm_ms.sysid.optimize import Group, evaluate_groups
        from realm_ms.sysid.replay import SegmentSet

        cfg = DiagnoseConfig()
        ss = SegmentSet.build(self.heldout, start.physics_hz, cfg.segment_s, cfg.burn_in_s, gains=start.gains)
        runs = []
        for label, m in (("nominal" if not start.effects else "start", start), ("final", final)):
            ((r,),) = evaluate_groups(self.evaluator, [ss], sorted(m.effects, key=lambda f: f.order), [Group.of([])],
                                      [np.zeros((1, 0))])
            runs.append((label, r.sim[0]))
        return replay_flange(ss, runs)

    def report(self, model: RobotModel | None, out: Path, data_name: str, auto=None, diagnosis=None, fit_result=None,
               waterfall: bool = True, log=print) -> Path:
        from realm_ms.sysid.report import build_report

        return build_report(self.train, self.heldout, model or RobotModel(), out, self.evaluator, diagnosis=diagnosis,
                            fit_result=fit_result, waterfall=waterfall, data_name=data_name, log=log, auto=auto)


def within_budget(trajs: list[Trajectory], budget_s: float | None) -> list[Trajectory]:
    """The trajectories, in order, whose durations fit in ``budget_s`` (first fit; at least the
    first); all of them for a budget of None or 0."""
    if not budget_s:
        return list(trajs)
    out, used = [], 0.0
    for tr in trajs:
        if not out or used + tr.duration <= budget_s:
            out.append(tr)
            used += tr.duration
    return out


#: the spaces by ``--space`` name; ``auto`` picks the first whose needs the data meets (``suits``)
SPACES = {"position": PositionSpace, "torque": TorqueSpace}
