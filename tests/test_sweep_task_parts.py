"""One bicycle of a sweep (comparisons/stages/sweep_task.py), every function called in this
process (no Dask): the columns and their order, the 'not computed' row, a lost task's row, the
row of an agreeing, a disagreeing, a failing and an invalid bicycle, the terms, the localization
text, the forward runs' verdicts, the runs' scenario and the per-process model cache.

Expected values come from the module docstring's contract, Meijaard et al. (2007) (Table 1's
bicycle, Table 2's critical speeds), `stages.stability`'s own scenario builder, numpy's
SeedSequence, and tiny engines with a known fault: the reference's M with the front wheel's spin
inertia I5yy typed as I5xx changes by (I5yy - I5xx) c c^T, c the rates' components along the
axle (c_eps = 1, the others direction cosines below 1 in size), so most in M[eps, eps] = I5yy,
by 0.1395 kg m^2, judged against max|M| = M[xc, xc] = the total mass m2 + m3 + m4 + m5 = 94 kg
(Table 1).

The forward runs (12 s a bicycle for real) are checked with fake setups and a fake judgment;
the eigen check's failures with a patched `critical_speeds`. Each test names the planted bug
(a one-line change of the module) it was seen failing on.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import comparisons.judgments.diagnose as diagnose
import comparisons.judgments.eigenvalues as eigenvalues
import comparisons.stages.stability as stability
from comparisons.judgments.terms import random_states
from comparisons.judgments.tolerances import Tolerances
from comparisons.stages import sweep_task as st
from comparisons.stages.sweep_spec import derived_values, make_spec, sample_parameters
from reference_model import ParameterError, load_model
from reference_model.params import PARAMETER_NAMES
from test_sweep import BROKEN_ENGINE, CAPSIZE, WEAVE

#: the term quantities in the documented order (docs/engines.md; judgments.terms)
TERMS = ("mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
         "constraint_jacobian", "constraint_bias", "forward_acceleration")
HEAD = ["bicycle", "seed", "status", "failures"]
DERIVED = ["trail", "head_angle", "wheelbase"]
PARAMS = [f"p.{n}" for n in PARAMETER_NAMES]
GRID = ["m3=85:95:2", "trail=0.08:0.12:2"]      # k: (85, .08), (85, .12), (95, .08), (95, .12)

ENGINES = '''
import numpy as np

from engines.base import Engine
from engines.facts import RunSetup


class WheelTypo(Engine):
    """The reference's M of the bicycle with the front wheel's I5yy typed as I5xx."""
    capabilities = frozenset({"mass_matrix"})

    def __init__(self, model):
        super().__init__(model)
        p = model.params
        self._typo = model.with_params(p.replace(I5yy=p.I5xx))

    def mass_matrix(self, q):
        return self._typo.mass_matrix(q)


class WheelTypo2(WheelTypo):
    """The same typo in a second port."""


class ThetaSkew(Engine):
    """The reference's M with 1e-3 |theta| added to M[xc, xc]: worst where |theta| is."""
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        M = np.array(self.model.mass_matrix(q), dtype=float)
        M[..., 0, 0] += 1e-3 * np.abs(np.asarray(q)[..., 3])
        return M


class NoLoad(Engine):
    """The reference's M; its constructor raises for a rider heavier than 90 kg."""
    capabilities = frozenset({"mass_matrix"})

    def __init__(self, model):
        if model.params.m3 > 90.0:
            raise RuntimeError("no rider that heavy")
        super().__init__(model)

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)


class Flaky(Engine):
    """M raises; the inverse dynamics are the reference's."""
    capabilities = frozenset({"mass_matrix", "inverse_dynamics"})

    def mass_matrix(self, q):
        raise RuntimeError("M  not\\n assembled")

    def inverse_dynamics(self, q, dq, ddq):
        return self.model.inverse_dynamics(q, dq, ddq)


class Narrow(Engine):
    """Declares M and Qgrav; an instance computes M only (an option narrowed it)."""
    capabilities = frozenset({"mass_matrix", "gravity"})

    def __init__(self, model):
        super().__init__(model)
        self.capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

    def gravity(self, q):
        raise RuntimeError("gravity asked of an instance that does not provide it")


class Runner(Engine):
    """Simulates (never run here); M and generalized forces from the reference model."""
    capabilities = frozenset({"generalized_forces", "simulate", "mass_matrix"})

    def __init__(self, model, step=0.001):
        super().__init__(model)

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self.model.generalized_forces(q, dq, torques)

    def simulate(self, scenario, **options):
        raise RuntimeError("not run in these tests")


class ThesisOnly(Runner):
    contacts = ("thesis",)


class DiscOnly(Runner):
    contacts = ("disc",)


class Soft(Runner):
    run_difference = "a soft wheel-ground contact"


class TwoSetups(Runner):
    run_setups = (RunSetup(suffix="inverse", kinds=("inverse",)),
                  RunSetup(suffix="forward", options=(("step", 0.01),), kinds=("forward",)))
'''


@pytest.fixture(scope="module")
def params():
    return load_model("benchmark").params


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Engine specs by class name: the tiny engines above and test_sweep's Broken."""
    d = tmp_path_factory.mktemp("sweep_task")
    (d / "mine.py").write_text(ENGINES)
    (d / "broken.py").write_text(BROKEN_ENGINE)
    names = ("WheelTypo", "WheelTypo2", "ThetaSkew", "NoLoad", "Flaky", "Narrow", "Runner",
             "ThesisOnly", "DiscOnly", "Soft", "TwoSetups")
    return {n: f"{d / 'mine.py'}:{n}" for n in names} | {"Broken": f"{d / 'broken.py'}:Broken"}


@pytest.fixture(scope="module")
def full(params, files):
    """Every check on the Table 1 grid, Pinocchio and the typo engine."""
    return make_spec(params, varies=GRID, engines=("pinocchio", files["WheelTypo"]),
                     checks=("terms", "eigen", "runs"), n_states=2, seed=11)


@pytest.fixture(scope="module")
def real_rows(params, files):
    """Bicycles 0 (Table 1) and 2 (rider 95 kg: Broken raises) with Pinocchio and Broken."""
    spec = make_spec(params, varies=GRID, engines=("pinocchio", files["Broken"]),
                     checks=("terms", "eigen"), n_states=2)
    return spec, st.chunk_rows(spec, (0, 2))


def _seed(seed, k):
    """The states' seed of bicycle k (module docstring: SeedSequence([seed, k, 1]))."""
    return int(np.random.SeedSequence([seed, k, 1]).generate_state(1)[0])


def _nan(v):
    return isinstance(v, float) and math.isnan(v)


# -- columns, quantities, labels, run options -----------------------------------------------------

def test_columns_follow_the_documented_order(full):
    """Head, vary.* in grid order, the derived three, the 30 p.*, per engine err/entry pairs in
    the terms' order, the terms' summary, the speeds, run.<mode>.<factor>.<engine> (weave then
    capsize, 0.9 then 1.1, the reference then Pinocchio; the typo engine does not simulate),
    runs_confirmed, task_seconds.
    Planted: vary and derived swapped; entry before err; 'max_error' dropped; capsize before
    weave; the engine label not stripped to the class name; factors as 1.1 only."""
    runs = [f"run.{m}.{f}.{e}" for m in ("weave", "capsize") for f in ("0.9", "1.1")
            for e in ("reference", "pinocchio")]
    expected = (HEAD + ["vary.m3", "vary.trail"] + DERIVED + PARAMS
                + [c for q in TERMS for c in (f"err.pinocchio.{q}", f"entry.pinocchio.{q}")]
                + ["err.WheelTypo.mass_matrix", "entry.WheelTypo.mass_matrix",
                   "max_error", "terms_passed", "localization", "weave_speed", "capsize_speed"]
                + runs + ["runs_confirmed", "task_seconds"])
    assert st.columns(full) == expected


def test_columns_of_fewer_checks(params, files):
    """Only the asked checks' columns: eigen alone has no err/run columns; terms alone no speeds.
    Planted: the eigen columns written when only terms were asked ('eigen' in checks or
    'terms'); the terms columns for any spec."""
    eigen = make_spec(params, varies=["m3=85:95:2"], engines=("pinocchio",), checks=("eigen",))
    base = HEAD + ["vary.m3"] + DERIVED + PARAMS
    assert st.columns(eigen) == base + ["weave_speed", "capsize_speed", "task_seconds"]
    terms = make_spec(params, varies=["m3=85:95:2"], engines=(files["Narrow"],), checks=("terms",))
    assert st.columns(terms) == base + ["err.Narrow.mass_matrix", "entry.Narrow.mass_matrix",
                                        "err.Narrow.gravity", "entry.Narrow.gravity",
                                        "max_error", "terms_passed", "localization",
                                        "task_seconds"]


def test_quantities_are_what_engine_and_reference_both_declare(params, files):
    """Keyed by the spec as given, in the terms' order; a non-term capability (simulate) is not
    a quantity. Planted: the engine's capabilities in set order; the reference's capabilities
    for every engine."""
    spec = make_spec(params, varies=["m3=85:95:2"], checks=("terms",),
                     engines=("pinocchio", files["Runner"], files["WheelTypo"]))
    assert st.quantities(spec) == {"pinocchio": TERMS,
                                   files["Runner"]: ("mass_matrix", "generalized_forces"),
                                   files["WheelTypo"]: ("mass_matrix",)}


@pytest.mark.parametrize("spec, label", [("pinocchio", "pinocchio"),
                                         ("/some/where/my_engine.py:MyEngine", "MyEngine"),
                                         ("my_package.engines:Other", "Other")])
def test_label_of_is_the_name_or_the_class(spec, label):
    """An engine's column name: its registered name, or the class of a spec (module docstring).
    Planted: the spec returned as it is."""
    assert st.label_of(spec) == label


def test_run_options_reference_first_then_simulating_engines_of_the_contact(params, files):
    """The reference first although given last; then, in the spec's order, each engine that
    models the contact and has a setup running forward scenarios without a declared model
    difference: its first such setup (TwoSetups' second), under its label. Not: a thesis-only
    engine on the disc contact, a soft contact, an engine that cannot simulate. On the thesis
    contact the thesis-only engine is in and the disc-only one out.
    Planted: the reference not put first; the contact test inverted; `simulating` negated;
    the first setup taken instead of the first simulating one; keyed by the setup label."""
    order = ("TwoSetups", "ThesisOnly", "Soft", "WheelTypo", "DiscOnly")
    engines = tuple(files[n] for n in order) + ("reference",)
    disc = make_spec(params, varies=["m3=85:95:2"], engines=engines, checks=("terms",))
    got = st.run_options(disc)
    assert list(got) == ["reference", "TwoSetups", "DiscOnly"]
    assert got["reference"].engine == "reference" and "forward" in got["reference"].kinds
    two = got["TwoSetups"]
    assert (two.label, two.engine, two.kinds, two.options) == (
        "TwoSetups-forward", files["TwoSetups"], ("forward",), (("step", 0.01),))
    assert got["DiscOnly"].engine == files["DiscOnly"]
    thesis = make_spec(load_model("thesis").params, varies=["m3=85:95:2"], engines=engines,
                       checks=("terms",))
    assert list(st.run_options(thesis)) == ["reference", "TwoSetups", "ThesisOnly"]


# -- the empty and the failed row ----------------------------------------------------------------

def test_empty_row_has_every_column_at_not_computed(full):
    """Every column, in order; text columns "", the two verdicts None, numbers NaN; the
    bicycle's index and its states' seed SeedSequence([seed, k, 1]).
    Planted: 'run.' columns NaN; runs_confirmed NaN; seed from SeedSequence([seed, k]); the
    seed of k + 1."""
    row = st.empty_row(full, 3)
    assert list(row) == st.columns(full)
    assert row["bicycle"] == 3
    assert row["seed"] == _seed(11, 3) and isinstance(row["seed"], int)
    assert row["seed"] != _seed(11, 2) and row["seed"] != _seed(0, 3)
    for c, v in row.items():
        if c in ("bicycle", "seed"):
            continue
        if c.startswith(("entry.", "run.")) or c in ("status", "failures", "localization"):
            assert v == "", c
        elif c in ("terms_passed", "runs_confirmed"):
            assert v is None, c
        else:
            assert _nan(v), c


def test_failed_row_of_a_grid_keeps_its_point(full):
    """A lost task's row: failed, the message, NaN seconds, the grid's values (first grid
    slowest: bicycle 2 is m3 95, trail 0.08), nothing computed.
    Planted: the grid point of bicycle k - 1; status 'disagree'."""
    row = st.failed_row(full, 2, "task lost when run alone: RuntimeError: worker died")
    assert list(row) == st.columns(full)
    assert (row["status"], row["failures"]) == (
        "failed", "task lost when run alone: RuntimeError: worker died")
    assert (row["vary.m3"], row["vary.trail"]) == (95.0, 0.08)
    assert (row["bicycle"], row["seed"]) == (2, _seed(11, 2))
    assert all(_nan(row[c]) for c in ("task_seconds", "p.m3", "trail", "max_error", "weave_speed"))
    assert row["terms_passed"] is None and row["localization"] == ""


def test_failed_row_of_a_sample_leaves_vary_empty(params):
    """A sample has no grid: its vary values stay NaN (the bicycle was never built).
    Planted: `if spec.grids` dropped (grid_point of a sample raises)."""
    spec = make_spec(params, sample=4, spread=10.0, seed=3, checks=("eigen",))
    row = st.failed_row(spec, 1, "lost")
    assert (row["status"], row["failures"], row["bicycle"]) == ("failed", "lost", 1)
    assert all(_nan(row[f"vary.{n}"]) for n in spec.varied)


# -- real rows -----------------------------------------------------------------------------------

def test_table1_bicycle_agrees_with_the_published_speeds(real_rows):
    """Bicycle 0 is Table 1's (rider 85 kg, trail 0.08 m): Table 2's weave and capsize speeds to
    1e-9 m/s, the derived trail 0.08 m, head angle pi/2 - pi/10, wheelbase 1.02 m, the model's
    parameters (rear radius 0.3, front 0.35 m), Pinocchio's terms to round-off, status agree.
    Planted: weave and capsize swapped in the row; the derived values not written; max_error
    the last error instead of the largest; `if not c.passed` negated; a dropped `not` on the
    terms' verdict; the entry's state one off; task_seconds the clock's reading."""
    spec, (row, _) = real_rows
    assert (row["bicycle"], row["seed"]) == (0, _seed(0, 0))
    assert (row["status"], row["failures"], row["localization"]) == ("agree", "", "")
    assert abs(row["weave_speed"] - WEAVE) < 1e-9 and abs(row["capsize_speed"] - CAPSIZE) < 1e-9
    assert (row["vary.m3"], row["vary.trail"]) == (85.0, 0.08)
    assert abs(row["trail"] - 0.08) < 1e-12 and abs(row["wheelbase"] - 1.02) < 1e-12
    assert abs(row["head_angle"] - (math.pi / 2 - math.pi / 10)) < 1e-12
    assert (row["p.m3"], row["p.R_rear"], row["p.R_front"], row["p.g"]) == (85.0, 0.3, 0.35, 9.81)
    errs = [row[f"err.pinocchio.{q}"] for q in TERMS]
    assert all(0.0 <= e < 1e-10 for e in errs) and row["max_error"] == max(errs)
    assert row["terms_passed"] is True
    for q in TERMS:
        entry = row[f"entry.pinocchio.{q}"]
        assert "[" in entry and entry.endswith(("@ state 0", "@ state 1")), entry
    assert row["err.Broken.mass_matrix"] == 0.0          # Broken raises above 90 kg only
    assert 0.0 < row["task_seconds"] < 60.0


def test_an_engine_raising_on_one_bicycle_is_that_rows_failure(real_rows):
    """Bicycle 2 (rider 95 kg): Broken's M raises, 'Class quantity: Type: message'; the other
    checks still ran (Pinocchio's terms, the speeds), terms_passed False, status failed.
    Planted: the quantity dropped from the message; the model not given the bicycle's
    parameters (Broken would not raise); terms_passed ignoring failures; p.* from the base
    model; messages cut at 50 characters."""
    spec, (_, row) = real_rows
    assert (row["bicycle"], row["vary.m3"], row["vary.trail"], row["p.m3"]) == (2, 95.0, 0.08, 95.0)
    assert row["status"] == "failed"
    assert row["failures"] == ("Broken mass_matrix: ModelEvaluationError: singular mass matrix "
                               "for this bicycle")
    assert row["terms_passed"] is False
    assert row["err.pinocchio.mass_matrix"] < 1e-12
    assert math.isfinite(row["weave_speed"]) and abs(row["weave_speed"] - WEAVE) > 1e-3
    assert _nan(row["err.Broken.mass_matrix"]) and row["localization"] == ""


@pytest.fixture(scope="module")
def typo_row(params, files):
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=3, seed=5,
                     engines=("reference", files["WheelTypo"], files["WheelTypo2"]))
    return spec, st.bicycle_row(spec, 0)


def test_a_planted_inertia_typo_disagrees_and_is_localized(params, typo_row):
    """I5yy := I5xx changes M most at M[eps, eps], by I5yy - I5xx = 0.1395 kg m^2 at every
    state, judged against max|M| = the total mass 94 kg: err 1.484e-3, every state alike, so
    state 0 (the first worst) is named. Status
    disagree with no failure; each failing engine listed 'E q err at entry' joined by '; ', then
    diagnose's best explanation naming I5yy; the reference itself agrees to 0.
    Planted: localization only for the last engine; the explanation's prefix changed; the
    passing engines given to localize instead of the failing ones; the error with two digits;
    localize without the spec's tolerances; the missing-explanation test inverted."""
    spec, row = typo_row
    p = params
    err = (p.I5yy - p.I5xx) / (p.m2 + p.m3 + p.m4 + p.m5)
    assert abs(err - 0.1395 / 94.0) < 1e-15
    assert (row["status"], row["failures"], row["terms_passed"]) == ("disagree", "", False)
    for e in ("WheelTypo", "WheelTypo2"):
        assert row[f"err.{e}.mass_matrix"] == pytest.approx(err, rel=1e-9)
        assert row[f"entry.{e}.mass_matrix"] == "M[eps, eps] @ state 0"
    assert row["max_error"] == pytest.approx(err, rel=1e-9)
    assert row["err.reference.mass_matrix"] == 0.0
    head = ("WheelTypo mass_matrix 1.5e-03 at M[eps, eps]; "
            "WheelTypo2 mass_matrix 1.5e-03 at M[eps, eps]; best explanation: ")
    loc = row["localization"]
    assert loc.startswith(head), loc
    assert "I5yy" in loc[len(head):].split(";")[0], loc


def test_the_terms_are_compared_at_the_bicycles_states(params, files):
    """The states are judgments.terms.random_states(n_states, seed = the row's seed): ThetaSkew
    is worst at the state of largest |theta|, err 1e-3 max|theta| / 94 kg.
    Planted: the states seeded by the bicycle's index; the state named one off."""
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=4, seed=9,
                     engines=(files["ThetaSkew"],))
    row = st.bicycle_row(spec, 0)
    theta = np.abs(random_states(4, seed=_seed(9, 0)).q[:, 3])
    assert row["status"] == "disagree"
    assert row["err.ThetaSkew.mass_matrix"] == pytest.approx(1e-3 * theta.max() / 94.0, rel=1e-9)
    assert row["entry.ThetaSkew.mass_matrix"] == f"M[xc, xc] @ state {int(theta.argmax())}"


def test_the_specs_tolerances_judge_the_terms(params, files):
    """The tolerances travel in the spec: a mass-matrix tolerance of 0.5 accepts the typo
    (1.5e-3), so the same bicycle agrees.
    Planted: the packaged tolerances loaded instead of the spec's."""
    import dataclasses
    base = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=2,
                     engines=(files["WheelTypo"],))
    loose = Tolerances(tuple(dataclasses.replace(t, tolerance=0.5) if t.quantity == "mass_matrix"
                             else t for t in base.tolerances.entries))
    spec = dataclasses.replace(base, tolerances=loose)
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["terms_passed"], row["localization"]) == ("agree", True, "")
    assert row["err.WheelTypo.mass_matrix"] == pytest.approx(0.1395 / 94.0, rel=1e-9)


def test_an_engine_that_does_not_load_fails_the_terms(params, files):
    """NoLoad's constructor raises for the 95 kg rider: 'NoLoad: EngineLoadError: ...' ending in its
    message, terms_passed False although no compared term failed, status failed;
    the 85 kg rider agrees; the engine after it is still compared.
    Planted: terms_passed = passed (load failures ignored); the failure naming the engine's
    spec instead of its class; `break` for `continue` after the load failure."""
    spec = make_spec(params, varies=["m3=85:95:2"], checks=("terms",), n_states=1,
                     engines=(files["NoLoad"], "reference"))
    light, heavy = st.bicycle_row(spec, 0), st.bicycle_row(spec, 1)
    assert (light["status"], light["terms_passed"], light["failures"]) == ("agree", True, "")
    assert light["err.NoLoad.mass_matrix"] == 0.0
    assert heavy["status"] == "failed" and heavy["terms_passed"] is False
    assert heavy["failures"].startswith("NoLoad: EngineLoadError: "), heavy["failures"]
    assert heavy["failures"].endswith("RuntimeError: no rider that heavy"), heavy["failures"]
    assert _nan(heavy["err.NoLoad.mass_matrix"]) and heavy["err.reference.mass_matrix"] == 0.0
    assert heavy["localization"] == "" and heavy["max_error"] == 0.0


def test_a_quantity_that_raises_is_skipped_alone(params, files):
    """Flaky's M raises: 'Flaky mass_matrix: Type: message' on one line, its M columns stay
    empty, its inverse dynamics are still compared (and agree), status failed.
    Planted: `break` for `continue` after a quantity's failure."""
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=1,
                     engines=(files["Flaky"],))
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["terms_passed"]) == ("failed", False)
    assert row["failures"] == "Flaky mass_matrix: RuntimeError: M not assembled"
    assert _nan(row["err.Flaky.mass_matrix"]) and row["entry.Flaky.mass_matrix"] == ""
    assert row["err.Flaky.inverse_dynamics"] == 0.0 and row["max_error"] == 0.0


def test_terms_passed_counts_only_the_terms_own_failures(params):
    """_terms called after an earlier check failed: that failure is not the terms' (their
    verdict stays True), and the list is kept.
    Planted: failures counted from 0 instead of from the list's length on entry."""
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=1,
                     engines=("reference",))
    row = st.empty_row(spec, 0)
    failures = ["eigen: ValueError: earlier"]
    model = st._template("disc").with_params(params)
    assert st._terms(spec, model, row, failures) is True
    assert row["terms_passed"] is True and failures == ["eigen: ValueError: earlier"]
    assert row["max_error"] == 0.0 and row["localization"] == ""


def test_an_instance_that_narrows_its_capabilities_is_compared_on_what_it_has(params, files):
    """Narrow declares M and Qgrav, its instance computes M only: gravity is not compared (NaN,
    ""), not a failure.
    Planted: the `engine.supports(q)` filter dropped."""
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=1,
                     engines=(files["Narrow"],))
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["failures"], row["terms_passed"]) == ("agree", "", True)
    assert row["err.Narrow.mass_matrix"] == 0.0
    assert _nan(row["err.Narrow.gravity"]) and row["entry.Narrow.gravity"] == ""


def test_a_sampled_bicycle_reports_its_sampled_values(params):
    """A sample's vary.<name> are the bicycle's sampled values (every varied name), p.* all 30,
    the derived three of its Table 1 counterpart; the states' seed is the spec seed's.
    Planted: vary values from the base; derived values not written; p.* from the base."""
    spec = make_spec(params, sample=3, spread=10.0, seed=5, checks=("terms",), n_states=1,
                     engines=("reference",))
    row = st.bicycle_row(spec, 2)
    p = sample_parameters(spec, 2)
    assert (row["bicycle"], row["seed"], row["status"]) == (2, _seed(5, 2), "agree")
    for n in spec.varied:
        assert row[f"vary.{n}"] == getattr(p, n), n
    assert row["vary.m3"] != 85.0
    for n in PARAMETER_NAMES:
        assert row[f"p.{n}"] == getattr(p, n), n
    for n, v in derived_values(p).items():
        assert math.isfinite(v) and row[n] == v, n


# -- invalid, eigen, status (patched pieces) ------------------------------------------------------

def _clock(monkeypatch, *times):
    """st.time.perf_counter returning ``times`` in turn."""
    ticks = iter(times)
    monkeypatch.setattr(st, "time", SimpleNamespace(perf_counter=lambda: next(ticks)))


@pytest.mark.parametrize("grid", [True, False])
def test_an_invalid_bicycle_is_a_row_saying_why(params, monkeypatch, grid):
    """Parameters that are not a bicycle: status invalid, 'parameters: <the error>', the time
    taken, the grid's values (a sample's stay NaN), nothing computed (no model built).
    Planted: status 'failed'; the 'parameters: ' prefix dropped; task_seconds t0 - now; the
    grid test inverted."""
    spec = (make_spec(params, varies=GRID, checks=("eigen",)) if grid else
            make_spec(params, sample=4, spread=10.0, checks=("eigen",)))
    exc = ParameterError("<memory>", "inertia.I3xx", "not positive definite", "narrow the spread")

    def invalid(s, k):
        raise exc
    monkeypatch.setattr(st, "bicycle_parameters", invalid)
    monkeypatch.setattr(st, "_template", lambda contact: pytest.fail("a model was built"))
    _clock(monkeypatch, 10.0, 12.5)
    row = st.bicycle_row(spec, 3)
    assert (row["status"], row["bicycle"]) == ("invalid", 3)
    assert row["failures"] == ("parameters: <memory>: inertia.I3xx: not positive definite; "
                               "fix: narrow the spread")
    assert row["task_seconds"] == 2.5
    assert _nan(row["weave_speed"]) and _nan(row["p.m3"]) and _nan(row["trail"])
    if grid:
        assert (row["vary.m3"], row["vary.trail"]) == (95.0, 0.12)
    else:
        assert all(_nan(row[f"vary.{n}"]) for n in spec.varied)


def test_an_eigen_failure_is_a_failed_row_on_one_line(params, monkeypatch):
    """critical_speeds raising: 'eigen: Type: message' (whitespace collapsed), NaN speeds, status
    failed, and with the runs asked no run. Planted: the message not made one line; split on
    ' ' only (newlines kept); the critical speeds None before the eigen check (the runs then
    raise out of the row)."""
    def broken(model, speeds):
        raise ValueError("no\n   root   found")
    monkeypatch.setattr(eigenvalues, "critical_speeds", broken)
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("eigen",))
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["failures"]) == ("failed", "eigen: ValueError: no root found")
    assert _nan(row["weave_speed"]) and _nan(row["capsize_speed"])
    # with the runs asked too: no critical speed known, so no run and no verdict (still a row)
    monkeypatch.setattr(st, "run_options", lambda s: {})
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("eigen", "runs"))
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["failures"]) == ("failed", "eigen: ValueError: no root found")
    assert row["runs_confirmed"] is None


def test_eigen_asks_the_speed_range_and_passes_the_found_speeds_to_the_runs(params, monkeypatch):
    """critical_speeds on the bicycle's model over stability.SPEED_RANGE; a speed not found is
    NaN and not run; the speeds found go to the runs by mode; the runs' verdict makes the
    status; task_seconds is the clock's difference.
    Planted: weave and capsize swapped in the dict; a None speed kept; the runs check negated;
    the template's parameters; task_seconds the clock's reading."""
    calls, given = [], []

    def speeds(model, v):
        calls.append((model.params.m3, np.asarray(v).tolist()))
        return None, 6.5

    def runs(spec, model, crit, row, failures):
        given.append((model.params.m3, dict(crit)))
        return True
    monkeypatch.setattr(eigenvalues, "critical_speeds", speeds)
    monkeypatch.setattr(st, "_runs", runs)
    monkeypatch.setattr(st, "run_options", lambda spec: {})
    spec = make_spec(params, varies=["m3=80:90:2"], checks=("eigen", "runs"))
    _clock(monkeypatch, 3.0, 3.25)
    row = st.bicycle_row(spec, 1)
    assert calls == [(90.0, [0.0, 10.0])]
    assert given == [(90.0, {"capsize": 6.5})]
    assert _nan(row["weave_speed"]) and row["capsize_speed"] == 6.5
    assert (row["status"], row["failures"], row["task_seconds"]) == ("agree", "", 0.25)


@pytest.mark.parametrize("terms_ok, runs_ok, status", [(False, True, "disagree"),
                                                       (True, False, "disagree"),
                                                       (True, True, "agree")])
def test_status_disagrees_when_the_terms_or_the_runs_do(params, monkeypatch, terms_ok, runs_ok,
                                                        status):
    """'disagree' when either the terms or the runs contradict, 'agree' when both hold (module
    docstring). Planted: `disagree = not _runs(...)` (the terms' verdict overwritten);
    `disagree |= _terms(...)` (a dropped `not`)."""
    monkeypatch.setattr(eigenvalues, "critical_speeds", lambda model, v: (4.0, 6.0))
    monkeypatch.setattr(st, "_terms", lambda *a: terms_ok)
    monkeypatch.setattr(st, "_runs", lambda *a: runs_ok)
    monkeypatch.setattr(st, "run_options", lambda spec: {})
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms", "eigen", "runs"),
                     engines=("reference",))
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["failures"]) == (status, "")


def test_failures_outrank_disagreement_and_are_joined(params, monkeypatch):
    """A failure makes the row 'failed' even when the terms disagree; the failures of every
    check are joined by ' | ' in order; the terms and the runs get the row and the same list.
    Planted: joined by '; '; 'disagree' before 'failed'; the runs check negated; weave and
    capsize swapped."""
    seen = []

    def terms(spec, model, row, failures):
        seen.append(("terms", row["bicycle"]))
        failures.append("A mass_matrix: boom")
        return False

    def runs(spec, model, crit, row, failures):
        seen.append(("runs", crit))
        failures.append("reference run weave 0.9x: RuntimeError: bang")
        return True
    monkeypatch.setattr(eigenvalues, "critical_speeds", lambda model, v: (4.0, 6.0))
    monkeypatch.setattr(st, "_terms", terms)
    monkeypatch.setattr(st, "_runs", runs)
    monkeypatch.setattr(st, "run_options", lambda spec: {})
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms", "eigen", "runs"),
                     engines=("reference",))
    row = st.bicycle_row(spec, 0)
    assert seen == [("terms", 0), ("runs", {"weave": 4.0, "capsize": 6.0})]
    assert row["status"] == "failed"
    assert row["failures"] == "A mass_matrix: boom | reference run weave 0.9x: RuntimeError: bang"
    assert (row["weave_speed"], row["capsize_speed"]) == (4.0, 6.0)


def test_unasked_checks_do_not_run(params, monkeypatch):
    """Eigen alone: neither the terms nor the runs are called.
    Planted: `if "runs" in spec.checks` negated; the terms run for every spec."""
    monkeypatch.setattr(eigenvalues, "critical_speeds", lambda model, v: (4.0, 6.0))
    monkeypatch.setattr(st, "_terms", lambda *a: pytest.fail("terms not asked"))
    monkeypatch.setattr(st, "_runs", lambda *a: pytest.fail("runs not asked"))
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("eigen",))
    row = st.bicycle_row(spec, 0)
    assert (row["status"], row["weave_speed"]) == ("agree", 4.0)


# -- text helpers ---------------------------------------------------------------------------------

def test_one_line_collapses_whitespace_and_caps_at_500():
    """'Type: message' with every run of whitespace one space, at most 500 characters.
    Planted: the cap 50; the message split on ' ' only (newlines kept)."""
    assert st._one_line(ValueError("a\n  b\t\tc ")) == "ValueError: a b c"
    long = st._one_line(RuntimeError("x" * 600))
    assert len(long) == 500 and long == ("RuntimeError: " + "x" * 600)[:500]


def test_explanation_texts(monkeypatch):
    """localize's best explanation as '; best explanation: <describe()>', '' without one,
    '; localization failed: Type: message' when it raises; localize gets the model, states,
    the failing engines and the tolerances.
    Planted: the prefix changed; the missing-explanation test inverted; the tolerances not
    passed; localize's failure not made one line."""
    got = []

    def with_text(model, states, engines, tolerances):
        got.append((model, states, engines, tolerances))
        return SimpleNamespace(explanation=SimpleNamespace(describe=lambda: "I5yy (front wheel)"))
    monkeypatch.setattr(diagnose, "localize", with_text)
    assert st._explanation("M", "S", ["E"], "T") == "; best explanation: I5yy (front wheel)"
    assert got == [("M", "S", ["E"], "T")]
    monkeypatch.setattr(diagnose, "localize", lambda *a, **k: SimpleNamespace(explanation=None))
    assert st._explanation("M", "S", ["E"], "T") == ""

    def fails(*a, **k):
        raise RuntimeError("singular\n   fit")
    monkeypatch.setattr(diagnose, "localize", fails)
    assert (st._explanation("M", "S", ["E"], "T")
            == "; localization failed: RuntimeError: singular fit")


# -- the forward runs (fake setups) ---------------------------------------------------------------

class FakeSetup:
    """A setup whose engine's simulate returns (label, scenario), raising at ``fail_at`` speeds."""

    def __init__(self, label, fail_at=(), log=None):
        self.label, self.fail_at, self.log = label, fail_at, log if log is not None else []

    def build(self, model):
        self.log.append(("build", self.label, model.params.m3))
        return SimpleNamespace(simulate=self.simulate)

    def simulate(self, scenario):
        speed = scenario.dq_ind0[1] * 0.3          # the benchmark's rear radius
        if any(abs(speed - s) < 1e-12 for s in self.fail_at):
            raise RuntimeError("diverged\n  at  t = 1 s")
        return (self.label, scenario)


@pytest.fixture
def fake_runs(monkeypatch):
    """Two fake setups (the reference and 'Fake') and a judgment that contradicts the weave run
    at 0.9 x on the reference only; records every judgment."""
    judged, judged_models = [], []

    def judge(model, mode, speed, traj):
        label, scenario = traj
        judged.append((mode, speed, label, scenario))
        judged_models.append(model)
        planted = mode == "weave" and label == "reference" and abs(speed - 3.6) < 1e-12
        return {"passed": not planted}
    monkeypatch.setattr(stability, "judge_run", judge)
    judge.models = judged_models
    _FAKE_JUDGE.append(judge)
    return judged


_FAKE_JUDGE: list = []     # the fake judgment of the current test (its models judged)


def _model():
    return st._template("disc")


def test_runs_give_a_verdict_per_mode_factor_and_engine(fake_runs, monkeypatch):
    """Weave 4 and capsize 6 m/s: runs at 3.6, 4.4, 5.4, 6.6 m/s on the reference and Fake, in
    that order, each on stability's scenario at that speed; the contradicted run makes the
    runs fail; a failed run is 'failed: Type: message' and 'E run mode 0.9x: ...' in the
    failures, not a contradiction, and the next engine still runs at that speed.
    Planted: `ok &= passed` as `ok = passed` and as `ok |= passed`; the column's factor and
    mode swapped; the scenario at speed / factor; judged at factor x speed; the failures' 'x'
    dropped; the verdict words swapped; the scenario's R_front; built on the template; `break`
    for `continue` after a failed run; run_options(None); judge_run given no model."""
    setups = {"reference": FakeSetup("reference", fail_at=(5.4,)), "Fake": FakeSetup("Fake")}
    monkeypatch.setattr(st, "run_options", lambda spec: {"spec": setups}[spec])
    row, failures = {}, []
    model = _model()
    ok = st._runs("spec", model, {"weave": 4.0, "capsize": 6.0}, row, failures)
    # the runs' engines come from the spec's run options, each run judged on this model
    assert _FAKE_JUDGE[-1].models and all(m is model for m in _FAKE_JUDGE[-1].models)
    assert ok is False and row["runs_confirmed"] is False
    assert row == {"run.weave.0.9.reference": "contradicted", "run.weave.0.9.Fake": "confirmed",
                   "run.weave.1.1.reference": "confirmed", "run.weave.1.1.Fake": "confirmed",
                   "run.capsize.0.9.reference": "failed: RuntimeError: diverged at t = 1 s",
                   "run.capsize.0.9.Fake": "confirmed",
                   "run.capsize.1.1.reference": "confirmed", "run.capsize.1.1.Fake": "confirmed",
                   "runs_confirmed": False}
    assert failures == ["reference run capsize 0.9x: RuntimeError: diverged at t = 1 s"]
    assert [(m, round(s, 12), e) for m, s, e, _ in fake_runs] == [
        ("weave", 3.6, "reference"), ("weave", 3.6, "Fake"), ("weave", 4.4, "reference"),
        ("weave", 4.4, "Fake"), ("capsize", 5.4, "Fake"), ("capsize", 6.6, "reference"),
        ("capsize", 6.6, "Fake")]
    for mode, speed, _, scenario in fake_runs:
        assert scenario == stability.scenario("benchmark", speed)


def test_runs_confirmed_when_nothing_contradicts(fake_runs, monkeypatch):
    """Only confirmed runs and a failed one: True (a failure is not a contradiction: the status
    says failed through the failures). Planted: the verdict words swapped; the run's failure
    not made one line; the failures' 'x' dropped."""
    setups = {"Fake": FakeSetup("Fake", fail_at=(4.4,))}
    monkeypatch.setattr(st, "run_options", lambda spec: setups)
    row, failures = {}, []
    assert st._runs("spec", _model(), {"weave": 4.0}, row, failures) is True
    assert row == {"run.weave.0.9.Fake": "confirmed",
                   "run.weave.1.1.Fake": "failed: RuntimeError: diverged at t = 1 s",
                   "runs_confirmed": True}
    assert failures == ["Fake run weave 1.1x: RuntimeError: diverged at t = 1 s"]


def test_no_critical_speed_no_run_and_no_verdict(fake_runs, monkeypatch):
    """No critical speed in the range: nothing built, runs_confirmed None, the runs hold.
    Planted: runs_confirmed = ok whatever the speeds."""
    log = []
    setups = {"reference": FakeSetup("reference", log=log)}
    monkeypatch.setattr(st, "run_options", lambda spec: setups)
    row = {}
    assert st._runs("spec", _model(), {}, row, []) is True
    assert row == {"runs_confirmed": None} and log == [] and fake_runs == []


def test_run_columns_use_the_factor_as_g_and_match_columns(params, fake_runs, monkeypatch):
    """With factors 1 and 2 the columns read run.<mode>.1.<engine> (format g, as `columns`
    writes them) and every column a run writes is one of the row's; the setups build the
    bicycle's model.
    Planted: the factor formatted with str() in _runs (1.0); runs built on the template's model;
    _runs given None for the spec; a capsize speed not found kept as None."""
    log = []
    setups = {"reference": FakeSetup("reference", log=log)}
    spec = make_spec(params, varies=["m3=80:80:1"], checks=("eigen", "runs"))
    monkeypatch.setattr(stability, "FACTORS", (1.0, 2.0))
    monkeypatch.setattr(st, "run_options", lambda s: setups if s is spec else pytest.fail(
        f"run_options given {s!r}, not the spec"))
    monkeypatch.setattr(eigenvalues, "critical_speeds", lambda model, v: (4.0, None))
    row = st.bicycle_row(spec, 0)
    # no capsize speed in the range: NaN (the documented 'NaN where none'), not None
    assert row["weave_speed"] == 4.0 and _nan(row["capsize_speed"])
    assert list(row) == st.columns(spec)
    assert row["run.weave.1.reference"] == row["run.weave.2.reference"] == "confirmed"
    assert row["runs_confirmed"] is True and row["status"] == "agree"
    assert log == [("build", "reference", 80.0)] * 2


def test_the_runs_scenario_is_stabilitys(params):
    """The in-memory model's scenario equals stages.stability.scenario for the named model; for
    another rear radius the initial rear-wheel rate is speed / R_rear (R_rear psi_dot = v).
    Planted: R_front instead of R_rear; the roll-rate kick dropped; constraints 'baumgarte'."""
    model = _model()
    assert st._scenario(model, 4.6) == stability.scenario("benchmark", 4.6)
    other = model.with_params(params.replace(R_rear=0.4))
    s = st._scenario(other, 5.0)
    assert (s.name, s.kind, s.model, s.grid) == ("stability-v5.0000", "forward", "benchmark",
                                                 (0.0, 0.01, 501))
    assert s.dq_ind0 == (0.05, 12.5, 0.0) and s.q0 == (0,) * 8 and s.torques == (0.0, 0.0, 0.0)
    assert (s.constraints, s.tags) == ("projection", ("model-stability",))


# -- the chunk and the per-process cache ----------------------------------------------------------

def test_chunk_rows_maps_bicycle_row_in_the_given_order(monkeypatch):
    """One row per index, in the chunk's order, each of the same spec.
    Planted: the indices sorted."""
    monkeypatch.setattr(st, "bicycle_row", lambda spec, k: {"spec": spec, "k": k})
    assert st.chunk_rows("S", (3, 1, 2)) == [{"spec": "S", "k": 3}, {"spec": "S", "k": 1},
                                             {"spec": "S", "k": 2}]


def test_template_loads_one_model_per_contact(monkeypatch):
    """The disc contact's template is the benchmark, the thesis contact's the thesis model,
    each loaded once per process. Planted: the two names swapped; no caching."""
    import reference_model
    loaded = []

    def load(name):
        loaded.append(name)
        return f"model {name}"
    monkeypatch.setattr(st, "_TEMPLATES", {})
    monkeypatch.setattr(reference_model, "load_model", load)
    assert st._template("disc") == "model benchmark"
    assert st._template("disc") == "model benchmark"
    assert st._template("thesis") == "model thesis"
    assert st._template("thesis") == "model thesis"
    assert loaded == ["benchmark", "thesis"]


def test_localize_is_given_the_failing_engines_only(params, files, monkeypatch):
    """The localization explains the disagreeing engines (module docstring: 'for a bicycle that
    disagrees: the failing entries and diagnose's best explanation'): of the reference (exact)
    and the I5yy typo, localize gets the typo's engine alone, on the bicycle's model.
    Planted: every engine counted as failing (ok_engine False from the start)."""
    given = []

    def localize(model, states, engines, tolerances=None):
        given.append([type(e).__name__ for e in engines])
        return SimpleNamespace(explanation=None)
    monkeypatch.setattr(diagnose, "localize", localize)
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("terms",), n_states=2,
                     engines=("reference", files["WheelTypo"]))
    row = st.bicycle_row(spec, 0)
    assert row["status"] == "disagree"
    assert given == [["WheelTypo"]]


def test_the_bicycles_model_is_built_on_its_contacts_template(params, monkeypatch):
    """bicycle_row asks `_template` for the spec's contact ('disc' for the benchmark).
    Planted: _template(None)."""
    asked = []
    real = st._template

    def template(contact):
        asked.append(contact)
        return real(contact)
    monkeypatch.setattr(st, "_template", template)
    monkeypatch.setattr(eigenvalues, "critical_speeds", lambda model, v: (4.0, 6.0))
    spec = make_spec(params, varies=["m3=85:85:1"], checks=("eigen",))
    st.bicycle_row(spec, 0)
    assert asked == [spec.contact] == ["disc"]
