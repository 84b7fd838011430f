"""Proof on data with a hidden effect: the hidden effect is ranked first (first two for a
documented confound pair), fitting it brings the held-out RMSE to <= 1.5x the noise floor (and
>= 5x down from the start for a strong effect), parameters come back within 20 %, and data with
no hidden effect yields "no missing effect".

``make test`` runs a fast subset (small data: a hidden command ramp against its look-alikes, and
the null case on 3 + 2 trajectories x 2 s at 100 Hz; a hidden delay diagnosed, fitted and stepped
through ``auto`` is the CLI's test, ``tests/sysid/test_sysid_cli.py``); ``make test-slow`` the same
delay on this file's small data, and the sweep over every effect x 3 seeds x {15 Hz, 100 Hz}
logging, two-effect pairs and the null case at the bench size (7 + 3 trajectories x 10 s).
"""

from __future__ import annotations

import pytest

from realm_ms.sysid.data_io import load_split
from realm_ms.sysid.diagnose import diagnose
from realm_ms.agents.effects import confounded_with
from realm_ms.sysid.engine import Evaluator
from realm_ms.sysid.fit import FitConfig, fit
from realm_ms.sysid.effect_spec import parse_effects
from realm_ms.sysid.synth import SynthConfig, synth

NOISE = 2e-4
#: hidden effect -> spec at a realistic, clearly visible strength (sysid-notes.md §9 ranges)
HIDDEN = {
    "coulomb_friction": "coulomb_friction:fc=0.3",
    "viscous_damping": "viscous_damping:b=0.5",
    "stribeck_friction": "stribeck_friction:fs=0.5,fc_ratio=0.3,vs=0.08",
    "armature": "armature:ia=0.2",
    "payload": "payload:mass=0.5",
    "gravity_comp_error": "gravity_comp_error:scale=0.1",
    "latency": "latency:delay=0.02",
    "target_filter": "target_filter:tau=0.05",
    "gain_mismatch": "gain_mismatch:stiffness_error=0.2,damping_error=0.2",
    "torque_limit": "torque_limit:rate_limit=1000,effort_scale=1.0",  # libfranka's limit
    # backlash is only observable where the gravity load changes sign (joints 2, 4, 6 in the
    # excitation workspace); joints 1, 3, 5, 7 carry ~no gravity torque
    "backlash": "backlash:half_gap2=0.002,half_gap4=0.002,half_gap6=0.002",
    "encoder_bias": "encoder_bias:bias=0.003,bias2=-0.002,bias5=0.004",
}
PAIRS = ["latency:delay=0.015,viscous_damping:b=0.5", "coulomb_friction:fc=0.3,gain_mismatch:stiffness_error=0.2"]


@pytest.fixture(scope="module")
def ev():
    e = Evaluator(workers=1, device="cpu")
    yield e
    e.close()


SMALL = dict(n_train=3, n_heldout=2, duration_s=4.0)
BENCH = dict(n_train=7, n_heldout=3, duration_s=10.0)


def run_case(tmp_path, ev, hidden: str, seed: int, rate: float, size: dict, log=lambda *a: None):
    info = synth(hidden, tmp_path, SynthConfig(seed=seed, noise_rad=NOISE, rate_hz=rate, **size), evaluator=ev)
    train, held = load_split(tmp_path)
    d = diagnose(train, held, evaluator=ev, log=log)
    return info, train, held, d


def check_rank(d, names: list[str]):
    ranked = [s.effect for s in d.suspects]
    for name in names:
        allowed = len(names) + (1 if any(c in ranked[: len(names) + 1] for c in confounded_with(name)) else 0)
        assert name in ranked[:allowed], f"{name} ranked {ranked.index(name) + 1}: {ranked[:4]}"
    # named: "found" when its screening already reaches the floor, else "partially explained"
    # (the fit in check_fit must then reach the floor)
    assert d.verdict in ("found", "partially_explained"), d.message


def check_fit(info, train, held, d, ev, names: list[str], strong: bool = True):
    f = fit(train, held, config=FitConfig(add=",".join(names)), evaluator=ev, progress=False, log=lambda *a: None)
    before, after = f.before["heldout_rmse_rad"], f.after["heldout_rmse_rad"]
    floor = min(d.noise_floor, NOISE * 1.05)
    assert after <= 1.5 * floor, f"held-out {after:.2e} rad vs floor {floor:.2e}"
    if strong:
        assert before >= 5 * after, f"only {before / after:.1f}x better"
    truth = info["truth"]
    fitted = {fx.name: fx for fx in f.model.effects}
    for key, est in f.params.items():
        eff, local = key.split(".")
        p = next(p for p in fitted[eff].params if p.local_key == local)
        true = truth.get(key, p.spec.off)
        # parameters the hidden effect does not use (truth = off) may be unidentifiable (a saturation
        # that never binds); their harmlessness is what the held-out RMSE criterion checks
        if abs(true - p.spec.off) > 1e-9:
            assert abs(est - true) <= 0.2 * abs(true - p.spec.off), f"{key}: {est:.4g} vs truth {true:.4g}"
    return f


# ---------------------------------------------------------------------------- fast (make test)
# the hidden delay is make test's through the CLI (test_sysid_cli.py: ranked first, re-screening,
# fitted to the floor within 20 %); here it is the sweep's small-data member
@pytest.mark.slow
@pytest.mark.parametrize("name, rate", [("latency", 15.0)])
def test_hidden_effect_fast(tmp_path, ev, name, rate):
    logs = []
    info, train, held, d = run_case(tmp_path, ev, HIDDEN[name], seed=0, rate=rate, size=SMALL, log=logs.append)
    check_rank(d, [name])
    # the effects inert at their off-values (payload CoM, Stribeck and smooth shapes) are screened
    # again from typical strengths exactly when no first-pass candidate already reaches the floor
    rescreened = [m for m in logs if m.startswith("re-screening")]
    skipped = [m for m in logs if m.startswith("not re-screening")]
    assert len(rescreened) + len(skipped) == 1, logs
    if skipped:
        assert d.verdict == "found" and f": {d.suspects[0].effect} already" in skipped[0], (skipped, d.message)
    check_fit(info, train, held, d, ev, [name])


def test_hidden_command_interpolation_is_told_from_its_look_alikes(tmp_path, ev):
    """A ramp between the 15 Hz targets, screened against the other forms a command path can take
    (transport delay, first-order filter): named first, fitted to within 20 % and to the floor."""
    from realm_ms.sysid.diagnose import DiagnoseConfig

    hidden = "target_interpolation:duration=0.1"
    info = synth(hidden, tmp_path, SynthConfig(seed=0, noise_rad=NOISE, n_train=2, n_heldout=1, duration_s=3.0), evaluator=ev)
    train, held = load_split(tmp_path)
    cfg = DiagnoseConfig(candidates=("latency", "target_filter", "target_interpolation"))
    d = diagnose(train, held, config=cfg, evaluator=ev, log=lambda *a: None)
    assert d.suspects[0].effect == "target_interpolation", [s.effect for s in d.suspects]
    check_fit(info, train, held, d, ev, ["target_interpolation"])


def test_no_hidden_effect_fast(tmp_path, ev):
    # 2 s logged at 100 Hz: as many samples for the noise floor as 4 s at 15 Hz has and half the
    # replay (which costs per second of log); the null verdict held on seeds 0-2 at this size
    _, _, _, d = run_case(tmp_path, ev, "none", seed=0, rate=100.0, size=dict(SMALL, duration_s=2.0))
    assert d.verdict == "no_missing_effect" and not d.missing_effect_found and not d.unexplained, d.message
    assert "no missing effect" in d.message


# ---------------------------------------------------------------------------- slow sweep
@pytest.mark.slow
@pytest.mark.parametrize("rate", [15.0, 100.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("name", list(HIDDEN))
def test_hidden_effect_sweep(tmp_path, ev, name, seed, rate):
    info, train, held, d = run_case(tmp_path, ev, HIDDEN[name], seed=seed, rate=rate, size=BENCH)
    check_rank(d, [name])
    check_fit(info, train, held, d, ev, [name])


@pytest.mark.slow
@pytest.mark.parametrize("spec", PAIRS)
def test_two_hidden_effects(tmp_path, ev, spec):
    names = [fx.name for fx in parse_effects(spec)]
    info, train, held, d = run_case(tmp_path, ev, spec, seed=0, rate=15.0, size=BENCH)
    ranked = [s.effect for s in d.suspects]
    # the top suspect is one of the hidden effects (or a documented look-alike of one) ...
    assert ranked[0] in names + [c for n in names for c in confounded_with(n)], ranked[:4]
    assert all(n in ranked[:4] for n in names), ranked[:4]  # ... and both are among the suspects
    # one effect alone cannot reach the floor: the honest verdict names it and the next suspect
    assert d.verdict == "partially_explained" and "next suspects" in d.message, d.message
    check_fit(info, train, held, d, ev, names)  # fitting both brings the error to the noise floor


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("rate", [15.0, 100.0])
def test_no_hidden_effect_sweep(tmp_path, ev, seed, rate):
    _, _, _, d = run_case(tmp_path, ev, "none", seed=seed, rate=rate, size=BENCH)
    assert not d.missing_effect_found, d.message
