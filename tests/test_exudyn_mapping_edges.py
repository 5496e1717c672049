"""Edges of the map between the thesis's coordinates and the body poses
(engines/exudyn/mapping.py) that the round trips of tests/test_exudyn.py do not reach: the
precision of the map when its inputs come in single precision (a float32 record of the sensor
data, a float32 angle), and `unwrap_angles` on a fast ride, whose contact-point coordinates
move by more than pi per sample and are no angles. Each test names the planted bugs (mutmut's
survivors of the module's first measurement) it fails on.

Expected values: the rotations written out again in tests/exudyn_checks.py (docs/engines.md's
second formulation) evaluated in double precision, the same map on the float64 copy of the same
numbers (the module converts its inputs to float64 first), and the thesis's coordinate
definitions (docs/model.md: xc, yc are the rear contact point's position, not angles). Pure
numpy: no Exudyn needed, well under a second.
"""

from __future__ import annotations

import numpy as np
import pytest

from engines.exudyn import mapping
from engines.exudyn.mapping import poses_to_q, unwrap_angles, velocities_to_dq
from exudyn_checks import Rx, Ry, Rz, random_states, rotations

#: float32 has a 24-bit mantissa: one rounding of a number of size ~1 is ~6e-8, so a map that
#: computes in single precision is off by ~1e-7 and more; the same float64 arithmetic is exact
SINGLE = 1e-9


@pytest.fixture(scope="module")
def record32(disc):
    """A float32 record of what the redundant build's sensors give for 12 general states: the
    rear hub position and the four rotation matrices (the rotations of exudyn_checks, the hub
    [xc, yc, 0] + A_lean [0, 0, R_rear] by docs/model.md), and angular velocities and a hub
    velocity of size ~10 (the map is linear in them: any vectors are valid inputs)."""
    q, _, rng = random_states(12, seed=31)
    R = disc.params.R_rear
    poses = {b: [] for b in ("r2", 2, 3, 4, 5)}
    for qi in q:
        A = rotations(qi)
        poses["r2"].append(np.array([qi[0], qi[1], 0.0]) + A["lean"] @ np.array([0.0, 0.0, R]))
        for b in (2, 3, 4, 5):
            poses[b].append(A[b])
    poses = {k: np.array(v, dtype=np.float32) for k, v in poses.items()}
    vel = {k: rng.uniform(-10, 10, (len(q), 3)).astype(np.float32)
           for k in ("v2", 2, 3, 4, 5)}
    return q, poses, vel


def _as64(d):
    return {k: v.astype(np.float64) for k, v in d.items()}


def test_a_float32_pose_record_is_mapped_in_double_precision(disc, record32):
    """Poses stored in float32 give exactly the q of the float64 copy of the same numbers (the
    map converts first, then computes in double precision), and that q is the states' own to
    the float32 rounding of the poses (angles to whole turns).
    Planted: the conversion to float dropped or dtype=None in poses_to_q (theta, beta, phi and
    the joint angles then computed by arctan2 in float32: off by ~1e-7)."""
    q, p32, _ = record32
    p64 = _as64(p32)
    args = ("r2", 2, 3, 4, 5)
    got = poses_to_q(disc.params, *(p32[k] for k in args))
    want = poses_to_q(disc.params, *(p64[k] for k in args))
    assert got.dtype == np.float64
    np.testing.assert_allclose(got, want, rtol=0, atol=SINGLE)
    turns = (got - q)[:, 2:] / (2 * np.pi)
    assert np.abs(got[:, :2] - q[:, :2]).max() < 1e-5          # metres, float32 of ~10 m
    assert np.abs(turns - np.round(turns)).max() < 1e-6


def test_a_float32_velocity_record_is_mapped_in_double_precision(disc, record32):
    """Angular velocities and the hub velocity stored in float32 give the dq of the float64
    copy of the same numbers: the relative angular velocities w4 - w3 and w5 - w4 (steer and
    front-wheel rates) are differences taken in double precision, not rounded to float32.
    Planted: the conversion to float dropped or dtype=None on v2, w2..w5 in velocities_to_dq
    (w4 - w3 rounded to float32: dgamma, deps off by ~1e-6)."""
    q, _, v32 = record32
    v64 = _as64(v32)
    args = ("v2", 2, 3, 4, 5)
    got = velocities_to_dq(disc.params, q, *(v32[k] for k in args))
    want = velocities_to_dq(disc.params, q, *(v64[k] for k in args))
    assert got.dtype == np.float64
    np.testing.assert_allclose(got, want, rtol=0, atol=SINGLE)
    # the relative rates by hand: (w4 - w3) . A3 e_z and (w5 - w4) . A4 e_y, in float64
    for i, qi in enumerate(q):
        A = rotations(qi)
        w = {b: v64[b][i] for b in (3, 4, 5)}
        assert abs(got[i, 6] - (w[4] - w[3]) @ A[3][:, 2]) < 1e-12
        assert abs(got[i, 7] - (w[5] - w[4]) @ A[4][:, 1]) < 1e-12


@pytest.mark.parametrize("name, hand", [("Rx", Rx), ("Ry", Ry), ("Rz", Rz)])
def test_a_float32_angle_gives_the_double_precision_rotation(name, hand):
    """The elementary rotations of a float32 angle (one, and a batch) are float64 matrices
    equal to the hand-written rotation of that angle's float64 value: the cosine and sine are
    taken in double precision.
    Planted: the conversion to float dropped or dtype=None in _rot (cos, sin in float32: a
    float32 matrix off by ~3e-8)."""
    rot = getattr(mapping, name)
    angles = np.array([0.3, -1.2, 2.9, 1e-3], dtype=np.float32)
    one = rot(angles[0])
    assert one.dtype == np.float64 and one.shape == (3, 3)
    np.testing.assert_allclose(one, hand(float(angles[0])), rtol=0, atol=1e-15)
    batch = rot(angles)
    assert batch.dtype == np.float64 and batch.shape == (4, 3, 3)
    for a, m in zip(angles, batch):
        np.testing.assert_allclose(m, hand(float(a)), rtol=0, atol=1e-15)


def test_unwrap_leaves_the_contact_point_of_a_fast_ride_alone():
    """A ride at 60 m/s sampled every 0.1 s: xc gains 6 m a sample and yc loses 4 m, jumps
    larger than pi that are distances, not wrapped angles (docs/model.md: xc, yc are the rear
    contact point's position): unwrap_angles leaves them exactly as they come, also when q0's
    contact point is elsewhere (only the angles are shifted by whole turns, psi here by two),
    while psi, wrapped, is made continuous.
    Planted: the index of the angles replaced by None (every column unwrapped and shifted,
    xc, yc included)."""
    n = 6
    q = np.zeros((n, 8))
    q[:, 0] = 6.0 * np.arange(n)                       # xc: 0, 6, 12, ... m
    q[:, 1] = 2.0 - 4.0 * np.arange(n)                 # yc: 2, -2, -6, ... m
    q[:, 4] = 4 * np.pi + 0.5 + 2.0 * np.arange(n)     # psi: two turns up, 2 rad a sample
    wrapped = q.copy()
    wrapped[:, 2:] = (wrapped[:, 2:] + np.pi) % (2 * np.pi) - np.pi
    out = unwrap_angles(wrapped)
    assert np.array_equal(out[:, :2], q[:, :2])
    np.testing.assert_allclose(out[:, 4], q[:, 4] - 4 * np.pi, atol=1e-12)
    q0 = q[0].copy()
    q0[:2] = [-50.0, 30.0]                             # a start elsewhere: no turns for xc, yc
    out = unwrap_angles(wrapped, q0)
    assert np.array_equal(out[:, :2], q[:, :2])
    np.testing.assert_allclose(out[:, 2:], q[:, 2:], atol=1e-12)
