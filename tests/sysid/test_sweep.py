"""The sweep's verdicts (``sweep.judge``): ranked first (confound partners count), the floor is the
larger of the noise floor and the seed's no-effect RMSE, the fit must reach 1.5x that floor."""

from realm_ms.sysid.sweep import CaseResult, judge, markdown


def _row(effect, seed=0, found=True, ranked=("latency",), floor=1e-4, base=3e-4, after=None, unexplained=False):
    return CaseResult(effect, seed, "mujoco", 1e-4, "msg", found, unexplained, list(ranked), floor, base,
                      heldout_before_rad=None if effect == "none" else base, heldout_after_rad=after)


def test_judge_uses_the_null_rmse_as_floor_and_accepts_confound_partners():
    rows = judge([
        _row("none", base=3e-4, found=False),
        _row("latency", ranked=("latency",), base=1e-2, after=4e-4),  # 4e-4 <= 1.5 * 3e-4
        _row("latency", ranked=("viscous_damping", "latency"), base=1e-2, after=4e-4),  # documented confound
        _row("latency", ranked=("armature",), base=1e-2, after=4e-4),  # wrong effect named
        _row("coulomb_friction", ranked=("coulomb_friction",), base=6e-3, after=2e-3),  # fit stalls
    ])
    null, ok, confound, wrong, stalled = rows
    assert null.passed and null.ranked_first is None and null.floor_rad == 3e-4
    assert ok.passed and ok.floor_rad == 3e-4
    assert confound.ranked_first and confound.passed
    assert not wrong.ranked_first and not wrong.passed
    assert stalled.ranked_first and not stalled.passed
    assert "**no**" in markdown(rows)


def test_null_case_fails_when_it_names_an_effect_or_is_unexplained():
    assert not judge([_row("none", found=True)])[0].passed
    assert not judge([_row("none", found=False, unexplained=True)])[0].passed
    partial = _row("none", found=False)
    partial.verdict_code = "partially_explained"
    assert not judge([partial])[0].passed
    # a hidden effect named as "partially explained" by the screening counts as ranked (the fit decides)
    named = _row("latency", found=False, after=2.9e-4)
    named.verdict_code = "partially_explained"
    assert judge([named])[0].ranked_first
    # without a null row for the seed the noise floor is the floor
    assert judge([_row("latency", seed=5, floor=2e-4, after=2.9e-4)])[0].passed


def test_sweep_resumes_without_the_cases_it_finished_and_runs_seed_by_seed():
    from realm_ms.sysid.sweep import sweep_cases

    todo = sweep_cases(("latency", "armature"), (0, 1), "mujoco", 1e-4)
    assert [c[:2] for c in todo] == [("none", 0), ("none", 1), ("latency", 0), ("armature", 0), ("latency", 1), ("armature", 1)]
    left = sweep_cases(("latency", "armature"), (0, 1), "mujoco", 1e-4, [_row("none", 0), _row("latency", 0)])
    assert [c[:2] for c in left] == [("none", 1), ("armature", 0), ("latency", 1), ("armature", 1)]
