"""The benchmark bicycle's stage (comparisons/stages/benchmark.py): the contract of what its
parts hand to summary.json and to the reader, a complement to tests/test_benchmark_stage_parts.py
(whose planted engines, tolerances and helpers it reuses).

The contract, from outside the module:

* docs/report.md, *The verdict line*: every row of summary.json's ``comparisons`` has the same
  common keys in one order (`comparisons.judgments.rows.COMMON`), then only the keys its kind
  adds (a trajectory row its ``horizon``, an order row its ``order``, ...); the module
  docstring: outcome checks carry ``measured`` and ``expected``. A key renamed is a new key and
  a missing one: a reader filtering on ``tolerance`` or ``scenario`` would miss the row;
* docs/report.md, *The summary table*: the rows of the published values are the reference
  against ``published`` (`reference (nonlinear)` against `linearize` for the fits), ``-`` when
  nothing is localized;
* `comparisons/judgments/tolerances.toml`: a tolerance is "the largest accepted error", so a
  row passes when its error equals its tolerance; each boundary is checked at exact equality,
  with the tolerance set to the error the row itself reports (or to a value whose computation
  here is the documented formula on the same floats);
* Meijaard et al. (2007): the weave and capsize speeds 4.29238253634111 and 6.02426201538837
  m/s (`test_benchmark_stage_parts`), the speeds 0..10 m/s of Table 2;
* the module docstring and docs/report.md for the facts each paragraph of the section states
  (the reference's integrator, the horizon's definition, IFToMM's drift, how the physics is
  measured, the fits' tolerance and the order band), asserted case-sensitively as phrases
  spanning the sentence's pieces.

Each test names the bugs planted by hand (in a copy of the module, one at a time) it was seen
failing on. Cost: benchmark-v4 and -v8 on the reference, benchmark-v4.6 with its twins and one
planted engine run (~0.6 s), the Table 2 part four times, the rest on hand-built fits.
"""

from __future__ import annotations

import dataclasses
import time
from types import SimpleNamespace

import numpy as np
import pytest

from comparisons.judgments.benchmark import ModeFit
from comparisons.judgments.convergence import HORIZON_PERTURBATION, HORIZON_THRESHOLD
from comparisons.judgments.rows import COMMON, Comparison
from comparisons.stages import benchmark as bm
from comparisons.stages.results import Section, Text
from reference_model import COORDINATES
from test_benchmark_stage_parts import (CAPSIZE_SPEED, SHIFT_RUN, TOLS, WEAVE_SPEED, WEAVE_4,
                                        CAPSIZE_4, CASTOR_4, _figure, _study, _tables, _texts,
                                        bench)  # noqa: F401 - bench is a fixture

THETA = COORDINATES.index("theta")

#: the keys each kind of row adds after COMMON (docs/report.md; the module docstring)
EXTRA = {"trajectory (benchmark)": ["horizon", "horizon_reason"],
         "constraint_residual": [],
         "energy drift percent (IFToMM)": [],
         "outcome": ["measured", "expected", "linear"],
         "convergence order": ["order", "steps", "errors", "verdict", "expected", "reason"],
         "order": ["order"]}


def _keys(row) -> list[str]:
    return list(row.as_dict())


@pytest.fixture(scope="module")
def runs():
    """A --quick layout: benchmark-v4 and -v8 on the reference only (no twins), benchmark-v4.6
    with the planted Shift run and its small-amplitude twins; with the wall time of the
    benchmark-v4.6 call."""
    t0 = time.perf_counter()
    mid = bm.benchmark_manoeuvre("benchmark-v4.6", (SHIFT_RUN,))
    wall = time.perf_counter() - t0
    return [bm.benchmark_manoeuvre("benchmark-v4", twins=False), mid,
            bm.benchmark_manoeuvre("benchmark-v8", twins=False)], wall


def _tols(**tolerances):
    return {**TOLS, **{k: SimpleNamespace(tolerance=v) for k, v in tolerances.items()}}


# -- the manoeuvres ----------------------------------------------------------------------------

def test_the_runs_are_timed_in_seconds_of_wall_time(runs):
    """``seconds``: the time the reference (with its twin) and each engine run took, each a
    part of the call's wall time, measured around it here. Planted: the clock's reading added
    to the start instead of subtracted (for the reference, for an engine)."""
    (_, mid, _), wall = runs
    assert list(mid.seconds) == ["reference + twin", "Shift"]
    assert all(0 < s <= wall for s in mid.seconds.values())
    assert sum(mid.seconds.values()) <= wall


@pytest.fixture(scope="module")
def manoeuvre_sec(runs, bench):
    sec = Section("t")
    bm._manoeuvre_part(TOLS, sec, bench, runs[0], {"Shift": "k t in xc"})
    return sec


def test_the_manoeuvre_rows_have_exactly_their_keys(manoeuvre_sec):
    """Every row of the IFToMM part: the common keys in summary.json's order, then only its
    kind's own (a trajectory row: its horizon and the horizon's reason); the trajectory row is
    reported (tolerance and passed null) with the note pointing to the convergence check.
    Planted: 'tolerance' or 'passed' of the trajectory row renamed (XXtoleranceXX, TOLERANCE,
    XXpassedXX, PASSED), the note's last words wrapped or upper-cased."""
    rows = manoeuvre_sec.comparisons
    assert {r["quantity"] for r in rows} == set(EXTRA) - {"outcome", "convergence order",
                                                          "order"}
    for r in rows:
        assert _keys(r) == list(COMMON) + EXTRA[r["quantity"]], r["quantity"]
        assert r["model"] == "benchmark"
    (traj,) = [r for r in rows if r["quantity"] == "trajectory (benchmark)"]
    assert traj["engines"] == ["reference", "Shift"] and traj["scenario"] == "benchmark-v4.6"
    assert traj["tolerance"] is None and traj["passed"] is None
    assert traj["note"].startswith("reported, not judged")
    assert traj["note"].endswith("integrator error at h = 1e-3 (see the convergence check)")


def test_a_residual_or_a_drift_equal_to_its_tolerance_passes(runs, bench):
    """tolerances.toml: a tolerance is the largest accepted error. The reference's max |C| and
    IFToMM drift on benchmark-v4.6, read from its rows, given back as the tolerances
    ([constraint_residual], [iftomm_energy_drift]): both rows pass; Shift's planted 5e-4 in C
    (above the reference's) fails. Planted: < for <= on the residual, on the drift."""
    mr = runs[0][1]
    first = Section("t")
    bm._manoeuvre_part(TOLS, first, bench, [mr], {})
    c_ref, d_ref = [r for r in first.comparisons if r["engines"] == ["reference"]]
    assert c_ref["quantity"] == "constraint_residual" and 0 < c_ref["max_error"] < 5e-4
    assert d_ref["quantity"] == "energy drift percent (IFToMM)" and d_ref["max_error"] > 0
    sec = Section("t")
    bm._manoeuvre_part(_tols(constraint_residual=c_ref["max_error"],
                             iftomm_energy_drift=d_ref["max_error"]), sec, bench, [mr], {})
    judged = {(r["quantity"], r["engines"][-1]): (r["max_error"], r["tolerance"], r["passed"])
              for r in sec.comparisons if r["passed"] is not None}
    assert judged[("constraint_residual", "reference")] == (c_ref["max_error"],) * 2 + (True,)
    assert judged[("energy drift percent (IFToMM)", "reference")] == (
        d_ref["max_error"],) * 2 + (True,)
    assert judged[("constraint_residual", "Shift")][2] is False


def test_the_manoeuvre_text_states_the_method(manoeuvre_sec):
    """The paragraph under the IFToMM heading (module docstring, docs/report.md): 5 s every
    0.01 s, the reference DOP853 rtol 1e-11 with projection; errors in all eight coordinates
    up to the horizon where two reference runs 1e-9 rad/s apart in theta_dot(0) separate by
    1e-6 (the horizon's definition, comparisons.judgments.convergence),
    reported and judged by the convergence check; IFToMM's drift over the 0.01 s output against
    IFToMM's acceptance, stricter than [energy_drift]; the constraint residual's tolerance.
    Planted: each piece of the sentence wrapped in XX, lower- or upper-cased (IFToMM, DOP853,
    Energy, Emax, tolerances.toml)."""
    intro = _texts(manoeuvre_sec)[0]
    assert intro.startswith("5 s, output every 0.01 s (IFToMM). Reference: DOP853 rtol 1e-11, "
                            "projection. Shift: k t in xc. ")
    assert (HORIZON_PERTURBATION, HORIZON_THRESHOLD) == (1e-9, 1e-6)
    assert ("Errors in all eight coordinates up to the horizon where two reference runs 1e-9 "
            "rad/s apart in theta_dot(0) separate by 1e-6; reported, not judged (the "
            "convergence check below judges them). ") in intro
    assert ("Energy drift 100 (Emax - Emin)/|E0| over the 0.01 s output, judged against "
            "IFToMM's acceptance 0.002 % (stricter than the generic `tolerances.toml` "
            "[energy_drift], which bounds any second-order run at h = 1e-3); constraint "
            "residual against [constraint_residual] 0.0003.") in intro


def test_the_manoeuvres_run_on_the_reference_only_are_listed(manoeuvre_sec):
    """--quick (docs/report.md): the engines on benchmark-v4.6 only, the other two on the
    reference; the text names both, separated by ', '. Planted: the separator wrapped in
    XX."""
    assert _texts(manoeuvre_sec)[1] == ("Run on the reference only (`--quick`: the engines run "
                                        "benchmark-v4.6): benchmark-v4, benchmark-v8.")


# -- the physics -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def outcome_sec(runs, bench):
    """benchmark-v4.6 with an engine 'Wild': the reference's run with d theta/dt multiplied by
    e^(1 /s t), so its roll-rate envelope grows at the linear weave's rate + 1 /s (> 0) where
    the weave should decay."""
    mr = runs[0][1]
    ref = mr.reference
    dq = ref.dq.copy()
    dq[:, THETA] *= np.exp(1.0 * ref.t)
    wild = dataclasses.replace(ref, dq=dq)
    sec = Section("t")
    bm._outcome_part(sec, bench, [dataclasses.replace(mr, engines={"Wild": wild})])
    return sec


def test_an_outcome_that_does_not_show_fails(outcome_sec):
    """'Wild' grows where the published speeds predict a decaying weave (4.6 m/s, between
    4.29 and 6.02 m/s): its verdict is FAIL (`results.verdict_word`) in the table and false in
    its row, its measured rate the reference's + 1 /s; the reference passes. Each row: the
    common keys, then measured, expected and linear. Planted: the table's verdict always
    'pass', 'FAIL' wrapped or lower-cased, 'scenario', 'max_error' or 'tolerance' renamed."""
    (table,) = _tables(outcome_sec)
    ref_row, wild_row = table.rows
    assert (ref_row[1], ref_row[2], ref_row[5]) == ("reference", "weave decays", "pass")
    assert (wild_row[1], wild_row[2], wild_row[5]) == ("Wild", "weave decays", "FAIL")
    assert float(wild_row[3]) - float(ref_row[3]) == pytest.approx(1.0, abs=0.01)
    ref, wild = outcome_sec.comparisons
    assert (ref["passed"], wild["passed"]) == (True, False)
    for r in (ref, wild):
        assert _keys(r) == list(COMMON) + EXTRA["outcome"]
        assert r["scenario"] == "benchmark-v4.6"
        assert r["max_error"] is None and r["tolerance"] is None


def test_the_physics_text_says_how_each_outcome_is_measured(outcome_sec):
    """The module docstring: the slow capsize from 3 s on, theta keeping one sign and |theta|
    growing monotonically at a rate sigma with sigma * 5 s < 1, no fall; the linear value
    beside. Planted: those pieces of the sentence wrapped in XX, lower- or upper-cased."""
    (text,) = _texts(outcome_sec)
    assert ("Capsize: from 3 s on theta keeps one sign and |theta| grows monotonically, at a "
            "rate sigma with sigma * 5 s < 1 (slow), no fall. ") in text
    assert text.endswith(" The linear weave real part / capsize eigenvalue is given beside.")


# -- nonlinear against linear, on hand-built fits ----------------------------------------------

LIN = complex(-1.0, 4.0)     # 1/s: the 'linear' eigenvalue of the hand-built fits


def _fit(scenario, engine, rate, a, d, tol, mode="weave"):
    return ModeFit(scenario, engine, mode, 5.0, rate, a, LIN * (1 + d), LIN, d, tol)


#: the twins' fits: 1e-3 within 2 a^2 + 1e-8, 1e-2 exactly at its tolerance (1e-4)
TWINS = [_fit("s-roll0.001", "reference", 1e-3, 1e-3, 1e-6, 2e-6 + 1e-8),
         _fit("s-roll0.01", "reference", 1e-2, 1e-2, 1e-4, 1e-4)]
#: the IFToMM run's fit: 1e-2 against 2 (0.05)^2 + 1e-8 = 5e-3, out of it
IFTOMM = _fit("s", "reference", 0.05, 0.05, 1e-2, 5e-3 + 1e-8)
#: the engines' weave fits on the same run: Edge 3e-5 off in the real part, Off 1e-3
ENGINE_FITS = {"Edge": IFTOMM.fitted + 3e-5, "Off": IFTOMM.fitted + 1e-3}
EDGE = abs(ENGINE_FITS["Edge"] - IFTOMM.fitted) / abs(IFTOMM.fitted)   # the relative difference


@pytest.fixture()
def nonlinear_sec(monkeypatch, bench):
    """_nonlinear_part on one manoeuvre 's' whose fits are the hand-built ones above (the pencil
    fit, `mode_fits`, replaced by them), with [benchmark_weave_fit] equal to Edge's relative
    difference from the reference's fit."""
    def fits(model, scenario, traj, engine="reference", modes=None):
        if engine == "reference":
            return [IFTOMM]
        return [dataclasses.replace(IFTOMM, engine=engine, fitted=ENGINE_FITS[engine])]

    monkeypatch.setattr(bm, "mode_fits", fits)
    mr = bm.ManoeuvreRuns(SimpleNamespace(name="s"), 5.0, "reference run", None,
                          engines={"Edge": "edge run", "Off": "off run"}, small_fits=TWINS)
    sec = Section("t")
    bm._nonlinear_part(_tols(benchmark_weave_fit=EDGE), sec, bench, [mr])
    return sec


def test_a_fit_at_its_tolerance_passes_and_one_past_it_fails(nonlinear_sec):
    """The fits against the linearization: the 1e-2 twin's deviation equals its tolerance:
    pass; the IFToMM fit's is twice its own: FAIL in the table (`results.verdict_word`) and
    false in its row. Each row: the common keys only, the model, reference (nonlinear) against
    linearize. Planted: < for <=, the verdict always 'pass', 'FAIL' wrapped or lower-cased,
    'model' renamed."""
    fits_table = _tables(nonlinear_sec)[0]
    assert [(r[0], r[8]) for r in fits_table.rows] == [
        ("s-roll0.001", "pass"), ("s-roll0.01", "pass"), ("s", "FAIL")]
    rows = [r for r in nonlinear_sec.comparisons
            if r["quantity"].endswith("nonlinear fit vs linear")]
    assert [(r["scenario"], r["max_error"], r["tolerance"], r["passed"]) for r in rows] == [
        (f.scenario, f.deviation, f.tolerance, ok) for f, ok in zip(TWINS + [IFTOMM],
                                                                    (True, True, False))]
    for r in rows:
        assert _keys(r) == list(COMMON)
        assert r["model"] == "benchmark"
        assert r["engines"] == ["reference (nonlinear)", "linearize"]


def test_an_engine_fit_at_the_weave_fit_tolerance_passes(nonlinear_sec):
    """[benchmark_weave_fit] is set to Edge's relative difference |f - f_ref| / |f_ref| (the
    documented measure): Edge passes, Off (33 times further) fails. Each row: the common keys
    only, the model, the note on why the nonlinearity cancels. Planted: < for <=, 'model' or
    'note' renamed, the note wrapped in XX or upper-cased."""
    table = _tables(nonlinear_sec)[1]
    assert [(r[1], r[5]) for r in table.rows] == [("Edge", "pass"), ("Off", "FAIL")]
    rows = [r for r in nonlinear_sec.comparisons
            if r["quantity"] == "weave eigenvalue fit, engine vs reference (same run)"]
    assert [(r["engines"], r["max_error"], r["tolerance"], r["passed"]) for r in rows] == [
        (["reference", "Edge"], EDGE, EDGE, True),
        (["reference", "Off"], pytest.approx(1e-3 / abs(IFTOMM.fitted), rel=1e-9), EDGE, False)]
    for r in rows:
        assert _keys(r) == list(COMMON) and r["model"] == "benchmark"
        assert r["note"] == ("same amplitude, so the nonlinearity cancels; (omega h)^2 "
                             "integrator error")


def test_the_nonlinear_text_states_the_method_and_the_tolerances(nonlinear_sec):
    """The module docstring's method: the matrix pencil on theta and gamma, 0.04 s grid, order
    4, against the linearization at the run's speed; the relative deviation within 2 a^2 +
    1e-8 (the dropped terms are O(a^2)); the order between the two small amplitudes in [1.8,
    2.2]. Then the engines' fits against the reference's on the same run (the nonlinearity
    cancels) within the O((omega h)^2) error at h = 1e-3. Planted: the paragraph None, each of
    its pieces wrapped in XX, lower- or upper-cased, the band printed [2.2, 2.2]."""
    method, engines = _texts(nonlinear_sec)
    assert method.startswith("Eigenvalues identified from the nonlinear runs (matrix pencil on "
                             "theta and gamma, 0.04 s grid, order 4) against the linearization "
                             "at the run's speed. Tolerance on the relative deviation: 2 a² + "
                             "1e-08, a = max |theta|, |gamma| of the run")
    assert ("of the run (the terms the linearization drops are O(a²) relative; the floor is the "
            "fit's accuracy). Between the two small amplitudes") in method
    assert method.endswith("the deviation must scale as a^order with order in [1.8, 2.2]: it "
                           "is the nonlinearity, not a model difference.")
    assert engines.startswith("The engines' weave fits on the IFToMM runs against the "
                              "reference's fit on the same run (the nonlinearity cancels); ")
    assert engines.endswith(" relative, the O((omega h)^2) error of the integrator at h = 1e-3:")


def test_an_order_at_either_end_of_the_band_passes():
    """The order in the amplitude passes within [1.8, 2.2], ends included (docstring: 'order
    in [1.8, 2.2]'). Deviations c a^1.8 and c a^2.2 at a = 1e-3 and 2e-3, whose computed orders
    are exactly 1.8 and 2.2 (checked): both pass. Each row: the common keys, then the order.
    Planted: < for <= at the lower end, at the upper end."""
    def fit(scenario, rate, a, d, mode):
        return ModeFit(scenario, "reference", mode, 7.0, rate, a, LIN * (1 + d), LIN, d, 1.0)

    by = {"s7": [fit("s7-1", 1e-3, 1e-3, 0.5 * 1e-3 ** 1.8, "weave"),
                 fit("s7-2", 1e-2, 2e-3, 0.5 * 2e-3 ** 1.8, "weave"),
                 fit("s7-1", 1e-3, 1e-3, 3.0 * 1e-3 ** 2.2, "capsize"),
                 fit("s7-2", 1e-2, 2e-3, 3.0 * 2e-3 ** 2.2, "capsize")]}
    sec = Section("t")
    bm._order_part(sec, SimpleNamespace(name="bike"), by)
    weave, capsize = sec.comparisons
    assert (weave["order"], capsize["order"]) == (1.8, 2.2)
    assert (weave["passed"], capsize["passed"]) == (True, True)
    assert [r[4] for r in _tables(sec)[0].rows] == ["pass", "pass"]
    for r in (weave, capsize):
        assert _keys(r) == list(COMMON) + EXTRA["order"]


# -- convergence, the section ------------------------------------------------------------------

def test_a_convergence_row_has_exactly_its_keys():
    """The convergence row: the common keys (tolerance null: the verdict is on the order), then
    the study's order, steps, errors, verdict, the expected verdict and its reason. Planted:
    'tolerance' renamed (XXtoleranceXX, TOLERANCE)."""
    sec = Section("t")
    bm._convergence_part(sec, SimpleNamespace(name="benchmark"), "ex",
                         _study([5 * h * h for h in (4e-3, 2e-3, 1e-3, 5e-4)], "converges"))
    (row,) = sec.comparisons
    assert _keys(row) == list(COMMON) + EXTRA["convergence order"]
    assert row["tolerance"] is None


def test_the_section_leaves_the_terms_stage_result_as_it_was(runs, bench):
    """benchmark_section copies the terms stage's rows into its own list: the terms' Section
    (a stage's result, which the caller keeps) is not changed by the rows the other parts
    add. Planted: the section's list made the terms' list itself (= for +=)."""
    terms = Section("benchmark terms")
    terms.heading("Terms")
    row = Comparison.of({"quantity": "mass_matrix", "scenario": "upright", "model": "benchmark",
                         "engines": ["reference", "x"], "max_error": 0.0, "tolerance": 1e-3,
                         "passed": True})
    terms.comparisons.append(row)
    sec = bm.benchmark_section(TOLS, True, [runs[0][1]], terms, {})
    assert terms.comparisons == [row] and len(terms.blocks) == 1
    assert sec.comparisons[0] == row and len(sec.comparisons) > 1


# -- Table 2 and the published speeds ----------------------------------------------------------

@pytest.fixture(scope="module")
def table2_sec(bench):
    sec = Section("t")
    bm._eigenvalue_part(TOLS, sec, bench)
    return sec


def test_the_published_rows_name_the_reference_against_published(table2_sec):
    """docs/report.md: the linearization against the published values is the reference
    against 'published', on the benchmark upright: Table 2 over its speeds 0..10 m/s (eleven,
    four eigenvalues each), the critical speeds. Each row has the common keys only. Planted:
    'scenario', 'model', 'engines' or 'note' renamed, the scenarios or the engines' names or
    the note wrapped in XX or upper-cased."""
    from comparisons.judgments.published import MEIJAARD_TABLE2
    eig, weave, capsize = table2_sec.comparisons
    speeds = sorted(MEIJAARD_TABLE2)
    assert eig["scenario"] == f"benchmark upright, v = {speeds[0]}..{speeds[-1]}"
    assert eig["note"] == ("exact linearization (complex step), 4 eigenvalues at "
                           f"{len(speeds)} speeds")
    assert (weave["scenario"], capsize["scenario"]) == ("benchmark upright",) * 2
    for r in (eig, weave, capsize):
        assert _keys(r) == list(COMMON)
        assert r["model"] == "benchmark" and r["engines"] == ["reference", "published"]


def test_the_table_gives_each_speeds_error_against_meijaard(table2_sec, bench):
    """The table's error column of the weave and capsize speeds: |ours - published| with the
    published 4.29238253634111 and 6.02426201538837 m/s (Meijaard et al. 2007) and ours the
    reference's weave_speed / capsize_speed; the sentence above it says what is compared.
    Planted: the sum for the difference, the sentence None, wrapped in XX, lower- or
    upper-cased."""
    from reference_model.linearize import capsize_speed, weave_speed
    _, weave_row, capsize_row = _tables(table2_sec)[0].rows
    assert weave_row[3] == f"{abs(weave_speed(bench) - WEAVE_SPEED):.1e}"
    assert capsize_row[3] == f"{abs(capsize_speed(bench) - CAPSIZE_SPEED):.1e}"
    assert float(weave_row[3]) < 1e-9 and float(capsize_row[3]) < 1e-9
    (text,) = _texts(table2_sec)
    assert text.startswith("Linearized about upright straight running (roll and steer; exact "
                           "derivatives), against the published Table 2")
    assert text.endswith("against the published Table 2:")


def test_errors_equal_to_their_tolerances_pass(table2_sec, bench):
    """tolerances.toml: the largest accepted error. [benchmark_eigenvalues] set to the
    eigenvalues' own max error, [benchmark_speeds] to the larger of the two speeds' errors (as
    the rows report them): every row passes. Planted: < for <= on the eigenvalues, on the
    speeds."""
    eig, weave, capsize = table2_sec.comparisons
    worst_speed = max(weave["max_error"], capsize["max_error"])
    sec = Section("t")
    bm._eigenvalue_part(_tols(benchmark_eigenvalues=eig["max_error"],
                              benchmark_speeds=worst_speed), sec, bench)
    assert [(r["max_error"], r["passed"]) for r in sec.comparisons] == [
        (eig["max_error"], True), (weave["max_error"], True), (capsize["max_error"], True)]
    assert worst_speed in [r["tolerance"] for r in sec.comparisons[1:]]


def test_a_table_2_matched_exactly_localizes_nothing(bench, monkeypatch):
    """A Table 2 equal to the linearization at every speed (the published function replaced by
    it): max error 0, pass, and nothing to localize: '-' (docs/report.md), in the row and the
    table. Planted: the worst speed taken on ties (>= for >: 'v = 10 m/s'), the '-' wrapped in
    XX."""
    import comparisons.judgments.published as published
    from reference_model.linearize import eigenvalues
    monkeypatch.setattr(published, "table2_eigenvalues", lambda v: eigenvalues(bench, float(v)))
    sec = Section("t")
    bm._eigenvalue_part(TOLS, sec, bench)
    eig = sec.comparisons[0]
    assert (eig["max_error"], eig["passed"], eig["localized_to"]) == (0.0, True, "-")
    assert _tables(sec)[0].rows[0][3] == "0.0e+00 (worst at -)"


def test_the_eigenvalue_figure_spans_the_declared_speeds(bench, monkeypatch):
    """EIGENVALUE_SPEEDS is (start, stop, step) of the figure's speeds: the grid runs from
    start to stop, both included, every step; with (4, 6, 0.5) m/s: 4, 4.5, ..., 6, its v = 4
    column Table 2's (weave pair, capsize, castor). Planted: stop + start for stop - start."""
    monkeypatch.setattr(bm, "EIGENVALUE_SPEEDS", (4.0, 6.0, 0.5))
    sec = Section("t")
    bm._eigenvalue_part(TOLS, sec, bench)
    fig = _figure(sec, "benchmark_eigenvalues.png")
    assert np.allclose(fig.data["v"], [4.0, 4.5, 5.0, 5.5, 6.0], rtol=0, atol=1e-12)
    assert fig.data["re"][0] == pytest.approx([WEAVE_4.real, WEAVE_4.real, CAPSIZE_4, CASTOR_4],
                                              abs=1e-10)
    assert not any(isinstance(b, Text) and b.text is None for b in sec.blocks)
