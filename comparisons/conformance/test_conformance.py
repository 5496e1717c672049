"""The conformance checks: an engine against the reference built from the same parameters.

Each check is parametrized by the plugin (`plugin.py`) over the engines and models given on
the command line and only where the engine's capabilities allow it. Tolerances, each with the
reason for its size, are the session's (the plugin's ``--tolerances FILE``, default
`comparisons/judgments/tolerances.toml`): the ``tolerances`` fixture.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from comparisons.judgments.terms import States, compare_term, random_states
SWEEP_STATES = 200
#: checks that need capabilities beyond the quantity's own
NEEDS = {"test_zigzag_torques_and_multipliers": ("mass_matrix", "generalized_forces",
                                                 "constraint_jacobian", "constraint_bias"),
         "test_trajectory_to_the_meaningful_horizon": ("simulate",),
         "test_eigenvalues_against_the_exact_linearization": ("eigenvalues",)}

angle = st.floats(-np.pi, np.pi)
state = st.tuples(
    st.lists(st.floats(-10, 10), min_size=2, max_size=2),           # xc, yc [m]
    angle, st.floats(-1.3, 1.3), angle, st.floats(-0.6, 0.6),         # phi, theta, psi, beta [rad]
    st.one_of(st.floats(-1.5, 1.5), st.sampled_from([-1.5707, 1.5707, 1.57])),  # gamma, incl. +-pi/2
    angle,                                                             # eps [rad]
    st.lists(st.floats(-30, 30), min_size=8, max_size=8),              # rates, incl. fast spins
    st.lists(st.floats(-10, 10), min_size=8, max_size=8),              # accelerations
    st.lists(st.floats(-20, 20), min_size=3, max_size=3),              # torques [N m]
)


def _states(s) -> States:
    (xy, phi, theta, psi, beta, gamma, eps, dq, ddq, T) = s
    q = np.array([[*xy, phi, theta, psi, beta, gamma, eps]])
    return States(q, np.array([dq]), np.array([ddq]), np.array([T]))


def test_term_at_hypothesis_states(candidate, reference, quantity, tolerances, conformance):
    """Each term at hypothesis-generated states: large angles, fast spins, steer near +-pi/2
    (25 of them; 5 at ``--conformance-depth quick``)."""
    @settings(max_examples=conformance.depth.examples)
    @given(s=state)
    def at(s):
        res = compare_term(quantity, reference, candidate.engine, _states(s), tolerances[quantity])
        assert res.passed, res.describe()
    at()


def test_term_sweep(candidate, reference, quantity, tolerances):
    """Each term over 200 deterministic states (reproducible numbers for a report)."""
    res = compare_term(quantity, reference, candidate.engine, random_states(SWEEP_STATES, seed=7),
                       tolerances[quantity])
    assert res.passed, res.describe()


def test_zigzag_torques_and_multipliers(candidate, conformance, tolerances):
    """The thesis's zig-zag through the engine's terms in the 13x13 inverse dynamics (the
    engine's own inverse kinematics on its D) gives the reference's rider torques and
    multipliers within [torques] and [multipliers] of tolerances.toml."""
    from reference_model.scenarios import SCENARIOS, run_inverse
    eng = candidate.engine
    sc = SCENARIOS["zigzag"]
    ref = run_inverse(conformance.model(candidate.model_name), sc)
    got = eng.run_inverse(sc)
    for name, a, b in (("torques", ref.T, got.T), ("multipliers", ref.lam, got.lam)):
        tol = tolerances[name]
        err = float(np.abs(b - a).max()) / tol.normalizer(a)
        k, i = np.unravel_index(int(np.argmax(np.abs(b - a))), a.shape)
        assert err <= tol.tolerance, (f"{name}: error {err:.2e} > {tol.tolerance:g} ({tol.scale}) "
                                      f"at column {i}, t = {ref.motion.t[k]:.2f} s")


test_zigzag_torques_and_multipliers.needs_method = "run_inverse"   # collected only where offered


#: the forward scenarios and how much of each is run (s; None: to its end or fall). The stability
#: run at psi_dot(0) = 5 rad/s leans, steers and rolls (every term and constraint at work) and
#: falls within about a second on the thesis geometry; the replay's first second drives the
#: bicycle with the zig-zag's rider torques (the S T term)
TRAJECTORIES = {"stability-psid5": None, "replay": 1.0}


@pytest.mark.parametrize("scenario", list(TRAJECTORIES))
def test_trajectory_to_the_meaningful_horizon(candidate, conformance, tolerances, scenario):
    # (collected for every --model given; without --model, on DEFAULT_TRAJECTORY_MODELS only)
    """The engine's own forward run against the reference's (DOP853, rtol 1e-11, projection),
    all eight coordinates up to the meaningful horizon (two reference runs 1e-9 rad/s apart in
    theta_dot(0) part by 1e-6; beyond it no comparison means anything), within
    [trajectory_conformance] of tolerances.toml."""
    from reference_model.scenarios import SCENARIOS

    from comparisons.judgments.convergence import error_vs_time, reference_horizon, reference_run
    from reference_model import COORDINATES
    model = conformance.model(candidate.model_name)
    sc = SCENARIOS[scenario]
    if TRAJECTORIES[scenario] is not None:
        start, step, _ = sc.grid
        sc = dataclasses.replace(sc, grid=(start, step, int(round(TRAJECTORIES[scenario] / step)) + 1))
    ref = reference_run(model, sc)
    horizon = reference_horizon(model, sc, reference=ref)
    traj = candidate.engine.simulate(sc)
    assert traj.status != "failed", f"{candidate.spec} failed: {traj.message}"
    err = error_vs_time(ref, traj, coords=COORDINATES, horizon=horizon.t)
    tol = tolerances["trajectory_conformance"]
    k = int(np.argmax(err["max"]))
    worst = max(COORDINATES, key=lambda c: err[c][k])
    assert err["max"].max() <= tol.tolerance, (
        f"{scenario}: max error {err['max'].max():.2e} > {tol.tolerance:g} rad or m, worst "
        f"{worst} at t = {err['t'][k]:.2f} s (horizon {horizon.t:.2f} s: {horizon.reason})")


def test_eigenvalues_against_the_exact_linearization(candidate, conformance, tolerances):
    # (collected for every --model given; without --model, on every model, or at
    # --conformance-depth quick on the benchmark only and without the critical speeds)
    """The engine's roll/steer eigenvalues (its ``eigenvalues`` capability) at 11 speeds 0-10
    m/s and its weave and capsize speeds against the reference's exact linearization
    (`reference_model.linearize`: complex-step derivatives of its own reduced equations), on
    the model without drag (no steady upright motion otherwise), within [engine_eigenvalues]
    and [engine_critical_speeds] of tolerances.toml (`judgments.engine_eigenvalues`)."""
    from engines import load_engine
    from engines.linear import critical_speeds as engine_critical

    from comparisons.judgments.eigenvalues import critical_speeds
    from comparisons.judgments.engine_eigenvalues import judge_eigenvalues
    model = conformance.model(candidate.model_name)
    free = model.with_params(model.params.replace(cv=0.0))
    eng = load_engine(candidate.spec, free, **conformance.options.get(candidate.spec, {}))
    v = np.linspace(0.0, 10.0, 11)
    both = conformance.depth.critical_speeds
    check = judge_eigenvalues(candidate.spec, free.name, v, eng.eigenvalues(v),
                              free.eigenvalues(v),
                              engine_critical(eng.eigenvalues, (0.0, 10.0)) if both else (None,) * 2,
                              critical_speeds(free, np.array([0.0, 10.0])) if both else (None,) * 2,
                              (0.0, 10.0), tolerances)
    assert check.eigenvalues_passed, (f"eigenvalues: error {check.error:.2e} > "
                                      f"{check.tolerance:g} at v = {check.worst_speed:g} m/s")
    for c in check.critical:
        assert c.passed, f"{c.mode} speed: engine {c.engine}, reference {c.reference}"
