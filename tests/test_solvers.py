"""Tests of the solvers (reference_model/solvers.py) and the scenarios that drive them.

Every expected value comes from a source independent of the code under test: an analytic
result derived here (statics of straight rolling, the contact kinematics at the upright
state), a physical law (the work-energy theorem), a number published in the thesis's
listing, or the numpy oracle of tests/oracle.py (a second, energy-based formulation).

Scales behind the tolerances: lengths ~1 m, total mass ~84 kg, forces up to ~300 N (the
front normal force ~243 N, the zigzag multipliers up to ~300 N, the anti-roll torque up to
~270 N m), rates ~5 rad/s, energies ~1e3 J (mostly potential, measured from the ground).
"""

import re

import numpy as np
import pytest
from scipy.integrate import simpson

import oracle as o
from reference_model import load_model
from reference_model.model import DEP, IND, Model
from reference_model.scenarios import (SCENARIOS, initial_state, run_forward, run_inverse,
                                       torque_input)
from reference_model.solvers import (DEFAULT_FALL_LIMIT, THESIS_BAUMGARTE, consistent_state,
                                     dependent_rates, simulate)

XC, YC, PHI, THETA, PSI, BETA, GAMMA, EPS = range(8)
EPS64 = np.finfo(float).eps

# The thesis's forward initial velocity (listing of Dinamica_directa), digits as printed
THESIS_DQ0 = np.array([1.6, 0.0, -0.035520618556701, -1.0 / 3.0, 5.0, 0.0, 0.5, 5.0])
STABILITY_Q0 = np.array([0, 0, 0, np.pi / 16, 0, 0, np.pi / 16, 0], dtype=float)


# --------------------------------------------------------------------------------------------
# fixtures: models and the expensive runs, once per module
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def model():
    return load_model("thesis")


@pytest.fixture(scope="module")
def P(model):
    """The model's parameters as read by the oracle."""
    return o.params_from(model.params)


@pytest.fixture(scope="module")
def check(model):
    return run_inverse(model, SCENARIOS["check"])


@pytest.fixture(scope="module")
def zigzag(model):
    return run_inverse(model, SCENARIOS["zigzag"])


@pytest.fixture(scope="module")
def zigzag_reprojected(model):
    return run_inverse(model, SCENARIOS["zigzag"], reproject=True)


class _StateSpy:
    """The model, recording every single state its forward dynamics is evaluated at: the
    integrator's own states, before `simulate` projects anything onto its output grid."""

    def __init__(self, model):
        self._model = model
        self.states: list[tuple[np.ndarray, np.ndarray]] = []

    def __getattr__(self, name):
        return getattr(self._model, name)

    def forward(self, q, dq, *args, **kwargs):
        if np.ndim(q) == 1:
            self.states.append((np.array(q), np.array(dq)))
        return self._model.forward(q, dq, *args, **kwargs)


def _carried_states_C(model, constraints, rtol, atol):
    """max |C| of the state each accepted step of the replay's first second ends on (the state
    the next step starts from), and the trajectory. simulate's right-hand side evaluates the
    torque at t and then the model at (t, y); the last evaluation at an accepted step's time
    is the one on the state the integrator carries on (after the projection, if any)."""
    sc = SCENARIOS["replay"]
    init = initial_state(model, sc)
    torque = torque_input(model, sc)
    spy, times, steps = _StateSpy(model), [], []

    def timed_torque(t):
        times.append(t)
        return torque(t)

    traj = simulate(spy, init.q, init.dq, sc.t[:101], timed_torque, constraints=constraints,
                    rtol=rtol, atol=atol, progress=steps.append)
    times = np.array(times[:len(spy.states)])   # the last torque calls fill the output T
    C = np.array([np.abs(model.constraint_residual(q, dq)).max() for q, dq in spy.states])
    carried = np.array([C[np.flatnonzero(times == ts)[-1]] for ts in steps])
    return carried, traj


@pytest.fixture(scope="module")
def loose_runs(model):
    """The replay's first second at rtol 1e-6 (6 steps): integration errors large enough that
    drift off the constraints shows, with the carried states' max |C| per step."""
    return {c: _carried_states_C(model, c, rtol=1e-6, atol=1e-8) for c in ("projection", "none")}


@pytest.fixture(scope="module")
def replay_runs(model):
    """The replay scenario over its first second with each constraint handling, rtol 1e-10."""
    sc = SCENARIOS["replay"]
    init = initial_state(model, sc)
    torque = torque_input(model, sc)
    t = sc.t[:101]  # 0 .. 1 s
    return {c: simulate(model, init.q, init.dq, t, torque, constraints=c, rtol=1e-10)
            for c in ("projection", "baumgarte", "none")}


def upright_D(P):
    """D at q = 0 (upright, straight, beta = 0), derived by hand from the geometry.

    At q = 0: rC = 0, rG2 = [0, 0, R_rear], rG5 = [xa + x5, 0, R_rear + za + z5],
    rD = rG5 - R_front e_z. Small rotations give
      [rD]_z  rate : -(xa + x5) dbeta                       (pitch about y lowers the front)
      vC_x = dxc - R_rear dpsi                             (rolling of the rear wheel)
      vC_y = dyc + (-R_rear dtheta) + (R_rear dtheta)      (hub sway cancels the rim's)
      vD_x = dxc + (za + z5) dbeta - R_front (dbeta + deps)
      vD_y = dyc + (xa + x5) dphi - (za + z5) dtheta + x5 dgamma
    (for vD_y: yaw swings the front contact at arm xa + x5, steer swings the hub at arm x5,
    and roll moves the hub by -(R_rear + za + z5) dtheta while the rim point below it moves
    by +R_front dtheta).
    """
    D = np.zeros((5, 8))
    D[0, BETA] = -(P.xa + P.x5)
    D[1, [XC, PSI]] = [1.0, -P.R_rear]
    D[2, YC] = 1.0
    D[2, THETA] = -P.R_rear + P.R_rear
    D[3, [XC, BETA, EPS]] = [1.0, P.za + P.z5 - P.R_front, -P.R_front]
    D[4, [YC, PHI, THETA, GAMMA]] = [1.0, P.xa + P.x5, -(P.za + P.z5), P.x5]
    return D


def upright_rates(P, dq_ind):
    """Full dq at q = 0 from D dq = 0 solved by hand with upright_D (dyc = dbeta = 0)."""
    dtheta, dpsi, dgamma = dq_ind
    dxc = P.R_rear * dpsi
    dphi = ((P.za + P.z5) * dtheta - P.x5 * dgamma) / (P.xa + P.x5)
    deps = dxc / P.R_front
    return np.array([dxc, 0.0, dphi, dtheta, dpsi, 0.0, dgamma, deps])


# --------------------------------------------------------------------------------------------
# 1. check scenario (inverse): straight rolling, analytic torques and multipliers
# --------------------------------------------------------------------------------------------
def test_check_pedal_torque_balances_drag(model, check):
    """Mped = cv v^2 R_rear with v = R_rear psi_dot: the drag cv v^2 on the frame balanced by
    the rear-wheel torque through the wheel radius; no steer or anti-roll torque is needed."""
    p = model.params
    v = p.R_rear * 5.0
    expected = np.array([0.0, p.cv * v**2 * p.R_rear, 0.0])
    assert check.T.shape == (629, 3)
    # the 13x13 solve mixes unknowns up to ~250 N (front normal force); a few hundred ulps of
    # that scale is ~1e-11 N m (the state is exactly symmetric, so the rest is exact zeros)
    np.testing.assert_allclose(check.T, np.broadcast_to(expected, check.T.shape), rtol=0,
                               atol=1e-11)


def test_check_kinematics_is_uniform_rolling(model, check):
    p = model.params
    m = check.motion
    v = p.R_rear * 5.0
    # dependent rates from D dq = 0 at an exactly upright state: O(1) coefficients, so a few
    # ulps of the largest rate (5 rad/s) -> 1e-14
    expected = np.array([v, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0, v / p.R_front])
    np.testing.assert_allclose(m.dq, np.broadcast_to(expected, m.dq.shape), rtol=0, atol=1e-14)
    # coordinates: xc = v t integrated at rtol 1e-12 over 629 samples to ~10 m: <= 1e-10 m;
    # the rest stay exactly where the symmetry puts them (beta from [rD]_z = 0 is 0 upright)
    np.testing.assert_allclose(m.q[:, XC], v * m.t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(m.q[:, [YC, PHI, THETA, BETA, GAMMA]], 0.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(m.q[:, PSI], 5.0 * m.t, rtol=0, atol=1e-12)
    # steady motion: no acceleration at all (forces ~1e2 N over masses ~1..80 kg: 1e-12)
    np.testing.assert_allclose(check.ddq, 0.0, rtol=0, atol=1e-12)


def test_check_multipliers_are_the_contact_forces(model, check):
    """The multipliers are constant and equal minus the contact forces from statics.

    With M ddq + D^T lambda = Q, the constraint force is -D^T lambda; row 1 is [rD]_z, so
    lambda_1 = -N_front; rows 2..5 are contact velocities, so lambda_k = -(friction force).
    Moments about the rear contact (global y), steady motion:
        N_front (xa + x5) = g (m3 x3 + m4 (xa + dx4) + m5 (xa + x5))
                            - cv v^2 (R_rear + z3) + Mped,       Mped = cv v^2 R_rear
    (gravity; drag at the frame CoM height; the single-sided pedal torque acts as an external
    torque on the system). Horizontal balance: the free-spinning front wheel carries no
    friction, so the rear friction balances the drag: F_rear_x = cv v^2. Lateral forces: 0.
    """
    p = model.params
    v = p.R_rear * 5.0
    n_front = (p.g * (p.m3 * p.x3 + p.m4 * (p.xa + p.dx4) + p.m5 * (p.xa + p.x5))
               - p.cv * v**2 * (p.R_rear + p.z3) + p.cv * v**2 * p.R_rear) / (p.xa + p.x5)
    expected = -np.array([n_front, p.cv * v**2, 0.0, 0.0, 0.0])
    # forces ~250 N from a 13x13 solve: 1e-10 N is ~2000 ulps of that scale
    np.testing.assert_allclose(check.lam, np.broadcast_to(expected, check.lam.shape), rtol=0,
                               atol=1e-10)
    # constant along the motion: every sample is the same state up to xc and psi, on which
    # nothing depends, so the samples agree to the last few bits
    assert np.ptp(check.lam, axis=0).max() <= 1e-12


# --------------------------------------------------------------------------------------------
# 2. replay scenario: the thesis's forward dq0
# --------------------------------------------------------------------------------------------
def test_upright_constraint_jacobian_derived_by_hand(model, disc, P):
    """The model's D at q = 0, for both contact models (they coincide upright: the fork's x
    axis is horizontal, so the rim point below the hub is the lowest point of the disc), is the
    hand derivation upright_D; the oracle's complex-step D agrees too, so the hand derivation is
    itself checked by a third formulation."""
    expected = upright_D(P)
    # entries are lengths (~1 m) evaluated in closed form: exact to a few ulps
    for name, m in (("thesis contact", model), ("disc contact", disc)):
        np.testing.assert_allclose(m.constraint_jacobian(np.zeros(8)), expected, rtol=0,
                                   atol=1e-15, err_msg=name)
    # complex-step derivatives of the same lengths: exact to a few ulps as well
    np.testing.assert_allclose(o.constraint_jacobian(P, np.zeros(8)), expected, rtol=0,
                               atol=1e-15)


def test_replay_initial_rates_match_thesis(model, zigzag, P):
    dq_ind = (-1.0 / 3.0, 5.0, 0.5)   # zigzag rates at t = 0: -cos(0)/3, 5, cos(0)/2
    analytic = upright_rates(P, dq_ind)
    # the front contact's lateral velocity vD_y = dyc + (xa + x5) dphi + x5 dgamma
    # - (za + z5) dtheta vanishes; with za + z5 = 0 (thesis: z5 = -z4) dphi = -x5 dgamma / (xa + x5)
    assert P.za + P.z5 == pytest.approx(0.0, abs=1e-15)
    assert analytic[PHI] == pytest.approx(-P.x5 * 0.5 / (P.xa + P.x5), abs=1e-16)
    # the thesis prints 15 decimals (rounding <= 5e-16); the rest is a few ulps of 5: 1e-14
    np.testing.assert_allclose(analytic, THESIS_DQ0, rtol=0, atol=1e-14)

    ik = zigzag.motion.dq[0]
    init = initial_state(model, SCENARIOS["replay"])
    direct = dependent_rates(model, np.zeros(8), dq_ind)
    for name, dq in (("inverse kinematics", ik), ("initial_state", init.dq),
                     ("dependent_rates", direct)):
        # a linear solve with O(1) coefficients at an exactly upright state: a few ulps of 5
        np.testing.assert_allclose(dq, THESIS_DQ0, rtol=0, atol=1e-14, err_msg=name)
        np.testing.assert_allclose(dq, analytic, rtol=0, atol=1e-14, err_msg=name)
    # the replay starts at q = 0, which satisfies [rD]_z = 0 exactly: no correction
    np.testing.assert_array_equal(init.q, np.zeros(8))
    assert init.beta_correction == 0.0


# --------------------------------------------------------------------------------------------
# 3. zigzag inverse kinematics
# --------------------------------------------------------------------------------------------
def test_zigzag_prescribed_motion(zigzag):
    m = zigzag.motion
    t = 0.01 * np.arange(629)
    np.testing.assert_allclose(m.t, t, rtol=0, atol=1e-15 * 2 * np.pi)  # 0:0.01:2*pi
    # the prescribed coordinates and rates are evaluated, not integrated: exact to rounding
    np.testing.assert_allclose(m.q[:, [THETA, PSI, GAMMA]],
                               np.stack([-np.sin(t) / 3, 5 * t, np.sin(t) / 2], 1), atol=1e-14)
    np.testing.assert_allclose(m.dq[:, [THETA, PSI, GAMMA]],
                               np.stack([-np.cos(t) / 3, 5 + 0 * t, np.cos(t) / 2], 1), atol=1e-14)
    np.testing.assert_allclose(m.ddq_ind, np.stack([np.sin(t) / 3, 0 * t, -np.sin(t) / 2], 1),
                               atol=1e-14)
    np.testing.assert_array_equal(m.q[0, DEP], np.zeros(5))  # q_dep(0) = 0


def test_zigzag_constraints_hold(model, zigzag, P):
    m = zigzag.motion
    C = model.constraint_residual(m.q, m.dq)
    # [rD]_z: beta is integrated, not solved. DOP853 at rtol = atol = 1e-12 keeps each step's
    # local error below ~1e-12 (beta ~ 0.02 rad, so atol dominates); a few dozen steps over
    # 2 pi s accumulate at most ~5e-11 rad, and d[rD]_z/dbeta ~ xa + x5 ~ 1 m: 1e-10 m
    assert np.abs(C[:, 0]).max() <= 1e-10
    # velocity rows: dq solved from D dq = 0 at every sample: round-off of O(1) coefficients
    # times rates ~5: 1e-13
    assert np.abs(C[:, 1:]).max() <= 1e-13
    # the oracle agrees on a few samples (it evaluates the constraints independently)
    for k in (0, 157, 314, 471, 628):
        Co = o.constraint_residual(P, m.q[k], m.dq[k])
        assert abs(Co[0]) <= 1e-10 and np.abs(Co[1:]).max() <= 1e-13, k


def test_zigzag_reprojected(model, zigzag, zigzag_reprojected):
    a, b = zigzag, zigzag_reprojected
    C = model.constraint_residual(b.motion.q, b.motion.dq)
    # beta solved by Newton to |[rD]_z| <= 1e-14 at every sample: round-off of a ~1 m height
    assert np.abs(C[:, 0]).max() < 1e-13
    assert np.abs(C[:, 1:]).max() <= 1e-13  # as above
    # the two differ by the integration error of the dependent coordinates (<= ~1e-10, see
    # above; xc grows to ~10 m, so rtol 1e-12 allows ~1e-11 per step there): 1e-9 is a safe
    # bound that still catches any real difference between the two procedures
    np.testing.assert_allclose(b.motion.q, a.motion.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.motion.dq, a.motion.dq, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.ddq, a.ddq, rtol=0, atol=1e-9)
    # torques: the same state errors times a force sensitivity of order max|T| per unit of
    # state: 1e-9 relative to the largest torque (the anti-roll ~270 N m)
    np.testing.assert_allclose(b.T, a.T, rtol=0, atol=1e-9 * np.abs(a.T).max())


# --------------------------------------------------------------------------------------------
# 4. inverse dynamics fed back into the forward dynamics
# --------------------------------------------------------------------------------------------
def test_inverse_dynamics_torques_reproduce_prescribed_accelerations(model, zigzag, P):
    m = zigzag.motion
    ks = np.linspace(0, m.t.size - 1, 20).round().astype(int)
    for k in ks:
        t = m.t[k]
        q, dq, T = m.q[k], m.dq[k], zigzag.T[k]
        prescribed = np.array([np.sin(t) / 3, 0.0, -np.sin(t) / 2])  # d2/dt2 of the zigzag
        ddq = model.forward_acceleration(q, dq, T)
        ddq_oracle, lam_oracle = o.forward_acceleration(P, q, dq, T)
        # both solve a 13x13 KKT system of condition ~2e4 (tests/test_physics.py) with
        # right-hand sides up to ~3e2 (torques, forces): eps * cond * 3e2 ~ 1e-9
        np.testing.assert_allclose(ddq[IND], prescribed, rtol=0, atol=1e-9, err_msg=f"t={t}")
        np.testing.assert_allclose(ddq_oracle[IND], prescribed, rtol=0, atol=1e-9,
                                   err_msg=f"oracle t={t}")
        np.testing.assert_allclose(ddq_oracle, zigzag.ddq[k], rtol=0, atol=1e-9,
                                   err_msg=f"oracle full ddq t={t}")
        # multipliers are forces ~3e2 N: the same 1e-9 relative
        np.testing.assert_allclose(lam_oracle, zigzag.lam[k], rtol=0,
                                   atol=1e-9 * max(1.0, np.abs(lam_oracle).max()),
                                   err_msg=f"oracle lambda t={t}")


# --------------------------------------------------------------------------------------------
# 5. work-energy theorem along forward runs
# --------------------------------------------------------------------------------------------
def _energy(model, traj):
    return model.kinetic_energy(traj.q, traj.dq) + model.potential_energy(traj.q)


@pytest.mark.parametrize("constraints", ["none", "projection"])
def test_power_balance_along_forward_run(model, constraints):
    """E(t) - E(0) = integral of dq.(Qaero + S T): rolling constraints do no work.

    stability-psid5 over 0.8 s (it falls at ~1 s), rtol 1e-11, sampled every 1 ms.
    """
    sc = SCENARIOS["stability-psid5"]
    init = initial_state(model, sc)
    t = np.linspace(0.0, 0.8, 801)
    traj = simulate(model, init.q, init.dq, t, sc.torques, constraints=constraints,
                    rtol=1e-11, atol=1e-13)
    assert traj.status == "completed", traj.message
    E = _energy(model, traj)
    power = np.einsum("ni,ni->n", traj.dq,
                      model.Qaero(traj.q, traj.dq) + model.S(traj.q) @ np.asarray(sc.torques))
    scale = model.kinetic_energy(traj.q, traj.dq).max() + model.potential_energy(traj.q).max()
    for k in range(100, 801, 100):  # even indices: Simpson on an even number of intervals
        work = simpson(power[:k + 1], x=traj.t[:k + 1])
        # quadrature error estimated by Richardson from the half-resolution Simpson (error
        # ~h^4: |S_h - S_2h| / 15); it must itself be tiny, or the bound below is meaningless
        coarse = simpson(power[:k + 1:2], x=traj.t[:k + 1:2])
        quad = abs(work - coarse) / 15
        assert quad < 1e-7
        # integration: local error <= rtol relative per step, ~100 steps, so E is off by at
        # most ~1e-9 of its scale (~1e3 J) -> 1e-6 J, plus 10x the quadrature estimate. Any
        # missing term is of order joules (drag work ~-6.8 J, pedal work ~+4.2 J by 0.8 s).
        assert abs(E[k] - E[0] - work) <= 1e-9 * scale + 10 * quad, (traj.t[k], E[k] - E[0], work)
    assert abs(E[-1] - E[0]) > 1.0  # the check is not vacuous: energy does change by joules


@pytest.mark.parametrize("constraints", ["none", "projection", "baumgarte"])
def test_energy_conserved_without_drag_or_torque(model, constraints):
    free = Model(model.params.replace(cv=0.0))
    sc = SCENARIOS["stability-psid5"]
    init = initial_state(free, sc)
    t = np.linspace(0.0, 0.8, 81)
    traj = simulate(free, init.q, init.dq, t, (0.0, 0.0, 0.0), constraints=constraints,
                    rtol=1e-11, atol=1e-13)
    assert traj.status == "completed", traj.message
    E = _energy(free, traj)
    scale = free.kinetic_energy(traj.q, traj.dq).max() + free.potential_energy(traj.q).max()
    # rtol 1e-11 per step over ~100 steps: <= 1e-9 of the energy scale (~1.5e3 J). KE grows
    # from ~125 J to ~490 J as the bike falls, so a non-conservative term would show in joules
    assert np.abs(E - E[0]).max() <= 1e-9 * scale
    assert np.ptp(free.kinetic_energy(traj.q, traj.dq)) > 10.0  # energy is exchanged


# --------------------------------------------------------------------------------------------
# 6. consistent initial state
# --------------------------------------------------------------------------------------------
def test_consistent_state_of_the_stability_q0(model, P):
    q0 = STABILITY_Q0.copy()
    # independent rates of stability-psid5, with deliberately wrong dependent rates
    dq0 = np.array([0.3, -0.2, 0.1, 0.0, 5.0, 0.7, 0.0, -1.0])
    cs = consistent_state(model, q0, dq0)

    # the given state violates [rD]_z = 0 by millimetres (thesis quirk) and the velocity rows
    before = o.constraint_residual(P, q0, dq0)
    assert 1e-3 < abs(before[0]) < 1e-2
    np.testing.assert_allclose(cs.residual_before, before, rtol=0, atol=1e-14)

    # beta: the oracle's own Newton on [rD]_z = 0 (complex-step slope); both converge to
    # ~1e-14 m of height with slope ~1 m/rad: 1e-13 rad
    q_oracle, _ = o.consistent_state(P, q0, dq0)
    assert cs.q[BETA] == pytest.approx(q_oracle[BETA], abs=1e-13)
    assert cs.beta_correction == pytest.approx(q_oracle[BETA] - q0[BETA], abs=1e-13)
    assert abs(cs.beta_correction) > 1e-3  # millimetres of height at ~1 m of lever arm
    assert f"{cs.beta_correction:+.6e}" in cs.describe()
    # Newton converges quadratically: ~3e-3 m of height -> ~1e-5 -> ~1e-10 -> round-off; a
    # fixed-point iteration with the wrong step would need ~10 or more
    assert 1 <= cs.iterations <= 4

    # only beta moves; theta, psi, gamma and their rates are kept exactly, and so are the
    # coordinates the constraints do not fix (xc, yc, phi, eps)
    keep = [XC, YC, PHI, THETA, PSI, GAMMA, EPS]
    np.testing.assert_array_equal(cs.q[keep], q0[keep])
    np.testing.assert_array_equal(cs.dq[IND], dq0[IND])

    # dependent rates: D_dep dq_dep = -D_ind dq_ind with the ORACLE's D (unique solution)
    Do = o.constraint_jacobian(P, cs.q)
    dq_dep = np.linalg.solve(Do[:, DEP], -Do[:, IND] @ dq0[IND])
    np.testing.assert_allclose(cs.dq[DEP], dq_dep, rtol=0, atol=1e-12)  # rates ~5, cond ~1e2

    # all five constraints at round-off, by the model and by the oracle
    after = o.constraint_residual(P, cs.q, cs.dq)
    assert abs(after[0]) <= 5e-14               # a ~1 m height from ~10 terms: a few ulps
    assert np.abs(after[1:]).max() <= 1e-13     # velocities ~5 m/s: a few hundred ulps
    assert abs(cs.residual_after[0]) <= 1e-14   # solve_beta's own stopping rule
    assert np.abs(cs.residual_after[1:]).max() <= 1e-13
    np.testing.assert_allclose(cs.residual_after, model.constraint_residual(cs.q, cs.dq),
                               rtol=0, atol=0)


def test_consistent_state_rejects_non_finite(model):
    with pytest.raises(ValueError, match="finite"):
        consistent_state(model, [np.nan] + [0.0] * 7, np.zeros(8))


# --------------------------------------------------------------------------------------------
# 7. forward runs: falls, completion, failures
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fall_limit", [DEFAULT_FALL_LIMIT, 0.5])
def test_run_that_falls(model, fall_limit):
    sc = SCENARIOS["stability-psid0"]   # leaned pi/16 at rest: it topples
    traj = run_forward(model, sc, fall_limit=fall_limit)
    assert traj.status == "fell", traj.message
    n = traj.t.size
    assert n >= 3
    # brentq locates the crossing to xtol 1e-14 s; theta moves at ~ rad/s: far below 1e-9
    assert abs(traj.q[-1, THETA]) == pytest.approx(fall_limit, abs=1e-9)
    assert np.all(np.abs(traj.q[:-1, THETA]) < fall_limit)
    # the grid samples are exactly the requested ones up to the fall, then the fall itself
    np.testing.assert_array_equal(traj.t[:-1], sc.t[:n - 1])
    assert sc.t[n - 2] < traj.t[-1] < sc.t[n - 1]
    assert traj.t_end == traj.t[-1]
    assert f"{traj.t_end:.6f}" in traj.message
    for name in ("t", "q", "dq", "ddq", "C", "T"):
        a = getattr(traj, name)
        assert a.shape[0] == n, name
        assert np.all(np.isfinite(a)), name


MIRROR = np.array([1.0, -1.0, -1.0, -1.0, 1.0, 1.0, -1.0, 1.0])   # reflection in the x-z plane


def test_mirrored_run_falls_to_the_other_side_at_the_same_time(model):
    """The bicycle is symmetric about its x-z plane (the products of inertia are xz only):
    reflecting the initial state (yc, phi, theta, gamma and their rates change sign) reflects
    the whole motion, pedal torque unchanged. stability-psid0 falls to +theta; its mirror must
    fall at the same time to -fall_limit. Every shipped scenario falls to +theta, so a fall
    test that forgets |theta| passes on them."""
    sc = SCENARIOS["stability-psid0"]
    ahead = run_forward(model, sc)
    init = initial_state(model, sc)
    mirror = consistent_state(model, MIRROR * init.q, MIRROR * init.dq)
    other = simulate(model, mirror.q, mirror.dq, sc.t, sc.torques, constraints=sc.constraints,
                     baumgarte=sc.baumgarte)
    assert ahead.status == other.status == "fell", (ahead.message, other.message)
    assert ahead.q[-1, THETA] == pytest.approx(DEFAULT_FALL_LIMIT, abs=1e-9)
    assert other.q[-1, THETA] == pytest.approx(-DEFAULT_FALL_LIMIT, abs=1e-9)
    # the same arithmetic with mirrored signs (measured: identical to the last bit); 1e-9 s
    # allows round-off amplified by the lean instability (e^(3 t) over 1 s)
    assert other.t_end == pytest.approx(ahead.t_end, abs=1e-9)
    np.testing.assert_allclose(MIRROR * other.q, ahead.q, rtol=0, atol=1e-9)


def test_run_starting_beyond_the_fall_limit_on_the_negative_side_falls_at_once(model):
    q = np.zeros(8)
    q[THETA] = -1.5
    traj = simulate(model, q, np.zeros(8), np.linspace(0.0, 1.0, 11))
    assert traj.status == "fell" and traj.t_end == 0.0, traj.message
    assert "at the start" in traj.message


@pytest.mark.parametrize("constraints", ["none", "projection", "baumgarte"])
def test_straight_rolling_run_completes_straight_at_constant_speed(model, constraints):
    """q0 = 0, dq0 = [v, 0, 0, 0, 5, 0, 0, 5], Mped = cv v^2 R: the analytic steady state of
    the check scenario, run forward for 3 s."""
    p = model.params
    v = p.R_rear * 5.0
    dq0 = np.array([v, 0, 0, 0, 5.0, 0, 0, v / p.R_front])
    t = 0.01 * np.arange(301)
    traj = simulate(model, np.zeros(8), dq0, t, (0.0, p.cv * v**2 * p.R_rear, 0.0),
                    constraints=constraints)
    assert traj.status == "completed", traj.message
    np.testing.assert_array_equal(traj.t, t)
    # lateral motion: the state is mirror-symmetric and nothing breaks the symmetry except
    # rounding; 1e-10 would already be a visible lean
    np.testing.assert_allclose(traj.q[:, [YC, PHI, THETA, GAMMA]], 0.0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(traj.q[:, BETA], 0.0, rtol=0, atol=1e-10)
    # speed: an exact equilibrium (ddq = 0 to rounding, tests/test_physics.py), stable in the
    # speed direction (more speed, more drag), so errors do not grow: per step DOP853 keeps the
    # local error below atol + rtol |y| ~ 5e-10 on the 5 rad/s rates; 100 steps at most: 5e-8
    np.testing.assert_allclose(traj.dq, np.broadcast_to(dq0, traj.dq.shape), rtol=0, atol=5e-8,
                               err_msg=f"speed not constant ({constraints})")
    np.testing.assert_allclose(traj.q[:, XC], v * t, rtol=0, atol=5e-8 * 3)
    np.testing.assert_allclose(traj.q[:, PSI], 5.0 * t, rtol=0, atol=5e-8 * 3)


@pytest.mark.parametrize("where", [(0, np.nan), (3, np.inf), (8 + 4, np.nan)])
def test_non_finite_initial_state_raises(model, where):
    y = np.zeros(16)
    y[where[0]] = where[1]
    with pytest.raises(ValueError, match="finite"):
        simulate(model, y[:8], y[8:], np.linspace(0, 1, 11))


@pytest.mark.parametrize("kwargs", [dict(constraints="bogus"), dict(fall_limit=0.0),
                                    dict(t_eval=[0.0, 0.2, 0.1]), dict(torques=(1.0, 2.0)),
                                    dict(torques=(0.0, np.nan, 0.0))])
def test_simulate_rejects_bad_arguments(model, kwargs):
    args = dict(t_eval=np.linspace(0, 1, 11))
    args.update(kwargs)
    t_eval = args.pop("t_eval")
    with pytest.raises(ValueError):
        simulate(model, np.zeros(8), np.zeros(8), t_eval, **args)


def _message_time(message):
    found = re.search(r"t = ([0-9]+\.[0-9]+) s", message)
    assert found, message
    return float(found.group(1))


def test_torque_turning_nan_gives_failed_partial_run(model):
    sc = SCENARIOS["stability-psid5"]  # falls only at ~1 s
    init = initial_state(model, sc)
    T_ok = np.array(sc.torques, dtype=float)

    def torque(t):
        return T_ok if t <= 0.5 else np.array([0.0, np.nan, 0.0])

    traj = simulate(model, init.q, init.dq, sc.t, torque)
    assert traj.status == "failed"
    # the failing evaluation lies inside the first step that reaches past 0.5 s (steps are a
    # few hundredths of a second here)
    t_fail = _message_time(traj.message)
    assert 0.5 < t_fail < 0.6, traj.message
    # the partial trajectory: grid samples up to the last accepted step (<= 0.5 s)
    n = traj.t.size
    np.testing.assert_array_equal(traj.t, sc.t[:n])
    assert 0.4 <= traj.t[-1] <= 0.5
    assert traj.t_end == traj.t[-1]
    for name in ("q", "dq", "ddq", "C", "T"):
        a = getattr(traj, name)
        assert a.shape[0] == n and np.all(np.isfinite(a)), name
    # and it is the real motion: the same as a clean run with the same torques, whose steps up
    # to the failure are identical (same integrator, same inputs) -- to rounding
    clean = simulate(model, init.q, init.dq, sc.t, T_ok)
    np.testing.assert_allclose(traj.q, clean.q[:n], rtol=0, atol=1e-12)
    np.testing.assert_allclose(traj.dq, clean.dq[:n], rtol=0, atol=1e-12)


def test_torque_nan_from_the_start_fails_cleanly(model):
    sc = SCENARIOS["stability-psid5"]
    init = initial_state(model, sc)
    traj = simulate(model, init.q, init.dq, sc.t, lambda t: np.array([np.nan, 0.0, 0.0]))
    assert traj.status == "failed"
    assert _message_time(traj.message) == 0.0
    for name in ("t", "q", "dq", "ddq", "C", "T"):
        assert np.all(np.isfinite(getattr(traj, name))), name


# --------------------------------------------------------------------------------------------
# 8. constraint handling
# --------------------------------------------------------------------------------------------
def test_projection_keeps_constraints_at_round_off(replay_runs, loose_runs):
    traj = replay_runs["projection"]
    assert traj.status == "completed", traj.message
    # after a projection beta solves [rD]_z = 0 to 1e-14 m and dq satisfies D dq = 0 up to
    # the rounding of a linear solve with rates ~5 (cond of D M^-1 D^T ~1e2): ~1e-13; 1e-12
    # leaves a factor 10
    worst = np.abs(traj.C).max(axis=0)
    assert worst.max() <= 1e-12, f"max |C| per row on the output grid: {worst}"
    # the output samples are projected by simulate itself, so they say nothing about the
    # integration: the states the integrator carries from step to step must be on the manifold
    # too, even at rtol 1e-6 (where the unprojected run drifts by ~4e-9 in a second). Round-off
    # of the projection: [rD]_z <= 1e-14 by solve_beta's stopping rule, D dq a few ulps of 5
    # m/s (measured <= 1e-15); 1e-13 is far below the drift
    carried, loose = loose_runs["projection"]
    assert loose.status == "completed", loose.message
    assert carried.size >= 3, "too few steps to say anything"
    assert carried.max() <= 1e-13, f"max |C| of the integrator's states per step: {carried}"


def test_baumgarte_keeps_constraints_small(replay_runs):
    traj = replay_runs["baumgarte"]
    assert traj.status == "completed", traj.message
    # Baumgarte pulls C back (rates 10/s and 120/s), so C stays at the integration-error level:
    # local error tolerance ~ rtol |dq| = 1e-10 * 5, times 2 -> 1e-9 (thesis: < 2e-3 at 1e-3)
    worst = np.abs(traj.C).max(axis=0)
    assert worst.max() <= 1e-9, f"max |C| per row: {worst}"


def test_no_stabilisation_drifts_more_than_projection(loose_runs):
    """On the integrator's own states (not simulate's projected output): without
    stabilisation the integration errors accumulate in C, with projection they are removed
    after every step. Both runs start on the same consistent state with the same exact
    accelerations, so if the projection step did nothing the two would be identical."""
    (none, t_none), (proj, t_proj) = loose_runs["none"], loose_runs["projection"]
    assert t_none.status == t_proj.status == "completed"
    # rtol 1e-6 on rates ~5 rad/s: the local errors (~1e-8 per step in dq) leave C at ~1e-9
    # after a few steps (measured 3.8e-9); the projected states stay at round-off (~1e-15)
    assert none[-1] > 1e-10, f"no drift to measure: {none}"
    assert none[-1] > 1e3 * proj.max(), f"max |C| per step: none {none}, projection {proj}"


def _off_manifold(model, row, size=1e-6):
    """The replay's consistent initial state with dq moved so that D dq = size e_row (the
    smallest such change): a velocity violation of the chosen constraint row only."""
    sc = SCENARIOS["replay"]
    init = initial_state(model, sc)
    e = np.zeros(5)
    e[row] = size
    dq = init.dq + np.linalg.lstsq(model.constraint_jacobian(init.q), e, rcond=None)[0]
    return init.q, dq, torque_input(model, sc)


def test_baumgarte_decay_of_a_height_rate_violation(model):
    """Baumgarte imposes d2h/dt2 = -2 a1 dh/dt - a2^2 h on the contact height h = [rD]_z
    exactly (D is its gradient, dD dq the rest of its second derivative), whatever the bike
    does. With a1 = a2 = 10 (thesis) the roots are a double -10: from h(0) = 0, dh/dt(0) = v0,
    h(t) = v0 t e^(-10 t). A different pair (e.g. (10, 1)) gives another curve (3.4e-8 m
    higher at 0.3 s here); starting on the manifold, as every other test does, would show
    nothing, since C then stays at integration-error size whatever the coefficients."""
    assert THESIS_BAUMGARTE == (10.0, 10.0)
    v0 = 1e-6
    q, dq, torque = _off_manifold(model, 0, v0)
    t = np.linspace(0.0, 0.3, 31)
    traj = simulate(model, q, dq, t, torque, constraints="baumgarte", rtol=1e-12, atol=1e-14)
    assert traj.status == "completed", traj.message
    # the integration's own error in C at rtol 1e-12 on rates ~5 (measured 7e-17): 1e-12 m,
    # against a signal of up to 3.7e-8 m
    np.testing.assert_allclose(traj.C[:, 0], v0 * t * np.exp(-10.0 * t), rtol=0, atol=1e-12)
    np.testing.assert_allclose(traj.C[:, 1:], 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("row", [1, 4])   # vC_x (rear contact), vD_y (front contact)
def test_baumgarte_decay_of_a_velocity_violation(model, row):
    """For a velocity constraint c = D_row dq, Baumgarte imposes dc/dt = -(2 a1 + a2^2) c:
    c(t) = c(0) e^(-120 t) for the thesis's a1 = a2 = 10 ((10, 1) would give e^(-21 t))."""
    c0 = 1e-6
    q, dq, torque = _off_manifold(model, row, c0)
    t = np.linspace(0.0, 0.05, 6)
    traj = simulate(model, q, dq, t, torque, constraints="baumgarte", rtol=1e-12, atol=1e-14)
    assert traj.status == "completed", traj.message
    # as above: integration error measured 2e-14 against a signal 1e-6 .. 2.5e-9
    np.testing.assert_allclose(traj.C[:, row], c0 * np.exp(-120.0 * t), rtol=0, atol=1e-12)
    others = [k for k in range(5) if k != row]
    np.testing.assert_allclose(traj.C[:, others], 0.0, rtol=0, atol=1e-12)


def test_without_stabilisation_a_violation_stays_as_it_was(model):
    """With the exact accelerations (D ddq = -dD dq) and nothing else, the constraint errors
    obey dc/dt = 0 for the velocity rows and d2h/dt2 = 0 for the height: a 1e-6 violation of
    vC_x stays 1e-6, a height rate of 1e-6 m/s makes h = 1e-6 t. 'none' must mean no
    Baumgarte terms at all (with them the errors would decay as in the tests above)."""
    t = np.linspace(0.0, 0.3, 31)
    for row in (0, 1):
        q, dq, torque = _off_manifold(model, row, 1e-6)
        traj = simulate(model, q, dq, t, torque, constraints="none", rtol=1e-12, atol=1e-14)
        assert traj.status == "completed", traj.message
        assert traj.settings["baumgarte"] is None
        expected = 1e-6 * t if row == 0 else np.full_like(t, 1e-6)
        # integration error as in the decay tests: 1e-12 against a 1e-6 signal
        np.testing.assert_allclose(traj.C[:, row], expected, rtol=0, atol=1e-12, err_msg=row)


def test_projection_puts_an_off_manifold_start_back(model):
    q, dq, torque = _off_manifold(model, 1, 1e-6)
    traj = simulate(model, q, dq, np.linspace(0.0, 0.1, 11), torque, constraints="projection")
    assert traj.status == "completed", traj.message
    # round-off of the projection (see test_projection_keeps_constraints_at_round_off)
    assert np.abs(traj.C).max() <= 1e-12


def test_projection_and_baumgarte_agree(replay_runs):
    """Both integrate the same motion on the constraint manifold: the Baumgarte terms are
    proportional to C, which stays at the integration-error level (~1e-11), so the two differ
    only by integration errors (rtol 1e-10) amplified by the unstable lean mode over 0.5 s
    (growth rate of a few 1/s: a factor < 10). 1e-6 is far above that and far below the
    size of any real difference in the dynamics (the motion itself is O(0.1..1))."""
    a, b = replay_runs["projection"], replay_runs["baumgarte"]
    n = 51  # 0 .. 0.5 s
    np.testing.assert_array_equal(a.t[:n], b.t[:n])
    np.testing.assert_allclose(a.q[:n], b.q[:n], rtol=0, atol=1e-6)
    np.testing.assert_allclose(a.dq[:n], b.dq[:n], rtol=0, atol=1e-6)


# --------------------------------------------------------------------------------------------
# 9. thesis contact vs disc contact
# --------------------------------------------------------------------------------------------
def test_contact_models_agree_in_check_scenario(model, disc, check):
    """theta = gamma = beta = 0: the fork's x axis is horizontal, so the rim point below the hub
    along -z4 IS the lowest point of the disc; the two models are the same motion."""
    other = run_inverse(disc, SCENARIOS["check"])
    q = check.motion.q
    # the contact points coincide (lengths ~1 m: a few ulps)
    np.testing.assert_allclose(model.points(q)["rD"], disc.points(q)["rD"], rtol=0, atol=1e-14)
    # torques and multipliers from the same 13x13 system: forces ~250 N, 1e-11 is rounding
    np.testing.assert_allclose(other.T, check.T, rtol=0, atol=1e-11)
    np.testing.assert_allclose(other.lam, check.lam, rtol=0, atol=1e-10)


def test_contact_models_differ_in_zigzag(model, disc, zigzag):
    other = run_inverse(disc, SCENARIOS["zigzag"])
    # with lean 1/3 rad and steer 1/2 rad together the points are centimetres apart, so the
    # torques differ by newton-metres; 0.1 N m and 1 mm only say "clearly not the same model"
    assert np.abs(other.T - zigzag.T).max() > 0.1
    rD_a = model.points(zigzag.motion.q)["rD"]
    rD_b = disc.points(zigzag.motion.q)["rD"]
    assert np.abs(rD_a - rD_b).max() > 1e-3
