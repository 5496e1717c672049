"""The claims judges (comparisons/judgments/claims.py) on hand-made runs: every verdict of every judge.

No engine runs here: each `Run` is built from synthetic arrays chosen to sit clearly on one
side of a judge's threshold (the thresholds are the plain reading of the thesis's words, see
claims.py), and each test checks the verdict *and* that the evidence states the numbers the
verdict rests on. The only model used is the thesis's (parameters for the check's pedal
torque; constraint residuals for the replay's constraint error).
"""

import re

import numpy as np
import pytest

from comparisons.judgments.claims import (CHECK_RELATIVE, CLAIMS, CONSTRAINT_ERROR, CRUISE_SPEED, DEPART,
                                QUICK_FALL, SOME_METRE, VERTICAL, judge_claims)
from engines.runs import Run

VERDICTS = {"reproduced", "partly", "not reproduced", "not assessed"}
JUDGE = {c.id: c.judge for c in CLAIMS}
DT = 0.01
THETA, PSI, GAMMA = 3, 4, 6


def run(scenario, status="completed", t_end=2.0, q=None, dq=None, engine="reference",
        kind="forward", T=None, message=""):
    """A Run on the 0.01 s grid up to t_end (a fall adds its event row off the grid)."""
    t = np.arange(0.0, t_end + DT / 2, DT)
    if status == "fell" and not np.isclose(t[-1], t_end):
        t = np.append(t, t_end)
    n = t.size
    q = np.zeros((n, 8)) if q is None else q(t)
    dq = np.zeros((n, 8)) if dq is None else dq(t)
    return Run(engine, scenario, "thesis", kind, status, message or status, 0.0, t, q, dq, T=T)


def travelling(distance, direction=(0.6, 0.8)):
    """q(t) for a run whose rear contact moves `distance` metres from (3, -4) m by its end,
    along ``direction`` (a unit vector)."""
    def q(t):
        out = np.zeros((t.size, 8))
        out[:, 0] = 3.0 + direction[0] * distance * t / t[-1]
        out[:, 1] = -4.0 + direction[1] * distance * t / t[-1]
        return out
    return q


def number(evidence, pattern):
    """The float the regex group captures in the evidence (so the test reads it back)."""
    found = re.search(pattern, evidence)
    assert found, f"{pattern!r} not in {evidence!r}"
    return float(found.group(1))


def judge(claim_id, runs, model=None, engine="reference"):
    v = JUDGE[claim_id](engine, {(r.engine, r.scenario): r for r in runs}, model)
    assert v.verdict in VERDICTS
    return v


# -- every claim: a scenario that was not run, or failed, is "not assessed" ----------------------

@pytest.mark.parametrize("claim", [c for c in CLAIMS if c.id != "check-pedal-torque"],
                         ids=lambda c: c.id)
@pytest.mark.parametrize("status", ["missing", "not run", "failed"])
def test_missing_or_failed_scenario_is_not_assessed(thesis, claim, status):
    runs = {}
    if claim.id == "replay-identical":
        runs[("reference", "zigzag")] = run("zigzag", kind="inverse", t_end=6.28)
    for sc in claim.scenarios:
        if sc != "zigzag" and status != "missing":
            runs[("reference", sc)] = run(sc, status=status, t_end=0.0,
                                          message="boom" if status == "failed" else "")
    v = claim.judge("reference", runs, thesis)
    assert v.verdict == "not assessed", v
    if status == "missing":
        assert "not run in this report" in v.evidence
    else:
        assert status in v.evidence
        if status == "failed":
            assert "boom" in v.evidence   # the engine's own message is passed on


# -- check (5.3): constant pedal torque balancing the drag ------------------------------------

def _mped(model):
    """Mped = cv v^2 R_rear with v = 5 R_rear (straight rolling at psi_dot = 5 rad/s)."""
    p = model.params
    return p.cv * (5.0 * p.R_rear) ** 2 * p.R_rear


def _check_runs(model, torque_error=0.0, speed_change=0.0, lean=0.0, yaw=0.0,
                forward_status="completed"):
    inv = run("check", kind="inverse", t_end=6.28)
    inv.T = np.tile([0.0, _mped(model), 0.0], (inv.t.size, 1))
    inv.T[100, 0] = torque_error

    def rates(t):
        dq = np.zeros((t.size, 8))
        dq[:, PSI] = 5.0 * (1 + speed_change * t / t[-1])
        return dq

    def coords(t):
        q = np.zeros((t.size, 8))
        q[:, THETA] = lean * np.sin(t)
        q[:, 2] = yaw * np.sin(t)
        return q

    return [inv, run("check-forward", forward_status, t_end=6.28, q=coords, dq=rates)]


def test_check_reproduced(thesis):
    v = judge("check-pedal-torque", _check_runs(thesis, torque_error=1e-16), thesis)
    assert v.verdict == "reproduced", v
    assert number(v.evidence, r"Mped = (\S+) N m") == pytest.approx(_mped(thesis), rel=1e-5)
    assert number(v.evidence, r"to (\S+) N m") == pytest.approx(1e-16, rel=0.05)


def test_check_partly_when_the_inverse_torque_is_wrong(thesis):
    bad = 2 * CHECK_RELATIVE * _mped(thesis)     # a steer torque twice the round-off bound
    v = judge("check-pedal-torque", _check_runs(thesis, torque_error=bad), thesis)
    assert v.verdict == "partly", v
    assert number(v.evidence, r"to (\S+) N m") == pytest.approx(bad, rel=0.05)


def test_check_partly_when_the_forward_run_leans(thesis):
    v = judge("check-pedal-torque", _check_runs(thesis, lean=1e-6), thesis)
    assert v.verdict == "partly", v
    assert number(v.evidence, r"max \|theta\| (\S+) rad") == pytest.approx(1e-6, rel=0.05)


def test_check_partly_when_the_forward_run_yaws(thesis):
    v = judge("check-pedal-torque", _check_runs(thesis, yaw=1e-6), thesis)
    assert v.verdict == "partly", v
    assert number(v.evidence, r"max \|phi\| (\S+) rad") == pytest.approx(1e-6, rel=0.05)


def test_check_partly_when_the_forward_run_falls(thesis):
    """Straight rolling that falls has not cruised, whatever its lean before the event."""
    v = judge("check-pedal-torque", _check_runs(thesis, forward_status="fell"), thesis)
    assert v.verdict == "partly", v
    assert "(fell)" in v.evidence


def test_check_not_reproduced_when_both_fail(thesis):
    runs = _check_runs(thesis, torque_error=1.0, speed_change=100 * CRUISE_SPEED)
    v = judge("check-pedal-torque", runs, thesis)
    assert v.verdict == "not reproduced", v
    assert number(v.evidence, r"psi_dot varies by (\S+)") == pytest.approx(100 * CRUISE_SPEED,
                                                                           rel=0.05)


def test_check_forward_only_engine_is_judged_on_its_forward_run(thesis):
    """Exudyn has no inverse dynamics: its check is the forward run alone."""
    runs = _check_runs(thesis)
    for r in runs:
        r.engine = "exudyn-tree"
    v = judge("check-pedal-torque", [runs[1]], thesis, engine="exudyn-tree")
    assert v.verdict == "reproduced" and "inverse" not in v.evidence, v


def test_check_not_assessed_without_either_run(thesis):
    v = judge("check-pedal-torque", [], thesis)
    assert v.verdict == "not assessed" and "neither" in v.evidence


# -- replay (6.2.2.1): identical to the zig-zag; constraint error below 2e-3 --------------------

def _zigzag(t):
    q = np.zeros((t.size, 8))
    q[:, THETA], q[:, GAMMA] = -np.sin(t) / 3, np.sin(t) / 2
    return q


def _replay(depart_at=None, status="completed", t_end=6.28):
    """The zig-zag's coordinates, leaving it (theta off by 0.1 rad) from ``depart_at`` s."""
    def q(t):
        out = _zigzag(t)
        if depart_at is not None:
            out[t >= depart_at - 1e-12, THETA] += 0.1
        return out
    return run("replay", status=status, t_end=t_end, q=q)


ZIGZAG = run("zigzag", kind="inverse", t_end=6.28, q=_zigzag)


def test_replay_identical_reproduced():
    v = judge("replay-identical", [ZIGZAG, _replay()])
    assert v.verdict == "reproduced", v
    assert number(v.evidence, r"whole (\S+) s") == pytest.approx(6.28)


@pytest.mark.parametrize("depart_at, verdict", [(3.5, "partly"), (1.5, "partly"),
                                               (1.0, "partly"),    # 'for a while' = >= 1 s
                                               (0.5, "not reproduced")])
def test_replay_identical_departing(depart_at, verdict):
    """'partly' when the replay follows the zig-zag for at least 1 s, else 'not reproduced'."""
    v = judge("replay-identical", [ZIGZAG, _replay(depart_at, status="fell", t_end=5.0)])
    assert v.verdict == verdict, v
    assert number(v.evidence, r"until (\S+) s") == pytest.approx(depart_at)
    assert "fell at 5.000 s" in v.evidence
    assert f"{DEPART:.0e}" in v.evidence


def test_replay_identical_but_fell_is_only_partly():
    """Within 1 mrad as long as it ran, but it did not finish the 6.28 s."""
    v = judge("replay-identical", [ZIGZAG, _replay(status="fell", t_end=4.0)])
    assert v.verdict == "partly", v
    assert number(v.evidence, r"until (\S+) s") == pytest.approx(4.0)


def test_replay_identical_needs_the_zigzag():
    v = judge("replay-identical", [_replay()])
    assert v.verdict == "not assessed" and "zigzag" in v.evidence


def test_replay_constraint_error(thesis):
    """Upright, at rest: every constraint holds exactly (C = 0); the rear contact sliding
    forward at 3e-3 m/s (dxc with no wheel spin) violates vC_x by exactly that."""
    ok = judge("replay-constraint-error", [run("replay", t_end=6.28)], thesis)
    assert ok.verdict == "reproduced", ok
    assert number(ok.evidence, r"max \|C\| = (\S+)") == 0.0

    def sliding(t):
        dq = np.zeros((t.size, 8))
        dq[:, 0] = 1.5 * CONSTRAINT_ERROR
        return dq
    bad = run("replay", q=lambda t: np.zeros((t.size, 8)), dq=sliding)
    v = judge("replay-constraint-error", [bad], thesis)
    assert v.verdict == "not reproduced", v
    assert number(v.evidence, r"max \|C\| = (\S+)") == pytest.approx(1.5 * CONSTRAINT_ERROR,
                                                                      rel=0.05)


# -- stability (6.2.2.2) ---------------------------------------------------------------------

@pytest.mark.parametrize("t_fall", [1.041, QUICK_FALL])   # 'within 2 s' includes 2 s
def test_psid0_falls_quickly(t_fall):
    v = judge("stability-psid0", [run("stability-psid0", "fell", t_fall, travelling(0.19))])
    assert v.verdict == "reproduced", v
    assert f"fell at {t_fall:.3f} s" in v.evidence
    assert number(v.evidence, r"travelled (\S+) m") == pytest.approx(0.19)


@pytest.mark.parametrize("status, t_end", [("fell", QUICK_FALL + 0.5), ("completed", 6.28)])
def test_psid0_not_quickly(status, t_end):
    v = judge("stability-psid0", [run("stability-psid0", status, t_end)])
    assert v.verdict == "not reproduced", v
    assert f"{t_end:.2f}" in v.evidence


def test_psid1_falls_sooner_than_psid0():
    runs = [run("stability-psid0", "fell", 1.2), run("stability-psid1", "fell", 1.0)]
    v = judge("stability-psid1", runs)
    assert v.verdict == "reproduced", v
    assert "fell at 1.000 s" in v.evidence and "fell at 1.200 s" in v.evidence
    assert "not sooner" not in v.evidence
    assert number(v.evidence, r"sooner by (\S+) s") == pytest.approx(0.2)


def test_psid1_falling_later_than_psid0_is_only_partly():
    """The flip of the comparison (sooner <-> later) must change the verdict and its words."""
    runs = [run("stability-psid0", "fell", 1.0), run("stability-psid1", "fell", 1.2)]
    v = judge("stability-psid1", runs)
    assert v.verdict == "partly", v
    assert number(v.evidence, r"not sooner by (\S+) s") == pytest.approx(-0.2)


def test_psid1_falling_at_the_same_time_is_not_sooner():
    runs = [run("stability-psid0", "fell", 1.0), run("stability-psid1", "fell", 1.0)]
    v = judge("stability-psid1", runs)
    assert v.verdict == "partly" and "not sooner" in v.evidence, v


def test_psid1_sooner_when_psid0_does_not_fall():
    runs = [run("stability-psid0", "completed", 6.28), run("stability-psid1", "fell", 1.5)]
    v = judge("stability-psid1", runs)
    assert v.verdict == "reproduced", v
    assert "completed to 6.28 s" in v.evidence


def test_psid1_that_does_not_fall_is_not_reproduced():
    runs = [run("stability-psid0", "fell", 1.0), run("stability-psid1", "completed", 6.28)]
    v = judge("stability-psid1", runs)
    assert v.verdict == "not reproduced", v
    assert "completed to 6.28 s" in v.evidence


def test_psid1_needs_psid0():
    v = judge("stability-psid1", [run("stability-psid1", "fell", 1.0)])
    assert v.verdict == "not assessed" and "stability-psid0" in v.evidence


@pytest.mark.parametrize("status, distance, verdict", [
    ("fell", 1.86, "reproduced"),
    ("fell", SOME_METRE, "reproduced"),  # 'some metre' = at least 1 m
    ("fell", 0.5, "partly"),             # falls, but before some metre
    ("completed", 3.0, "partly"),        # travels, but never falls
    ("completed", 0.5, "not reproduced"),
])
def test_psid5(status, distance, verdict):
    t_end = 1.0 if status == "fell" else 6.28
    # along x, so that 1 m is exactly 1 m (3 -> 4) for the boundary case
    path = travelling(distance, (1.0, 0.0) if distance == SOME_METRE else (0.6, 0.8))
    v = judge("stability-psid5", [run("stability-psid5", status, t_end, path)])
    assert v.verdict == verdict, v
    assert number(v.evidence, r"travelled (\S+) m") == pytest.approx(distance)
    assert f"{SOME_METRE:g} m" in v.evidence


def _lean(theta_of_t):
    def q(t):
        out = np.zeros((t.size, 8))
        out[:, THETA] = theta_of_t(t)
        return out
    return q


def test_psid10_comes_upright_and_stays():
    # pi/16 e^(-2 t) < 0.05 for t > ln(pi / 0.8) / 2 = 0.684 s: first grid time 0.69 s
    lean = _lean(lambda t: np.pi / 16 * np.exp(-2 * t))
    v = judge("stability-psid10", [run("stability-psid10", "completed", 6.28, lean)])
    assert v.verdict == "reproduced", v
    assert number(v.evidence, r"first below \S+ rad at (\S+) s") == pytest.approx(0.69)
    assert number(v.evidence, r"\|theta\| = (\S+) rad at the end") < VERTICAL


def test_psid10_comes_upright_then_falls_is_partly():
    lean = _lean(lambda t: np.where(t < 1.0, 0.2 * (1 - t), 1.4 * (t - 1.0) / 0.5))
    v = judge("stability-psid10", [run("stability-psid10", "fell", 1.5, lean)])
    assert v.verdict == "partly", v
    assert number(v.evidence, r"< \S+ rad at (\S+) s") == pytest.approx(0.76)
    assert "fell at 1.500 s" in v.evidence


def test_psid10_completed_but_leaned_is_not_stabilised():
    """Running to the end in a steady lean (circling) is not 'a vertical plane'."""
    v = judge("stability-psid10", [run("stability-psid10", "completed", 6.28,
                                       _lean(lambda t: 0.3 + 0 * t))])
    assert v.verdict == "not reproduced", v
    assert "completed to 6.28 s" in v.evidence


def test_psid10_upright_then_leaned_to_the_end_is_partly():
    lean = _lean(lambda t: np.where(t < 2.0, 0.2 * np.abs(1 - t), 0.3))
    v = judge("stability-psid10", [run("stability-psid10", "completed", 6.28, lean)])
    assert v.verdict == "partly", v


def test_psid10_never_upright_is_not_reproduced():
    """Upright only at the very start (t <= 0.1 s does not count), then falls."""
    lean = _lean(lambda t: 0.01 + t)
    v = judge("stability-psid10", [run("stability-psid10", "fell", 1.39, lean)])
    assert v.verdict == "not reproduced", v
    assert "never below" in v.evidence


# -- which claims are judged ---------------------------------------------------------------

def test_every_claim_of_a_selected_scenario_is_judged_for_every_engine(thesis):
    runs = {}
    for e in ("reference", "pinocchio"):
        runs[(e, "stability-psid0")] = run("stability-psid0", "fell", 1.2, engine=e)
        runs[(e, "stability-psid1")] = run("stability-psid1", "fell", 1.0, engine=e)
        runs[(e, "replay")] = run("replay", engine=e)   # upright at rest: C = 0
    out = judge_claims(runs, ["reference", "pinocchio"], thesis,
                       ["stability-psid0", "stability-psid1", "replay"])
    got = {(c["claim_id"], c["engine"]): c["verdict"] for c in out}
    assert got == {(cid, e): "reproduced" for cid in ("stability-psid0", "stability-psid1",
                                                      "replay-constraint-error")
                   for e in ("reference", "pinocchio")} | {
        ("replay-identical", e): "not assessed" for e in ("reference", "pinocchio")}
    texts = {c.id: c.text for c in CLAIMS}
    for c in out:
        assert set(c) == {"claim", "claim_id", "engine", "verdict", "evidence"}
        assert c["claim"] == texts[c["claim_id"]] and c["evidence"]
    # a claim needing an unselected scenario is still listed (partly selected), not assessed
    out = judge_claims(runs, ["reference"], thesis, ["stability-psid1"])
    assert {c["claim_id"]: c["verdict"] for c in out} == {"stability-psid1": "reproduced"}


# -- replay: one coordinate at a time, and a replay with no samples (issue 24) ------------------

def _replay_departing_in(coordinate, depart_at=2.5):
    """The zig-zag's coordinates with only ``coordinate`` (an index of q) off by 0.1 rad from
    ``depart_at`` s: 100 x DEPART, on one side of the threshold whatever the round-off."""
    def q(t):
        out = _zigzag(t)
        out[t >= depart_at - 1e-12, coordinate] += 0.1
        return out
    return run("replay", t_end=6.28, q=q)


@pytest.mark.parametrize("coordinate", [THETA, GAMMA])
def test_replay_departing_in_one_judged_coordinate_is_seen_when_it_departs(coordinate):
    """theta alone, or gamma alone, leaving the zig-zag at 2.5 s: 'partly', departing at
    2.5 s (the claim is about theta and gamma, so either one leaving is a departure)."""
    v = judge("replay-identical", [ZIGZAG, _replay_departing_in(coordinate)])
    assert v.verdict == "partly", v
    assert number(v.evidence, r"until (\S+) s") == pytest.approx(2.5)


@pytest.mark.parametrize("coordinate", [0, 1, 2, PSI, 5, 7])
def test_replay_departing_in_another_coordinate_is_still_identical(coordinate):
    """The claim is about theta and gamma (6.2.2.1's figures): the position, yaw, wheel angle,
    steer-frame pitch or rear-wheel angle leaving the zig-zag does not make it 'not identical'."""
    v = judge("replay-identical", [ZIGZAG, _replay_departing_in(coordinate)])
    assert v.verdict == "reproduced", v


@pytest.mark.parametrize("status, samples", [("fell", 0), ("fell", 1), ("completed", 0)])
def test_replay_with_nothing_to_compare_is_not_assessed(status, samples):
    """A replay that ends at once (no sample past the initial state in common with the
    zig-zag) compares nothing: 'not assessed', never 'within 1e-03 rad until ...'."""
    r = run("replay", status=status, t_end=6.28, q=_zigzag)
    r.t, r.q, r.dq = r.t[:samples], r.q[:samples], r.dq[:samples]
    v = judge("replay-identical", [ZIGZAG, r])
    assert v.verdict == "not assessed", v
    assert "within" not in v.evidence and "sample" in v.evidence


def test_a_replay_that_fell_after_one_step_is_judged_on_that_step():
    """Two samples: the initial state and one past it, in common with the zig-zag, so there is
    something to compare; it followed the zig-zag for 0.01 s and fell (< the 1 s of 'partly'):
    'not reproduced', not 'not assessed'."""
    r = run("replay", status="fell", t_end=6.28, q=_zigzag)
    r.t, r.q, r.dq = r.t[:2], r.q[:2], r.dq[:2]
    v = judge("replay-identical", [ZIGZAG, r])
    assert v.verdict == "not reproduced", v
    assert number(v.evidence, r"until (\S+) s") == pytest.approx(DT)


# -- the survivors of `make mutants` in the check and psid10 judges ---------------------------

def test_check_speed_change_is_relative_to_the_starting_speed(thesis):
    """psi_dot 5 rad/s at the start, 10 rad/s from the next sample on: the relative change is
    (10 - 5) / 5 = 1, not 5 / 10 (the speed the run starts from is the one the thesis
    holds)."""
    runs = _check_runs(thesis)
    runs[1].dq[1:, PSI] = 10.0
    v = judge("check-pedal-torque", runs, thesis)
    assert v.verdict == "partly", v
    assert number(v.evidence, r"psi_dot varies by (\S+)") == pytest.approx(1.0)


def test_psid10_that_falls_before_0_1_s_is_not_reproduced():
    """A run that falls at 0.05 s has no sample after 0.1 s: it never came to the vertical."""
    v = judge("stability-psid10", [run("stability-psid10", "fell", 0.05,
                                       _lean(lambda t: 0.2 + t))])
    assert v.verdict == "not reproduced", v
    assert "never below" in v.evidence and "fell at 0.050 s" in v.evidence


def test_psid10_is_judged_on_its_last_sample():
    """Upright from 0.5 s; the end is the last sample: 0.01 rad there is 'reproduced' with
    |theta| = 0.010 at the end (0.04 on the sample before), 0.3 there is 'partly'."""
    def lean(last):
        def q(t):
            out = np.zeros((t.size, 8))
            out[:, THETA] = np.where(t < 0.5, 0.2, 0.04)
            out[-1, THETA] = last
            return out
        return q
    v = judge("stability-psid10", [run("stability-psid10", "completed", 6.28, lean(0.01))])
    assert v.verdict == "reproduced", v
    assert number(v.evidence, r"\|theta\| = (\S+) rad at the end") == pytest.approx(0.01)
    v = judge("stability-psid10", [run("stability-psid10", "completed", 6.28, lean(0.3))])
    assert v.verdict == "partly", v
