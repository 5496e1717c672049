"""The claims judges (comparisons/judgments/claims.py) exactly at their thresholds and their
evidence word for word, on hand-made runs (no engine runs).

The thresholds are docs/report.md's reading of the thesis's words ("The thesis's claims"):
"identical" = theta and gamma *within* 1e-3 rad (a deviation of exactly 1e-3 is within);
"constraint error below 2e-3" (exactly 2e-3 is not below); the check's forward run "speed
constant to 1e-9 relative and no lean or yaw beyond 1e-9 rad" (exactly 1e-9 is not beyond);
"frame in a vertical plane" = |theta| *below* 0.05 rad, looked for *after* 0.1 s (a sample at
exactly 0.05 rad is not below, one at exactly 0.1 s is not after). Each run is built so that
the judged number equals the threshold exactly in floating point (hand arithmetic in each
test), so '<' and '<=' part. The evidence strings are the judges' own sentences, asserted
whole where the existing tests read only their numbers.

Each test names the planted bugs (mutmut's survivors of the module's first measurement) it
fails on.
"""

from __future__ import annotations

import numpy as np
import pytest

from comparisons.judgments.claims import (CLAIMS, CONSTRAINT_ERROR, CRUISE_SPEED, DEPART,
                                          UPRIGHT, VERTICAL)
from engines.runs import Run
from reference_model import load_model

JUDGE = {c.id: c.judge for c in CLAIMS}
THETA, PHI, PSI, GAMMA = 3, 2, 4, 6


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis")


def _run(scenario, t, q=None, dq=None, status="completed", kind="forward", T=None):
    t = np.asarray(t, dtype=float)
    q = np.zeros((t.size, 8)) if q is None else q
    dq = np.zeros((t.size, 8)) if dq is None else dq
    return Run("reference", scenario, "thesis", kind, status, status, 0.0, t, q, dq, T=T)


def _judge(claim, runs, model=None):
    return JUDGE[claim]("reference", {(r.engine, r.scenario): r for r in runs}, model)


# -- check (5.3) ------------------------------------------------------------------------------------

#: psi_dot = 1953125 / 2**19 = 1e9 / 2**28 rad/s (exact in binary), and that plus 2**-28: their
#: difference is exactly 2**-28 (Sterbenz), and 2**-28 / (1e9 / 2**28) = 1e-9 exactly in the
#: reals, so the relative change rounds to the double 1e-9, CRUISE_SPEED itself
PSI_DOT = 1953125 / 2 ** 19
T6 = np.arange(0.0, 6.285, 0.01)


def _forward(change=0.0, lean=0.0, yaw=0.0):
    dq = np.zeros((T6.size, 8))
    dq[:, PSI] = PSI_DOT
    dq[300, PSI] += change
    q = np.zeros((T6.size, 8))
    q[200, THETA], q[400, PHI] = -lean, yaw
    return _run("check-forward", T6, q=q, dq=dq)


def _inverse(mped, mdir=0.0):
    T = np.tile([0.0, mped, 0.0], (T6.size, 1))
    T[100, 0] = mdir
    return _run("check", T6, kind="inverse", T=T)


def test_the_cruise_bounds_are_inclusive(thesis):
    """The forward check's speed change of exactly 1e-9 relative (see PSI_DOT), a lean of
    exactly 1e-9 rad and a yaw of exactly 1e-9 rad are each within the documented bound ('to
    1e-9', 'no lean or yaw beyond 1e-9 rad'): reproduced; twice the change is not. Planted:
    '<' for '<=' in the speed, the lean or the yaw bound."""
    assert CRUISE_SPEED == 1e-9 and UPRIGHT == 1e-9
    assert float(np.ptp(_forward(2.0 ** -28).dq[:, PSI]) / PSI_DOT) == 1e-9
    for run in (_forward(change=2.0 ** -28), _forward(lean=1e-9), _forward(yaw=1e-9)):
        v = _judge("check-pedal-torque", [run], thesis)
        assert v.verdict == "reproduced", v
    v = _judge("check-pedal-torque", [_forward(change=2.0 ** -27)], thesis)
    assert v.verdict == "not reproduced", v


def test_the_checks_evidence_is_both_parts_joined(thesis):
    """The check's evidence, whole: the inverse part (Mped = cv (5 R_rear)^2 R_rear = 0.8 x
    1.6^2 x 0.32 = 0.65536 N m for the thesis bicycle: drag cv v^2 at v = 5 rad/s x 0.32 m,
    times the wheel radius) and the forward part, joined by '; '; with neither run, the
    reason (a steer torque of 1e-13 N m, within 1e-12 x Mped, is the largest error). Planted:
    the joining '; ' changed; the reason's words changed."""
    v = _judge("check-pedal-torque", [_inverse(0.65536, mdir=1e-13), _forward(yaw=1e-9)],
               thesis)
    assert v.verdict == "reproduced", v
    assert v.evidence == (
        "inverse: Mped = 0.65536 N m constant, Mdir = Mvue = 0 to 1.0e-13 N m "
        "(bound 1e-12 x Mped); forward under that torque: psi_dot varies by 0.0e+00 (relative, "
        "bound 1e-09), max |theta| 0.0e+00 rad, max |phi| 1.0e-09 rad over 6.28 s (completed)")
    none = _judge("check-pedal-torque", [], thesis)
    assert (none.verdict, none.evidence) == (
        "not assessed", "neither check nor check-forward run on this engine")


# -- replay (6.2.2.1) --------------------------------------------------------------------------------

def test_a_replay_exactly_1_mrad_from_the_zigzag_is_identical():
    """'identical' = theta and gamma within 1e-3 rad: a replay whose lean is exactly 1e-3 rad
    off the (upright) zig-zag's, |1e-3 - 0| = 1e-3 exactly, is reproduced over the whole run.
    Planted: '>=' for '>' in the departure test."""
    assert DEPART == 1e-3
    zig = _run("zigzag", T6, kind="inverse")
    q = np.zeros((T6.size, 8))
    q[:, THETA] = 1e-3
    v = _judge("replay-identical", [zig, _run("replay", T6, q=q)])
    assert v.verdict == "reproduced", v
    assert v.evidence == "theta and gamma within 1.0e-03 rad of the zig-zag over the whole 6.28 s"


def test_the_replays_reasons_for_not_judging_are_said_whole():
    """Without the zig-zag, and with a replay sharing one sample with it, the verdict is 'not
    assessed' and the evidence the judge's sentence. Planted: either sentence's words changed
    or cased."""
    one = _run("replay", [0.0], status="fell")
    v = _judge("replay-identical", [one])
    assert (v.verdict, v.evidence) == (
        "not assessed", "the zigzag inverse kinematics was not run in this report")
    v = _judge("replay-identical", [_run("zigzag", T6, kind="inverse"), one])
    assert (v.verdict, v.evidence) == (
        "not assessed", "the replay and the zig-zag share 1 sample(s) (replay fell at 0.000 s): "
                        "nothing past the initial state to compare")


def test_a_constraint_error_of_exactly_2e_3_is_not_below_it(thesis):
    """'constraint error below 2e-3': upright and at rest, the rear contact moved forward at
    exactly 2e-3 m/s with the wheels not turning slides both contact points at that speed, so
    max |C| = 2e-3 exactly, which is not below the bound. Planted: '<=' for '<'."""
    assert CONSTRAINT_ERROR == 2e-3
    dq = np.zeros((T6.size, 8))
    dq[:, 0] = 2e-3
    v = _judge("replay-constraint-error", [_run("replay", T6, dq=dq)], thesis)
    assert v.verdict == "not reproduced", v
    assert v.evidence == "max |C| = 2.0e-03 (bound 2e-03) up to 6.28 s (completed)"


# -- stability-psid10 (Fig. 6-7) ----------------------------------------------------------------------

T2 = np.array([0.0, 0.05, 0.1, 0.15, 0.2])


def _psid10(theta, status="completed"):
    q = np.zeros((T2.size, 8))
    q[:, THETA] = theta
    return _run("stability-psid10", T2, q=q, status=status)


def test_vertical_means_below_0_05_rad_after_0_1_s():
    """'frame in a vertical plane' = |theta| below 0.05 rad, looked for after 0.1 s: upright
    only up to the sample at exactly 0.1 s is never upright after it; exactly 0.05 rad later
    is not below; upright after 0.1 s and ending at exactly 0.05 rad came to the vertical but
    does not stay. Planted: '>=' for '>' at 0.1 s; '<=' for '<' in coming upright or in
    staying."""
    assert VERTICAL == 0.05
    v = _judge("stability-psid10", [_psid10([0.0, 0.0, 0.0, 0.2, 0.3])])
    assert v.verdict == "not reproduced", v
    assert v.evidence.startswith("|theta| never below 0.05 rad after 0.1 s; ")
    v = _judge("stability-psid10", [_psid10([0.2, 0.2, 0.2, 0.05, 0.05])])
    assert v.verdict == "not reproduced", v
    v = _judge("stability-psid10", [_psid10([0.2, 0.2, 0.2, 0.01, 0.05])])
    assert v.verdict == "partly", v
    assert v.evidence.startswith("the frame comes to the vertical (|theta| < 0.05 rad at 0.15 s) "
                                 "but does not stay: completed to 0.20 s")
