"""The diagnosis's batches: a re-screen from typical strengths, asked for up front, runs in the first
pass's own batches and ranks as the separate round does."""

import pytest


def test_typical_starts_asked_for_run_in_the_first_pass_batches_and_rank_alike(tmp_path):
    """At zero mass a payload's centre of mass does nothing, so the diagnosis steps the payload from
    its typical strengths too. Asked for in ``typical_starts`` (``auto`` passes what its last
    diagnosis re-screened), that start is probed and stepped with the first pass: two replay batches
    fewer, the same suspects, values and errors."""
    from realm_ms.sysid.data_io import load_dir
    from realm_ms.sysid.diagnose import DiagnoseConfig, diagnose
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.synth import SynthConfig, synth

    class Counting(Evaluator):
        calls = 0

        def simulate(self, segset, effects, n_candidates=1):
            Counting.calls += 1
            return super().simulate(segset, effects, n_candidates)

    synth("payload:mass=0.8,com_x=0.12,com_z=0.05", tmp_path, SynthConfig(seed=1, noise_rad=1e-4, n_train=1, n_heldout=1,
                                                                          duration_s=3), evaluator=Evaluator(workers=1))
    train, held = load_dir(tmp_path / "train"), load_dir(tmp_path / "heldout")
    runs = []
    for hint in ((), ("payload",)):
        Counting.calls = 0
        logs = []
        # a fresh evaluator each: the rollout cache would hide the batches the hint saves
        d = diagnose(train, held, config=DiagnoseConfig(candidates=("payload", "armature"), typical_starts=hint),
                     evaluator=Counting(workers=1), log=logs.append)
        runs.append((d, Counting.calls, logs))
    (plain, n_plain, logs_plain), (hinted, n_hinted, logs_hinted) = runs
    assert plain.rescreened == hinted.rescreened == ["payload"]
    assert any(m.startswith("re-screening payload") for m in logs_plain + logs_hinted)
    assert n_hinted == n_plain - 2, (n_plain, n_hinted)
    assert [s.effect for s in hinted.suspects] == [s.effect for s in plain.suspects]
    assert hinted.suspects[0].effect == "payload"
    for a, b in zip(plain.suspects, hinted.suspects):
        assert b.heldout_rmse_after == pytest.approx(a.heldout_rmse_after, rel=1e-3)
        assert b.params == pytest.approx(a.params, rel=1e-2, abs=1e-4)
