"""The SymBRiM engine (SymBRiM's Whipple bicycle, sympy's KanesMethod) against the reference.

Two independent formulations: the thesis's Newton-Euler projection in its own coordinates
(generated C, KKT solve) and the Whipple bicycle as SymBRiM assembles it from its published
parts (WhippleBicycleMoore, KnifeEdgeWheel, NonHolonomicTire, FlatGround), in Moore's
coordinates, joined by the project's Moore mapping (`reference_model.moore`), its parameters
from BicycleParameters' own conversion (`engines.symbrim.parameters`; checked against the
project's map, `engines.kane.moore_parameters`, at the end of this file). Agreement to round-off on every disc-contact bicycle
(thesis-disc, benchmark, and the conformance suite's general bicycle, whose three distinct
wheel moments, unequal wheels and off-axis fork CoM break the symmetries a swapped key would
hide) is evidence for SymBRiM's model, for the maps and for the reference.

Tolerances as in tests/test_kane.py, for the same reasons: every term is straight-line code of
~10^3..10^4 flops on both sides (1e-12 relative to the largest entry); the constrained
accelerations go through two different linear solves (5x5 elimination and a 3x3 reduced
system against the 13x13 KKT): 1e-10 relative, the issue's figure. Trajectories: both
right-hand sides go through the reference's solvers and differ by round-off, 1e-8 (rad or m)
up to the meaningful horizon (two orders above the integrator's own error there, two below
the horizon's 1e-6).

Cost in make test: the engines from the disk cache (~0.1 s each; a cold derivation is ~40-60 s
once per machine, symbrim and sympy version), the term and acceleration checks ~1 s. The
trajectories and the second route for the mapping (SymBRiM's own body points, which needs
SymBRiM's model built, ~12 s) are `slow`.
"""

import dataclasses

import numpy as np
import pytest

from comparisons.conformance.models import conformance_model
from comparisons.judgments.convergence import error_vs_time, reference_horizon
from engines import CapabilityError, load_engine
from engines.facts import engine_facts
from engines.kane.names import MOORE_PARAMETERS
from engines.symbrim import SymbrimEngine, codegen
from reference_model import COORDINATES
from reference_model.moore import to_moore
from reference_model.scenarios import get_scenario
from reference_model.solvers import consistent_state

MODELS = ("thesis-disc", "benchmark", "general-disc")
TERM_TOL = 1e-12      # straight-line code on both sides: round-off (module docstring)
ACCEL_TOL = 1e-10     # two different linear solves (module docstring)
TRAJ_TOL = 1e-8       # two orders above the integrator's own error (module docstring)
RUNS = (("thesis-disc", "stability-psid5"), ("benchmark", "benchmark-v4"))


@pytest.fixture(scope="module")
def pairs():
    out = {}
    for name in MODELS:
        model = conformance_model(name)
        out[name] = (load_engine("reference", model), SymbrimEngine(model))
    return out


def _rel(a, b):
    """Error relative to the largest reference entry, floored at 1 (SI unit): where a term
    vanishes both sides are round-off and relative to 0 would be meaningless."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1.0))


def _consistent_states(ref, n=12, seed=0):
    """``n`` random states projected on the reference's constraints (lean, steer within
    +-1 rad; rates within +-5 /s; torques within +-20 N m)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        q = rng.uniform(-1.0, 1.0, 8)
        q[5] = 0.0          # the pitch: solved from the front contact's height
        cs = consistent_state(ref.model, q, rng.uniform(-5.0, 5.0, 8))
        out.append((cs.q, cs.dq, rng.uniform(-20.0, 20.0, 3)))
    return out


@pytest.mark.parametrize("name", MODELS)
def test_every_term_matches_the_reference(pairs, name):
    ref, eng = pairs[name]
    for q, dq, T in _consistent_states(ref):
        for term, args in (("mass_matrix", (q,)), ("generalized_forces", (q, dq, T)),
                           ("constraint_jacobian", (q,)), ("constraint_bias", (q, dq))):
            assert _rel(getattr(eng, term)(*args), getattr(ref, term)(*args)) < TERM_TOL, term


@pytest.mark.parametrize("name", MODELS)
def test_constrained_accelerations_match_the_reference(pairs, name):
    ref, eng = pairs[name]
    for q, dq, T in _consistent_states(ref, seed=1):
        assert _rel(eng.forward_acceleration(q, dq, T), ref.forward_acceleration(q, dq, T)) \
            < ACCEL_TOL


def test_a_wrong_parameter_conversion_is_caught(pairs):
    """A planted bug of the parameter conversion (the frame's xz product without its sign
    flip) moves M far beyond the tolerance on the general bicycle: the test above can fail."""
    ref, eng = pairs["general-disc"]
    bad = SymbrimEngine(eng.model)
    bad.p = bad.p.copy()
    bad.p[MOORE_PARAMETERS.index("ICxz")] *= -1
    q = _consistent_states(ref, n=1)[0][0]
    assert _rel(bad.mass_matrix(q), ref.mass_matrix(q)) > 1e3 * TERM_TOL


def test_the_wheels_third_moment_reaches_the_equations(pairs):
    """SymBRiM's wheel is axisymmetric; the engine gives it its own izz. On the general
    bicycle (I2zz != I2xx) the rear wheel's zz moment set to its xx one (SymBRiM's own wheel)
    changes M: the third moment is read, not dropped."""
    ref, eng = pairs["general-disc"]
    bad = SymbrimEngine(eng.model)
    bad.p = bad.p.copy()
    bad.p[MOORE_PARAMETERS.index("IDzz")] = bad.p[MOORE_PARAMETERS.index("IDxx")]
    q = _consistent_states(ref, n=1)[0][0]
    assert _rel(bad.mass_matrix(q), ref.mass_matrix(q)) > 1e3 * TERM_TOL


def test_thesis_contact_is_refused_with_the_reason(thesis):
    with pytest.raises(CapabilityError, match="disc's lowest point"):
        SymbrimEngine(thesis)


def test_the_cache_key_follows_symbrims_version_and_the_sources(monkeypatch):
    key = codegen.cache_key(False)
    assert key != codegen.cache_key(True)
    real = codegen.metadata.version
    monkeypatch.setattr(codegen.metadata, "version",
                        lambda d: "99.0" if d == "symbrim" else real(d))
    assert codegen.cache_key(False) != key
    monkeypatch.undo()
    assert codegen.cache_key(False) == key
    # every source the generated module depends on is hashed: the derivation, this
    # folder's codegen, and the Kane printer it prints with
    names = {p.name for p in codegen.KEY_SOURCES}
    assert {"derivation.py", "codegen.py"} <= names and len(codegen.KEY_SOURCES) == 4


def test_its_facts_are_its_own():
    f = engine_facts("engines.symbrim:SymbrimEngine")   # registered as symbrim (pyproject)
    assert (f.label, f.colour, f.marker) == ("SymBRiM", "tab:pink", "X")
    assert f.contacts == ("disc",) and f.run_difference is None


# -- slow: SymBRiM's own body points, trajectories ---------------------------------------

@pytest.mark.slow
def test_the_mapping_puts_symbrims_bodies_where_the_reference_does(pairs):
    """A second route for the coordinate mapping: SymBRiM's own body positions (the frame's
    and fork's CoMs, the front hub, the front contact point), evaluated at the mapped state
    with the mapped parameters, are the reference's points (Moore's N: x forward, y right,
    z down, so y and z change sign). Round-off: straight-line trigonometry, 1e-12 m."""
    import sympy as sp

    from engines.symbrim.derivation import EXTRA_PARAMETERS, build_bicycle, parameter_symbols
    bike = build_bicycle()
    N, origin = bike.ground.frame, bike.ground.origin
    P = parameter_symbols(bike)
    psyms = [P[k] for k in MOORE_PARAMETERS + EXTRA_PARAMETERS]
    points = {"rG3": bike.rear_frame.body.masscenter, "rG4": bike.front_frame.body.masscenter,
              "rG5": bike.front_wheel.center, "rD": bike.front_tire.contact_point}
    exprs = [[pt.pos_from(origin).dot(e) for e in (N.x, N.y, N.z)] for pt in points.values()]
    f = sp.lambdify([list(bike.q), psyms], exprs, "numpy")
    flip = np.array([1.0, -1.0, -1.0])
    for name in MODELS:
        ref, eng = pairs[name]
        for q, _, _ in _consistent_states(ref, n=5, seed=2):
            theirs = ref.model.points(q)
            mine = np.array(f(to_moore(q).q, eng.p), dtype=float)
            for k, key in enumerate(points):
                assert np.max(np.abs(flip * mine[k] - theirs[key])) < 1e-12, (name, key)


def _scenario(model_name: str, name: str):
    return dataclasses.replace(get_scenario(name), model=model_name)


@pytest.mark.slow
@pytest.mark.parametrize("model_name, name", RUNS)
def test_trajectories_match_the_reference_to_the_horizon(pairs, model_name, name):
    ref, eng = pairs[model_name]
    sc = _scenario(model_name, name)
    theirs, mine = ref.simulate(sc), eng.simulate(sc)
    horizon = reference_horizon(ref.model, sc)
    assert mine.status == theirs.status and abs(mine.t_end - theirs.t_end) < TRAJ_TOL
    err = error_vs_time(theirs, mine, coords=COORDINATES, horizon=horizon.t)
    assert err["t"][-1] >= horizon.t - 1e-9
    assert float(err["max"].max()) < TRAJ_TOL, horizon.describe()
    assert np.max(np.abs(mine.C)) < 1e-8


# -- the crown-radius option (SymBRiM's ToroidalWheel in front) ---------------------------

def test_a_bad_crown_radius_is_a_one_line_usage_error(pairs):
    from engines import EngineSpecError
    model = pairs["benchmark"][1].model
    for bad in (-0.01, model.params.R_front, "wide"):
        with pytest.raises(EngineSpecError, match="crown_radius"):
            SymbrimEngine(model, crown_radius=bad)


@pytest.mark.slow
def test_the_toroidal_variant_at_zero_crown_is_the_reference(pairs):
    """The toroidal front wheel's generated equations (a second derivation, ~65 s cold) with
    a crown radius of 0 are the disc: every term and the accelerations within the knife-edge
    bounds on the general bicycle."""
    ref, eng = pairs["general-disc"]
    torus = SymbrimEngine(eng.model)
    torus.code = codegen.load(front_crown=True)
    for q, dq, T in _consistent_states(ref, n=6, seed=3):
        for term, args in (("mass_matrix", (q,)), ("generalized_forces", (q, dq, T)),
                           ("constraint_jacobian", (q,)), ("constraint_bias", (q, dq))):
            assert _rel(getattr(torus, term)(*args), getattr(ref, term)(*args)) < TERM_TOL, term
        assert _rel(torus.forward_acceleration(q, dq, T), ref.forward_acceleration(q, dq, T)) \
            < ACCEL_TOL


@pytest.mark.slow
def test_a_crown_lifts_the_leaned_front_hub_as_a_torus_does(pairs):
    """Analytic: with the steer at 0 the front wheel leans with the frame, by theta. A disc
    of radius R holds its hub at R cos(theta); a torus of major radius R - c and crown c at
    (R - c) cos(theta) + c. At the reference's (disc) consistent state the torus's lowest
    point is therefore c (1 - cos theta) below the ground: rD_z = -c (1 - cos theta), zero
    upright (the hub's height kept). Round-off of a few trigonometric terms: 1e-12 m."""
    ref, eng = pairs["benchmark"]
    c = 0.02
    torus = SymbrimEngine(eng.model, crown_radius=c)
    for theta in (0.0, 0.2, -0.5):
        q = np.zeros(8)
        q[3] = theta
        cs = consistent_state(ref.model, q, np.zeros(8))
        rDz = torus.constraint_residual(cs.q, cs.dq)[0]
        assert abs(rDz - (-c * (1.0 - np.cos(theta)))) < 1e-12, theta


def test_the_crown_studys_linearization_at_zero_crown_is_the_references(pairs):
    """The engine's eigenvalues (`engines.linear`: central differences of its own
    accelerations, beta and the dependent rates from its own constraints) at crown 0 against
    the reference's exact linearization (complex step, its own derivation) on the benchmark
    bicycle at 2, 4 and 6 m/s. Tolerance 1e-8 relative to the largest |eigenvalue| (16 /s):
    the differences' truncation and round-off, measured ~4e-14 absolute at h = 1e-7."""
    ref, eng = pairs["benchmark"]
    v = np.array([2.0, 4.0, 6.0])
    theirs = ref.model.eigenvalues(v)
    assert np.max(np.abs(eng.eigenvalues(v) - theirs)) < 1e-8 * np.max(np.abs(theirs))


@pytest.mark.slow
def test_a_crown_lowers_the_weave_speed(pairs):
    """The declared model difference, quantified: the benchmark bicycle's weave speed (the
    weave's real part through zero) is Meijaard et al.'s 4.2924 m/s at crown 0 (their table:
    4.292 382 860 4) and falls monotonically with the crown (measured 4.084, 3.863, 3.626 m/s
    at 1, 2, 3 cm); the bracket of the root search to 1e-6 m/s."""
    from scipy.optimize import brentq

    _, eng = pairs["benchmark"]
    speeds = []
    for c in (0.0, 0.01, 0.02):
        e = SymbrimEngine(eng.model, crown_radius=c)
        speeds.append(brentq(lambda s: e.eigenvalues([s])[0][0].real, 3.0, 6.5,
                             xtol=1e-7))
    assert abs(speeds[0] - 4.2923828604) < 1e-5
    assert speeds[0] - 0.1 > speeds[1] > speeds[2] + 0.1


# -- the parameters through BicycleParameters' own conversion ------------------------------

def _measured(name: str):
    """A measured bicycle BicycleParameters ships, as the project's model parameters."""
    from reference_model.parameters import parameters_from_benchmark
    from shipped_sets import breaks_triangle, shipped, table1
    b = table1(shipped(name))
    return parameters_from_benchmark(b, name=name, allow_triangle_violation=breaks_triangle(b))


@pytest.mark.parametrize("name", ("thesis-disc", "benchmark", "Browser", "Crescendo", "Pista",
                                  "Yellowrev"))
def test_bicycleparameters_conversion_is_the_projects_moore_map(name):
    """Two routes to Moore's parameters: the engine's (the model's Table 1 values through
    BicycleParameters' Meijaard2007 -> Moore2012 conversion, DynamicistToolKit's
    benchmark_to_moore) and the project's own map of the thesis's geometry and tensors
    (`engines.kane.moore_parameters`, which the Kane engine uses). They share no code; both are
    closed-form trigonometry of the same numbers, so they agree to rounding: 1e-12 of each
    parameter's size (floored at 1, SI). Measured: 3e-16. A swapped or sign-flipped entry of
    the name map (ic31 for ICxz) is off by the entry itself."""
    from engines.kane.engine import moore_parameters as projects
    from engines.symbrim.parameters import BICYCLEPARAMETERS_ROUTE, moore_parameters, parameter_route
    params = conformance_model(name).params if "-" in name or name == "benchmark" else _measured(name)
    assert parameter_route(params) == BICYCLEPARAMETERS_ROUTE
    ours, theirs = projects(params), moore_parameters(params)
    err = np.abs(ours - theirs) / np.maximum(1.0, np.abs(ours))
    k = int(np.argmax(err))
    assert err[k] < 1e-12, f"{name}: {MOORE_PARAMETERS[k]} {theirs[k]!r} against {ours[k]!r}"


def test_a_bicycle_without_a_table1_counterpart_takes_the_projects_map_and_says_so():
    """The conformance suite's general bicycle: three distinct wheel moments, which Table 1's
    axisymmetric wheels cannot hold. It gets the project's map (exactly), and the route names
    why."""
    from engines.kane.engine import moore_parameters as projects
    from engines.symbrim.parameters import moore_parameters, parameter_route
    params = conformance_model("general-disc").params
    assert "project's own conversion" in parameter_route(params)
    assert np.array_equal(moore_parameters(params), projects(params))
