"""Parts of Drake's frame kinematics (engines/drake/kinematics.py), issue 24: the velocity of
a body's material point, `_Body.point_velocity`, on hand-built body states (no plant, no
context). Expected values come from rigid-body kinematics, v_P = v_O + omega x (P - O): a
wheel rolling without slip (its contact point at rest, its top at twice the hub's speed, its
front point moving down at the hub's speed), numpy's own cross product for a general state,
and the rigid-body law that two material points' relative velocity is perpendicular to the
segment between them. Planted bugs each test was seen failing on are named in it."""

import numpy as np

from engines.drake.kinematics import _Body

R, V = 0.35, 4.0          # wheel radius (m), hub speed (m/s)


def _body(o, w, v):
    """A body with origin o, angular velocity w and origin velocity v (world); the
    Jacobians (not used by point_velocity) zero."""
    zero = np.zeros((3, 8))
    return _Body(np.eye(3), np.asarray(o, float), zero, zero, np.asarray(w, float),
                 np.asarray(v, float))


def test_a_wheel_rolling_without_slip_has_its_contact_point_at_rest():
    """A wheel of radius R with its hub at (1.5, 0, R) moving at V along x and spinning at
    V/R about the axle y: the ground contact point (1.5, 0, 0) is at rest, the top
    (1.5, 0, 2R) moves at 2V, the front point (1.5 + R, 0, R) at (V, 0, -V). Planted: the
    spin's share subtracted (v - w x r), r = p + o instead of p - o."""
    wheel = _body([1.5, 0.0, R], [0.0, V / R, 0.0], [V, 0.0, 0.0])
    np.testing.assert_allclose(wheel.point_velocity(np.array([1.5, 0.0, 0.0])), [0, 0, 0],
                               atol=1e-12)
    np.testing.assert_allclose(wheel.point_velocity(np.array([1.5, 0.0, 2 * R])),
                               [2 * V, 0, 0], atol=1e-12)
    np.testing.assert_allclose(wheel.point_velocity(np.array([1.5 + R, 0.0, R])),
                               [V, 0, -V], atol=1e-12)
    np.testing.assert_allclose(wheel.point_velocity(wheel.o), wheel.v, atol=0)


def test_a_general_point_velocity_is_the_origins_plus_omega_cross_r():
    """A tumbling body at a general state: v_P = v_O + np.cross(omega, P - O) for several
    points, and any two points' relative velocity is perpendicular to the segment between
    them (their distance does not change). Planted: the angular velocity or the lever arm
    replaced by None, either argument dropped (each a TypeError)."""
    rng = np.random.default_rng(11)
    o, w, v = rng.normal(size=(3, 3))
    body = _body(o, w, v)
    points = rng.normal(size=(4, 3))
    got = np.array([body.point_velocity(p) for p in points])
    np.testing.assert_allclose(got, v + np.cross(w, points - o), rtol=1e-13, atol=1e-13)
    for i in range(4):
        for j in range(i):
            assert abs((got[i] - got[j]) @ (points[i] - points[j])) < 1e-12
