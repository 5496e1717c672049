"""The benchmark bicycle (Meijaard et al. 2007) in the engines and in nonlinear runs.

Every expected value comes from outside the code under test:

* the published linearized benchmark (Meijaard, Papadopoulos, Ruina, Schwab, Proc. R. Soc. A
  463 (2007), Table 2 and Appendix): the roll/steer mass matrix, the eigenvalues at 4 and 8 m/s,
  the weave speed 4.29238253634111 m/s and the capsize speed 6.02426201538837 m/s, typed here
  from the paper (not imported from the code);
* physics: below the weave speed the weave grows, between the two speeds it decays, above the
  capsize speed the bicycle leans over slowly; energy is conserved by the exact motion;
* the IFToMM benchmark's acceptance of the energy drift, 100 (Emax - Emin)/E0 < 1e-3 %.

The manoeuvres are the IFToMM "uncontrolled bicycle" (scenarios benchmark-v4, -v4.6, -v8).
"""

import numpy as np
import pytest

from comparisons.judgments.benchmark import (capsize_measure, identify_eigenvalues,
                                             judge_outcome, roll_rate_envelope, upright_state,
                                             with_roll_rate)
from comparisons.judgments.convergence import reference_run
from comparisons.judgments.energy import energy_drift
from comparisons.judgments.terms import States, compare_term, random_states
from comparisons.judgments.tolerances import load_tolerances
from comparisons.stages.benchmark import MANOEUVRES, fixed_step_runs, run_manoeuvres
from engines import load_engine
from reference_model import load_model
from reference_model.model import DEP, IND
from reference_model.scenarios import SCENARIOS


# -- published (Meijaard et al. 2007) --------------------------------------------------------
WEAVE_SPEED = 4.29238253634111       # m/s
CAPSIZE_SPEED = 6.02426201538837     # m/s
M_BENCHMARK = np.array([[80.81722, 2.31941332208709],            # [phi, delta], kg m^2
                        [2.31941332208709, 0.29784188199686]])
TABLE2 = {  # v: (weave, capsize), 1/s
    4.0: (0.41325331521125 + 3.07910818603206j, -1.42944427361326),
    8.0: (-2.69348683581097 + 8.46037971396931j, 0.14327879765713),
}
IFTOMM_DRIFT_PERCENT = 1e-3          # IFToMM acceptance (Exudyn's bicycleIftommBenchmark.py)
ENGINES = ("reference", "exudyn-tree", "exudyn-redundant")


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


@pytest.fixture(scope="module")
def runs(bench):
    """The three manoeuvres on the reference and both Exudyn builds at h = 1e-3 (~6 s)."""
    from engines.facts import engine_facts
    return {mr.scenario.name: mr for mr in run_manoeuvres(
        MANOEUVRES, fixed_step_runs(engine_facts("exudyn")), twins=False)}


def _trajectory(mr, engine):
    return mr.reference if engine == "reference" else mr.engines[engine]


# -- the scenarios -----------------------------------------------------------------------------

def test_manoeuvres_are_the_iftomm_ones(bench):
    # 4, 4.6, 8 m/s with roll rates 0.05, 0.5, 0.05 rad/s, upright, no torques, 5 s sampled
    # every 0.01 s; forward speed v = R_rear psi_dot with the model's own rear radius
    for name, v, roll_rate in (("benchmark-v4", 4.0, 0.05), ("benchmark-v4.6", 4.6, 0.5),
                               ("benchmark-v8", 8.0, 0.05)):
        sc = SCENARIOS[name]
        assert sc.model == "benchmark" and "benchmark" in sc.tags and sc.kind == "forward"
        assert sc.grid == (0.0, 0.01, 501) and sc.duration == pytest.approx(5.0)
        assert sc.torques == (0.0, 0.0, 0.0)
        assert sc.dq_ind0[0] == roll_rate and sc.dq_ind0[2] == 0.0
        assert bench.params.R_rear * sc.dq_ind0[1] == pytest.approx(v, rel=1e-15)
        assert sc.q0[3] == sc.q0[6] == 0.0                      # upright, straight steer
        assert round(0.01 / 1e-3) * 1e-3 == pytest.approx(0.01)  # Exudyn's step divides the grid


@pytest.mark.slow
def test_manoeuvres_move_forward_from_the_upright_pitch(runs):
    # the projection keeps beta = -lambda = -pi/10 (Table 1's head-angle complement), and the
    # rear wheel's positive spin drives the bike forward along +x at about v (the weave wiggles
    # the path by a few per cent at most in 5 s)
    for name, v in (("benchmark-v4", 4.0), ("benchmark-v4.6", 4.6), ("benchmark-v8", 8.0)):
        ref = runs[name].reference
        assert abs(ref.settings["beta_correction"]) < 1e-14
        assert ref.q[0, 5] == pytest.approx(-np.pi / 10, abs=1e-15)
        assert ref.dq[0, 0] == pytest.approx(v, rel=1e-12)
        assert ref.q[-1, 0] == pytest.approx(5.0 * v, rel=0.03)


# -- mass matrices -----------------------------------------------------------------------------

@pytest.mark.parametrize("engine", ["pinocchio", "exudyn"])
def test_mass_matrix_equals_reference_on_the_benchmark(bench, engine):
    # same parameters, different algebra: round-off only; tolerance from tolerances.toml
    # (1e-12 relative to max|M|, with its reason there)
    tol = load_tolerances()["mass_matrix"]
    ref = load_engine("reference", bench)
    eng = load_engine(engine, bench, **({"build": "tree"} if engine == "exudyn" else {}))
    q_up = upright_state(bench)
    upright = States(q_up[None, :], np.zeros((1, 8)), np.zeros((1, 8)), np.zeros((1, 3)))
    for states in (random_states(40, seed=3), upright):
        r = compare_term("mass_matrix", ref, eng, states, tol)
        assert r.passed, r.describe()


@pytest.mark.parametrize("engine", ["reference", "pinocchio", "exudyn"])
def test_reduced_upright_mass_matrix_is_the_published_one(bench, engine):
    # each engine's 8x8 M reduced to the independent rates at upright (dq = N dq_ind from the
    # constraints, M_r = N^T M N), roll/steer block in the benchmark's signs (delta = -gamma):
    # the published M to its 14-15 digits, i.e. round-off relative to max|M| (1e-12, as above)
    eng = load_engine(engine, bench, **({"build": "tree"} if engine == "exudyn" else {}))
    q = upright_state(bench)
    D = bench.constraint_jacobian(q)
    N = np.zeros((8, 3))
    N[IND, :] = np.eye(3)
    N[DEP, :] = -np.linalg.solve(D[:, DEP], D[:, IND])
    Mr = N.T @ eng.mass_matrix(q) @ N
    P = np.diag([1.0, -1.0])
    M = P @ Mr[np.ix_([0, 2], [0, 2])] @ P
    assert np.abs(M - M_BENCHMARK).max() <= 1e-12 * np.abs(M_BENCHMARK).max(), M
    assert np.abs(Mr[1, [0, 2]]).max() < 1e-12 * np.abs(Mr).max()   # psi decouples (symmetry)


# -- the manoeuvres: physics on every engine ---------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_weave_grows_at_4_m_s(runs, engine):
    # 4 m/s < weave speed: the roll-rate oscillation's envelope (peaks of |dtheta/dt| from 1 s,
    # castor mode gone) grows; the run completes (no fall in 5 s)
    assert 4.0 < WEAVE_SPEED
    tr = _trajectory(runs["benchmark-v4"], engine)
    env = roll_rate_envelope(tr)
    assert tr.status == "completed"
    assert env.peaks.size >= 3 and env.rate > 0, env
    assert env.peaks[-1] > 2.0 * env.peaks[0]
    assert judge_outcome("benchmark-v4", 4.0, tr, engine).passed


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_weave_decays_at_4_6_m_s(runs, engine):
    # weave speed < 4.6 m/s < capsize speed: self-stable, the envelope decays
    assert WEAVE_SPEED < 4.6 < CAPSIZE_SPEED
    tr = _trajectory(runs["benchmark-v4.6"], engine)
    env = roll_rate_envelope(tr)
    assert tr.status == "completed"
    assert env.peaks.size >= 4 and env.rate < 0, env
    assert env.peaks[-1] < 0.5 * env.peaks[0]
    assert judge_outcome("benchmark-v4.6", 4.6, tr, engine).passed


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_slow_capsize_at_8_m_s(runs, engine):
    # 8 m/s > capsize speed: the weave dies out (-2.69 /s) and the lean grows monotonically at
    # the capsize eigenvalue, 0.1433 /s published: slow (less than a factor e in 5 s), no fall.
    # Tolerance 1e-3 relative on the rate of log|theta| over 3-5 s: what is left of the weave
    # at 3 s is e^(-2.69 * 3) = 3e-4 of its start, and the O(a^2) nonlinearity at a = 6e-3 rad
    # is 4e-5
    assert 8.0 > CAPSIZE_SPEED
    tr = _trajectory(runs["benchmark-v8"], engine)
    cm = capsize_measure(tr, t_from=3.0)
    assert tr.status == "completed" and cm.monotone
    assert 0 < cm.rate * 5.0 < 1.0
    assert cm.rate == pytest.approx(TABLE2[8.0][1], rel=1e-3)
    assert 0 < abs(tr.q[-1, 3]) < 0.05
    assert judge_outcome("benchmark-v8", 8.0, tr, engine).passed


# -- nonlinear against linear --------------------------------------------------------------------

@pytest.mark.parametrize("v", [4.0, 8.0])
def test_small_roll_oscillations_have_the_published_eigenvalues(bench, v):
    # the manoeuvre with a roll rate of 1e-3 rad/s (amplitude a ~ 1e-4 to 2e-3 rad): the weave
    # (and at 8 m/s the capsize) identified from the nonlinear run (matrix pencil, theta and
    # gamma) equals Table 2 to 2 a^2 + 1e-8 relative. Why: the linearization drops terms of
    # relative size O(a^2) (cubic remainders of sin/cos of roll and steer, triple products of
    # small rates) with O(1) coefficients; 1e-8 is the fit's floor (reference rtol 1e-11
    # amplified by the pencil's conditioning ~1e3)
    sc = with_roll_rate(SCENARIOS[f"benchmark-v{v:g}"], 1e-3)
    tr = reference_run(bench, sc)
    a = np.abs(tr.q[:, [3, 6]]).max()
    lam = identify_eigenvalues(tr)
    weave = lam[np.argmax(lam.imag)]
    published_weave, published_capsize = TABLE2[v]
    tol = 2 * a**2 + 1e-8
    assert abs(weave - published_weave) / abs(published_weave) <= tol, (weave, a)
    if v > CAPSIZE_SPEED:
        real = lam[lam.imag == 0]
        capsize = real[np.argmin(np.abs(real - published_capsize))]
        assert abs(capsize - published_capsize) / abs(published_capsize) <= tol, (capsize, a)


def test_the_deviation_from_linear_is_the_nonlinearity(bench):
    # the weave's deviation from Table 2 at 4 m/s must scale as a^2 between roll rates 1e-3
    # and 1e-2 rad/s (order 2 +- 0.2): a model difference between the nonlinear equations and
    # the linearization would not vanish with the amplitude
    devs, amps = [], []
    for rate in (1e-3, 1e-2):
        tr = reference_run(bench, with_roll_rate(SCENARIOS["benchmark-v4"], rate))
        lam = identify_eigenvalues(tr)
        weave = lam[np.argmax(lam.imag)]
        devs.append(abs(weave - TABLE2[4.0][0]) / abs(TABLE2[4.0][0]))
        amps.append(np.abs(tr.q[:, [3, 6]]).max())
    order = np.log(devs[1] / devs[0]) / np.log(amps[1] / amps[0])
    assert 1.8 <= order <= 2.2, (devs, amps, order)


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["exudyn-tree", "exudyn-redundant"])
def test_exudyn_weave_at_8_m_s_is_the_published_one(runs, engine):
    # Exudyn's IFToMM run at 8 m/s (a = 6.2e-3 rad): the identified weave equals Table 2 to
    # 2 a^2 (the nonlinearity, 8e-5) + 1e-4 (the generalized-alpha scheme's relative error at
    # h = 1e-3, O((omega h)^2) = (8.46e-3)^2 = 7e-5)
    tr = _trajectory(runs["benchmark-v8"], engine)
    a = np.abs(tr.q[:, [3, 6]]).max()
    lam = identify_eigenvalues(tr)
    weave = lam[np.argmax(lam.imag)]
    assert abs(weave - TABLE2[8.0][0]) / abs(TABLE2[8.0][0]) <= 2 * a**2 + 1e-4


# -- energy ------------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("name", MANOEUVRES)
def test_energy_drift_is_bounded(bench, runs, name):
    # no torques, no drag, ideal rolling: E = T + V is conserved by the exact motion.
    # Exudyn: the IFToMM acceptance, drift < 1e-3 % of E0 over the 0.01 s output (its
    # generalized-alpha scheme at h = 1e-3 dissipates O(h^2)).
    # Reference: DOP853 at rtol 1e-11 with projection onto the constraints after every step
    # (the velocity projection in the kinetic-energy metric changes T only at second order in
    # the constraint error): the energy error is the integrator's, ~1e-11 relative per step
    # over ~1e3 steps, so < 1e-7 % (= 1e-9 relative) of E0 with margin
    mr = runs[name]
    assert energy_drift(bench, mr.reference)["drift_percent"] < 1e-7
    for build, tr in mr.engines.items():
        d = energy_drift(bench, tr)
        assert d["samples"] == 501
        assert d["drift_percent"] < IFTOMM_DRIFT_PERCENT, (build, d)


# -- the report section --------------------------------------------------------------------------

def test_benchmark_section_passes_and_draws(quick_report):
    """The benchmark section of the session's quick report (tests/conftest.py): every judged
    comparison passes, its figures are drawn, and the outcomes are the published physics."""
    out, _, summary = quick_report
    sec = [c for c in summary["comparisons"] if c.get("model") == "benchmark"]
    assert sec and all(c["passed"] is not False for c in sec), [c for c in sec if c["passed"] is False]
    keys = {"quantity", "scenario", "model", "engines", "max_error", "tolerance", "passed"}
    assert all(keys <= set(c) for c in sec)
    for fig in ("benchmark_roll.png", "benchmark_error.png", "benchmark_nonlinear.png",
                "benchmark_eigenvalues.png"):
        assert (out / "figures" / fig).stat().st_size > 0
    outcomes = {(c["scenario"], c["engines"][0]): c["expected"] for c in sec
                if c["quantity"].startswith("outcome")}
    # --quick runs Exudyn on benchmark-v4.6 only (each engine's outcome on every manoeuvre is
    # tested above on the `runs` fixture)
    assert outcomes[("benchmark-v4", "reference")] == "weave grows"
    assert outcomes[("benchmark-v4.6", "reference")] == "weave decays"
    assert outcomes[("benchmark-v4.6", "exudyn-tree")] == "weave decays"
    assert outcomes[("benchmark-v8", "reference")] == "slow capsize"
