"""Pinocchio's adapter beyond the conformance suite (comparisons/conformance, which checks every
term of every engine on five models): its own consistency, the thesis's joint order, the
zig-zag and the replay through the reference's solvers, negative controls, the interface.
"""

import numpy as np
import pytest

from comparisons.judgments.terms import compare_terms, random_states
from comparisons.judgments.tolerances import load_tolerances
from engines import CAPABILITIES, CapabilityError, Engine, EngineError, load_engine
from reference_model import load_model
from reference_model.scenarios import SCENARIOS, run_inverse

# the named models, and `general` (tests/conftest.py): unequal wheels, an off-axis fork CoM,
# every inertia entry distinct, so a swapped key or a wrong frame shows in M (the named models'
# axisymmetric wheels and on-axis fork hide e.g. I5xx <-> I5zz)
MODELS = ("thesis", "thesis-disc", "general")
TOLERANCES = load_tolerances()


@pytest.fixture(scope="module", params=MODELS)
def model(request):
    if request.param == "general":
        return request.getfixturevalue("general")   # session fixture, built once
    return load_model(request.param)


def test_general_bicycle_is_general(general):
    """The model the conformance runs on really has what it is there for (else the tests above
    would silently lose their power): distinct inertia entries, unequal wheels, an off-axis
    fork CoM."""
    p = general.params
    for body in (2, 3, 4, 5):
        I = p.inertia(body)
        entries = [I[0, 0], I[1, 1], I[2, 2]] + ([I[0, 2]] if body in (3, 4) else [])
        assert len(set(entries)) == len(entries) and all(entries), (body, entries)
    assert p.R_rear != p.R_front and p.dx4 != 0 and p.dz4 != 0 and p.za + p.z5 != 0


def test_pinocchio_mass_matrix_from_rnea_columns(model):
    """Pinocchio's own consistency, as its test suite checks it: column j of M is
    rnea(q, 0, e_j) - rnea(q, 0, 0) (gravity cancels), equal to the symmetrised crba."""
    import pinocchio as pin
    eng = load_engine("pinocchio", model)
    pm, data = eng.pin_model, eng.pin_model.createData()
    for q in random_states(20, seed=3).q:
        g = pin.rnea(pm, data, q, np.zeros(8), np.zeros(8)).copy()
        cols = np.column_stack([pin.rnea(pm, data, q, np.zeros(8), e) - g for e in np.eye(8)])
        M = eng.mass_matrix(q)
        # round-off of 8 RNEA passes relative to max|M| (~1e2): ~1e-15; 1e-12 as for M
        assert np.abs(cols - M).max() <= 1e-12 * np.abs(M).max()


def test_joint_order_is_the_thesis_order(model):
    eng = load_engine("pinocchio", model)
    assert tuple(eng.pin_model.names[1:]) == model.coordinates
    assert list(eng.pin_model.idx_qs[1:]) == list(range(8))


def test_zigzag_inverse_dynamics_through_pinocchio(model):
    """Pinocchio's M, forces and constraints in the thesis's 13x13 system, along the
    zig-zag's inverse kinematics (also integrated on Pinocchio's D), give the reference's
    torques to 1e-8 N m: the torques reach 266 N m, the two D agree to 1e-15, so the
    integrated motions agree to ~1e-12 and the torques to ~1e-10 N m."""
    sc = SCENARIOS["zigzag"]
    ref = run_inverse(model, sc)
    pin_res = run_inverse(load_engine("pinocchio", model), sc)
    assert np.abs(pin_res.T - ref.T).max() <= 1e-8
    assert np.abs(pin_res.lam - ref.lam).max() <= 1e-8 * max(1.0, np.abs(ref.lam).max())


def test_replay_forward_on_pinocchio_tracks_reference():
    """The replay on Pinocchio's right-hand side, same integrator (DOP853, rtol 1e-10) and
    same torque spline, stays within 1e-8 of the reference over its first second: the two
    right-hand sides agree to ~1e-13 and the integrator's error control is identical, so
    only their difference propagates (the bike's instability grows it ~e^(3 t))."""
    from reference_model.scenarios import initial_state, torque_input
    from reference_model.solvers import simulate
    model = load_model("thesis")
    sc = SCENARIOS["replay"]
    init = initial_state(model, sc)
    torque = torque_input(model, sc)
    t = sc.t[:101]
    ref = simulate(model, init.q, init.dq, t, torque, rtol=1e-10)
    pin_traj = simulate(load_engine("pinocchio", model), init.q, init.dq, t, torque, rtol=1e-10)
    assert ref.status == pin_traj.status == "completed"
    assert np.abs(pin_traj.q - ref.q).max() <= 1e-8
    assert np.abs(pin_traj.dq - ref.dq).max() <= 1e-8


# -- negative controls: a 1e-6 change in one engine only must fail and name the term ----------

@pytest.mark.parametrize("change, expected", [
    ({"I3xz": 1e-6}, "mass_matrix"),
    ({"I4yy": 1e-6}, "mass_matrix"),
    ({"I2yy": -1e-6}, "mass_matrix"),   # downwards: the thin-disc wheel is at the triangle limit
    ({"x3": 1e-6}, "gravity"),
    ({"z3": 1e-6}, "gravity"),
    ({"x5": 1e-6}, "constraint_jacobian"),
    ({"R_front": 1e-6}, "constraint_jacobian"),
])
def test_negative_control_is_detected_and_named(change, expected):
    model = load_model("thesis")
    p = model.params
    perturbed = model.with_params(p.replace(**{k: getattr(p, k) + v for k, v in change.items()}))
    ref = load_engine("reference", model)
    bad = load_engine("pinocchio", perturbed)
    results = {r.quantity: r for r in compare_terms(ref, bad, random_states(30, seed=11), TOLERANCES)}
    assert not results[expected].passed, f"{change} not detected in {expected}"
    # and the entry it names involves the coordinate the parameter acts on
    assert results[expected].worst_entry


def test_negative_control_leaves_unrelated_terms_passing():
    """An inertia change does not touch gravity or the constraints: the suite localises."""
    model = load_model("thesis")
    bad = load_engine("pinocchio", model.with_params(model.params.replace(I3xz=model.params.I3xz + 1e-6)))
    results = {r.quantity: r for r in compare_terms(load_engine("reference", model), bad,
                                                    random_states(30, seed=12), TOLERANCES)}
    assert not results["mass_matrix"].passed
    assert results["gravity"].passed and results["constraint_jacobian"].passed
    assert results["constraint_bias"].passed


def _check_eigenvalues(name, model, eng):
    """The ``eigenvalues`` capability against the reference's exact linearization
    (`reference_model.linearize`, complex steps of its own reduced equations) at 1 and 5 m/s,
    on the model without drag (no steady motion otherwise), within [engine_eigenvalues]; an
    engine without it raises CapabilityError naming it."""
    from comparisons.judgments.engine_eigenvalues import matched_error
    if "eigenvalues" not in eng.capabilities:
        with pytest.raises(CapabilityError, match="eigenvalues"):
            eng.eigenvalues([1.0])
        return
    free = model.with_params(model.params.replace(cv=0.0))
    v = np.array([1.0, 5.0])
    lam = np.asarray(load_engine(name, free).eigenvalues(v))
    assert lam.shape == (2, 4)
    err = float(matched_error(lam, free.eigenvalues(v)).max())
    assert err <= TOLERANCES["engine_eigenvalues"].tolerance, err


# -- the interface itself -----------------------------------------------------------------

def test_unknown_engine_is_a_clear_error(model):
    with pytest.raises(EngineError, match="unknown engine 'bullet'.*available: reference, pinocchio"):
        load_engine("bullet", model)


def test_missing_capability_names_engine_and_capability(model):
    class Partial(Engine):
        name = "partial"
        capabilities = frozenset({"mass_matrix"})
    with pytest.raises(CapabilityError, match="engine 'partial' cannot compute constraint_jacobian"):
        Partial(model).constraint_jacobian(np.zeros(8))


@pytest.mark.parametrize("name", ("reference", "pinocchio"))
def test_declared_capabilities_are_implemented(model, name):
    """Every declared capability answers with the documented shape and the value of the
    reference model's own function (within the term's tolerance, tolerances.toml); every
    capability not declared raises CapabilityError naming it. A stub that returns zeros, the
    wrong term or the wrong shape fails here, not only one that raises."""
    import dataclasses
    eng = load_engine(name, model)
    assert set(eng.capabilities) <= set(CAPABILITIES)
    s = random_states(2, seed=5)
    q, dq, ddq, T = s.q[0], s.dq[0], s.ddq[0], s.T[0]
    calls = {
        "mass_matrix": (lambda e: e.mass_matrix(q), model.mass_matrix(q)),
        "inverse_dynamics": (lambda e: e.inverse_dynamics(q, dq, ddq),
                             model.inverse_dynamics(q, dq, ddq)),
        "gravity": (lambda e: e.gravity(q), model.Qgrav(q)),
        "generalized_forces": (lambda e: e.generalized_forces(q, dq, T),
                               model.generalized_forces(q, dq, T)),
        "constraint_jacobian": (lambda e: e.constraint_jacobian(q), model.constraint_jacobian(q)),
        "constraint_bias": (lambda e: e.constraint_bias(q, dq), model.constraint_bias(q, dq)),
        "forward_acceleration": (lambda e: e.forward_acceleration(q, dq, T),
                                 model.forward_acceleration(q, dq, T)),
    }
    assert set(calls) | {"simulate", "eigenvalues"} == set(CAPABILITIES)
    for cap, (call, expected) in calls.items():
        if cap not in eng.capabilities:
            with pytest.raises(CapabilityError, match=cap):
                call(eng)
            continue
        out = np.asarray(call(eng))
        assert out.shape == expected.shape, (cap, out.shape)
        tol = TOLERANCES[cap]
        err = np.abs(out - expected).max() / tol.normalizer(expected)
        assert err <= tol.tolerance, f"{cap}: {err:.2e} > {tol.tolerance:.0e}"
    _check_eigenvalues(name, model, eng)
    if "simulate" in eng.capabilities:
        # 0.1 s of the check's straight rolling: xc = R_rear psi_dot t exactly (steady state,
        # tests/test_solvers.py); DOP853 at rtol 1e-10 over 0.5 m: 1e-9 m
        sc = SCENARIOS["check-forward"]
        traj = eng.simulate(dataclasses.replace(sc, grid=(0.0, 0.01, 11)))
        assert traj.status == "completed", traj.message
        np.testing.assert_allclose(traj.t, 0.01 * np.arange(11), rtol=0, atol=1e-15)
        v = model.params.R_rear * sc.dq_ind0[1]
        np.testing.assert_allclose(traj.q[:, 0], v * traj.t, rtol=0, atol=1e-9)
