"""The Exudyn engine under hostile options (issue 14, items 8 and 9): a step that cannot land
on the output grid is a usage error before anything runs; a long run says how long it will
take and how far it is."""

from __future__ import annotations

import math

import pytest

from engines import EngineError, EngineUsageError, load_engine
from engines.exudyn import engine as exudyn_engine
from reference_model.scenarios import get_scenario

SCENARIO = get_scenario("stability-psid10")     # sampled every 0.01 s


@pytest.mark.parametrize("step", [3e-3, 0.015, 7e-4])
def test_step_not_dividing_the_grid_is_a_usage_error(disc, step):
    """Issue 14: exit 1 (a usage error is 2) after building the system; now a ValueError
    subclass the CLI maps to exit 2, raised before the run, with steps that would work."""
    eng = load_engine("exudyn", disc, build="tree", step=step)
    with pytest.raises(EngineUsageError) as info:
        eng.simulate(SCENARIO)
    err = info.value
    assert isinstance(err, ValueError) and isinstance(err, EngineError)
    text = str(err)
    assert "\n" not in text and f"{step:g}" in text and "0.01" in text and "fix:" in text
    # the suggested steps divide 0.01 s (checked with the independent arithmetic 0.01/h)
    for suggestion in text.split("e.g. ")[1].split(" or "):
        k = 0.01 / float(suggestion)
        assert abs(k - round(k)) < 1e-6, suggestion


@pytest.mark.parametrize("step", [0.0, -1e-3, math.nan, math.inf, True, "1e-3"])
def test_step_that_is_no_time_is_a_usage_error(disc, step):
    with pytest.raises(EngineUsageError, match="step"):
        load_engine("exudyn", disc, build="tree", step=step)


def test_unknown_build_is_a_usage_error(disc):
    with pytest.raises(EngineUsageError, match="unknown Exudyn build 'tre'"):
        load_engine("exudyn", disc, build="tre")


def test_long_run_is_estimated_and_reports_progress(disc, monkeypatch):
    """A run longer than LONG_RUN_SECONDS announces steps x cost per step before it starts,
    re-estimates from its own cost, and reports progress (shrunk thresholds: a 50-step run)."""
    monkeypatch.setattr(exudyn_engine, "LONG_RUN_SECONDS", 1e-3)
    monkeypatch.setattr(exudyn_engine, "MEASURE_AFTER", 0.0)
    monkeypatch.setattr(exudyn_engine, "PROGRESS_EVERY", 0.0)
    lines, times = [], []
    eng = load_engine("exudyn", disc, build="tree", step=1e-3)
    tr = eng.simulate(SCENARIO, t_end=0.05, notify=lines.append, progress=times.append)
    assert tr.status == "completed"
    # 0.05 s / 1e-3 s = 50 steps, announced before the first step
    assert "50 steps of h = 0.001 s" in lines[0] and "estimated" in lines[0], lines[0]
    assert any("measured" in line and "ms per step" in line for line in lines[1:]), lines
    assert any("%" in line and "left" in line for line in lines[1:]), lines
    assert all("\n" not in line for line in lines)
    assert len(times) == 50 and times == sorted(times) and times[-1] == pytest.approx(0.05)


def test_short_run_is_silent(disc, capsys):
    eng = load_engine("exudyn", disc, build="tree", step=1e-3)
    eng.simulate(SCENARIO, t_end=0.02)
    assert capsys.readouterr().err == ""
