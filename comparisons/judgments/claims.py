"""The thesis's claims, judged engine by engine on the runs of `scenario_runs`.

Each claim is the thesis's sentence, the scenarios it needs and a judge that reads the runs
and returns a verdict with its evidence (numbers, always). Verdicts:

* ``reproduced``      the engine's run shows what the thesis says;
* ``partly``          some of it (e.g. the replay follows the zig-zag for a while, then leaves);
* ``not reproduced``  the run shows something else;
* ``not assessed``    the engine cannot run the scenario, or a scenario the claim needs was not
                      selected (the evidence says which).

The thresholds that turn a run into a verdict are stated in each judge's evidence; they are
the plain reading of the thesis's words (chapter 6), not tuned to any engine.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from engines.runs import Run

DEPART = 1e-3          # rad: 'identical' to the zig-zag means theta and gamma within 1 mrad
QUICK_FALL = 2.0       # s: 'falls quickly' = falls within the first 2 s of the 2 pi s run
SOME_METRE = 1.0       # m: 'travels some metre' = the rear contact ends >= 1 m from its start
VERTICAL = 0.05        # rad: 'frame in a vertical plane' = |theta| below ~3 degrees
CONSTRAINT_ERROR = 2e-3  # the thesis's own bound on the constraint error (6.2.2.1)
CHECK_RELATIVE = 1e-12   # check torques: round-off of the 13x13 solve, relative to Mped
CRUISE_SPEED = 1e-9      # check forward: relative change of psi_dot (rtol-sized)
UPRIGHT = 1e-9           # rad: check forward stays exactly upright (symmetric motion)


@dataclass(frozen=True)
class Verdict:
    verdict: str
    evidence: str


@dataclass(frozen=True)
class Claim:
    """One claim of the thesis, and how a run is judged against it."""

    id: str
    text: str
    scenarios: tuple[str, ...]
    judge: Callable[[str, dict[tuple[str, str], Run], object], Verdict]


def _missing(runs, engine, names) -> Verdict | None:
    for n in names:
        r = runs.get((engine, n))
        if r is None:
            return Verdict("not assessed", f"scenario {n} not run in this report")
        if r.status in ("not run", "failed"):
            return Verdict("not assessed", f"{n}: {r.status} ({r.message})")
    return None


def _distance(r: Run) -> float:
    return float(np.hypot(*(r.q[-1, :2] - r.q[0, :2])))


def _fall(r: Run) -> str:
    return f"fell at {r.t_end:.3f} s" if r.status == "fell" else f"{r.status} to {r.t_end:.2f} s"


# -- judges ------------------------------------------------------------------------------------

def _check(engine, runs, model) -> Verdict:
    p = model.params
    expected = p.cv * (p.R_rear * 5.0) ** 2 * p.R_rear
    parts, ok = [], []
    inv, fwd = runs.get((engine, "check")), runs.get((engine, "check-forward"))
    if inv is not None and inv.T is not None:
        err = float(np.max(np.abs(inv.T - [0.0, expected, 0.0])))
        ok.append(err <= CHECK_RELATIVE * expected)
        parts.append(f"inverse: Mped = {expected:.6g} N m constant, Mdir = Mvue = 0 to {err:.1e} N m "
                     f"(bound {CHECK_RELATIVE:.0e} x Mped)")
    if fwd is not None and fwd.status in ("completed", "fell"):
        dpsi = fwd.dq[:, 4]
        change = float(np.ptp(dpsi) / abs(dpsi[0]))
        lean = float(np.abs(fwd.q[:, 3]).max())
        yaw = float(np.abs(fwd.q[:, 2]).max())
        ok.append(fwd.status == "completed" and change <= CRUISE_SPEED and lean <= UPRIGHT
                  and yaw <= UPRIGHT)
        parts.append(f"forward under that torque: psi_dot varies by {change:.1e} (relative, bound "
                     f"{CRUISE_SPEED:.0e}), max |theta| {lean:.1e} rad, max |phi| {yaw:.1e} rad over "
                     f"{fwd.t_end:.2f} s ({fwd.status})")
    if not ok:
        return Verdict("not assessed", "neither check nor check-forward run on this engine")
    return Verdict("reproduced" if all(ok) else ("partly" if any(ok) else "not reproduced"),
                   "; ".join(parts))


def _replay_identical(engine, runs, model) -> Verdict:
    miss = _missing(runs, engine, ("replay",))
    if miss:
        return miss
    zig = runs.get(("reference", "zigzag"))
    if zig is None:
        return Verdict("not assessed", "the zigzag inverse kinematics was not run in this report")
    r = runs[(engine, "replay")]
    n = min(len(r.t), len(zig.t))
    if n < 2:     # nothing past the initial state to compare: no verdict on zero samples
        return Verdict("not assessed", f"the replay and the zig-zag share {n} sample(s) "
                                       f"(replay {_fall(r)}): nothing past the initial state "
                                       "to compare")
    dev = np.abs(r.q[:n, [3, 6]] - zig.q[:n, [3, 6]]).max(axis=1)
    over = np.flatnonzero(dev > DEPART)
    if not over.size and r.status == "completed":
        return Verdict("reproduced", f"theta and gamma within {dev.max():.1e} rad of the zig-zag "
                                     f"over the whole {r.t_end:.2f} s")
    t_dev = float(r.t[over[0]]) if over.size else r.t_end
    verdict = "partly" if t_dev >= 1.0 else "not reproduced"
    return Verdict(verdict, f"theta, gamma within {DEPART:.0e} rad of the zig-zag until "
                            f"{t_dev:.2f} s, then depart; {_fall(r)} of the 6.28 s")


def _replay_constraint(engine, runs, model) -> Verdict:
    miss = _missing(runs, engine, ("replay",))
    if miss:
        return miss
    r = runs[(engine, "replay")]
    C = float(np.abs(model.constraint_residual(r.q, r.dq)).max())
    return Verdict("reproduced" if C < CONSTRAINT_ERROR else "not reproduced",
                   f"max |C| = {C:.1e} (bound {CONSTRAINT_ERROR:.0e}) up to {r.t_end:.2f} s ({r.status})")


def _psid0(engine, runs, model) -> Verdict:
    miss = _missing(runs, engine, ("stability-psid0",))
    if miss:
        return miss
    r = runs[(engine, "stability-psid0")]
    quick = r.status == "fell" and r.t_end <= QUICK_FALL
    return Verdict("reproduced" if quick else "not reproduced",
                   f"{_fall(r)} (quickly = within {QUICK_FALL:g} s), travelled {_distance(r):.2f} m")


def _psid1(engine, runs, model) -> Verdict:
    miss = _missing(runs, engine, ("stability-psid0", "stability-psid1"))
    if miss:
        return miss
    r0, r1 = runs[(engine, "stability-psid0")], runs[(engine, "stability-psid1")]
    if r1.status != "fell":
        return Verdict("not reproduced", f"psi_dot(0) = 1: {_fall(r1)}")
    sooner = r0.status != "fell" or r1.t_end < r0.t_end
    return Verdict("reproduced" if sooner else "partly",
                   f"psi_dot(0) = 1 {_fall(r1)}, psi_dot(0) = 0 {_fall(r0)}: "
                   f"{'sooner' if sooner else 'not sooner'} by {r0.t_end - r1.t_end:+.3f} s")


def _psid5(engine, runs, model) -> Verdict:
    miss = _missing(runs, engine, ("stability-psid5",))
    if miss:
        return miss
    r = runs[(engine, "stability-psid5")]
    d = _distance(r)
    fell, far = r.status == "fell", d >= SOME_METRE
    verdict = "reproduced" if fell and far else ("partly" if fell or far else "not reproduced")
    return Verdict(verdict, f"travelled {d:.2f} m (some metre = at least {SOME_METRE:g} m), {_fall(r)}")


def _psid10(engine, runs, model) -> Verdict:
    miss = _missing(runs, engine, ("stability-psid10",))
    if miss:
        return miss
    r = runs[(engine, "stability-psid10")]
    theta = np.abs(r.q[:, 3])
    later = r.t > 0.1
    came_upright = bool(np.any(theta[later] < VERTICAL))
    t_up = float(r.t[later][np.argmax(theta[later] < VERTICAL)]) if came_upright else None
    stays = r.status == "completed" and theta[-1] < VERTICAL
    if stays:
        return Verdict("reproduced", f"|theta| = {theta[-1]:.3f} rad at the end ({r.t_end:.2f} s), "
                                     f"first below {VERTICAL} rad at {t_up:.2f} s")
    if came_upright:
        return Verdict("partly", f"the frame comes to the vertical (|theta| < {VERTICAL} rad at "
                                 f"{t_up:.2f} s) but does not stay: {_fall(r)}, travelled {_distance(r):.2f} m")
    return Verdict("not reproduced", f"|theta| never below {VERTICAL} rad after 0.1 s; {_fall(r)}, "
                                     f"travelled {_distance(r):.2f} m")


CLAIMS: tuple[Claim, ...] = (
    Claim("check-pedal-torque", "check (5.3): only the pedal torque is non-zero, and constant, "
          "balancing the drag", ("check", "check-forward"), _check),
    Claim("replay-identical", "replay (6.2.2.1): the forward motion under the zig-zag's torques "
          "is identical to the zig-zag", ("replay", "zigzag"), _replay_identical),
    Claim("replay-constraint-error", "replay (6.2.2.1): the constraint error stays below 2e-3",
          ("replay",), _replay_constraint),
    Claim("stability-psid0", "stability (Fig. 6-4): at psi_dot(0) = 0 the bicycle falls quickly",
          ("stability-psid0",), _psid0),
    Claim("stability-psid1", "stability (Fig. 6-5): at psi_dot(0) = 1 rad/s it falls, sooner than "
          "at 0", ("stability-psid0", "stability-psid1"), _psid1),
    Claim("stability-psid5", "stability (Fig. 6-6): at psi_dot(0) = 5 rad/s it travels some metre "
          "before falling", ("stability-psid5",), _psid5),
    Claim("stability-psid10", "stability (Fig. 6-7): at psi_dot(0) = 10 rad/s it places its frame "
          "in a vertical plane and stabilises", ("stability-psid10",), _psid10),
)


def judge_claims(runs: dict[tuple[str, str], Run], engines, model, selected) -> list[dict]:
    """Every claim whose scenarios were (at least partly) selected, for every engine setup."""
    out = []
    for claim in CLAIMS:
        if not any(s in selected for s in claim.scenarios):
            continue
        for engine in engines:
            v = claim.judge(engine, runs, model)
            out.append({"claim": claim.text, "claim_id": claim.id, "engine": engine,
                        "verdict": v.verdict, "evidence": v.evidence})
    return out
