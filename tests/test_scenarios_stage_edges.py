"""Edges of the scenario stages (comparisons/stages/scenarios.py) the section tests leave open:
which run, model, reference and tolerances each judgment is handed, the custom scenarios of a
case (not built-ins), the engines that cannot be built, the figures' columns (theta is q[:, 3],
the yaw q[:, 6]), the analytic check's bound taken inclusively, and the section's words a
reader reads. Every judgment is a recorder here (they are tested on their own)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from comparisons.judgments.rows import Comparison
from comparisons.stages import scenarios as sn
from comparisons.stages.results import Table, Text
from engines.runs import Run
from test_stage_sections import _MEngine

TOLS = object()     # the tolerances: every judgment must be handed this very object


def _run(engine, scenario, kind="forward", status="completed", n=5, message="", T=None,
         model="thesis"):
    """A run whose coordinate k is 100 k + sample index (every column tells itself apart)."""
    t = np.linspace(0.0, 0.04, n)
    q = 100.0 * np.arange(8) + np.arange(n)[:, None]
    return Run(engine, scenario, model, kind, status, message, 0.1, t=t, q=q,
               dq=np.zeros((n, 8)), T=T)


# -- the reference's rows and the check scenario ------------------------------------------

def test_the_analytic_bound_is_inclusive_and_relative_to_mped():
    """docs: the check passes when max |T - (0, Mped, 0)| <= 1e-12 Mped. Mped on the thesis
    bicycle is 0.8 (0.32 * 5)^2 0.32 = 0.65536 N m: a deviation of exactly 1e-12 Mped passes,
    one of 1e-12 N m (1.5e-12 Mped) fails. Planted: '<' for '<='; the bound 1e-12 / Mped
    (1.5e-12 N m, letting 1e-12 N m pass)."""
    from reference_model import load_model
    model = load_model("thesis")
    p = model.params
    mped = p.cv * (p.R_rear * 5.0) ** 2 * p.R_rear
    assert abs(mped - 0.65536) < 1e-12
    T = np.tile([0.0, mped, 0.0], (4, 1))
    T[2, 0] = 1e-12 * mped
    edge = sn.analytic_check(_run("reference", "check", "inverse", n=4, T=T), model)
    assert edge["value"] == edge["tolerance"] and edge["passed"] is True
    T[2, 0] = 1e-12
    assert sn.analytic_check(_run("reference", "check", "inverse", n=4, T=T),
                             model)["passed"] is False


def test_only_the_check_scenario_gets_the_analytic_check_and_corrections_keep_their_rest():
    """An inverse run with torques that is not the check gets no analytic check; an inverse
    run's correction is its message after the first '; ' (all of it, '; ' included).
    Planted: 'or run.T is not None'; rsplit, split without maxsplit, split on whitespace."""
    runs = {("reference", "zigzag"): _run(
        "reference", "zigzag", "inverse", T=np.zeros((5, 3)),
        message="ran on another geometry; beta corrected by 1e-9 rad; then held")}
    runs[("reference", "zigzag")].q[:] = 0.0
    rows, checks, corrections = sn.reference_rows(["zigzag"], runs)
    assert checks == []
    assert corrections == {"zigzag": "beta corrected by 1e-9 rad; then held"}
    assert [r["scenario"] for r in rows] == ["zigzag"]


def test_an_engines_integer_mass_matrices_are_kept_as_floats():
    """M as the engine gives it, as float arrays whatever its element type (an engine may
    answer in integers). Planted: np.asarray without dtype=float."""
    class IntEngine(_MEngine):
        def mass_matrix(self, q):
            return [np.eye(8, dtype=int).tolist() for _ in range(len(q))]
    batch = sn._MassInOneCall(IntEngine(), {"a": np.zeros((2, 8))})
    M = batch.at("a").mass_matrix(None)
    assert M.dtype == np.float64 and np.array_equal(M, np.tile(np.eye(8), (2, 1, 1)))


# -- compare_scenarios on a case's own scenarios ------------------------------------------

CASES = {
    "mine-inv": SimpleNamespace(name="mine-inv", model="thesis", kind="inverse",
                                compared=("mass_matrix", "torques"), tags=()),
    "other-inv": SimpleNamespace(name="other-inv", model="benchmark", kind="inverse",
                                 compared=("mass_matrix", "torques"), tags=()),
    "mine-fwd": SimpleNamespace(name="mine-fwd", model="thesis", kind="forward",
                                compared=("constraint_residual", "trajectory"),
                                tags=("stability",)),
    "notraj": SimpleNamespace(name="notraj", model="thesis", kind="forward",
                              compared=("constraint_residual",), tags=()),
    "dead": SimpleNamespace(name="dead", model="thesis", kind="forward",
                            compared=("trajectory",), tags=()),
}
NAMES = list(CASES)
HORIZONS = {"mine-fwd": SimpleNamespace(t=0.03), "notraj": SimpleNamespace(t=0.02)}


@pytest.fixture
def env(monkeypatch):
    """Recorders for every judgment, noting what each is handed; engines S (a declared soft
    contact, listed before A), A, E (its M raises), U (cannot represent a model), X (raises
    while built), N (its runs not run)."""
    from engines import UnsupportedModel
    e = SimpleNamespace(calls=[])

    def row(quantity, scenario, engines, **kw):
        return Comparison.of({"quantity": quantity, "scenario": scenario, "model": "m",
                              "engines": engines, "max_error": 1e-9, "tolerance": 1e-6,
                              "passed": True, **kw})

    def mass(name, model, q, engines, tols):
        (label, eng), = engines.items()
        M = np.asarray(eng.mass_matrix(q))
        e.calls.append(("M", name, model.name, label, tols is TOLS,
                        np.array_equal(M[:, 0, 0], q[:, 0])))
        return [row("mass_matrix", name, ["reference", label])]

    def inverse(ref, r, tols):
        e.calls.append(("inverse", r.scenario, ref.engine, r.engine, tols is TOLS))
        return [row("torques", r.scenario, ["reference", r.engine])]

    def constraints(model, r, tols):
        e.calls.append(("C", r.scenario, model.name, r.engine, tols is TOLS))
        return row("constraint_residual", r.scenario, [r.engine], localized_to="rD_z")

    def series(model, r):
        e.calls.append(("series", r.scenario, model.name, r.engine))
        i = np.arange(len(r.t), dtype=float)[:, None]
        return np.hstack([i + 1, i + 30, i + 10, i + 20, 0 * i])   # column 1 the largest

    def declared(ref, r, hor, difference, cmax, cwhere):
        e.calls.append(("declared", r.scenario, ref.engine, r.engine, hor.t))
        return [row("trajectory", r.scenario, ["reference", r.engine], passed=None),
                row("slip", r.scenario, [r.engine], passed=None)]

    def forward(model, ref, r, hor, tols, judged_by, reported_because):
        e.calls.append(("forward", r.scenario, model.name, ref.engine, r.engine, hor.t,
                        tols is TOLS))
        err = np.arange(len(r.t))[:, None] + np.arange(8.0)          # row max: i + 7
        return [row("trajectory", r.scenario, ["reference", r.engine])], SimpleNamespace(
            t=r.t, errors=err)

    def traj_error(ref, r, t):
        e.calls.append(("trajectory_error", r.scenario, ref.engine, r.engine, t))
        err = 2.0 * np.arange(len(r.t))[:, None] + np.arange(8.0)    # row max: 2 i + 7
        return SimpleNamespace(t=r.t, errors=err)

    facts = {"soft": SimpleNamespace(run_difference="a soft contact", trajectory_tolerance=None,
                                     trajectory_judged_by=None),
             "ideal": SimpleNamespace(run_difference=None, trajectory_tolerance="trajectory",
                                      trajectory_judged_by=None)}
    for name, f in (("compare_mass_matrix", mass), ("compare_inverse", inverse),
                    ("compare_constraints", constraints), ("constraint_series", series),
                    ("declared_difference_rows", declared), ("compare_forward", forward),
                    ("trajectory_error", traj_error),
                    ("engine_facts", lambda spec: facts[spec])):
        monkeypatch.setattr(sn, name, f)

    def build_raising(exc):
        def build(m):
            raise exc
        return build

    def setup(label, spec="ideal", build=None):
        return SimpleNamespace(label=label, engine=spec,
                               build=build or (lambda m: _MEngine()))
    e.setups = {"reference": setup("reference"), "S": setup("S", "soft"), "A": setup("A"),
                "E": setup("E", build=lambda m: _MEngine(raises=KeyError("no M"))),
                "U": setup("U", build=build_raising(UnsupportedModel("no front contact"))),
                "X": setup("X", build=build_raising(RuntimeError("no compiler"))),
                "N": setup("N")}
    T = np.zeros((5, 3))
    runs = {}
    for name, model in (("mine-inv", "thesis"), ("other-inv", "benchmark")):
        for lab in ("reference", "A"):
            runs[(lab, name)] = _run(lab, name, "inverse", T=T, model=model)
    for name in ("mine-fwd", "notraj"):
        for lab in ("reference", "S", "A"):
            runs[(lab, name)] = _run(lab, name)
        runs[("N", name)] = _run("N", name, status="not run", n=0)
    runs[("reference", "dead")] = _run("reference", "dead", status="failed", n=0,
                                       message="it fell")
    runs[("A", "dead")] = _run("A", "dead")
    runs[("reference", "zigzag")] = _run("reference", "zigzag", "inverse", n=6)
    runs[("A", "replay")] = _run("A", "replay", n=4)
    e.runs = runs
    e.sec = sn.compare_scenarios(TOLS, NAMES, e.setups, runs, HORIZONS, CASES)
    return e


def test_m_is_asked_of_each_engine_built_on_the_scenarios_own_model(env):
    """M of a case's scenario is the engine's at the reference's states of that scenario
    (built on its own model, the benchmark's states not mixed into the thesis's), handed the
    model and the tolerances; an engine whose M raises is its own failing row naming the
    quantity and model; one that cannot represent the model is skipped, one that raises
    while built is a failing row per model. Planted: _scenario(n, None) (a case's scenario
    not found); '!=' for the scenarios of the model; engines[lab] = None / at(None); no
    blocks; the None engine wrapped; compare_mass_matrix given model or tols None; the
    engine-call row's quantity or model None; failures appended to None."""
    mass = [c for c in env.calls if c[0] == "M"]
    assert mass == [("M", n, m, lab, True, True) for n, m in (("mine-inv", "thesis"),
                                                             ("other-inv", "benchmark"))
                    for lab in ("S", "A", "N")]
    rows = [r.as_dict() for r in env.sec.comparisons]
    calls = [r for r in rows if r["quantity"] == "engine call"]
    assert [(r["scenario"], r["model"], r["engines"], r["passed"]) for r in calls] == [
        ("mine-inv", "thesis", ["E"], False), ("other-inv", "benchmark", ["E"], False)]
    assert all(r["note"] == "E failed while its mass_matrix was compared" for r in calls)
    builds = [r for r in rows if r["quantity"] == "engine build"]
    assert [(r["model"], r["engines"]) for r in builds] == [("thesis", ["X"]),
                                                            ("benchmark", ["X"])]
    assert not any("U" in r["engines"] for r in rows)


def test_each_judgment_is_handed_the_reference_the_model_and_the_tolerances(env):
    """compare_inverse(ref, run, tols), compare_constraints(model, run, tols),
    constraint_series(model, run), declared_difference_rows(ref, ...),
    trajectory_error(ref, run, horizon), compare_forward(model, ref, run, horizon, tols):
    each with the reference's run, the scenario's model and the very tolerances given.
    Planted: any of these handed None."""
    calls = env.calls
    assert [c for c in calls if c[0] == "inverse"] == [
        ("inverse", "mine-inv", "reference", "A", True),
        ("inverse", "other-inv", "reference", "A", True)]
    assert [c for c in calls if c[0] == "C"] == [
        ("C", n, "thesis", lab, True) for n in ("mine-fwd", "notraj")
        for lab in ("reference", "S", "A")]
    assert [c for c in calls if c[0] == "series"] == [
        ("series", n, "thesis", lab) for n in ("mine-fwd", "notraj")
        for lab in ("reference", "S", "A")]
    assert [c for c in calls if c[0] == "declared"] == [
        ("declared", "mine-fwd", "reference", "S", 0.03),
        ("declared", "notraj", "reference", "S", 0.02)]
    assert [c for c in calls if c[0] == "trajectory_error"] == [
        ("trajectory_error", "mine-fwd", "reference", "S", 0.03)]


def test_a_forward_run_is_compared_only_where_the_trajectory_is_and_after_a_declared_engine(env):
    """The trajectory is compared for the engines after one with a declared difference (A
    after S) and only on a scenario listing 'trajectory'; a declared engine's trajectory row
    is kept only there, its other rows everywhere; a run not run is no row at all.
    Planted: 'break' for 'continue'; 'and' for 'or' in the skip; '==' for '!=' in the
    declared rows' filter; 'not run' runs compared."""
    assert [c for c in env.calls if c[0] == "forward"] == [
        ("forward", "mine-fwd", "thesis", "reference", "A", 0.03, True)]
    got = [(r["quantity"], r["scenario"], tuple(r["engines"])) for r in env.sec.comparisons
           if r["scenario"] in ("mine-fwd", "notraj")]
    assert got == [
        ("constraint_residual", "mine-fwd", ("reference",)),
        ("trajectory", "mine-fwd", ("reference", "S")), ("slip", "mine-fwd", ("S",)),
        ("constraint_residual", "mine-fwd", ("A",)), ("trajectory", "mine-fwd", ("reference", "A")),
        ("constraint_residual", "notraj", ("reference",)),
        ("slip", "notraj", ("S",)),
        ("constraint_residual", "notraj", ("A",))]


def test_a_scenario_whose_reference_failed_is_one_not_compared_row(env):
    """docs/report.md: the common keys, the engines that ran, no numbers, failing, with
    why. Planted: the keys 'model', 'max_error', 'tolerance' misspelt."""
    (row,) = [r for r in env.sec.comparisons if r["scenario"] == "dead"]
    assert row.as_dict() == {
        "quantity": "not compared", "scenario": "dead", "model": "thesis", "engines": ["A"],
        "max_error": None, "tolerance": None, "passed": False,
        "localized_to": "not compared: the reference's run failed (it fell)", "note": ""}


def test_the_figures_columns(env):
    """The trajectory figure names its scenario and has each engine's largest coordinate
    error per sample; the residual panel C[:, 0] (the first constraint) and the largest of
    the four others per sample; the stability figure theta = q[:, 3]; the replay and zigzag
    theta = q[:, 3] and yaw q[:, 6]. Planted: scenario None; errors.max(axis=None); C[:, 1],
    C[:, 2:], max(axis=None); q[:, 4]; q[:, 7]."""
    figs = {f.name: f for f in env.sec.figures}
    traj = figs["mine-fwd_trajectories.png"]
    assert traj.data["scenario"] == "mine-fwd" and list(traj.data["runs"]) == ["reference", "S", "A"]
    i = np.arange(5)
    np.testing.assert_array_equal(traj.data["errors"]["A"][1], i + 7.0)
    np.testing.assert_array_equal(traj.data["errors"]["S"][1], 2.0 * i + 7.0)
    t, c0, rest = figs["constraint_residuals.png"].data["panels"]["notraj"]["A"]
    np.testing.assert_array_equal(c0, i + 1.0)
    np.testing.assert_array_equal(rest, i + 30.0)
    stab = figs["stability_theta.png"].data["runs"]
    assert list(stab) == ["reference", "S", "A"]
    np.testing.assert_array_equal(stab["A"]["mine-fwd"][1], 300.0 + i)
    rz = figs["replay_vs_zigzag.png"].data
    _, theta, yaw = rz["zigzag"]
    np.testing.assert_array_equal(theta, 300.0 + np.arange(6))
    np.testing.assert_array_equal(yaw, 600.0 + np.arange(6))
    _, theta, yaw = rz["replays"]["A"]
    np.testing.assert_array_equal(theta, 300.0 + np.arange(4))
    np.testing.assert_array_equal(yaw, 600.0 + np.arange(4))


def test_the_sections_words(env):
    """What a reader reads before and under the table (docs/report.md): what is compared,
    about M_STATES states, the horizon's threshold; the table's units. Planted: the text
    None or its wording altered; the note's wording altered."""
    (text,) = [b.text for b in env.sec.blocks if isinstance(b, Text)]
    assert text == (
        "What each scenario's file (`reference_model/scenario_data/`) lists as compared: M at "
        f"~100 of the reference's states, torques and multipliers along the inverse scenarios, "
        "all eight coordinates up to the *meaningful horizon* (where two reference runs 1e-9 "
        f"rad/s apart in theta_dot(0) part by more than {sn.HORIZON_THRESHOLD:g}: the bike is "
        "unstable, beyond it no comparison means anything) and the constraint residual of "
        "every run, measured by the reference model.")
    (table,) = [b for b in env.sec.blocks if isinstance(b, Table)]
    from reference_model import CONSTRAINT_NAMES
    assert table.note == (
        "Errors are relative to the scale the tolerance names for terms, torques and "
        "multipliers; absolute (rad or m) for trajectories; m or m/s for constraint "
        f"residuals ({', '.join(CONSTRAINT_NAMES)}).")
