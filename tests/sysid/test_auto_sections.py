"""The auto waterfall draws the run's own "at the floor" line: found_factor x the judging floor."""

from types import SimpleNamespace

import pytest

from realm_ms.sysid.report import auto_sections


@pytest.mark.parametrize("factor", [1.5, 2.0])
def test_waterfall_line_is_the_runs_found_factor_times_the_floor(monkeypatch, factor):
    figs = []
    monkeypatch.setattr(auto_sections, "to_img", lambda fig, alt="": figs.append(fig) or "")
    auto = {"unit": "rad", "nominal_heldout_rmse": 4e-3, "steps": [{"effect": "latency", "heldout_rmse": 5e-4}],
            "final": {"heldout_rmse": 5e-4, "noise_floor": 2e-4, "verdict": "partially_explained"},
            "details": {"judging_floor": 3e-4, "found_factor": factor}}
    auto_sections.auto_waterfall(SimpleNamespace(auto=auto))
    ax = figs[0].axes[0]
    lines = {ln.get_label(): ln.get_ydata()[0] for ln in ax.get_lines()}
    assert lines[f"{factor:g}x judging floor"] == pytest.approx(factor * 3e-4 * 1e3)
