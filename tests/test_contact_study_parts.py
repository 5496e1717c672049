"""Each soft-contact engine's share of the soft-contact study (engines/<engine>/contact_study.py:
`SoftContact.settings_rows`, `.conclusion` and the `.refinements` series), called the way
comparisons/stages/soft_contact.py calls them, for DART, MuJoCo and Drake.

Expected values come from outside the modules under test:

* the settings tables from a real run of each engine at its defaults (its ``settings`` dict, as
  the study passes it), the defaults checked against the tables of docs/engines.md and the
  versions against each library's own (``dartpy.__version__``, ``mujoco.__version__``, the
  installed drake distribution's metadata);
* the conclusions from synthetic refinement results (`comparisons.judgments.contact.Refinement`
  with hand-picked values, errors and slips, the series' names and held settings being the
  engine's declared ones), every number of the text recomputed by hand in the test (slip RMS
  over the finest value, the errors' range, local orders log(e_i/e_i+1)/log(v_i/v_i+1));
* the refinement series from what each series declares (its parameter and ``held`` text,
  docs/engines.md and docs/report.md): each series' options, given to the engine for a real
  run on the study's 0.01 s output grid, must show up in that run's recorded settings as the
  series says (e.g. MuJoCo: timestep = time constant / 2, the damping ratio held), every time
  step must divide the 0.01 s grid, each series halves its value and spans the 8x that a
  verdict needs (docs/report.md: order >= 0.5 over >= 8x), MuJoCo's time constant stays >= 2
  timesteps (the smallest it honours).

Each test names the planted bugs (mutmut's mutants of the three modules) it was seen failing on.
Cost: one default run per engine plus 28 runs of 0.01 s (one output step), ~1.5 s with the
three libraries' imports.
"""

from __future__ import annotations

import dataclasses
import math
import re

import pytest

from comparisons.judgments.contact import Refinement as Study
from reference_model import load_model
from reference_model.scenarios import get_scenario

#: the study's output interval (s): every time step must divide it
GRID = 0.01
#: docs/report.md: a verdict needs values spanning at least 8x
MIN_SPAN = 8.0

#: docs/engines.md's option tables, the defaults each engine's runs record
DART_DEFAULTS = {"timestep": 5e-4, "collision_detector": "ode", "friction": 2.0,
                 "solver": "dantzig", "wheel_half_width": 1e-6, "split_impulse": False}
MUJOCO_DEFAULTS = {"timestep": 1e-4, "integrator": "implicit", "solref": (2e-4, 1.0),
                   "solimp": (0.99, 0.999, 1e-3, 0.5, 2.0), "friction": 2.0, "cone": "elliptic",
                   "condim": 3, "noslip_iterations": 0, "solver": "Newton", "iterations": 100,
                   "tolerance": 1e-10, "wheel_half_width": 1e-6}
DRAKE_DEFAULTS = {"time_step": 5e-4, "approximation": "tamsi", "contact_model": "point",
                  "stiction_tolerance": 1e-4, "friction": 2.0, "point_stiffness": 1e8,
                  "dissipation": 10.0, "hydroelastic_modulus": 1e9, "wheel_half_width": 1e-6}


def _scenario():
    """The study's manoeuvre (stability-psid10) cut to one 0.01 s output step."""
    return dataclasses.replace(get_scenario("stability-psid10"), grid=(0.0, GRID, 2))


@pytest.fixture(scope="module")
def model():
    return load_model("thesis-disc")


def _engine_and_run(model, module, cls):
    import importlib
    engine = getattr(importlib.import_module(module), cls)(model)
    return engine, engine.simulate(_scenario())


@pytest.fixture(scope="module")
def dart(model):
    """(engine, default run) of DART on thesis-disc."""
    pytest.importorskip("dartpy")
    return _engine_and_run(model, "engines.dart", "DartEngine")


@pytest.fixture(scope="module")
def mujoco(model):
    """(engine, default run) of MuJoCo on thesis-disc."""
    pytest.importorskip("mujoco")
    return _engine_and_run(model, "engines.mujoco", "MujocoEngine")


@pytest.fixture(scope="module")
def drake(model):
    """(engine, default run) of Drake on thesis-disc."""
    pytest.importorskip("pydrake")
    return _engine_and_run(model, "engines.drake", "DrakeEngine")


def _defaults_of(settings: dict, documented: dict) -> dict:
    return {k: (tuple(settings[k]) if isinstance(documented[k], tuple) else settings[k])
            for k in documented}


def _study(series, errors, slips, order, verdict, reason="hand-made"):
    """A refinement result of ``series`` (an engine's declared `Refinement`), coarsest first as
    the study orders it, with the given errors, slip RMS and fitted order."""
    values = tuple(sorted(series.values, reverse=True))
    return Study(series.parameter, series.held, 0.2, values, tuple(errors), tuple(slips),
                 (1e-6,) * len(values), order, 0.0, verdict, reason)


def _in_order(text: str, sentences: list[str]):
    """Each sentence is in ``text``, in this order, and together they are the whole text."""
    at = [text.find(s) for s in sentences]
    assert all(i >= 0 for i in at), [s for s, i in zip(sentences, at) if i < 0]
    assert at == sorted(at)
    assert text == "".join(sentences)


def _divides_grid(h: float) -> bool:
    n = GRID / h
    return abs(n - round(n)) < 1e-9 and round(n) >= 1


# -- DART -----------------------------------------------------------------------------------------

def test_dart_defaults_are_the_documented_ones(dart):
    """The run the settings tests read records docs/engines.md's DART defaults (the expected
    values below rest on them)."""
    _, run = dart
    assert _defaults_of(run.settings, DART_DEFAULTS) == DART_DEFAULTS


def test_dart_settings_rows_show_the_runs_settings(dart):
    """The table: one row per contact setting, in the study's order, each value the run's own
    (the version dartpy reports, the detector, LCP solver and split impulse of the defaults,
    the 5e-4 s step). Planted: any row's label or key misspelt or upper-cased, str(None) for the
    version, split impulse shown 'ON'/'XXoffXX', the wrong settings key for any value."""
    import dartpy
    from engines.dart.contact_study import SOFT_CONTACT
    _, run = dart
    s = run.settings
    assert SOFT_CONTACT.settings_rows(s) == [
        ("DART version", dartpy.__version__),
        ("geometry", s["wheels"]),
        ("collision detector", "ode"),
        ("friction", s["friction_coefficients"]),
        ("contact solver", "boxed LCP, dantzig; split impulse off"),
        ("time step, integrator", f"0.0005 s, {s['integrator']}"),
        ("rear wheel height", s["rear_height_joint"]),
        ("loads", s["loads"])]
    assert "half-width 1e-06 m" in s["wheels"]


def test_dart_settings_rows_say_split_impulse_on_when_it_is(dart):
    """A run with split impulses on says so, and the solver row names that run's solver.
    Planted: the split-impulse test forced false ('and False') or true ('or True'), 'XXonXX',
    'ON'."""
    from engines.dart.contact_study import SOFT_CONTACT
    engine, _ = dart
    run = engine.simulate(_scenario(), split_impulse=True, solver="pgs")
    rows = dict(SOFT_CONTACT.settings_rows(run.settings))
    assert rows["contact solver"] == "boxed LCP, pgs; split impulse on"


def _dart_studies(quick=False):
    from engines.dart.contact_study import SOFT_CONTACT
    step, width = SOFT_CONTACT.refinements
    # slip RMS at the finest step 1.25e-4 s: 3.0e-4 m/s, i.e. 2.40 x the step
    main = _study(step, (8.5e-4, 4.3e-4, 2.2e-4, 1.1e-4), (2.0e-3, 1.1e-3, 6.0e-4, 3.0e-4),
                  0.98, "approaches ideal rolling", "order 0.98 over 8x")
    if quick:
        return [main]
    return [main, _study(width, (5.4e-3, 2.8e-3, 1.5e-3, 8.6e-4), (1e-3,) * 4, 0.886,
                         "approaches ideal rolling")]


DART_FIRST = ("**Conclusion.** DART's rigid LCP contact has no stiffness to refine: its departure "
              "from rolling is the time stepping's. With the time step, DART approaches ideal "
              "rolling (order 0.98 over 8x); its slip RMS is 2.40 x the step (m/s per s), the "
              "contact point's acceleration times the step.")
DART_DEFAULTS_TEXT = (" Defaults: time step 0.0005 s, half-width 1e-06 m, the ode detector, "
                      "dantzig LCP, friction 2.")


def test_dart_conclusion_reads_both_series(dart):
    """The conclusion: the step series' verdict and its slip per step at the finest step
    (3.0e-4 / 1.25e-4 = 2.40), the half-width series at its held step with its order (0.886 ->
    0.89) and its errors from the coarsest 5.4e-3 to the finest 8.6e-4, then the defaults of
    the run (docs/engines.md). Planted: the second series read as the main one, the slip times
    (not over) the step or the wrong end of either series, the width series looked for from
    the third series on or under a misspelt name, max/min of None, any '+=' turned into '=',
    the closing sentence's text mangled, any default read under a wrong key."""
    from engines.dart.contact_study import SOFT_CONTACT
    _, run = dart
    text = SOFT_CONTACT.conclusion(_dart_studies(), run.settings)
    _in_order(text, [
        DART_FIRST,
        " The cylinder's half-width at a fixed time step 0.00025 s: approaches ideal rolling "
        "(order 0.89; errors 5.4e-03 to 8.6e-04): a leaned cylinder rests on its cap's rim, "
        "beside the disc's contact point.",
        DART_DEFAULTS_TEXT])


def test_dart_conclusion_of_a_quick_study_has_no_width_sentence(dart):
    """A --quick study runs only the series with quick values (the time step): no half-width
    sentence, the defaults still follow. Planted: the first study replaced by None, the text
    replaced by None."""
    from engines.dart.contact_study import SOFT_CONTACT
    _, run = dart
    assert [r.quick_values is not None for r in SOFT_CONTACT.refinements] == [True, False]
    text = SOFT_CONTACT.conclusion(_dart_studies(quick=True), run.settings)
    _in_order(text, [DART_FIRST, DART_DEFAULTS_TEXT])


def test_dart_series_options_reach_the_run_as_declared(dart):
    """Every value of both series, run by DART on the 0.01 s grid: the step series changes the
    step alone (the half-width stays the default the series' ``held`` names, 1e-6 m); the
    half-width series sets the half-width at the step its ``held`` names (2.5e-4 s). Planted:
    the option keys misspelt or upper-cased ('XXtimestepXX', 'WHEEL_HALF_WIDTH', ...)."""
    from engines.dart.contact_study import SOFT_CONTACT
    engine, run = dart
    step, width = SOFT_CONTACT.refinements
    assert step.held == "half-width 1e-06 m" and width.held == "time step 0.00025 s"
    for v in step.values:
        s = engine.simulate(_scenario(), **step.options(v, run.settings)).settings
        assert (s["timestep"], s["wheel_half_width"]) == (v, 1e-6)
        assert s["ignored_options"] == []
    for v in width.values:
        s = engine.simulate(_scenario(), **width.options(v, run.settings)).settings
        assert (s["timestep"], s["wheel_half_width"]) == (2.5e-4, v)


# -- MuJoCo ---------------------------------------------------------------------------------------

def test_mujoco_defaults_are_the_documented_ones(mujoco):
    """The run the settings tests read records docs/engines.md's MuJoCo defaults."""
    _, run = mujoco
    assert _defaults_of(run.settings, MUJOCO_DEFAULTS) == MUJOCO_DEFAULTS


def test_mujoco_settings_rows_show_the_runs_settings(mujoco):
    """The table, each value the run's own in docs/engines.md's units: solref (2e-4 s, 1),
    solimp (0.99, 0.999, 1e-3 m, 0.5, 2), 0 noslip iterations, the 1e-4 s implicit step, Newton
    with 100 iterations to 1e-10, the version mujoco reports. Planted: any label misspelt or
    upper-cased, str(None) for the version or the noslip iterations, 'XX, XX' between the solimp
    entries, a wrong settings key for any value."""
    import mujoco as mj
    from engines.mujoco.contact_study import SOFT_CONTACT
    _, run = mujoco
    s = run.settings
    assert SOFT_CONTACT.settings_rows(s) == [
        ("MuJoCo version", mj.__version__),
        ("geometry", s["wheels"]),
        ("friction", "sliding 2, torsional 0, rolling 0; cone elliptic, condim 3"),
        ("solref (time constant s, damping ratio)", "0.0002, 1"),
        ("solimp (dmin, dmax, width m, midpoint, power)", "0.99, 0.999, 0.001, 0.5, 2"),
        ("noslip iterations", "0"),
        ("timestep, integrator", "0.0001 s, implicit"),
        ("constraint solver", "Newton, 100 iterations, tolerance 1e-10"),
        ("rear wheel height", s["rear_height_joint"]),
        ("loads", s["loads"])]
    assert s["friction_coefficients"] == "sliding 2, torsional 0, rolling 0"


def _mujoco_studies(quick=False):
    from engines.mujoco.contact_study import SOFT_CONTACT
    tc_step, step, tc = SOFT_CONTACT.refinements
    # slip RMS 1.3e-4 m/s at the finest time constant 1.25e-4 s: 1.04 x the time constant
    main = _study(tc_step, (5.2e-4, 2.6e-4, 1.3e-4, 5.9e-5), (1.0e-3, 5.1e-4, 2.6e-4, 1.3e-4),
                  1.04, "approaches ideal rolling", "order 1.04 over 8x")
    if quick:
        return [main]
    # errors 1e-3 ... 4e-4 out of order; slips 1.9e-3 ... 2.1e-3 out of order
    by_step = _study(step, (1.0e-3, 4.0e-4, 7.0e-4, 5.0e-4), (2.1e-3, 2.0e-3, 1.9e-3, 2.05e-3),
                     0.17, "does not approach")
    # values 2e-3 ... 2.5e-4 halving, errors 8e-3, 4e-3, 1e-3, 5e-4: local orders
    # log 2 / log 2 = 1, log 4 / log 2 = 2, log 2 / log 2 = 1
    by_tc = _study(tc, (8e-3, 4e-3, 1e-3, 5e-4), (2e-3, 1e-3, 5e-4, 2.5e-4), 0.86,
                   "approaches ideal rolling")
    return [main, by_step, by_tc]


MUJOCO_FIRST = ("**Conclusion.** With the timestep at half the time constant, MuJoCo approaches "
                "ideal rolling (order 1.04 over 8x); its slip RMS is 1.04 x the time constant "
                "(m/s per s).")
MUJOCO_LAST = (" MuJoCo honours time constants down to two steps, so the setting closest to ideal "
               "rolling at a given cost is time constant = 2 x timestep. Defaults chosen: "
               "timestep 0.0001 s, solref (0.0002, 1), integrator implicit, cone elliptic, "
               "condim 3, noslip iterations 0, solimp (0.99, 0.999, 0.001, 0.5, 2).")


def test_mujoco_conclusion_reads_all_three_series(mujoco):
    """The conclusion: the main series' slip per time constant (1.3e-4 / 1.25e-4 = 1.04), the
    timestep series at its held time constant with its errors' and slips' ranges (smallest
    first: 4.0e-4 to 1.0e-3, 1.90e-3 to 2.10e-3 m/s), the time-constant series at its held step
    with its local orders (1.00, 2.00, 1.00 by hand), then the defaults (docs/engines.md).
    Planted: the slip times the value or the wrong end of the series, the timestep or solref
    series not found (name misspelt or upper-cased, None, [1] of a one-element list), any '+='
    turned into '=', min/max of None, 'XX, XX' between the local orders or the solimp entries,
    the damping ratio printed as the time constant, any sentence's text mangled."""
    from engines.mujoco.contact_study import SOFT_CONTACT
    _, run = mujoco
    text = SOFT_CONTACT.conclusion(_mujoco_studies(), run.settings)
    assert _mujoco_studies()[2].orders == pytest.approx((1.0, 2.0, 1.0))
    _in_order(text, [
        MUJOCO_FIRST,
        " The timestep alone, at a fixed time constant 0.002 s: does not approach (order 0.17; "
        "errors 4.0e-04 to 1.0e-03, where the integrator's own first-order error and the "
        "contact's add or cancel), and the slip stays 1.90e-03 to 2.10e-03 m/s: the step does "
        "not remove the contact's departure from rolling.",
        " The time constant alone, at a fixed timestep 0.000125 s: approaches ideal rolling "
        "(order 0.86; local orders 1.00, 2.00, 1.00), down to the integrator's own error at "
        "that step.",
        MUJOCO_LAST])


def test_mujoco_conclusion_of_a_quick_study(mujoco):
    """--quick runs the main series alone: no timestep or time-constant sentence, the
    defaults' sentence whole. Planted: the first study replaced by None or read from [1]."""
    from engines.mujoco.contact_study import SOFT_CONTACT
    _, run = mujoco
    assert [r.quick_values is not None for r in SOFT_CONTACT.refinements] == [True, False, False]
    _in_order(SOFT_CONTACT.conclusion(_mujoco_studies(quick=True), run.settings),
              [MUJOCO_FIRST, MUJOCO_LAST])


def test_mujoco_series_options_reach_the_run_as_declared(mujoco):
    """Every value of the three series, run by MuJoCo on the 0.01 s grid, records what the
    series declares: time constant tc with timestep tc / 2; the step h at the held time
    constant 2e-3 s; tc at the held step 1.25e-4 s; the damping ratio always the run's own
    (0.7 here, not the default 1, so that it is read, not assumed). MuJoCo honours tc >= 2
    timesteps only (docs/engines.md): every run keeps it. Planted: tc / 3 or tc * 2 as the step,
    the option keys misspelt or upper-cased, the damping ratio read from solref[2]."""
    from engines.mujoco.contact_study import SOFT_CONTACT
    engine, run = mujoco
    s = {**run.settings, "solref": [2e-4, 0.7]}
    tc_step, step, tc = SOFT_CONTACT.refinements
    assert (tc_step.held, step.held, tc.held) == ("timestep = time constant / 2",
                                                  "time constant 0.002 s", "timestep 0.000125 s")
    expect = {0: lambda v: (v / 2, [v, 0.7]), 1: lambda v: (v, [2e-3, 0.7]),
              2: lambda v: (1.25e-4, [v, 0.7])}
    for i, series in enumerate(SOFT_CONTACT.refinements):
        for v in series.values:
            got = engine.simulate(_scenario(), **series.options(v, s)).settings
            assert (got["timestep"], list(got["solref"])) == expect[i](v), (series.parameter, v)
            assert got["solref"][0] >= 2 * got["timestep"] * (1 - 1e-12)
            assert got["ignored_options"] == []


# -- Drake ----------------------------------------------------------------------------------------

def test_drake_defaults_are_the_documented_ones(drake):
    """The run the settings tests read records docs/engines.md's Drake defaults."""
    _, run = drake
    assert _defaults_of(run.settings, DRAKE_DEFAULTS) == DRAKE_DEFAULTS


def test_drake_settings_rows_of_point_contact(drake):
    """The table of the default (point-contact) run: point, TAMSI, friction 2, stiction 1e-4
    m/s, 1e8 N/m and 10 s/m, the 5e-4 s step, the version of the installed drake. Planted: the
    contact model read as None or under a wrong key, the branch inverted or comparing with
    'XXpointXX'/'POINT', the stiffness row replaced by None, any label misspelt or re-cased,
    str(None) for the version, 'rows - [...]', a wrong settings key for any value."""
    from importlib.metadata import version
    from engines.drake.contact_study import SOFT_CONTACT
    _, run = drake
    s = run.settings
    assert SOFT_CONTACT.settings_rows(s) == [
        ("Drake version", version("drake")),
        ("geometry", s["wheels"]),
        ("contact model, discrete approximation", "point, tamsi"),
        ("Coulomb friction (static = dynamic)", "2"),
        ("stiction tolerance", "0.0001 m/s"),
        ("point contact stiffness, Hunt-Crossley dissipation", "1e+08 N/m, 10 s/m"),
        ("time step", "0.0005 s"),
        ("rear wheel height", s["rear_height_joint"]),
        ("loads", s["loads"])]


def test_drake_settings_rows_of_hydroelastic_contact(drake):
    """A hydroelastic run (a real one) shows its modulus, 1e9 Pa, in place of the point
    contact's stiffness. Planted: the branch inverted, the modulus row replaced by None, its
    label mangled, its key misspelt."""
    from engines.drake.contact_study import SOFT_CONTACT
    engine, _ = drake
    s = engine.simulate(_scenario(), contact_model="hydroelastic").settings
    rows = SOFT_CONTACT.settings_rows(s)
    assert rows[2] == ("contact model, discrete approximation", "hydroelastic, tamsi")
    assert rows[5] == ("hydroelastic modulus (compliant wheels, rigid ground)", "1e+09 Pa")
    assert [r[0] for r in rows[6:]] == ["time step", "rear wheel height", "loads"]
    assert not any("stiffness" in label for label, _ in rows)


def _drake_studies(quick=False):
    from engines.drake.contact_study import SOFT_CONTACT
    step, stiction, sap = SOFT_CONTACT.refinements
    # slip RMS 2.5e-4 m/s at the finest step 1.25e-4 s: 2.00 x the step
    main = _study(step, (8.5e-4, 4.3e-4, 2.1e-4, 1.1e-4), (2.1e-3, 1.0e-3, 4.9e-4, 2.5e-4), 0.99,
                  "approaches ideal rolling", "order 0.99 over 8x")
    if quick:
        return [main]
    return [main,
            _study(stiction, (8.5e-4, 8.3e-4, 7.8e-4, 8.0e-4), (1e-3,) * 4, -0.01,
                   "does not approach"),
            _study(sap, (2.0e-3, 1.0e-3, 5.0e-4, 2.5e-4), (4e-3, 2e-3, 1e-3, 5e-4), 1.01,
                   "approaches ideal rolling")]


DRAKE_FIRST = ("**Conclusion.** Refining the time step (the default solver and contact), Drake "
               "approaches ideal rolling (order 0.99 over 8x); its slip RMS is 2.00 x the step "
               "(m/s per s): each step's friction impulse leaves the slip the rolling point's "
               "acceleration builds up over one step.")
DRAKE_LAST = (" Defaults chosen: tamsi with point contact, time step 0.0005 s, point stiffness "
              "1e+08 N/m, stiction tolerance 0.0001 m/s, wheel half-width 1e-06 m: the closest "
              "to ideal rolling at about the cost of the other engines' runs.")


def test_drake_conclusion_reads_every_series(drake):
    """The conclusion: the step series' slip per step at the finest step (2.5e-4 / 1.25e-4 =
    2.00), then each other series named by its parameter without the unit ('stiction
    tolerance', 'time step') with its held setting, order and errors smallest first (7.8e-4 to
    8.5e-4; 2.5e-4 to 2.0e-3), then the defaults (docs/engines.md). Planted: the second study
    read as the main one, the slip times the step or the wrong end, the loop from the third
    study on, the name split on None / 'XX [XX' / its unit, any '+=' turned into '=', min/max of
    None, any default under a wrong key, any sentence's text mangled."""
    from engines.drake.contact_study import SOFT_CONTACT
    _, run = drake
    _in_order(SOFT_CONTACT.conclusion(_drake_studies(), run.settings), [
        DRAKE_FIRST,
        " The stiction tolerance (time step 0.001 s): does not approach (order -0.01; errors "
        "7.8e-04 to 8.5e-04).",
        " The time step (SAP): approaches ideal rolling (order 1.01; errors 2.5e-04 to 2.0e-03).",
        DRAKE_LAST])


def test_drake_conclusion_of_a_quick_study(drake):
    """--quick runs the default solver's step series alone: its sentence and the defaults.
    Planted: the first study replaced by None, the text replaced by None."""
    from engines.drake.contact_study import SOFT_CONTACT
    _, run = drake
    assert [r.quick_values is not None for r in SOFT_CONTACT.refinements] == [True, False, False]
    _in_order(SOFT_CONTACT.conclusion(_drake_studies(quick=True), run.settings),
              [DRAKE_FIRST, DRAKE_LAST])


def test_drake_series_options_reach_the_run_as_declared(drake):
    """Every value of the three series, run by Drake on the 0.01 s grid: the step series
    changes the step alone (TAMSI, point contact: 'the default solver and contact'); the
    stiction series sets the tolerance at its held step 1e-3 s; the SAP series the step with
    Drake's SAP solver. Planted: the option keys misspelt or upper-cased, 'XXsapXX' or 'SAP' for
    the solver (not one of Drake's approximations)."""
    from engines.drake.contact_study import SOFT_CONTACT
    engine, run = drake
    step, stiction, sap = SOFT_CONTACT.refinements
    assert (step.held, stiction.held, sap.held) == ("the default solver and contact",
                                                    "time step 0.001 s", "SAP")
    keys = ("time_step", "approximation", "contact_model", "stiction_tolerance")
    expect = ((step, lambda v: (v, "tamsi", "point", 1e-4)),
              (stiction, lambda v: (1e-3, "tamsi", "point", v)),
              (sap, lambda v: (v, "sap", "point", 1e-4)))
    for series, want in expect:
        for v in series.values:
            got = engine.simulate(_scenario(), **series.options(v, run.settings)).settings
            assert tuple(got[k] for k in keys) == want(v), (series.parameter, v)


# -- every engine's series ------------------------------------------------------------------------

@pytest.mark.parametrize("engine", ["dart", "mujoco", "drake"])
def test_every_series_halves_spans_8x_and_steps_divide_the_grid(engine, request):
    """Each declared series (and its quick values) runs coarsest first by a constant ratio (a
    halving for every step and time constant, Drake's stiction tolerance by decades) over the
    8x a verdict needs (docs/report.md), and every time step its options set divides the
    study's 0.01 s output grid (docs/engines.md: the step must divide the sampling interval), at
    every value."""
    import importlib
    _, run = request.getfixturevalue(engine)
    soft = importlib.import_module(f"engines.{engine}.contact_study").SOFT_CONTACT
    for series in soft.refinements:
        for values in (series.values, series.quick_values or ()):
            if not values:
                continue
            assert len(values) >= 3
            ratio = 0.1 if series.parameter.startswith("stiction") else 0.5
            assert all(math.isclose(b / a, ratio) for a, b in zip(values, values[1:]))
            assert max(values) / min(values) >= MIN_SPAN * (1 - 1e-12)
            for v in values:
                opts = series.options(v, run.settings)
                h = opts.get("timestep", opts.get("time_step"))
                assert h is not None and _divides_grid(h), (series.parameter, v, h)
        assert re.fullmatch(r"[a-z][a-z -]* \[(s|m|m/s)\]", series.parameter), series.parameter
