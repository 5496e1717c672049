"""The parts of reference_model/moore.py that tests/test_moore.py does not pin: the exact
user-facing messages of a refused call (a MooreState passed whole to ``from_moore``; rates or
accelerations of another shape than the coordinates, which numpy would otherwise broadcast
silently; the argument named in ``rates_from_moore``'s messages), and the inverse rate map
``rates_from_moore`` against a finite difference of the inverse position map ``from_moore``,
on configurations whose Moore coordinates are derived by hand below.

Expected values: the messages are the module's contract with a user (its docstrings name the
arguments ``moore_q``, ``moore_u``, ``moore_du``, ``q``, ``dq``, ``ddq`` and the shape rule
"(8,) or (..., 8)", "of the same shape"); the configurations come from the geometry of the
two frames (thesis z up, y left; Moore's N' z down, y right, v' = diag(1, -1, -1) v), worked
out in each test's docstring. Each test names the planted bugs (mutmut's survivors of the
module's measurement) it fails on.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from reference_model.moore import from_moore, rates_from_moore, to_moore

SHAPE_RULE = "must have shape (8,) or (..., 8) (last axis: the 8 coordinates); got shape"


def _message(call) -> str:
    """The one-line message of the ValueError or TypeError the call raises."""
    with pytest.raises((ValueError, TypeError)) as info:
        call()
    return str(info.value)


# -- refused calls, their messages ----------------------------------------------------------


def test_a_moore_state_passed_whole_is_refused_with_the_call_to_make_instead():
    """``from_moore`` takes arrays; given the MooreState that ``to_moore`` returns it raises a
    TypeError whose message says so and spells out the two calls to make instead, exactly.
    Planted: the message wrapped in XX, lower-cased ("moorestate") or upper-cased, in either
    of its two parts (from_moore__mutmut_2 .. 6)."""
    state = to_moore(np.zeros(8), np.zeros(8), np.zeros(8))
    with pytest.raises(TypeError) as info:
        from_moore(state)
    assert str(info.value) == ("from_moore takes arrays; for a MooreState s call "
                               "from_moore(s.q, s.u) (or from_moore(s.q, s.u, s.du))")
    # and the calls it names do work: they give back the zero state
    q, dq, ddq = from_moore(state.q, state.u, state.du)
    for x in (q, dq, ddq):
        np.testing.assert_array_equal(x, np.zeros(8))


def test_rates_from_moore_names_its_argument_moore_u_in_both_refusals():
    """``rates_from_moore`` refuses a vector of 5 and a vector of text, naming the argument as
    ``moore_u`` (the name ``from_moore`` also uses for Moore's rates), exactly.
    Planted: the argument's name None ("None must have shape ..."), wrapped in XX or
    upper-cased (rates_from_moore__mutmut_3, 6, 7)."""
    assert _message(lambda: rates_from_moore(np.zeros(5))) == f"moore_u {SHAPE_RULE} (5,)"
    assert _message(lambda: rates_from_moore(np.zeros((3, 7)))) == f"moore_u {SHAPE_RULE} (3, 7)"
    assert _message(lambda: rates_from_moore(["a"] * 8)) == (
        "moore_u must be numbers of shape (8,) or (..., 8); got dtype <U1")


@pytest.mark.parametrize("q_shape, u_shape", [((8,), (2, 8)), ((3, 8), (8,)), ((3, 8), (1, 8))])
def test_moore_u_of_another_shape_than_moore_q_is_refused(q_shape, u_shape):
    """Moore's rates must have the shape of his coordinates: u of (2, 8) for one state, or
    one u of (8,) / (1, 8) for a batch of three states (which numpy would broadcast into three
    copies of the same rates, silently), are refused naming ``moore_u`` and both shapes.
    Planted: the shape check of moore_u dropped (from_moore__mutmut_21, 24: the call returns
    rates of the wrong shape)."""
    message = _message(lambda: from_moore(np.zeros(q_shape), np.zeros(u_shape)))
    assert message == (f"moore_u must have the same shape as the coordinates, {q_shape}; "
                       f"got shape {u_shape}")


@pytest.mark.parametrize("q_shape, a_shape", [((8,), (2, 8)), ((3, 8), (8,))])
def test_accelerations_of_another_shape_than_the_coordinates_are_refused(q_shape, a_shape):
    """The same rule for the accelerations, both ways: ``to_moore``'s ddq and ``from_moore``'s
    moore_du of another shape than the coordinates are refused, naming the argument.
    Planted: the shape check of ddq dropped (to_moore__mutmut_28, 31: the call returns
    accelerations of the wrong shape)."""
    z_q, z_a = np.zeros(q_shape), np.zeros(a_shape)
    rule = f"must have the same shape as the coordinates, {q_shape}; got shape {a_shape}"
    assert _message(lambda: to_moore(z_q, z_q, z_a)) == f"ddq {rule}"
    assert _message(lambda: from_moore(z_q, z_q, z_a)) == f"moore_du {rule}"


# -- rates: the inverse rate map against a finite difference of the inverse position map ----


def _moore_of_hand_configuration(phi, theta, beta, psi, gamma, eps, xc=0.0, yc=0.0):
    """Moore's q1..q8 of a thesis configuration, derived by hand from the frames' geometry
    (not from the module's table):

    * rear contact [xc, yc, 0] (y left) is [xc, -yc, 0] in N' (y right): q1 = xc, q2 = -yc;
    * heading: the wheel plane's forward axis [cos phi, sin phi, 0] (thesis) is
      [cos phi, -sin phi, 0] in N' = Rz(q3) [1, 0, 0]: q3 = -phi;
    * lean: the frame's up axis Rx(theta) [0, 0, 1] = [0, -sin theta, cos theta] is
      [0, sin theta, -cos theta] in N', minus Moore's down axis Rx(q4) [0, 0, 1]: q4 = theta;
    * pitch: the steer axis Ry(beta) z = [sin beta, 0, cos beta] is [sin beta, 0, -cos beta]
      in N', minus Moore's c3 = Ry(q5) z = [sin q5, 0, cos q5]: q5 = -beta;
    * rear wheel: its x axis Ry(psi) x = [cos psi, 0, -sin psi] is [cos psi, 0, sin psi] in
      N' = Ry(q5 + q6) x = [cos(q5 + q6), 0, -sin(q5 + q6)]: q5 + q6 = -psi, q6 = beta - psi;
    * steer and front wheel: turns about the frame's up axis and the fork's left axis are
      turns about Moore's down axis and right axis by minus the angle: q7 = -gamma,
      q8 = -eps (both relative, as in the thesis).
    """
    return np.array([xc, -yc, -phi, theta, -beta, beta - psi, -gamma, -eps])


def test_hand_derived_configurations_map_back_to_the_thesis_state():
    """Pure yaw, pure lean, pure pitch with the wheel held in the frame, pure steer, pure
    wheel spins, and a mixed one: ``from_moore`` of the hand-derived Moore coordinates gives
    the thesis configuration back, and ``to_moore`` gives those coordinates. Guards the
    position maps that the rates below are differenced from."""
    cases = [
        dict(phi=0.7, theta=0.0, beta=0.0, psi=0.0, gamma=0.0, eps=0.0),
        dict(phi=0.0, theta=0.3, beta=0.0, psi=0.0, gamma=0.0, eps=0.0),
        dict(phi=0.0, theta=0.0, beta=-math.pi / 10, psi=-math.pi / 10, gamma=0.0, eps=0.0),
        dict(phi=0.0, theta=0.0, beta=0.0, psi=0.0, gamma=0.5, eps=0.0),
        dict(phi=0.0, theta=0.0, beta=0.0, psi=1.1, gamma=0.0, eps=-2.3),
        dict(phi=-1.2, theta=0.25, beta=0.15, psi=4.0, gamma=-0.6, eps=7.5, xc=3.0, yc=-1.5),
    ]
    for c in cases:
        thesis = np.array([c.get("xc", 0.0), c.get("yc", 0.0), c["phi"], c["theta"], c["psi"],
                           c["beta"], c["gamma"], c["eps"]])
        moore = _moore_of_hand_configuration(**c)
        q, dq = from_moore(moore)
        assert dq is None
        np.testing.assert_allclose(q, thesis, rtol=0, atol=1e-15, err_msg=str(c))
        np.testing.assert_allclose(to_moore(thesis).q, moore, rtol=0, atol=1e-15, err_msg=str(c))
    # the pitched frame with its wheel held: Moore's wheel angle relative to the frame is 0
    assert _moore_of_hand_configuration(0, 0, -0.3, -0.3, 0, 0)[5] == 0.0


def test_rates_from_moore_is_the_derivative_of_from_moore_along_u():
    """Thesis rates are the time derivative of the thesis coordinates: for Moore's state
    (m, u), rates_from_moore(u) = d/dt from_moore(m + t u) at t = 0, here the central finite
    difference with h = 1e-3 (exact up to round-off, the map being linear), on one state and
    on a batch (..., 8), and the same for accelerations through from_moore's third argument.
    Upright straight running by hand: u1 = v, u6 = -v/rR, u8 = -v/rF (wheels rolling forward
    turn backwards about Moore's right-pointing axles) is xc' = v, psi' = v/rR, eps' = v/rF."""
    rng = np.random.default_rng(2015)
    m = rng.uniform(-2, 2, (4, 3, 8))
    u = rng.uniform(-5, 5, (4, 3, 8))
    h = 1e-3
    fd = (from_moore(m + h * u)[0] - from_moore(m - h * u)[0]) / (2 * h)
    np.testing.assert_allclose(rates_from_moore(u), fd, rtol=0, atol=1e-11)
    np.testing.assert_allclose(rates_from_moore(u[1, 2]), fd[1, 2], rtol=0, atol=1e-11)
    du = rng.uniform(-9, 9, (4, 3, 8))
    _, dq, ddq = from_moore(m, u, du)
    np.testing.assert_allclose(dq, fd, rtol=0, atol=1e-11)
    fd2 = (from_moore(u + h * du)[0] - from_moore(u - h * du)[0]) / (2 * h)
    np.testing.assert_allclose(ddq, fd2, rtol=0, atol=1e-11)

    v, r_rear, r_front = 4.0, 0.5, 0.25
    upright = rates_from_moore([v, 0, 0, 0, 0, -v / r_rear, 0, -v / r_front])
    np.testing.assert_allclose(upright, [v, 0, 0, 0, v / r_rear, 0, 0, v / r_front],
                               rtol=0, atol=1e-15)
