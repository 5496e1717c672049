"""The soft-contact study (comparisons/stages/soft_contact.py) run in-process on a synthetic
soft-contact engine whose every departure from ideal rolling is planted, so that each number
the study prints is known before it runs.

The engine (`Synthetic`, loaded by the file spec `SPEC` as tests/soft_twin.py is) runs the
reference itself (`convergence.reference_run` on the study's model and scenario) and moves it
by known amounts:

* yc drifts at RATE(tc, h) = R0 (tc / TC0) (h / H0)^(1/4) m/s, so the trajectory error is
  RATE t (max over the eight coordinates: only yc moves), and the error at STUDY_TIME of a
  refinement series is exactly c v^1 in the time constant and c v^(1/4) in the step: local
  and fitted orders 1 and 0.25;
* its diagnostics are planted arrays (`_planted`): constant slips and penetrations with a few
  spikes at known samples, one before and one after the front wheel's planted lift-off at
  0.30 s (normal force 0 from there on), so max, RMS and the worst wheel follow by hand;
* its run time is a fake clock the study reads (COST s per simulated second at the default
  step, in proportion to 1 / h), so the run-time columns are known too;
* its settings rows, conclusion and ``about`` are its own text, which the section must carry.

The reference's ideal normal forces are checked against physics: the vertical balance
sum m_i (z''_i + g) with z'' from each state's own velocity and acceleration (not the grid's
differences), the front one against the KKT multiplier of rD_z, and at rest against the
statics of the wheelbase. The study's pull sentence (thesis-disc: the rear wheel from 0.44 s)
uses those independent forces.

Cost: the reference runs (~0.04 s each) and a dozen synthetic runs, each study made once per
module; the whole file about 2 s.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from comparisons.judgments.contact_ranking import ContactRow, rank
from comparisons.judgments.convergence import reference_run
from comparisons.stages import soft_contact as sct
from comparisons.stages.results import Figure, Heading, Table, Text
from engines.base import Engine, UnsupportedModel
from engines.facts import Refinement, RunSetup, SoftContact
from reference_model import load_model
from reference_model.scenarios import SCENARIOS
from reference_model.solvers import Trajectory

FILE = Path(__file__).resolve()
SPEC = f"{FILE}:Synthetic"

# -- the synthetic contact's laws ---------------------------------------------------------------
TC0 = 2e-3          # s: its default time constant
H0 = 8e-4           # s: its default step
R0 = 2e-3           # m/s: yc's drift at the defaults
COST = 0.2          # s of (fake) wall time per simulated second at the default step
YC = 1              # yc's column in q
LIFT = 30           # the sample (0.30 s) from which the front wheel carries nothing
TC_SERIES = (8e-3, 4e-3, 2e-3, 1e-3)
TC_QUICK = (8e-3, 2e-3, 1e-3)
H_SERIES = (4e-4, 1.6e-3, 2e-4, 8e-4)       # declared out of order: the study sorts them
SETTINGS_LINE = "the synthetic contact: time constant 2e-3 s, step 8e-4 s"


def rate(tc: float, h: float) -> float:
    """yc's drift (m/s) at time constant ``tc`` and step ``h``."""
    return R0 * (tc / TC0) * (h / H0) ** 0.25


def _planted(n: int, k: float, normal: bool) -> dict:
    """The diagnostics of an n-sample run on the 0.01 s grid, slips scaled by ``k``: rear slip
    1e-3, front 2e-3 with 4e-3 at 0.25 s and 6e-3 at 0.40 s; rear penetration 3e-5 with 7e-5 at
    0.35 s, front 1e-5 with 5e-5 at 0.10 s; normal forces 400 N rear, 250 N front up to LIFT,
    0 from it."""
    slip_front = np.full(n, 2e-3)
    pen_rear, pen_front = np.full(n, 3e-5), np.full(n, 1e-5)
    for a, i, v in ((slip_front, 25, 4e-3), (slip_front, 40, 6e-3), (pen_rear, 35, 7e-5),
                    (pen_front, 10, 5e-5)):
        if i < n:       # a refinement run ends at 0.2 s
            a[i] = v
    d = {"slip_speed_rear": np.full(n, 1e-3 * k), "slip_speed_front": k * slip_front,
         "penetration_rear": pen_rear, "penetration_front": pen_front}
    if normal:
        front = np.full(n, 250.0)
        front[LIFT:] = 0.0
        d.update(normal_force_rear=np.full(n, 400.0), normal_force_front=front)
    return d


def _tc_series(v, s):
    return {"time_constant": v, "step": s["step"]}


def _h_series(v, s):
    return {"step": v, "time_constant": s["time_constant"]}


def _settings_rows(s):
    return [("time constant", f"{s['time_constant']:g} s"), ("step", f"{s['step']:g} s")]


def _conclusion(studies, s):
    return (f"Synthetic reading of {len(studies)} series: the finest {studies[0].parameter} "
            f"reaches {min(studies[0].errors):.1e}; kept at {s['time_constant']:g} s.")


class Synthetic(Engine):
    """The reference moved by known amounts (module docstring)."""

    name = "Synthetic"
    label = "Synthetic soft"
    capabilities = frozenset({"simulate"})
    contacts = ("disc",)
    run_setups = (RunSetup(suffix="plain", kinds=("forward",)),
                  RunSetup(suffix="set", kinds=("forward",), settings=SETTINGS_LINE))
    soft_contact = SoftContact(
        refinements=(Refinement("time constant [s]", "step at its default", TC_SERIES,
                                _tc_series, quick_values=TC_QUICK),
                     Refinement("step [s]", "time constant at its default", H_SERIES,
                                _h_series)),
        settings_rows=_settings_rows, conclusion=_conclusion,
        about="a synthetic contact whose errors are known in advance")
    records_normal_force = True
    clock = {"now": 0.0}        # the fake wall clock (s), shared with the test
    calls: list = []            # (t_end, options) of each simulate call
    _refs: dict = {}

    def __init__(self, model, time_constant: float = TC0, step: float = H0):
        super().__init__(model)
        self.time_constant, self.step = time_constant, step

    def simulate(self, scenario, t_end=None, **options):
        type(self).calls.append((t_end, dict(options)))
        tc = options.get("time_constant", self.time_constant)
        h = options.get("step", self.step)
        key = (self.model.name, scenario.name, t_end)
        if key not in self._refs:
            self._refs[key] = reference_run(self.model, scenario, t_end=t_end)
        ref = self._refs[key]
        q = ref.q.copy()
        q[:, YC] += rate(tc, h) * ref.t
        self.clock["now"] += COST * (H0 / h) * float(ref.t_end)
        return Trajectory(t=ref.t.copy(), q=q, dq=ref.dq, ddq=ref.ddq, C=ref.C, T=ref.T,
                          status="completed", message="", t_end=float(ref.t_end),
                          settings={"time_constant": tc, "step": h},
                          diagnostics=_planted(ref.t.size, tc / TC0, self.records_normal_force))


class Plain(Synthetic):
    """No normal forces recorded (so no lift-off), no settings rows, no conclusion, no text
    about the contact and no refinement series: the study's bare minimum."""

    name = "Plain"
    label = "Plain soft"
    records_normal_force = False
    run_setups = ()
    soft_contact = SoftContact()


class Refuses(Synthetic):
    """Cannot represent any bicycle: a declared limitation (`UnsupportedModel`)."""

    name = "Refuses"
    label = "Refusing"

    def __init__(self, model, **options):
        raise UnsupportedModel("no tyre model for this bicycle")


# -- helpers ------------------------------------------------------------------------------------

GRID = np.round(np.arange(51) * 0.01, 12)


def _rms(*groups):
    """RMS of samples given as (count, value) groups."""
    return math.sqrt(sum(n * v * v for n, v in groups) / sum(n for n, _ in groups))


def _blocks(sec, kind):
    return [b for b in sec.blocks if isinstance(b, kind)]


def _engine_class(name="Synthetic"):
    from engines.registry import resolve
    return resolve(f"{FILE}:{name}")[0]


def _study(monkeypatch, name="Synthetic", quick=False, model=None):
    """The study of engine ``name``, its wall time read from the engine's fake clock; the
    engine's simulate calls."""
    cls = _engine_class(name)
    monkeypatch.setattr(sct, "time", SimpleNamespace(perf_counter=lambda: cls.clock["now"]))
    cls.calls.clear()
    args = (f"{FILE}:{name}", quick) + (() if model is None else (model,))
    return sct.contact_study(*args), list(cls.calls)


@pytest.fixture(scope="module")
def full():
    with pytest.MonkeyPatch.context() as mp:
        return _study(mp)


@pytest.fixture(scope="module")
def quick():
    with pytest.MonkeyPatch.context() as mp:
        return _study(mp, quick=True)


@pytest.fixture(scope="module")
def plain():
    with pytest.MonkeyPatch.context() as mp:
        return _study(mp, "Plain", quick=True)


@pytest.fixture(scope="module")
def bench():
    with pytest.MonkeyPatch.context() as mp:
        return _study(mp, quick=True, model="benchmark")


def _exact_forces(model, ref):
    """(rear, front) normal forces along ``ref`` from physics: front = -lambda of rD_z (the
    KKT solve, the scenario's pedal torque 1 N m), rear = sum m_i (z''_i + g) - front with z''
    of each centre of mass from the state's own dq and ddq (q(t +- h) to second order, h =
    1e-4 s), not from the output grid."""
    p = model.params
    T = np.tile(np.asarray(SCENARIOS["stability-psid10"].torques, dtype=float),
                (ref.t.size, 1))
    front = -model.forward(ref.q, ref.dq, T).lam[:, 0]

    def mz(q):
        pts = model.points(q)
        return (p.m2 * pts["rG2"][:, 2] + p.m3 * pts["rG3"][:, 2] + p.m4 * pts["rG4"][:, 2]
                + p.m5 * pts["rG5"][:, 2])
    h = 1e-4
    zpp = (mz(ref.q + h * ref.dq + h * h / 2 * ref.ddq) - 2 * mz(ref.q)
           + mz(ref.q - h * ref.dq + h * h / 2 * ref.ddq)) / h ** 2
    return (p.m2 + p.m3 + p.m4 + p.m5) * p.g + zpp - front, front


@pytest.fixture(scope="module")
def disc_forces():
    model = load_model("thesis-disc")
    ref = reference_run(model, SCENARIOS["stability-psid10"], t_end=0.5)
    return model, ref, _exact_forces(model, ref)


# -- the ideal normal forces ---------------------------------------------------------------------

def test_the_ideal_normal_forces_at_rest_are_the_wheelbase_statics():
    """Upright and at rest on thesis-disc (a constant trajectory, so z'' = 0): the two forces
    sum to the weight m g exactly, and the front one is the statics of the wheelbase,
    m g x_G / w (x_G the centre of mass ahead of the rear contact), less the load the pedal
    torque's 1 N m shifts to the rear, at most (M / r) h_G / w (all the torque as traction).
    Planted: the weight subtracted, g divided, the wrong multiplier (vC_x's) or its sign, the
    rear as the sum instead of the difference."""
    model = load_model("thesis-disc")
    p = model.params
    n = 5
    ref = SimpleNamespace(t=np.arange(n) * 0.01, q=np.zeros((n, 8)), dq=np.zeros((n, 8)))
    rear, front = sct.ideal_normal_forces(model, ref)
    m = p.m2 + p.m3 + p.m4 + p.m5
    np.testing.assert_allclose(rear + front, m * p.g, rtol=1e-12)
    pts = model.points(np.zeros((1, 8)))
    w = pts["rD"][0, 0] - pts["rC"][0, 0]
    x_g = sum(mi * pts[k][0, 0] for k, mi in (("rG2", p.m2), ("rG3", p.m3), ("rG4", p.m4),
                                              ("rG5", p.m5))) / m
    h_g = sum(mi * pts[k][0, 2] for k, mi in (("rG2", p.m2), ("rG3", p.m3), ("rG4", p.m4),
                                              ("rG5", p.m5))) / m
    static = m * p.g * x_g / w
    shift = (1.0 / pts["rG2"][0, 2]) * h_g / w
    assert np.all(front <= static) and np.all(front >= static - shift)
    assert 200.0 < front[0] < 260.0 and 560.0 < rear[0] < 630.0     # the frame sits rearward


def test_the_ideal_normal_forces_along_the_manoeuvre_balance_the_weight_and_the_accelerations(
        disc_forces):
    """Along the study's reference on thesis-disc: the front force is minus the KKT multiplier
    of rD_z, and the two sum to sum m_i (z''_i + g) with z'' from each state's dq and ddq, to
    2 N (0.25 % of the weight) on the samples 0.02-0.35 s, where the grid's second differences
    (second order in 0.01 s; the docstring: for the force's sign and size) follow the exact
    ones. Planted: the grid's index as time (np.gradient without t), a coordinate other than z,
    a mass divided, the weight's sign."""
    model, ref, (rear_x, front_x) = disc_forces
    rear, front = sct.ideal_normal_forces(model, ref)
    np.testing.assert_allclose(front, front_x, rtol=1e-12, atol=1e-9)
    k = slice(2, 36)
    np.testing.assert_allclose(rear[k], rear_x[k], atol=2.0)
    np.testing.assert_allclose((rear + front)[k], (rear_x + front_x)[k], atol=2.0)
    assert rear.shape == front.shape == ref.t.shape


# -- the study on a synthetic engine: thesis-disc, full ------------------------------------------

def test_the_study_says_who_on_which_model_and_the_default_runs_cost(full):
    """The title names the engine's label; the first paragraph its model, its own sentence
    about the contact, the study's scenario and the default run's cost from the fake clock:
    0.2 s per simulated second, 0.1 s for 0.5 s; the settings table is the engine's own rows
    of the run's settings. Planted: the run's settings not passed, the title's model suffix on
    thesis-disc, the cost per second from the wrong run."""
    study, _ = full
    sec = study.section
    assert sec.title == "Synthetic soft contact study: soft contact against ideal rolling"
    texts = [b.text for b in _blocks(sec, Text)]
    assert texts[0] == (
        "Synthetic soft with its own wheel-ground contact, on `thesis-disc` (a synthetic "
        "contact whose errors are known in advance), and `stability-psid10`, against the "
        "reference (DOP853, rtol 1e-11, projection: the rolling constraints hold exactly). The "
        "engine's default contact settings (the settings of its runs in every section), and "
        "their cost: this run took 0.2 s of wall time per simulated second (0.1 s for 0.50 s; "
        "measured, it varies with the machine's load):")
    tables = _blocks(sec, Table)
    assert tables[0].header == ("setting", "value")
    assert tables[0].rows == (("time constant", "0.002 s"), ("step", "0.0008 s"))


def test_the_engine_is_run_over_the_window_then_each_series_over_the_study_time(full, quick):
    """The default run over the 0.5 s window without options, then every refinement run over
    STUDY_TIME = 0.2 s with the series' options built from the default run's settings (the
    module docstring); a quick study runs only the series that declares quick values, at
    those. Planted: the window or the study time not passed to simulate, a series' values
    replaced by its quick ones (or the reverse), the defaults not passed to the options."""
    _, calls = full
    assert calls == ([(0.5, {})]
                     + [(0.2, {"time_constant": v, "step": H0}) for v in TC_SERIES]
                     + [(0.2, {"step": v, "time_constant": TC0}) for v in H_SERIES])
    _, calls = quick
    assert calls == [(0.5, {})] + [(0.2, {"time_constant": v, "step": H0}) for v in TC_QUICK]


def test_the_lift_off_and_the_ideal_pull_sentence(full, disc_forces):
    """The front wheel's normal force is 0 from 0.30 s: it lifts off there and carries load up
    to 0.29 s; the ideal model needs the rear wheel pulled down from 0.44 s, at about -135 N by
    the exact accelerations (the grid's differences print within 8 N of it). The reference's
    reproducibility is the twin runs' horizon, 0.50 s. Planted: the lift-off sample counted as
    loaded, the pull's second sample, the front wheel named, the lift-off and the
    both-loaded sentences swapped."""
    study, _ = full
    _, ref, (rear_x, front_x) = disc_forces
    k = int(np.flatnonzero(np.minimum(rear_x, front_x) < 0)[0])
    assert ref.t[k] == pytest.approx(0.44) and rear_x[k] < 0 < front_x[k]
    sec = study.section
    assert [b.text for b in _blocks(sec, Heading)][0] == (
        "Slip, penetration and trajectory error at the defaults")
    text = [b.text for b in _blocks(sec, Text)][1]
    m = re.fullmatch(
        re.escape("The reference is reproducible to 1e-06 over this window (horizon 0.50 s: two "
                  "reference runs 1e-9 rad/s apart in theta_dot(0) stay within 1e-06 (max ")
        + r"\d\.\de-\d\d"
        + re.escape(") up to the end of the shorter run (0.500 s; the last common grid time "
                    "0.50 s)). Synthetic soft's wheels carry load up to 0.29 s; a wheel lifts "
                    "off at 0.30 s, where the ideal model needs the ground to pull a wheel down "
                    "from t = 0.44 s (rear normal force ")
        + r"(-\d+)"
        + re.escape(" N): the soft contact is unilateral, the reference's rolling constraint is "
                    "not, so past that time the runs differ in kind (a declared model "
                    "difference), not in accuracy."), text)
    assert m is not None, text
    assert abs(int(m.group(1)) - rear_x[k]) < 8.0


def test_the_default_runs_table_and_its_summary_row(full):
    """Up to 0.29 s (30 samples): slip max 4e-3 (front at 0.25 s), penetration max 5e-5 (front
    at 0.10 s), error 2e-3 m/s x 0.29 s; over the whole 0.5 s (51 samples) the spikes after the
    lift-off count: slip 6e-3 (front at 0.40 s), penetration 7e-5 (rear at 0.35 s), error
    1e-3. RMS over both wheels' samples. summary.json's row (docs/report.md) is the loaded
    part only. Planted: the whole window's figures in the summary, a key misspelt, the
    lift-off or the ideal pull left out, the table's rows swapped."""
    study, _ = full
    sec = study.section
    table = _blocks(sec, Table)[1]
    assert table.header == ("up to", "slip max [m/s]", "slip RMS [m/s]", "penetration max [m]",
                            "penetration RMS [m]", "max error, 8 coordinates [rad, m]")
    slip_loaded = _rms((30, 1e-3), (29, 2e-3), (1, 4e-3))
    pen_loaded = _rms((30, 3e-5), (29, 1e-5), (1, 5e-5))
    slip_all = _rms((51, 1e-3), (49, 2e-3), (1, 4e-3), (1, 6e-3))
    pen_all = _rms((50, 3e-5), (1, 7e-5), (50, 1e-5), (1, 5e-5))
    assert table.rows == (
        ("while both wheels are loaded (0 - 0.29 s)", "4.00e-03 (front at 0.25 s)",
         f"{slip_loaded:.2e}", "5.00e-05 (front at 0.10 s)", f"{pen_loaded:.2e}", "5.80e-04"),
        ("whole window (0 - 0.50 s)", "6.00e-03 (front at 0.40 s)", f"{slip_all:.2e}",
         "7.00e-05 (rear at 0.35 s)", f"{pen_all:.2e}", "1.00e-03"))
    assert table.note == (
        "Slip: speed of each wheel's contact point (the disc's lowest point) in the ground "
        "plane, 0 for ideal rolling; penetration: depth of that point below the ground "
        "(negative: above it; a leaned cylinder rests on its cap's rim). Statistics over both "
        "wheels' samples on the 0.01 s grid.")
    row = sec.comparisons[0].as_dict()
    numbers = {k: row.pop(k) for k in ("max_error", "horizon", "slip_max", "slip_rms",
                                       "penetration_max", "penetration_rms", "lift_off_s",
                                       "ideal_pull_s")}
    assert numbers == pytest.approx({"max_error": 2e-3 * 0.29, "horizon": 0.29,
                                     "slip_max": 4e-3, "slip_rms": slip_loaded,
                                     "penetration_max": 5e-5, "penetration_rms": pen_loaded,
                                     "lift_off_s": 0.30, "ideal_pull_s": 0.44}, rel=1e-9)
    assert row == {
        "quantity": "contact fidelity (slip, penetration, trajectory)",
        "scenario": "stability-psid10", "model": "thesis-disc",
        "engines": ["reference", "Synthetic"], "tolerance": None, "passed": None,
        "localized_to": "slip max 4.0e-03 m/s (front at 0.25 s)",
        "note": "while both wheels are loaded; reported, not judged: a declared model "
                "difference (soft contact)"}


def test_the_default_runs_figure_carries_the_planted_arrays(full, disc_forces):
    """The figure ``<engine>_contact_run.png`` (no model tag on thesis-disc): the run's grid,
    its error against time (2e-3 t in yc, the max), the loaded horizon 0.29 s, each wheel's
    planted slip, penetration and normal force, and the reference's ideal normal forces (the
    front one the KKT multiplier's; the rear one the balance, to 2 N up to 0.35 s). Planted:
    a wheel's array under the other's name, the ideal forces' time from the run, the error up
    to the loaded horizon only."""
    study, _ = full
    _, ref, (rear_x, front_x) = disc_forces
    fig = study.section.figures[0]
    assert (fig.name, fig.kind, fig.caption) == ("Synthetic_contact_run.png", "contact_run", "")
    d = fig.data
    assert set(d) == {"t", "error", "horizon", "slip", "penetration", "normal", "ideal_normal",
                      "engine_label", "title"}
    np.testing.assert_allclose(d["t"], GRID, atol=1e-12)
    np.testing.assert_allclose(d["error"]["t"], GRID, atol=1e-12)
    np.testing.assert_allclose(d["error"]["yc"], 2e-3 * GRID, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(d["error"]["max"], 2e-3 * GRID, rtol=1e-9, atol=1e-15)
    assert d["horizon"] == pytest.approx(0.29)
    planted = _planted(51, 1.0, True)
    for what, key in (("slip", "slip_speed"), ("penetration", "penetration"),
                      ("normal", "normal_force")):
        assert set(d[what]) == {"rear", "front"}
        for wheel in ("rear", "front"):
            np.testing.assert_array_equal(d[what][wheel], planted[f"{key}_{wheel}"])
    ideal = d["ideal_normal"]
    assert set(ideal) == {"t", "rear", "front"}
    np.testing.assert_allclose(ideal["t"], GRID, atol=1e-12)
    np.testing.assert_allclose(ideal["front"], front_x, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(ideal["rear"][2:36], rear_x[2:36], atol=2.0)
    assert d["engine_label"] == "Synthetic soft"
    assert d["title"] == ("stability-psid10 on Synthetic soft (defaults) against the reference "
                          "thesis-disc")


def test_the_ranking_row_is_measured_up_to_the_last_sample_before_the_ground_must_pull(full):
    """The row on the shared horizon 0.43 s (the sample before the ideal pull at 0.44 s): error
    2e-3 x 0.43 there and at most, slip and penetration over 0.00-0.43 s (44 samples, the 0.40
    s slip spike and the 0.35 s penetration spike inside), the lift-off 0.30 s, the 0.5 s run's
    0.1 s of (fake) wall time, and the engine's first non-empty settings line. Planted: the
    pull's second sample, the row's model or scenario or lift-off left out, the wrong wall
    time."""
    study, _ = full
    row = study.row
    assert (row.engine, row.label, row.model, row.scenario, row.reached, row.settings) == (
        "Synthetic", "Synthetic soft", "thesis-disc", "stability-psid10", True, SETTINGS_LINE)
    assert row.horizon == pytest.approx(0.43)
    assert row.error_at_horizon == pytest.approx(2e-3 * 0.43, rel=1e-9)
    assert row.error_max == pytest.approx(2e-3 * 0.43, rel=1e-9)
    assert row.slip_max == pytest.approx(6e-3)
    assert row.slip_rms == pytest.approx(_rms((44, 1e-3), (42, 2e-3), (1, 4e-3), (1, 6e-3)))
    assert row.penetration_max == pytest.approx(7e-5)
    assert row.penetration_rms == pytest.approx(_rms((43, 3e-5), (1, 7e-5), (43, 1e-5),
                                                     (1, 5e-5)))
    assert row.lift_off_s == pytest.approx(0.30)
    assert row.simulated_s == pytest.approx(0.5)
    assert row.run_seconds == pytest.approx(COST * 0.5)
    assert row.run_time_per_simulated_second == pytest.approx(COST)


def test_the_refinement_table_orders_and_run_times(full):
    """Each series at 0.2 s: the time constant's errors 0.2 R0 v / TC0 (order 1 exactly: local
    orders and the fit 1.00, 'approaches ideal rolling'), the step's 0.2 R0 (v / H0)^(1/4)
    (order 0.25 < 0.5 over 8x: 'does not approach'), coarsest first whatever the declared
    order; slip RMS over both wheels (1e-3 and 2e-3, scaled by tc / TC0); the run time per
    simulated second from the fake clock, 0.2 H0 / h, in the study's order. Planted: the
    costs in the declared order, the unit left in the name, another series' study, the
    heading or the note garbled."""
    study, _ = full
    sec = study.section
    assert [b.text for b in _blocks(sec, Heading)] == [
        "Slip, penetration and trajectory error at the defaults",
        "Refinement: the error at 0.2 s against the contact's settings"]
    table = _blocks(sec, Table)[2]
    assert table.header == ("refined", "held", "values", "error at 0.2 s [rad, m]",
                            "slip RMS [m/s]", "local orders", "fitted order", "verdict",
                            "run time per simulated second [s]")
    slip0 = _rms((1, 1e-3), (1, 2e-3))
    tc_err = [0.2 * rate(v, H0) for v in TC_SERIES]
    h_sorted = sorted(H_SERIES, reverse=True)
    h_err = [0.2 * rate(TC0, v) for v in h_sorted]
    assert table.rows == (
        ("time constant", "step at its default", "0.008, 0.004, 0.002, 0.001",
         ", ".join(f"{e:.2e}" for e in tc_err),
         ", ".join(f"{slip0 * v / TC0:.2e}" for v in TC_SERIES),
         "1.00, 1.00, 1.00", "1.00", "approaches ideal rolling", "0.2, 0.2, 0.2, 0.2"),
        ("step", "time constant at its default", "0.0016, 0.0008, 0.0004, 0.0002",
         ", ".join(f"{e:.2e}" for e in h_err), ", ".join([f"{slip0:.2e}"] * 4),
         "0.25, 0.25, 0.25", "0.25", "does not approach", "0.1, 0.2, 0.4, 0.8"))
    assert tc_err[0] == pytest.approx(1.6e-3) and h_err[0] == pytest.approx(4e-4 * 2 ** 0.25)
    assert table.note == (
        "Error: max over the eight coordinates at the grid time 0.2 s (inside the reference's "
        "meaningful horizon and before any wheel unloads). Local orders: "
        "log(e_i/e_i+1)/log(v_i/v_i+1); fitted order: the slope of log error against log "
        "value. Every other setting at the defaults above. Run time: wall time of each run "
        "over its simulated 0.2 s (measured: the cost of each setting).")


def test_the_refinement_summary_rows(full):
    """summary.json's row of each series (docs/report.md): the smallest error as max_error,
    the fitted order, values coarsest first with their errors and slip RMS, the verdict and
    its reason, the run times. Planted: the largest error as max_error, a key misspelt, the
    series' name with its unit."""
    study, _ = full
    rows = [c.as_dict() for c in study.section.comparisons[1:]]
    assert len(rows) == 2
    slip0 = _rms((1, 1e-3), (1, 2e-3))
    h_sorted = sorted(H_SERIES, reverse=True)
    expected = [("time constant", "step at its default", 1.0, list(TC_SERIES),
                 [0.2 * rate(v, H0) for v in TC_SERIES], [slip0 * v / TC0 for v in TC_SERIES],
                 "approaches ideal rolling", [COST] * 4),
                ("step", "time constant at its default", 0.25, h_sorted,
                 [0.2 * rate(TC0, v) for v in h_sorted], [slip0] * 4, "does not approach",
                 [COST * H0 / v for v in h_sorted])]
    for row, (name, held, order, values, errors, slips, verdict, costs) in zip(rows, expected):
        assert row.pop("max_error") == pytest.approx(min(errors), rel=1e-9)
        assert row.pop("order") == pytest.approx(order, rel=1e-9)
        assert row.pop("values") == values
        for key, want in (("errors", errors), ("slip_rms", slips),
                          ("run_time_per_simulated_second", costs)):
            assert row.pop(key) == pytest.approx(want, rel=1e-9), key
        reason = row.pop("reason")
        assert f"order {order:.2f}" in reason
        assert row == {"quantity": f"contact refinement ({name}, {held})",
                       "scenario": "stability-psid10", "model": "thesis-disc",
                       "engines": ["reference", "Synthetic"], "tolerance": None,
                       "passed": None, "verdict": verdict,
                       "localized_to": f"order {order:.2f}: {verdict}",
                       "note": "reported, not judged: a declared model difference (soft "
                               "contact)"}


def test_the_engines_conclusion_and_the_refinement_figure(full):
    """The engine's own reading of its studies (given the studies in their order and the
    default settings) closes the text; the figure ``<engine>_contact_refinement.png`` has one
    curve per series, labelled with its order, at 0.2 s. Planted: no conclusion, the studies
    or the settings not passed, a curve's values or errors missing, the figure's name."""
    study, _ = full
    sec = study.section
    assert [b.text for b in _blocks(sec, Text)][-1] == (
        "Synthetic reading of 2 series: the finest time constant [s] reaches 2.0e-04; kept at "
        "0.002 s.")
    assert isinstance(sec.blocks[-1], Figure) and isinstance(sec.blocks[-2], Text)
    fig = sec.figures[1]
    assert (fig.name, fig.kind) == ("Synthetic_contact_refinement.png", "refinement")
    assert set(fig.data) == {"curves", "at_time", "title"}
    assert fig.data["at_time"] == 0.2
    assert fig.data["title"] == "Synthetic soft against ideal rolling, stability-psid10"
    curves = fig.data["curves"]
    assert [c["label"] for c in curves] == [
        "time constant (step at its default): order 1.00",
        "step (time constant at its default): order 0.25"]
    assert curves[0]["values"] == list(TC_SERIES)
    assert curves[0]["errors"] == pytest.approx([0.2 * rate(v, H0) for v in TC_SERIES],
                                                rel=1e-9)
    h_sorted = sorted(H_SERIES, reverse=True)
    assert curves[1]["values"] == h_sorted
    assert curves[1]["errors"] == pytest.approx([0.2 * rate(TC0, v) for v in h_sorted],
                                                rel=1e-9)
    assert [type(b).__name__ for b in sec.blocks] == [
        "Text", "Table", "Heading", "Text", "Table", "Figure", "Heading", "Table", "Text",
        "Figure"]


# -- quick, bare, refused, and on a user's bicycle -----------------------------------------------

def test_a_quick_study_runs_only_the_series_with_quick_values(quick):
    """--quick: the time constant's quick values (3 spanning 8x: order 1.00, a verdict), not
    the step's series (no quick values); the same default run and row. Planted: the quick
    filter inverted, the full values used."""
    study, _ = quick
    sec = study.section
    table = _blocks(sec, Table)[2]
    assert [r[0] for r in table.rows] == ["time constant"]
    assert table.rows[0][2:4] == ("0.008, 0.002, 0.001",
                                  ", ".join(f"{0.2 * rate(v, H0):.2e}" for v in TC_QUICK))
    assert table.rows[0][5:8] == ("1.00, 1.00", "1.00", "approaches ideal rolling")
    assert [c["quantity"] for c in sec.comparisons] == [
        "contact fidelity (slip, penetration, trajectory)",
        "contact refinement (time constant, step at its default)"]
    assert [b.text for b in _blocks(sec, Text)][-1] == (
        "Synthetic reading of 1 series: the finest time constant [s] reaches 2.0e-04; kept at "
        "0.002 s.")
    assert study.row.error_at_horizon == pytest.approx(2e-3 * 0.43, rel=1e-9)


def test_without_normal_forces_both_wheels_stay_loaded_and_nothing_optional_is_drawn(plain):
    """An engine that records no normal forces never lifts off: the loaded part is the whole
    window (0.50 s), the 'both wheels stay loaded' sentence with the ideal pull; no settings
    table, no sentence about the contact, no refinement heading, table or figure; the
    figure's normal forces None; the row's settings empty. Planted: the lift-off sentence
    without a lift-off, the settings table without rows, the refinement without series."""
    study, _ = plain
    sec = study.section
    assert sec.title == "Plain soft contact study: soft contact against ideal rolling"
    texts = [b.text for b in _blocks(sec, Text)]
    assert len(texts) == 2
    assert texts[0].startswith("Plain soft with its own wheel-ground contact, on "
                               "`thesis-disc`, and `stability-psid10`, against the reference")
    assert re.search(r"\)\. Both wheels stay loaded; the ideal model needs the ground to pull a "
                     r"wheel down from t = 0\.44 s \(rear normal force -\d+ N\)\.$", texts[1])
    assert [b.text for b in _blocks(sec, Heading)] == [
        "Slip, penetration and trajectory error at the defaults"]
    (table,) = _blocks(sec, Table)
    assert [r[0] for r in table.rows] == ["while both wheels are loaded (0 - 0.50 s)",
                                          "whole window (0 - 0.50 s)"]
    assert table.rows[0][1:] == table.rows[1][1:]
    assert [f.name for f in sec.figures] == ["Plain_contact_run.png"]
    d = sec.figures[0].data
    assert d["normal"] == {"rear": None, "front": None}
    assert d["horizon"] == pytest.approx(0.5)
    assert len(sec.comparisons) == 1
    summary = sec.comparisons[0]
    assert summary["lift_off_s"] is None and summary["ideal_pull_s"] == pytest.approx(0.44)
    assert summary["horizon"] == pytest.approx(0.5)
    row = study.row
    assert row.lift_off_s is None and row.settings == ""
    assert row.horizon == pytest.approx(0.43)


def test_the_pull_is_the_first_negative_needed_force_and_names_its_wheel(monkeypatch):
    """With the ideal normal forces planted (rear 300 N, front 200 N, but front exactly 0 N at
    0.10 s and 0.5 N at 0.15 s, neither a pull; at 0.20 s the front -50 N with the rear at
    exactly 0 N; at 0.21 s the rear -10 N): the pull is the front wheel's at 0.20 s, -50 N, and
    the ranking's horizon the sample before, 0.19 s. Planted: a zero or a small positive force
    counted as a pull, the wheel named by a force that is not negative or by the next sample,
    the force read at the next sample."""
    rear, front = np.full(51, 300.0), np.full(51, 200.0)
    front[10], front[15] = 0.0, 0.5
    rear[20], front[20] = 0.0, -50.0
    rear[21], front[21] = -10.0, 100.0
    monkeypatch.setattr(sct, "ideal_normal_forces", lambda model, ref: (rear, front))
    study, _ = _study(monkeypatch, "Plain", quick=True)
    text = [b.text for b in _blocks(study.section, Text)][1]
    assert text.endswith("). Both wheels stay loaded; the ideal model needs the ground to pull a "
                         "wheel down from t = 0.20 s (front normal force -50 N).")
    assert study.section.comparisons[0]["ideal_pull_s"] == pytest.approx(0.20)
    assert study.row.horizon == pytest.approx(0.19)
    assert study.row.error_at_horizon == pytest.approx(2e-3 * 0.19, rel=1e-9)
    ideal = study.section.figures[0].data["ideal_normal"]
    assert ideal["rear"] is rear and ideal["front"] is front


def test_a_reference_reproducible_for_less_than_the_window_bounds_the_whole_window_row(
        monkeypatch):
    """When the twin reference runs part at 0.40 s (the reproducible horizon planted), the
    comparison stops there: an engine without lift-off is loaded up to 0.40 s, the 'whole
    window' row too ends at 0.40 s (error 2e-3 x 0.40), and so does the ranking's horizon.
    Planted: the whole-window row up to the end of the run (0.50 s) regardless of the
    horizon."""
    real = sct.meaningful_horizon

    def short(*args, **kwargs):
        return dataclasses.replace(real(*args, **kwargs), t=0.40, reason="planted: parted")
    monkeypatch.setattr(sct, "meaningful_horizon", short)
    study, _ = _study(monkeypatch, "Plain", quick=True)
    sec = study.section
    assert "over this window (horizon 0.40 s: planted: parted). Both wheels stay loaded" in (
        [b.text for b in _blocks(sec, Text)][1])
    (table,) = _blocks(sec, Table)
    assert [(r[0], r[-1]) for r in table.rows] == [
        ("while both wheels are loaded (0 - 0.40 s)", "8.00e-04"),
        ("whole window (0 - 0.40 s)", "8.00e-04")]
    d = sec.figures[0].data
    np.testing.assert_allclose(d["error"]["t"], GRID[:41], atol=1e-12)
    assert d["horizon"] == pytest.approx(0.40)
    assert study.row.horizon == pytest.approx(0.40)


def test_an_engine_that_cannot_represent_the_model_is_said_not_run():
    """`UnsupportedModel` from the engine's constructor: the section says why in one
    paragraph ('Not run on this model: ...', the loader's message with the engine's reason),
    no comparisons, and no ranking row. Planted: the section or the reason dropped."""
    study = sct.contact_study(f"{FILE}:Refuses", True)
    sec = study.section
    assert study.row is None
    assert sec.title == "Refusing contact study: soft contact against ideal rolling"
    (text,) = [b.text for b in sec.blocks]
    assert text.startswith("Not run on this model: engine 'Refuses' (")
    assert text.endswith("cannot represent model 'thesis-disc': no tyre model for this bicycle")
    assert sec.comparisons == []


def test_the_study_on_a_users_bicycle(bench):
    """On ``--model benchmark`` (disc contact): the title and figures say the model (' on
    benchmark', '_benchmark'), the scenario is the study's bound to it
    ('stability-psid10-on-benchmark'); the benchmark's ideal normal forces stay positive over
    the window (both above 200 N by the exact balance), so the row's horizon is the window's
    0.50 s. Planted: the thesis-disc scenario on a user's model, the model tag or the title's
    model left out, the positive-forces sentence garbled."""
    study, calls = bench
    sec = study.section
    assert sec.title == ("Synthetic soft contact study on benchmark: soft contact against "
                         "ideal rolling")
    texts = [b.text for b in _blocks(sec, Text)]
    assert texts[0].startswith("Synthetic soft with its own wheel-ground contact, on "
                               "`benchmark` (a synthetic contact")
    assert texts[1].endswith(
        "Synthetic soft's wheels carry load up to 0.29 s; a wheel lifts off at 0.30 s, where "
        "the ideal model's normal forces stay positive: the soft contact is unilateral, the "
        "reference's rolling constraint is not, so past that time the runs differ in kind (a "
        "declared model difference), not in accuracy.")
    assert [f.name for f in sec.figures] == ["Synthetic_contact_run_benchmark.png",
                                             "Synthetic_contact_refinement_benchmark.png"]
    assert sec.figures[0].data["title"] == (
        "stability-psid10-on-benchmark on Synthetic soft (defaults) against the reference "
        "benchmark")
    assert sec.figures[1].data["title"] == (
        "Synthetic soft against ideal rolling, stability-psid10-on-benchmark")
    assert {(c["scenario"], c["model"]) for c in sec.comparisons} == {
        ("stability-psid10-on-benchmark", "benchmark")}
    assert sec.comparisons[0]["ideal_pull_s"] is None
    row = study.row
    assert (row.model, row.scenario) == ("benchmark", "stability-psid10-on-benchmark")
    assert row.horizon == pytest.approx(0.5)
    assert row.error_at_horizon == pytest.approx(2e-3 * 0.5, rel=1e-9)
    model = load_model("benchmark")
    ref = reference_run(model, sct._scenario_on("benchmark"), t_end=0.5)
    rear, front = _exact_forces(model, ref)
    assert np.minimum(rear, front).min() > 200.0
    np.testing.assert_allclose(sec.figures[0].data["ideal_normal"]["front"], front,
                               rtol=1e-12, atol=1e-9)
    assert calls[0] == (0.5, {})


def test_the_studys_scenario_on_each_model():
    """thesis-disc: the built-in scenario itself; a user's bicycle: the same scenario renamed
    for it, its model the spec (cases.on_model). Planted: the branches swapped."""
    assert sct._scenario_on("thesis-disc") is SCENARIOS["stability-psid10"]
    on = sct._scenario_on("benchmark")
    assert (on.name, on.model) == ("stability-psid10-on-benchmark", "benchmark")
    assert on.torques == SCENARIOS["stability-psid10"].torques


# -- the ranking ---------------------------------------------------------------------------------

def _row(engine, error, slip=1e-3, model="thesis-disc", lift=0.45):
    return ContactRow(engine=engine, label=engine.upper(), model=model,
                      scenario="stability-psid10", horizon=0.43, reached=True,
                      error_at_horizon=error, error_max=2 * error, slip_rms=slip,
                      slip_max=2 * slip, penetration_max=3e-5, penetration_rms=1e-5,
                      lift_off_s=lift, simulated_s=0.5, run_seconds=0.25, settings="defaults")


def test_the_ranking_section_says_how_the_engines_are_compared(full):
    """The study's own row beside two hand-made ones, in `contact_ranking.rank`'s order; the
    paragraph and the note state the shared horizon and how to read the table (docs/report.md,
    'Soft-contact engines side by side'). Planted: the text or note garbled or dropped."""
    study, _ = full
    rows = [_row("b", 1e-2), study.row, _row("a", 1e-4)]
    sec = sct.ranking_section(rows)
    order = [r.row.label for r in rank(rows)]
    assert order == ["A", "Synthetic soft", "B"]
    (text,) = [b.text for b in _blocks(sec, Text)]
    assert text == (
        "Every engine with a soft wheel-ground contact (3: A, Synthetic soft, B) on the same "
        "manoeuvre, `stability-psid10` on `thesis-disc`, at its default settings, against the "
        "ideal-rolling reference up to the same time, 0.43 s: the last output sample before "
        "ideal rolling needs the ground to pull a wheel down (which no unilateral contact can), "
        "within the reference's meaningful horizon. Ranked by the error at that time, then by "
        "slip RMS; a run that ends before it comes last. Reported, not judged: each soft "
        "contact is a declared model difference.")
    (table,) = _blocks(sec, Table)
    assert [r[1] for r in table.rows] == order
    assert table.rows[1][2] == f"{2e-3 * 0.43:.2e}" and table.rows[1][8] == "0.30"
    assert table.note == (
        "Errors: max over the eight coordinates; slip and penetration over both wheels' samples "
        "on the 0.01 s grid up to the shared time. Run time: wall time of the engine's default "
        "run of the study over its simulated time (measured on this machine, under its load; "
        "the only number here that varies from run to run). Each engine's settings and its "
        "refinement are in its contact study below.")


def test_the_ranking_of_a_single_engine():
    """One soft-contact engine alone: its table and summary entry (rank 1). Planted: the
    summary read from the second-ranked row."""
    rows = [_row("solo", 1e-3, model="mine")]
    sec = sct.ranking_section(rows)
    assert sec.title == "Soft-contact engines side by side: how close to ideal rolling on mine"
    assert [r[:2] for r in _blocks(sec, Table)[0].rows] == [("1", "SOLO")]
    summary = sct.ranking_summary(rows)
    assert (summary["model"], summary["scenario"], summary["horizon_s"]) == (
        "mine", "stability-psid10", 0.43)
    assert summary["rows"] == [{"rank": 1, **rows[0].as_dict()}]


# -- the stage's assembly ------------------------------------------------------------------------

def _plan():
    from comparisons.stages.stage import Plan
    facts = {"mj": SimpleNamespace(spec="mj", label="MJ"),
             "dk": SimpleNamespace(spec="dk", label="DK"),
             "p": SimpleNamespace(spec="p", label="P")}
    return Plan(SimpleNamespace(models=(), quick=False, scenarios=()), (), facts)


def test_the_stage_ranks_each_model_apart_whatever_the_order_of_the_results():
    """Results in any order (a claims task first, then a study that failed): every study is
    assembled, the failed one as its failure after the others, and the rows of each model are
    ranked on their own (two models, two rankings, one summary entry each). Planted: the loop
    stopped at the first task that is not a study or at the first failed study, every model's
    rows in one ranking, the reference's claims read when its task was not run."""
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.soft_contact_claims import DiscClaims
    claims = DiscClaims("mj", "MJ", ({"claim_id": "stability-a", "claim": "claim a",
                                      "engine": "mj", "verdict": "holds", "evidence": "ev"},))
    s = [sct.Section(f"study {i}") for i in range(4)]
    results = {
        ("claims", "mj", "thesis-disc"): TaskResult(None, claims, 1.0),
        ("study", "p", "thesis-disc"): TaskResult(None, None, 1.0, "boom"),
        ("study", "mj", "thesis-disc"): TaskResult(None, sct.ContactStudy(s[0], _row("mj", 2e-3)),
                                                   1.0),
        ("study", "dk", "thesis-disc"): TaskResult(None, sct.ContactStudy(s[1], _row("dk", 1e-3)),
                                                   1.0),
        ("study", "mj", "mine.toml"): TaskResult(None, sct.ContactStudy(
            s[2], _row("mj", 1e-3, model="mine")), 1.0),
        ("study", "dk", "mine.toml"): TaskResult(None, sct.ContactStudy(
            s[3], _row("dk", 5e-3, model="mine")), 1.0)}
    out = sct.SoftContactStage().assemble(_plan(), results)
    titles = [x.title for x in out.sections]
    assert titles == ["Soft-contact engines side by side: how close to ideal rolling",
                      "Soft-contact engines side by side: how close to ideal rolling on mine",
                      "study 0", "study 1", "study 2", "study 3", "P contact study",
                      "The thesis's stability claims on thesis-disc: the soft-contact engines"]
    assert [[r[1] for r in _blocks(x, Table)[0].rows] for x in out.sections[:2]] == [
        ["DK", "MJ"], ["MJ", "DK"]]
    assert [(e["model"], [r["engine"] for r in e["rows"]])
            for e in out.summary["soft_contact_ranking"]] == [("thesis-disc", ["dk", "mj"]),
                                                               ("mine", ["mj", "dk"])]
    # no reference claims task at all: the engines' claims alone, without a reference column
    claims_table = _blocks(out.sections[-1], Table)[0]
    assert claims_table.header == ("claim", "mj thesis-disc")
