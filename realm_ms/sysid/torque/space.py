"""Torque space: the workbench's verbs on the inverse-dynamics residual of measured ``tau`` (N·m).

``TorqueSpace`` answers ``compare``, ``diagnose``, ``fit`` and ``auto``'s steps (``sysid/space.py``
names what a space provides) with the residual, terms and least squares of ``residual.py``; its
results are ``TorqueCompare`` and ``TorqueFit`` (``diagnose`` gives the shared ``Diagnosis``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from realm_ms.errors import InputError
from realm_ms.sysid.alignment import no_flange
from realm_ms.sysid.gripper import gripper_json, gripper_lines
from realm_ms.sysid.timeseries import Trajectory
from realm_ms.sysid.torque.residual import UNIT, Term, TorqueSet, fit_terms, residual_bands, rmse, terms_of, torque_arm
from realm_ms.sysid.torque.terms import TERMS, TRACKING_ONLY

MAX_FIT_SAMPLES = 6000  # train samples the least squares sees (evenly thinned); held-out uses all
#: configured variants screened beside the library candidates: a link's CoM moves the torque in ways
#: no mass scale can (a regressor product per evaluation, so 28 parameters screen in seconds)
SCREENED_VARIANTS = ("link_mass:fit_com=true",)


@dataclass
class TorqueCompare:
    """``compare`` in torque space: the inverse-dynamics residual of every trajectory (N·m)."""

    rmse: float
    per_joint_rmse: list[float]
    noise_floor: float
    noise_floor_per_joint: list[float]
    samples: int
    residual_bands: dict
    gripper: object = None  # the gripper row (``sysid/gripper.GripperCheck``), set by the API when the data has one
    unit = UNIT

    def to_json(self) -> dict:
        return {"unit": UNIT, "rmse_nm": self.rmse, "per_joint_rmse_nm": self.per_joint_rmse,
                "noise_floor_nm": self.noise_floor, "noise_floor_per_joint_nm": self.noise_floor_per_joint,
                "samples": self.samples, "residual_bands": self.residual_bands, "flange": no_flange().to_json()} \
            | gripper_json(self.gripper)

    def lines(self) -> list[str]:
        """The terminal summary: residual RMSE per joint and by frequency band."""
        return [f"torque space ({self.samples} samples): inverse-dynamics residual RMSE {self.rmse:.3e} N·m, "
                f"noise floor ≈ {self.noise_floor:.2e} N·m",
                "joint       " + " ".join(f"{f'J{i}':>9}" for i in range(1, 8)),
                "RMSE [N·m]  " + " ".join(f"{v:9.3f}" for v in self.per_joint_rmse)] + band_lines(self.residual_bands) \
            + [no_flange().line()] + gripper_lines(self.gripper)


@dataclass
class TorqueFit:
    """``fit`` in torque space: least squares of the added (and, with refit, the model's) terms."""

    model: object  # RobotModel
    terms: list[Term]
    effects: list[str]
    params: dict[str, float]
    before: dict  # {train_rmse_nm, heldout_rmse_nm, per_joint_heldout_rmse_nm}
    after: dict
    noise_floor: float
    residual_bands: dict
    split: dict | None = None
    unit = UNIT

    @property
    def heldout_after(self) -> float:
        return float(self.after["heldout_rmse_nm"])

    def to_json(self) -> dict:
        out = {"unit": UNIT, "effects": self.effects, "params": self.params, "before": self.before, "after": self.after,
               "noise_floor_nm": self.noise_floor, "residual_bands": self.residual_bands,
               "at_bounds": self.model.params_at_bounds(), "flange": no_flange().to_json()}
        if self.split is not None:
            out["split"] = self.split
        return out

    def lines(self) -> list[str]:
        """The terminal summary: fitted values, per-joint held-out RMSE, residual by band."""
        from realm_ms.sysid.fit import at_bounds_lines

        out = [f"  {k:<32} {v:.5g}" for k, v in self.params.items()]
        for when, m in (("before", self.before), ("after", self.after)):
            out.append(f"{when:<6} held-out [N·m] " + " ".join(f"{v:9.3f}" for v in m["per_joint_heldout_rmse_nm"])
                       + f"  {m['heldout_rmse_nm']:9.3f}   (train {m['train_rmse_nm']:.3f})")
        return out + band_lines(self.residual_bands) + [no_flange().line()] + at_bounds_lines(self.model.params_at_bounds())


def band_lines(b: dict) -> list[str]:
    """Torque residual per frequency band (``torque/spectrum.py``), as terminal lines."""
    return (["by band     " + " ".join(f"{'J' + str(i):>9}" for i in range(1, 8)) + "    share"]
            + [f"{name:<11} " + " ".join(f"{v:9.3f}" for v in row) + f"   {100 * share:5.1f}%"
               for name, row, share in zip(b["bands"], b["rms_per_joint"], b["share"])])


def _errors(ts_tr: TorqueSet, ts_he: TorqueSet, terms: list[Term]) -> dict:
    tr, _ = rmse(ts_tr, terms)
    he, per = rmse(ts_he, terms)
    return {"train_rmse_nm": tr, "heldout_rmse_nm": he, "per_joint_heldout_rmse_nm": [float(x) for x in per]}


def model_of(terms: list[Term], base=None):
    """A MODEL.yaml for the terms, keeping the tracking effects of ``base``."""
    from realm_ms.agents.effects import make_effect
    from realm_ms.agents.robot_model import RobotModel

    base = (base or RobotModel()).copy()
    keep = [fx for fx in base.effects if fx.name in TRACKING_ONLY]
    fx = [make_effect(t.name, t.values, t.config_dict()) for t in terms]
    return RobotModel(sorted(keep + fx, key=lambda f: f.order), base.gains, base.joint_physics, base.physics_hz,
                      dict(base.provenance))


def _copy(terms: list[Term]) -> list[Term]:
    return [Term.make(t.name, dict(t.values), t.config_dict()) for t in terms]


def _base(spec: str) -> str:
    """Effect name of a candidate spec (``link_mass:fit_com=true`` -> ``link_mass``)."""
    return spec.split(":", 1)[0]


def parse_terms(spec: str) -> list[Term]:
    """Terms of an ``--add``-style spec, e.g. ``link_mass:link=4,fit_com=true,s4=0.1``: the effect's
    config keys set its config, the others start its free parameters."""
    from dataclasses import fields

    from realm_ms.agents.effects import EFFECTS
    from realm_ms.sysid.effect_spec import _value, split_specs

    out = []
    for name, kv in split_specs(spec):
        cfg_names = {f.name for f in fields(EFFECTS.get(name).Config)} if name in EFFECTS else set()
        t = Term.make(name, config={k: _value(v, k) for k, v in kv.items() if k in cfg_names})
        kv = {k: v for k, v in kv.items() if k not in cfg_names}
        unknown = [k for k in kv if k not in t.values]
        if unknown:
            raise InputError(f"{name}: unknown or fixed parameter(s) {unknown} in torque space; free: {list(t.values)}")
        t.values.update({k: float(_value(v, k)) for k, v in kv.items()})
        out.append(t)
    return out


class TorqueSpace:
    """Torque space: the inverse-dynamics residual of measured ``tau`` (N·m, any controller, no
    ``q_cmd`` needed). Every candidate is fitted in full by least squares (no simulation), so the
    diagnosis's values are a fit: ``auto`` keeps them instead of fitting again."""

    name = "torque"
    unit = UNIT
    fit_replays = False  # ``fit_suspect`` takes the screening's least squares: free, not one of auto's ``max_fits``

    def __init__(self, train: list[Trajectory], heldout: list[Trajectory]):
        self.train, self.heldout = train, heldout
        self._sets: tuple[TorqueSet, TorqueSet] | None = None

    @classmethod
    def build(cls, train, heldout, model=None, workers=None, device=None, progress: bool = True) -> "TorqueSpace":
        """No simulation: workers, device and progress do not apply."""
        return cls(train, heldout)

    def close(self) -> None:
        """Nothing to stop (no worker processes); the verbs use every space ``with``."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @staticmethod
    def suits(trajs: list[Trajectory]) -> bool:
        return all(t.tau is not None for t in trajs)

    @staticmethod
    def check(trajs: list[Trajectory]) -> None:
        from realm_ms.sysid.timeseries import DataError

        no_tau = [t.name for t in trajs if t.tau is None]
        if no_tau:
            has_q_cmd = all(t.q_cmd is not None for t in trajs)
            raise DataError(f"{no_tau[0]}: no tau (measured joint torque, N·m); torque space needs it "
                            + ("(or use --space position: the data has q_cmd)" if has_q_cmd else "in every trajectory"))

    @staticmethod
    def check_identifiable(trajs: list[Trajectory]) -> None:
        """A joint torque that never varies (a zero column: the sensor was not logged) identifies nothing."""
        from realm_ms.sysid.timeseries import DataError

        flat = [j for j in range(7) if all(np.ptp(tr.tau[:, j]) == 0 for tr in trajs)]
        if flat:
            value = float(trajs[0].tau[0, flat[0]])
            raise DataError(f"nothing to identify in torque space: tau of joint(s) {', '.join(str(j + 1) for j in flat)} "
                            f"is {value:g} N·m throughout every trajectory (not logged?); log the joint torques, or "
                            "use --space position (the replay of q_cmd)")

    def sets(self) -> tuple[TorqueSet, TorqueSet]:
        """Train (thinned for the least squares) and held-out sample sets, built once."""
        if self._sets is None:
            arm = torque_arm()
            self._sets = (TorqueSet.build(self.train, arm, max_samples=MAX_FIT_SAMPLES), TorqueSet.build(self.heldout, arm))
        return self._sets

    @staticmethod
    def replay_floor(cfg) -> float:
        """No simulation: the judging floor is the noise floor."""
        return 0.0

    @staticmethod
    def floor(ts: TorqueSet) -> float:
        return float(np.sqrt(np.mean(ts.noise**2)))

    def library(self) -> list[str]:
        """The effects this space can model."""
        return [n for n in TERMS if n not in TRACKING_ONLY]

    def candidates(self, cfg, given=None) -> list[str]:
        """``given``, else the config's library candidates + those position space screens only on
        request (link_mass: cheap here, a regressor fit) + ``SCREENED_VARIANTS``."""
        from realm_ms.agents.effects import EFFECTS

        if given is not None:
            return list(given)
        return [n for n in TERMS if n in cfg.candidates or not EFFECTS.get(n).screened] + list(SCREENED_VARIANTS)

    def searching(self, budget_s: float | None) -> "TorqueSpace":
        """All of the data: a least-squares fit simulates nothing, so it has no replay cost to cut."""
        return self

    def screened(self, cfg) -> list[str]:
        """Effect names the default diagnosis screens (``auto``'s contenders and its left-out note)."""
        return [_base(n) for n in self.candidates(cfg)]

    # ------------------------------------------------------------------ verbs
    def compare(self, model=None, **_) -> TorqueCompare:
        ts = TorqueSet.build(self.train + self.heldout, torque_arm())
        terms = terms_of(model, log=lambda *a: None)
        total, per = rmse(ts, terms)
        return TorqueCompare(total, [float(x) for x in per], self.floor(ts), [float(x) for x in ts.noise], len(ts.tau),
                             residual_bands(ts, terms))

    def diagnose(self, model=None, config=None, log=print, candidates=None):
        from realm_ms.sysid.diagnose import DiagnoseConfig, Diagnosis, Suspect, judge_verdict, unscreened

        cfg = config or DiagnoseConfig()
        tr, he = self.sets()
        base_terms = terms_of(model, log)
        present = {t.name for t in base_terms}
        names = [n for n in self.candidates(cfg, candidates) if _base(n) not in present and _base(n) not in TRACKING_ONLY]
        base_tr, _ = rmse(tr, base_terms)
        base_he, per_he = rmse(he, base_terms)
        floor = self.floor(he)
        log(f"torque space: baseline held-out RMSE {base_he:.3e} {UNIT}, noise floor ≈ {floor:.2e} {UNIT}")
        suspects = []
        for n in names:
            terms = _copy(base_terms) + parse_terms(n)
            after_tr = fit_terms(tr, terms)
            after_he, _ = rmse(he, terms)
            new = terms[-1]
            retuned = {f"{t.name}.{k}": round(v, 9) for t in terms[:-1] for k, v in t.values.items()}
            sc = (base_he - after_he) / base_he if base_he > 0 else 0.0
            suspects.append(Suspect(n, sc, after_he, after_tr, {k: round(v, 9) for k, v in new.values.items()},
                                    f"{n}: inverse-dynamics residual fitted by least squares", retuned_model_params=retuned))
        suspects.sort(key=lambda s: -s.score)
        left_out = unscreened({_base(n) for n in names}, present, self.library())
        verdict, msg, judge = judge_verdict(base_he, floor, suspects, cfg, unit=UNIT, left_out=left_out,
                                            replay_floor=self.replay_floor(cfg))
        return Diagnosis(base_he, base_tr, floor, he.noise, per_he, suspects, msg, verdict, judge, unit=UNIT)

    def fit(self, model=None, config=None, log=print) -> TorqueFit:
        """``config``: a ``fit.FitConfig``; its ``add`` and ``refit`` apply (no CMA-ES here)."""
        from realm_ms.sysid.fit import FitConfig

        cfg = config or FitConfig()
        refit = cfg.refit
        tr, he = self.sets()
        base_terms = terms_of(model, log)
        added = parse_terms(cfg.add)
        clash = [t.name for t in added if t.name in {b.name for b in base_terms}]
        if clash:
            raise InputError(f"{', '.join(clash)} already in the model; drop it from --add")
        if not added:
            raise InputError("nothing to fit: give effects with --add")
        before = _errors(tr, he, base_terms)
        fitted = (base_terms if refit else []) + added
        fit_terms(tr, fitted)
        terms = (base_terms if refit else _copy(base_terms)) + added
        after = _errors(tr, he, terms)
        log(f"torque space: held-out RMSE {before['heldout_rmse_nm']:.3e} -> {after['heldout_rmse_nm']:.3e} {UNIT}")
        params = {f"{t.name}.{k}": float(v) for t in fitted for k, v in t.values.items()}
        return TorqueFit(model_of(terms, model), terms, [t.name for t in fitted], params, before, after,
                         self.floor(he), residual_bands(he, terms))

    def fit_suspect(self, model, suspect, config, log=print) -> TorqueFit:
        """``auto``'s step: the diagnosis already fitted the suspect jointly with the model's terms
        (a full least squares), so its values are taken as they are."""
        tr, he = self.sets()
        terms = terms_of(model, log)
        new = parse_terms(suspect.effect)[0]
        new.values.update({k: v for k, v in suspect.params.items() if k in new.values})
        for t in terms:
            t.values.update({k.split(".", 1)[1]: v for k, v in suspect.retuned_model_params.items()
                             if k.split(".", 1)[0] == t.name})
        terms = terms + [new]
        params = {f"{t.name}.{k}": round(v, 9) for t in terms for k, v in t.values.items()}
        after = {"heldout_rmse_nm": rmse(he, terms)[0]}
        return TorqueFit(model_of(terms, model), terms, [t.name for t in terms], params, {}, after, self.floor(he), {})

    def flange(self, start, final):
        """``auto``'s flange figures: none in torque space (``no_flange``)."""
        return no_flange()

    def details(self, diagnosis, model) -> tuple[dict, str]:
        """``auto``'s space-specific details and a note on what is left (high-frequency residual)."""
        from realm_ms.sysid.torque.spectrum import high_frequency_note

        bands = residual_bands(self.sets()[1], terms_of(model, log=lambda *a: None))
        return {"space": self.name, "residual_bands": bands}, high_frequency_note(bands)

    def report(self, model, out, data_name: str, auto=None, **_) -> "Path":
        from realm_ms.sysid.report.torque_report import build_torque_report

        return build_torque_report(self.train, self.heldout, model, out, data_name, auto)
