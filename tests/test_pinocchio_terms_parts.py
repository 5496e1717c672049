"""The Pinocchio adapter's two term methods no other test calls (engines/pinocchio/engine.py,
issue 24): `Qaero(q, dq)`, the drag on the frame's CoM, and `S(q)`, the rider-torque map
(docs/engines.md, "The equations of motion": `Qaero = -cv |vG3| Jv3^T vG3`,
`S T = Jw4^T z4 Mdir + Jw2^T y2 Mped + Jw3^T x3 Mvue`).

Expected values from outside Pinocchio: the reference model's own Qaero and S (the thesis's
generated equations); Qaero rebuilt from the reference's CoM positions alone (Jv3 by central
differences of `points()['rG3']`) and held to the laws of a quadratic drag (zero at rest,
quadratic in the speed, opposing the motion: its power is -cv |vG3|^3); S in closed form at
hand-made states (the body axes and angular velocities of the joint chain written out by hand).
One state and a batch each. Each test names the planted bugs (mutmut's mutants of the two
methods, which no test reached before) it was seen failing on. ~0.1 s.
"""

from __future__ import annotations

import numpy as np
import pytest

from comparisons.judgments.terms import random_states
from reference_model import load_model
from round_off import assert_round_off

pin = pytest.importorskip("pinocchio")

from engines.pinocchio import PinocchioEngine  # noqa: E402

STATES = random_states(3, seed=23)
# a moderate hand-made state: lean, steer, pitch, wheel angles and rates of a ridden bicycle
Q0 = np.array([0.4, -0.3, 0.7, 0.15, 1.1, 0.02, 0.35, -0.8])
DQ0 = np.array([4.0, 1.5, 0.3, -0.6, 12.0, 0.05, 0.9, 11.0])
PHI, THETA, PSI, BETA, GAMMA = 2, 3, 4, 5, 6


@pytest.fixture(scope="module")
def model():
    return load_model("thesis")          # cv = 0.8 kg/m


@pytest.fixture(scope="module")
def engine(model):
    return PinocchioEngine(model)


def _jv3(model, q, h=1e-6):
    """d rG3 / dq (3, 8) by central differences of the reference's CoM position."""
    cols = []
    for k in range(8):
        e = np.zeros(8)
        e[k] = h
        cols.append((model.points(q + e)["rG3"] - model.points(q - e)["rG3"]) / (2 * h))
    return np.column_stack(cols)


def test_drag_is_the_references_for_one_state_and_a_batch(engine, model):
    """Qaero of one state is an (8,) array and of three states a (3, 8) one, each row the
    reference model's drag of that state (to round-off). Planted: the function handed to the
    batching None, q or dq None or dropped (one argument for two), a state argument None or
    missing in the kinematics call, the torques or the bias flag missing, the drag taken from
    the kinematics' sixth output (there are five), None returned for the drag. (The bias flag
    None or True gives the same drag: equivalent, not planted.)"""
    one = engine.Qaero(Q0, DQ0)
    assert isinstance(one, np.ndarray) and one.shape == (8,) and one.dtype == np.float64
    assert_round_off(one, model.Qaero(Q0, DQ0))
    many = engine.Qaero(STATES.q, STATES.dq)
    assert isinstance(many, np.ndarray) and many.shape == (3, 8) and many.dtype == np.float64
    assert_round_off(many, model.Qaero(STATES.q, STATES.dq))


def test_drag_is_minus_cv_speed_times_the_com_velocity_mapped_back(engine, model):
    """The formula from positions alone: Jv3 = d rG3 / dq by central differences (h = 1e-6 m
    or rad: truncation ~1e-12, round-off ~1e-10 per entry), vG3 = Jv3 dq, and
    Qaero = -cv |vG3| Jv3^T vG3, to 1e-7 of its size. Its power dq . Qaero is -cv |vG3|^3 < 0:
    the drag opposes the motion. Planted: as the test above (any wrong drag)."""
    J = _jv3(model, Q0)
    v = J @ DQ0
    expected = -model.params.cv * np.linalg.norm(v) * (J.T @ v)
    got = engine.Qaero(Q0, DQ0)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-7 * np.abs(expected).max())
    power = float(DQ0 @ got)
    assert power < 0
    assert power == pytest.approx(-model.params.cv * np.linalg.norm(v) ** 3, rel=1e-7)


def test_drag_is_zero_at_rest_quadratic_in_speed_and_opposes_the_motion(engine):
    """A quadratic drag -cv |v| v: none at rest (any posture), four times as large at twice
    the rates, reversed with the rates (the same magnitude), and zero on a pure wheel spin of
    the rear wheel about its own axle (the frame's CoM does not move). Planted: as the tests
    above; the rates replaced by None or missing (no drag computed from them)."""
    assert np.array_equal(engine.Qaero(Q0, np.zeros(8)), np.zeros(8))
    assert np.array_equal(engine.Qaero(STATES.q, np.zeros(8)), np.zeros((3, 8)))
    base = engine.Qaero(Q0, DQ0)
    assert np.abs(base).max() > 1.0                       # a drag worth testing (N or N m)
    assert_round_off(engine.Qaero(Q0, 2 * DQ0), 4 * base)
    assert_round_off(engine.Qaero(Q0, -DQ0), -base)
    spin = np.zeros(8)
    spin[PSI] = 30.0                                      # psi: the rear wheel's own rotation
    assert np.abs(engine.Qaero(Q0, spin)).max() < 1e-12


def test_drag_scales_with_the_drag_coefficient(model):
    """Qaero is linear in cv: none without drag (the benchmark-like cv = 0), twice as large at
    twice cv, at the same state (engines built on copies of the thesis parameters). Planted:
    as above."""
    q, dq = STATES.q[0], STATES.dq[0]
    base = PinocchioEngine(model).Qaero(q, dq)
    none = PinocchioEngine(model.with_params(model.params.replace(cv=0.0))).Qaero(q, dq)
    double = PinocchioEngine(model.with_params(model.params.replace(cv=2 * model.params.cv)))
    assert np.array_equal(none, np.zeros(8))
    assert_round_off(double.Qaero(q, dq), 2 * base)


def test_torque_map_is_the_references_for_one_state_and_a_batch(engine, model):
    """S of one state is (8, 3) and of three states (3, 8, 3), each the reference model's map
    (to round-off). Planted: the Jacobians computed with the model, data or q None or missing
    (Pinocchio refuses), the function handed to the batching None or missing, q None."""
    one = engine.S(Q0)
    assert isinstance(one, np.ndarray) and one.shape == (8, 3) and one.dtype == np.float64
    assert_round_off(one, model.S(Q0))
    many = engine.S(STATES.q)
    assert isinstance(many, np.ndarray) and many.shape == (3, 8, 3)
    assert_round_off(many, model.S(STATES.q))


def test_torque_map_in_closed_form(engine):
    """The chain by hand (R3 = Rz(phi) Rx(theta) Ry(beta), the fork turned by gamma about z3,
    the rear wheel Rz(phi) Rx(theta) Ry(psi)); column j of S holds the component along the
    torque's axis of the body's angular velocity per unit rate:
    steer (z4 on the fork): cos(theta) cos(beta) dphi + sin(beta) dtheta + dgamma;
    pedal (y2 on the rear wheel): sin(theta) dphi + dpsi;
    anti-roll (x3 on the frame): -cos(theta) sin(beta) dphi + cos(beta) dtheta;
    nothing on xc, yc, eps (translations, and the front wheel carries no torque), nor on beta
    (its axis y3 is normal to x3 and z4). Also the first state after another state's call
    (the Jacobians refreshed by each call). Planted: as the test above."""
    for q in (Q0, STATES.q[1], Q0):
        th, be = q[THETA], q[BETA]
        want = np.zeros((8, 3))
        want[PHI] = [np.cos(th) * np.cos(be), np.sin(th), -np.cos(th) * np.sin(be)]
        want[THETA] = [np.sin(be), 0.0, np.cos(be)]
        want[PSI, 1] = 1.0
        want[GAMMA, 0] = 1.0
        np.testing.assert_allclose(engine.S(q), want, rtol=0, atol=1e-14)
