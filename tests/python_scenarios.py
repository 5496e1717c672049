"""The built-in scenarios written in Python, as the registry had them before it was read from
``reference_model/scenario_data/*.toml``: the second, independent statement of the thesis's
scenarios that tests/test_scenario_files.py holds the files to, field by field.

The thesis's scenarios (chapters 4.3, 5.3, 6.2.2) and the IFToMM uncontrolled bicycle
(iftomm-multibody.org, problem Uncontrolled_bicycle; duration and output as Exudyn's
Examples/bicycleIftommBenchmark.py: tEnd = 5 s, sensors every 0.01 s).
"""

import numpy as np

from reference_model.scenarios import MOTIONS, ExpectedDifference, Scenario


def _stability(psid: float) -> Scenario:
    return Scenario(
        name=f"stability-psid{psid:g}",
        description=(f"stability study: leaned and steered by pi/16, pedal torque 1 N m, "
                     f"psi_dot(0) = {psid:g} rad/s (thesis Fig. 6-{ {0: 4, 1: 5, 5: 6, 10: 7}[psid] })"),
        kind="forward", q0=(0, 0, 0, np.pi / 16, 0, 0, np.pi / 16, 0), dq_ind0=(0.0, psid, 0.0),
        torques=(0.0, 1.0, 0.0),
        thesis_claim={0: "falls quickly", 1: "falls, sooner than at psi_dot(0) = 0",
                      5: "travels some metre before falling",
                      10: "places its frame in a vertical plane and stabilises"}[psid],
        tags=("stability",),
        expected_differences=(() if psid != 10 else (ExpectedDifference(
            "convergence order", "an engine with the disc contact vs the reference with the thesis contact",
            "model difference",
            "the thesis's front contact (the rim point along the fork's -z axis) and the true "
            "lowest point of the disc differ as soon as lean and steer are both non-zero (here "
            "from t = 0): the error of an engine with the true contact cannot shrink with its "
            "step"),)),
    )


# The IFToMM multibody benchmark "uncontrolled bicycle" (iftomm-multibody.org, problem
# Uncontrolled_bicycle): the Meijaard et al. (2007) benchmark bicycle released upright and
# straight at forward speed v with an initial roll rate, no torques, no drag. Duration and
# output as in Exudyn's implementation of the problem (Examples/bicycleIftommBenchmark.py,
# current revision: tEnd = 5 s, sensors every 0.01 s; an older revision ran 20 s).
IFTOMM_BICYCLE_GRID = (0.0, 0.01, 501)   # 0:0.01:5 s
BENCHMARK_R_REAR = 0.3                   # m: Table 1's rR (rear wheel radius of `benchmark`)


def _iftomm_bicycle(v: float, roll_rate: float, claim: str) -> Scenario:
    """IFToMM uncontrolled-bicycle manoeuvre on model 'benchmark': upright (theta = gamma = 0),
    steer rate 0, roll rate ``roll_rate`` (rad/s, positive = leaning to the right, as the
    benchmark's phi), rear wheel at psi_dot = v / rR > 0 (so xc grows: forward at v m/s)."""
    return Scenario(
        name=f"benchmark-v{v:g}",
        description=(f"IFToMM uncontrolled bicycle (Meijaard et al. 2007 benchmark): upright "
                     f"at {v:g} m/s, roll rate {roll_rate:g} rad/s, no torques, 5 s"),
        kind="forward", model="benchmark", grid=IFTOMM_BICYCLE_GRID,
        # beta = -lambda = -pi/10 is the upright frame pitch of the benchmark (steering axis =
        # frame z): the projection re-solves it from [rD]_z = 0 and reports the correction
        q0=(0, 0, 0, 0, 0, -np.pi / 10, 0, 0),
        dq_ind0=(float(roll_rate), float(v) / BENCHMARK_R_REAR, 0.0),
        torques=(0.0, 0.0, 0.0), constraints="projection", thesis_claim=claim,
        tags=("benchmark", "iftomm"))


PYTHON_SCENARIOS: dict[str, Scenario] = {s.name: s for s in (
    Scenario("check", "straight rolling at R*5 = 1.6 m/s: only the pedal torque, constant, "
             "balancing the drag", "inverse",
             motion=MOTIONS["check"],
             thesis_claim="only the pedal torque is non-zero, and constant"),
    Scenario("zigzag", "prescribed lean and steer oscillation: theta = -sin(t)/3, psi = 5t, "
             "gamma = sin(t)/2", "inverse",
             motion=MOTIONS["zigzag"]),
    Scenario("replay", "zigzag's rider torques (cubic spline) fed into the forward dynamics from "
             "its initial state, Baumgarte a1 = a2 = 10 (thesis 6.2.2.1)", "forward",
             q0=(0,) * 8, dq_ind0=(-1 / 3, 5.0, 0.5), torques="zigzag",
             thesis_claim="motion identical to the zigzag inverse kinematics; constraint error "
                          "below 2e-3"),
    *(_stability(v) for v in (0, 1, 5, 10)),
    Scenario("check-forward", "the check scenario run forward: upright straight rolling at "
             "1.6 m/s under the check's constant pedal torque (its inverse dynamics), the "
             "forward counterpart of the check's claim", "forward",
             q0=(0,) * 8, dq_ind0=(0.0, 5.0, 0.0), torques="check",
             thesis_claim="the constant pedal torque balances the drag: speed and heading stay "
                          "constant", tags=("check",)),
    _iftomm_bicycle(4.0, 0.05, "below the weave speed (4.292 m/s): the weave oscillation grows"),
    _iftomm_bicycle(4.6, 0.5, "in the self-stable range (4.292-6.024 m/s): the weave decays"),
    _iftomm_bicycle(8.0, 0.05, "above the capsize speed (6.024 m/s): the weave decays, then the "
                               "bicycle leans over slowly (capsize)"),
)}


