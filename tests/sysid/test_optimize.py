"""CMA-ES loop (history, stopping, resumable checkpoint) and the linearised screening step."""

import numpy as np
import pytest

from realm_ms.sysid.optimize import cma_fit


def test_cma_minimises_and_records_history():
    target = np.array([0.3, 0.7, 0.5])
    res = cma_fit(lambda u: ((u - target) ** 2).sum(1), np.full(3, 0.5), sigma0=0.2, max_generations=80,
                  patience=200, progress=False)
    assert np.abs(res.u - target).max() < 0.02
    h = res.history
    assert [x["generation"] for x in h] == list(range(1, len(h) + 1))
    best = [x["best_loss"] for x in h]
    assert all(b2 <= b1 for b1, b2 in zip(best, best[1:]))
    assert all(x["median_loss"] >= x["best_loss"] for x in h)


def test_one_dimensional_and_checkpoint_resume(tmp_path):
    ck = tmp_path / "ck.pkl"
    f = lambda u: (u[:, 0] - 0.25) ** 2  # noqa: E731
    first = cma_fit(f, np.array([0.8]), sigma0=0.2, max_generations=5, patience=100, checkpoint=ck, progress=False)
    assert ck.exists() and first.generations == 5
    resumed = cma_fit(f, np.array([0.8]), sigma0=0.2, max_generations=40, patience=100, checkpoint=ck, progress=False)
    assert resumed.history[:5] == first.history and resumed.generations == 40
    assert abs(resumed.u[0] - 0.25) < 0.01


def test_cma_stops_at_the_target_loss_and_does_not_start_below_it():
    f = lambda u: ((u - 0.3) ** 2).sum(1)  # noqa: E731
    free = cma_fit(f, np.full(2, 0.8), sigma0=0.2, max_generations=60, patience=100, progress=False)
    target = cma_fit(f, np.full(2, 0.8), sigma0=0.2, max_generations=60, patience=100, progress=False, target_loss=1e-3)
    assert free.stop == "max_generations" and free.generations == 60
    assert target.stop == "target" and target.loss <= 1e-3 and 0 < target.generations < 60
    assert target.history == free.history[: target.generations]  # the same run, cut where it got there
    # a start already at the target: no generation at all, the start comes back
    none = cma_fit(f, np.full(2, 0.31), sigma0=0.2, max_generations=60, progress=False, initial_loss=2e-4, target_loss=1e-3)
    assert none.stop == "target" and none.generations == 0 and np.allclose(none.u, 0.31)


def _viscous_data(tmp_path, ev):
    from realm_ms.sysid.data_io import load_split
    from realm_ms.sysid.synth import SynthConfig, synth

    # the second-difference estimate of the noise needs samples (on 2 x 5 s at 15 Hz it is still ~10 %
    # off the true noise) and a replay costs per second of log, not per sample: 3 x 3 s logged at 100 Hz
    synth("viscous_damping:b=0.8", tmp_path, SynthConfig(seed=2, noise_rad=2e-4, n_train=3, n_heldout=1, duration_s=3,
                                                         rate_hz=100), evaluator=ev)
    return load_split(tmp_path)


def _quiet(*a):
    pass


def test_fit_skips_cma_when_the_linearised_start_is_at_the_noise(tmp_path):
    """CMA-ES polishes what the data can still show: a linearised start that fits the train split
    to the measurement noise (estimated from its residual) leaves it nothing; data the model cannot
    fit to the noise runs its generations."""
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.fit import FitConfig, fit

    ev = Evaluator(workers=1, device="cpu")
    train, held = _viscous_data(tmp_path, ev)
    at = fit(train, held, config=FitConfig(add="viscous_damping", generations=4, uncertainty=False), evaluator=ev,
             progress=False, log=_quiet)
    assert at.noise_rmse == pytest.approx(2e-4, rel=0.1)  # the second-difference estimate of the noise
    assert at.cma_stop == "target" and at.history == []
    assert at.after["train_rmse_rad"] <= 1.05 * at.noise_rmse
    # the report's fit section still draws the linearised start and says why there are no generations
    from types import SimpleNamespace

    from realm_ms.sysid.report.sections import fit_health

    title, html = fit_health(SimpleNamespace(fit=at.to_json()))
    assert title.startswith("Fit history:") and "CMA-ES was not run" in html and "data:image/png" in html
    # data the model cannot fit to the noise (the effect left out): the generations run
    off = fit(train, held, config=FitConfig(add="latency", generations=1, uncertainty=False), evaluator=ev,
              progress=False, log=_quiet)
    assert off.cma_stop != "target" and len(off.history) == 1 and off.after["train_rmse_rad"] > 2 * off.noise_rmse
    ev.close()


@pytest.mark.slow
def test_generations_from_a_start_at_the_noise_find_nothing_better(tmp_path):
    """With the noise check off, the generations run from the linearised start and end where it was."""
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.fit import FitConfig, fit

    ev = Evaluator(workers=1, device="cpu")
    train, held = _viscous_data(tmp_path, ev)
    at = fit(train, held, config=FitConfig(add="viscous_damping", generations=4, uncertainty=False), evaluator=ev,
             progress=False, log=_quiet)
    full = fit(train, held, config=FitConfig(add="viscous_damping", generations=1, uncertainty=False, noise_stop=0),
               evaluator=ev, progress=False, log=_quiet)
    assert at.cma_stop == "target" and full.cma_stop != "target" and len(full.history) == 1
    assert full.after["heldout_rmse_rad"] == pytest.approx(at.after["heldout_rmse_rad"], rel=0.02)
    ev.close()


def test_linearized_step_recovers_a_viscous_coefficient(tmp_path):
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.optimize import Group, linearized_step
    from realm_ms.sysid.replay import SegmentSet
    from realm_ms.sysid.synth import SynthConfig, synth

    ev = Evaluator(workers=1, device="cpu")
    synth("viscous_damping:b=0.8", tmp_path, SynthConfig(seed=2, noise_rad=1e-4, n_train=2, n_heldout=1, duration_s=5), evaluator=ev)
    ss = SegmentSet.build(load_dir(tmp_path / "train"), 120.0)
    g = Group.of([make_effect("viscous_damping")])
    out = linearized_step(ev, ss, [], [g], first=True, block=True)[0]
    assert out.improved and out.mse_after < 0.05 * out.mse_before
    vals = g.effects[0].values()
    assert vals["b2"] == pytest.approx(0.8, rel=0.2) and vals["b4"] == pytest.approx(0.8, rel=0.2)


def test_a_zero_mass_payload_reports_its_centre_of_mass_as_insensitive_and_restarts_from_typical(tmp_path):
    """At zero mass the payload's centre of mass does nothing: the screening step must say so (the
    diagnosis then re-screens from the typical strengths), and the typical start moves only the
    parameters asked for."""
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.optimize import Group, linearized_step, typical_start
    from realm_ms.sysid.replay import SegmentSet
    from realm_ms.sysid.synth import SynthConfig, synth

    ev = Evaluator(workers=1, device="cpu")
    synth("payload:mass=0.8,com_x=0.12,com_z=0.05", tmp_path, SynthConfig(seed=1, noise_rad=1e-4, n_train=1, n_heldout=1, duration_s=4),
          evaluator=ev)
    ss = SegmentSet.build(load_dir(tmp_path / "train"), 120.0)
    g = Group.of([make_effect("payload"), make_effect("viscous_damping", {"b2": 0.3})])
    assert g.effects[0].values()["mass"] == 0.0
    alone = Group.of([make_effect("payload")])
    out = linearized_step(ev, ss, [], [alone], first=True, block=True)[0]
    keys = [alone.params.params[k].local_key for k in out.insensitive]
    assert {"com_x", "com_y", "com_z"} <= set(keys) and "mass" not in keys

    alt = typical_start(g, {p.key for p in g.effects[0].free_params})
    assert alt.effects[0].values()["mass"] == pytest.approx(0.5)  # the payload's typical mass
    assert alt.effects[1].values()["b2"] == pytest.approx(0.3)  # the other effect where it was
    assert g.effects[0].values()["mass"] == 0.0 and alt.effects[0] is not g.effects[0]  # a copy
    out = linearized_step(ev, ss, [], [alt], first=True, block=True)[0]
    assert not {"com_x", "com_y", "com_z"} & {alt.params.params[k].local_key for k in out.insensitive}


def test_train_and_heldout_run_as_one_rollout_with_the_scores_of_separate_ones(tmp_path):
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.optimize import Group, evaluate_groups
    from realm_ms.sysid.replay import SegmentSet
    from realm_ms.sysid.synth import SynthConfig, synth

    class Counting(Evaluator):
        calls = 0

        def simulate(self, segset, effects, n_candidates=1):
            Counting.calls += 1
            return super().simulate(segset, effects, n_candidates)

    ev = Counting(workers=1, device="cpu")
    synth("viscous_damping:b=0.8", tmp_path, SynthConfig(seed=3, noise_rad=1e-4, n_train=2, n_heldout=1, duration_s=3), evaluator=ev)
    tr, he = (SegmentSet.build(load_dir(tmp_path / d), 120.0) for d in ("train", "heldout"))
    g = Group.of([make_effect("viscous_damping")])
    pts = np.vstack([g.params.to_unit(g.params.off()), g.params.to_unit(g.params.nominal())])
    Counting.calls = 0
    both = evaluate_groups(ev, [tr, he], [], [g], [pts])
    assert Counting.calls == 1
    for ss, res in zip([tr, he], both):
        # a fresh evaluator: the first one's cache already holds every arm
        (alone,) = evaluate_groups(Evaluator(workers=1, device="cpu"), [ss], [], [g], [pts])
        np.testing.assert_allclose(res[0].mse, alone[0].mse, rtol=1e-4)  # mse per candidate
        np.testing.assert_allclose(res[0].sim, alone[0].sim, atol=1e-5)  # sampled q (float32 batch neighbours)
        assert res[0].mse[1] < 0.5 * res[0].mse[0]  # damping (the hidden effect) helps on both sets
