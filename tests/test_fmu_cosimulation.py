"""The fmu engine's runs through an FMU's Co-Simulation interface (engines/fmu/cosimulation.py):
`co_simulate` on bicycle-xval's own thesis FMU built with ``co_simulation=True`` (fixed-step
RK4 at 0.5 ms inside ``fmi2DoStep``; built once into the code cache by
`fmu_builds.cached_fmu`, ~10 s cold, then ~0.1 s to load), and `_inputs`, the torque table
fmpy's master reads.

The contract (docs/engines.md, "The fmu engine", and the module's docstring): the run starts
from the reference's projected initial state; the master steps the FMU over the scenario's grid
divided down to steps of at most `COMMUNICATION_STEP` = 0.5 ms and holds the rider torques over
each step; the states are reported on the scenario's grid ``scenario.t``; ``ddq`` is the
central differences of ``dq`` on that grid, ``C`` the thesis's constraints at the FMU's states,
``T`` the scenario's torques at the grid times; the scenario's Baumgarte a1, a2 reach the FMU
when its constraints are "baumgarte" (a1 = a2 = 0, the exact accelerations, otherwise); the run
ends as a fall at the first grid sample with |theta| >= the fall limit (the ``fall_limit``
argument, else the scenario's).

Independent expectations: the reference engine's DOP853 run of the same scenario (rtol 1e-10);
the reference's solver from the same state with the torques shifted by half a communication
step (a torque held over steps of h is, to first order, the torque delayed by h/2); the
Baumgarte law's closed-form decay of the constraint residuals (C'' + 2 a1 C' + a2^2 C = 0 for
the contact height, C' = -(2 a1 + a2^2) C for the four contact velocities) from a start off the
constraints; hand-computed torque tables; a stand-in for fmpy's master that records what the
module hands it (start values, inputs, the span and interval) for an FMU in other units, and
returns a known ramp. Each run is a fraction of a second of bicycle (0.2 to
0.6 s), so the whole file takes ~2 s with the FMU cached.

Co-Simulation runs were reached before only by the slow test
tests/test_fmu.py::test_a_co_simulation_fmu_gives_runs_only.
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

from engines import load_engine   # noqa: E402
from engines.fmu import cosimulation   # noqa: E402
from engines.fmu.cosimulation import COMMUNICATION_STEP, _inputs   # noqa: E402
from engines.fmu.mapping import Ref   # noqa: E402
from engines.reference import ReferenceEngine   # noqa: E402
from fmu_builds import cached_fmu   # noqa: E402
from reference_model.scenarios import (Scenario, TorqueSamples, get_scenario,   # noqa: E402
                                       initial_state, torque_input)
from reference_model.solvers import simulate   # noqa: E402

SPEC = "engines.fmu:FmuEngine"
#: docs/model.md's coordinate order
XC, YC, PHI, THETA, PSI, BETA, GAMMA, EPS = range(8)
#: asymmetric constant rider torques (Mdir, Mped, Mvue) in N m: each component distinct and
#: non-zero, so a permuted or dropped input shows
TORQUES = (0.3, 1.0, -0.2)
PREFIX = "the FMU's Co-Simulation failed: "


@pytest.fixture(scope="module")
def cs_fmu(thesis):
    return cached_fmu(thesis, co_simulation=True)


@pytest.fixture(scope="module")
def engine(thesis, cs_fmu):
    return load_engine(SPEC, thesis, fmu=str(cs_fmu), interface="cs")


@pytest.fixture(scope="module")
def steady(thesis, engine):
    """stability-psid5 (leaned and steered by pi/16, psi_dot(0) = 5 rad/s, Baumgarte 10, 10)
    with the torques `TORQUES`, cut to 0.3 s (31 samples): the FMU's run and the reference's."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 31),
                             torques=TORQUES)
    return sc, engine.simulate(sc), ReferenceEngine(thesis).simulate(sc)


# -- a run against the reference ------------------------------------------------------------

def test_a_constant_torque_run_follows_the_reference_on_its_grid(steady):
    """The run reports on the scenario's own grid (the same floats) and follows the reference's
    DOP853 run (rtol 1e-10, atol 1e-12) of the same scenario: the FMU's RK4 at 0.5 ms on this
    smooth constant-torque run is accurate to ~h^4 (measured 3.1e-13 rad/m in q and 3.7e-11
    rad/s in dq by 0.3 s; the slow test saw 1.3e-13 at 0.12 s). Bounded by 1e-10 in q and 1e-8
    in dq: the reference's own tolerance on coordinates of order 1 and rates of order 10-100
    rad/s, ~300 times the measurement, and far below what any slip below makes. Fails when
    the rates' start values go onto the coordinates (or the reverse), when the torques reach
    the FMU permuted (Mdir and Mvue swapped: 0.5 N m on the steering), when the output grid is
    off by one fine step (the states interpolated between the FMU's samples: ~1e-7), or when
    the FMU's states are read back in another order."""
    sc, got, ref = steady
    assert np.array_equal(got.t, sc.t)
    assert got.q.shape == got.dq.shape == (31, 8)
    assert np.max(np.abs(got.q - ref.q)) < 1e-10
    assert np.max(np.abs(got.dq - ref.dq)) < 1e-8
    # the run really moves: the bicycle travels and leans, the wheels turn
    assert np.max(np.abs(got.q[-1] - got.q[0])) > 0.1


def test_the_trajectory_holds_what_the_docs_say(thesis, steady):
    """docs/engines.md (Trajectory; the fmu engine's Co-Simulation): status "completed" with
    "reached the end of the grid", t_end the last grid time; T (N, 3) the scenario's torques
    at every sample; C (N, 5) the thesis's constraints at the FMU's states, which Baumgarte
    keeps at round-off level from the projected start (measured 2e-12; bound 1e-10, in m and
    m/s); ddq (N, 8) the central differences (dq[k+1] - dq[k-1]) / (2 dt) written here, to
    round-off (dq ~ 20 rad/s times 1e-16 over dt = 0.01 s, a few 1e-13; bound 1e-10 rad/s^2);
    the settings name the FMU's own integrator and the constraints and fall limit used.
    Fails when ddq is taken from q instead of dq or over the wrong spacing, when T's columns
    are permuted, when C is not the thesis's residual at these states."""
    sc, got, _ = steady
    assert got.status == "completed" and got.message == "reached the end of the grid"
    assert got.t_end == sc.t[-1] == pytest.approx(0.3)
    assert np.array_equal(got.T, np.tile(TORQUES, (31, 1)))
    assert got.C.shape == (31, 5)
    assert np.array_equal(got.C, thesis.constraint_residual(got.q, got.dq))
    assert np.max(np.abs(got.C)) < 1e-10
    assert got.ddq.shape == (31, 8)
    central = (got.dq[2:] - got.dq[:-2]) / (2 * 0.01)
    assert np.max(np.abs(got.ddq[1:-1] - central)) < 1e-10
    assert np.all(np.isfinite(got.ddq))
    assert got.settings["integrator"] == "the FMU's own (Co-Simulation, fmpy's master)"
    assert got.settings["constraints"] == "baumgarte" and got.settings["fall_limit"] == 1.4
    assert got.settings["ddq"] == "central differences of dq on the output grid"
    assert got.timing["wall_seconds"] > 0


@pytest.mark.parametrize("grid, substeps", [
    ((0.0, 0.01, 21), 20),      # 10 ms samples: twenty 0.5 ms steps each
    ((0.2, 0.01, 21), 20),      # a grid that starts at 0.2 s: the torques at 0.2 s onwards
    ((0.0, 0.0013, 101), 3),    # 1.3 ms: 2 steps would be 0.65 ms > 0.5 ms, so 3 of 0.433 ms
], ids=["10ms", "from-0.2s", "1.3ms"])
def test_time_varying_torques_are_held_over_each_communication_step(thesis, engine, grid,
                                                                    substeps):
    """The replay (zigzag's inverse-dynamics torques as a cubic spline: all three torques vary
    within the run). The master holds each input over a communication step h = dt / substeps,
    the fewest equal steps of at most 0.5 ms (the substeps worked out by hand above); a torque
    held from the step's start differs from the smooth one by -h/2 T' + O(h^2), so the run
    follows the reference's solver run from the same projected state with the torques delayed
    by h/2 to second order (measured 1.1e-8 rad/m in q, 2.7e-8 in dq over 0.2 s), while the
    run with the undelayed torques is 5e-6 to 1.4e-5 away (first order): bound 1e-7 in q and
    3e-7 in dq, ten times the measurement and well below the first-order gap. T is the
    scenario's spline at the grid times. Fails when the communication
    step is not the grid's divided down (held over whole 10 ms samples: 2.6e-4 off; two
    substeps of 0.65 ms on the 1.3 ms grid), when the inputs are tabled at other times than
    the master's steps, when the run starts at t = 0 instead of the grid's first time (the
    spline read 0.2 s early), or when the torques are permuted."""
    sc = dataclasses.replace(get_scenario("replay"), grid=grid)
    got = engine.simulate(sc)
    assert got.status == "completed", got.message
    assert np.array_equal(got.t, sc.t)
    h = grid[1] / substeps
    assert h <= COMMUNICATION_STEP * (1 + 1e-12)
    spline = torque_input(thesis, sc)
    init = initial_state(thesis, sc)
    held = simulate(thesis, init.q, init.dq, sc.t, lambda t: spline(t - h / 2),
                    constraints="baumgarte", baumgarte=sc.baumgarte)
    assert np.max(np.abs(got.q - held.q)) < 1e-7
    assert np.max(np.abs(got.dq - held.dq)) < 3e-7
    smooth = simulate(thesis, init.q, init.dq, sc.t, spline, constraints="baumgarte",
                      baumgarte=sc.baumgarte)
    assert np.max(np.abs(got.q - smooth.q)) > 1e-6      # the hold is what the bound sees
    assert np.array_equal(got.T, np.array([spline(t) for t in sc.t]))
    assert np.ptp(got.T, axis=0).min() > 0              # every torque varies


# -- the constraint handling and the parameters reach the FMU -------------------------------

@pytest.mark.parametrize("constraints, baumgarte", [
    ("baumgarte", (2.0, 6.0)),
    ("baumgarte", (6.0, 2.0)),
    ("projection", (2.0, 6.0)),     # the FMU at a1 = a2 = 0: the exact accelerations
], ids=["a1=2,a2=6", "a1=6,a2=2", "projection"])
def test_the_constraints_evolve_by_the_scenarios_baumgarte_law(thesis, engine, monkeypatch,
                                                               constraints, baumgarte):
    """A start off the constraints (the projected state with beta 1e-3 rad too large and the
    rear contact's x rate 1e-2 m/s too large: the module's `initial_state` replaced so) shows
    which a1, a2 the FMU integrates with. The Baumgarte law D ddq + dD dq = -2 a1 D dq -
    a2^2 C (reference_model Model.forward) makes the contact height obey
    C0'' + 2 a1 C0' + a2^2 C0 = 0 (C0' = D[0] dq) and each contact velocity
    C_i' = -(2 a1 + a2^2) C_i, solved here in closed form; a1 = a2 = 0 (projection: this
    engine does not project) leaves C0 linear in t and the velocities constant. The RK4 at
    0.5 ms follows these to 5e-16 m and 5e-12 m/s (measured; the fastest rate, 40/s, makes
    RK4's relative error ~t lambda (h lambda)^4 / 120 ~ 1e-8 of |C(0)| = 1e-2): bounded by
    1e-12 m and 1e-9 m/s. The whole state follows the reference's solver from the same state
    with the same handling (measured 1.6e-11 and 6.5e-10; bound 1e-9 in q, 1e-7 in dq). Fails
    when the scenario's a1, a2 do not reach the FMU (its own 10, 10: decay at 120/s), reach
    it swapped (16/s against 40/s), reach it for a projection scenario, or when the rates' start
    values are lost."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 21),
                             constraints=constraints, baumgarte=baumgarte)
    start = initial_state(thesis, sc)
    q0, dq0 = start.q.copy(), start.dq.copy()
    q0[BETA] += 1e-3
    dq0[XC] += 1e-2
    monkeypatch.setattr(cosimulation, "initial_state",
                        lambda model, scenario: SimpleNamespace(q=q0, dq=dq0))
    got = engine.simulate(sc)
    assert got.status == "completed", got.message
    t = sc.t
    C0 = thesis.constraint_residual(q0, dq0)
    rate0 = thesis.constraint_jacobian(q0)[0] @ dq0
    assert abs(C0[0]) > 5e-4 and abs(C0[1]) > 5e-3        # really off the constraints
    a1, a2 = baumgarte if constraints == "baumgarte" else (0.0, 0.0)
    if a1 or a2:
        r = np.roots([1.0, 2 * a1, a2 ** 2]).astype(complex)   # distinct roots for these a1, a2
        c = np.linalg.solve(np.array([[1.0, 1.0], r]), [C0[0], rate0])
        height = np.real(c[0] * np.exp(r[0] * t) + c[1] * np.exp(r[1] * t))
    else:
        height = C0[0] + rate0 * t
    velocities = C0[1:] * np.exp(-(2 * a1 + a2 ** 2) * t)[:, None]
    assert np.max(np.abs(got.C[:, 0] - height)) < 1e-12
    assert np.max(np.abs(got.C[:, 1:] - velocities)) < 1e-9
    ref = simulate(thesis, q0, dq0, t, sc.torques,
                   constraints="baumgarte" if constraints == "baumgarte" else "none",
                   baumgarte=baumgarte)
    assert np.max(np.abs(got.q - ref.q)) < 1e-9
    assert np.max(np.abs(got.dq - ref.dq)) < 1e-7
    assert got.settings["constraints"] == (
        constraints if constraints != "projection" else
        "none (the scenario's projection: a Co-Simulation FMU cannot project its state)")


def test_the_models_parameters_reach_the_fmu_unless_the_fmu_keeps_its_own(thesis, cs_fmu):
    """The thesis FMU used for a model whose frame is 2 kg heavier (m3): by default
    (parameters=model) its run is the heavier bicycle's, the reference's run of that model to
    1e-10 (the first test's bound; measured 2e-13); with parameters=fmu it is the FMU's own
    thesis bicycle's. The two bicycles' runs differ by 5e-4 over 0.2 s, so each comparison
    tells them apart. Fails when the mapped parameters' start values are not given to the
    FMU, or given under the wrong variables."""
    heavy = thesis.with_params(thesis.params.replace(m3=thesis.params.m3 + 2.0))
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 21),
                             torques=TORQUES)
    mine = load_engine(SPEC, heavy, fmu=str(cs_fmu), interface="cs").simulate(sc)
    own = load_engine(SPEC, heavy, fmu=str(cs_fmu), interface="cs",
                      parameters="fmu").simulate(sc)
    ref_heavy = ReferenceEngine(heavy).simulate(sc)
    ref_thesis = ReferenceEngine(thesis).simulate(sc)
    assert np.max(np.abs(ref_heavy.q - ref_thesis.q)) > 1e-5
    assert np.max(np.abs(mine.q - ref_heavy.q)) < 1e-10
    assert np.max(np.abs(own.q - ref_thesis.q)) < 1e-10


def test_the_master_gets_the_fmus_units_and_its_states_come_back_in_si(thesis, cs_fmu,
                                                                       monkeypatch, tmp_path):
    """An FMU in other units, seen through a mapping with scales (docs/engines.md: thesis
    value (SI) = scale * FMU value): lean and lean rate in degrees, the steering torque in
    N mm (scale 1e-3), the frame's mass in units of 2 kg (scale 2); fmpy's master replaced by
    a stand-in that records what it is given and returns every output as its start value plus
    1 FMU unit per second on the master's own output grid. So: the start values are the
    projected state divided by the scales (theta0 / DEG), the parameters the model's divided
    by theirs (m3 / 2), a1, a2 the scenario's; the inputs are tabled in FMU units (Mdir 0.3 N m
    = 300 N mm) on the fine grid of 0.5 ms steps from the first grid time to the last; and the
    run's q, dq are start + scale * (t - t0) at the grid times (the ramp is linear, so reading
    it at the grid is exact), in SI. Fails when a scale is applied the wrong way round or
    dropped on either side, when the start values or the outputs take the coordinates and
    rates in another order, or when the master is asked for another interval or span."""
    from reference_model.exports import fmu as fmu_export
    deg = np.pi / 180
    text = (fmu_export.mapping_text(thesis)
            .replace('theta = "theta"', f'theta = {{ name = "theta", scale = {deg!r} }}')
            .replace('theta = "d_theta"', f'theta = {{ name = "d_theta", scale = {deg!r} }}')
            .replace('Mdir = "Mdir"', 'Mdir = { name = "Mdir", scale = 1e-3 }')
            .replace('m3 = "m3"', 'm3 = { name = "m3", scale = 2.0 }'))
    assert text.count("{ name = ") == 4
    (tmp_path / "units.toml").write_text(text)
    eng = load_engine(SPEC, thesis, fmu=str(cs_fmu), mapping=str(tmp_path / "units.toml"),
                      interface="cs")
    calls = []

    def master(filename, **kwargs):
        calls.append(dict(kwargs, filename=filename))
        start, stop, dt = kwargs["start_time"], kwargs["stop_time"], kwargs["output_interval"]
        times = start + dt * np.arange(int(round((stop - start) / dt)) + 1)
        out = np.zeros(times.size, dtype=[("time", np.float64)]
                       + [(n, np.float64) for n in kwargs["output"]])
        out["time"] = times
        for n in kwargs["output"]:
            out[n] = kwargs["start_values"][n] + (times - start)
        return out

    monkeypatch.setattr(fmpy, "simulate_fmu", master)
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.1, 0.01, 11),
                             torques=TORQUES, baumgarte=(2.0, 6.0))
    got = eng.simulate(sc)
    start = initial_state(thesis, sc)
    (call,) = calls
    assert call["filename"] == str(cs_fmu) and call["fmi_type"] == "CoSimulation"
    assert call["start_time"] == sc.t[0] and call["stop_time"] == sc.t[-1]
    assert call["output_interval"] == pytest.approx(5e-4, rel=1e-12)
    names = ["xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps"]
    outputs = names + ["d_" + n for n in names]
    assert call["output"] == outputs
    sv = call["start_values"]
    scales = np.ones(16)
    scales[[THETA, 8 + THETA]] = deg
    y0 = np.concatenate([start.q, start.dq])
    assert np.allclose([sv[n] for n in outputs], y0 / scales, rtol=1e-15, atol=0)
    assert sv["m3"] == pytest.approx(thesis.params.m3 / 2.0, rel=1e-15)
    assert sv["R_rear"] == thesis.params.R_rear
    assert (sv["a1"], sv["a2"]) == (2.0, 6.0)
    rows = call["input"]
    assert np.allclose(rows["time"], 0.1 + 5e-4 * np.arange(201), rtol=0, atol=1e-15)
    assert np.allclose(rows["Mdir"], 300.0, rtol=1e-15, atol=0)
    assert np.array_equal(rows["Mped"], np.full(201, 1.0))
    assert np.array_equal(rows["Mvue"], np.full(201, -0.2))
    assert got.status == "completed", got.message
    ramp = (sc.t - sc.t[0])[:, None] * scales
    assert np.allclose(np.hstack([got.q, got.dq]), y0 + ramp, rtol=1e-13, atol=1e-13)


# -- the fall -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def falling():
    """stability-psid0 (falls quickly: leaned and steered by pi/16 from rest) cut to 0.6 s:
    with the default limit 1.4 rad it does not fall that soon (the reference falls at 1.04 s),
    with 0.3 rad it does (the reference locates the fall at 0.379 s)."""
    return dataclasses.replace(get_scenario("stability-psid0"), grid=(0.0, 0.01, 61))


def _mirrored(sc: Scenario) -> Scenario:
    """The scenario's mirror image (lean and steer negated; the thesis bicycle is symmetric
    about its plane and the pedal torque lies in it): the same fall, to the other side."""
    q0 = list(sc.q0)
    q0[THETA], q0[GAMMA] = -q0[THETA], -q0[GAMMA]
    return dataclasses.replace(sc, name=sc.name + "-mirrored", q0=tuple(q0))


def _check_fall(got, ref, sc, limit):
    """The run stops at the first grid sample at or after the reference's located fall (the
    two runs agree to 1e-10 before it, so the sample is the same unless the fall is within
    1e-10 s of a sample: 0.379 s here): that row's |theta| is past the limit, every earlier
    one below; the arrays end there; the message names the limit and that sample's time."""
    k = int(np.searchsorted(sc.t, ref.t_end))
    assert ref.status == "fell" and sc.t[k] - ref.t_end > 1e-6
    assert got.status == "fell"
    assert got.t_end == sc.t[k] and np.array_equal(got.t, sc.t[:k + 1])
    assert got.q.shape == got.dq.shape == got.ddq.shape == (k + 1, 8)
    assert got.C.shape == (k + 1, 5) and got.T.shape == (k + 1, 3)
    assert abs(got.q[-1, THETA]) >= limit and np.all(np.abs(got.q[:-1, THETA]) < limit)
    assert np.max(np.abs(got.q[:-1] - ref.q[:k])) < 1e-10
    assert got.message == (f"|theta| reached the fall limit {limit:.4f} rad by t = "
                           f"{sc.t[k]:.6f} s (first sample past it)")
    assert got.settings["fall_limit"] == limit


@pytest.mark.parametrize("mirror", [False, True], ids=["theta>0", "theta<0"])
def test_a_fall_ends_the_run_at_the_first_sample_past_the_limit(thesis, engine, falling,
                                                                mirror):
    """fall_limit = 0.3 rad given to simulate: the run ends at 0.38 s, the first grid sample
    after the reference's located fall at 0.379 s (with the same limit), and its last row is
    that sample (|theta| 0.3004 there, 0.2946 at 0.37 s); the mirrored start falls to
    negative theta at the same times. Fails when the cut drops the fall's own row or keeps one
    more, when the lean is read from another column than theta, when a lean to the negative
    side is not a fall (|theta| not taken), or when the argument is ignored for the
    scenario's 1.4 rad."""
    sc = _mirrored(falling) if mirror else falling
    got = engine.simulate(sc, fall_limit=0.3)
    ref = ReferenceEngine(thesis).simulate(sc, fall_limit=0.3)
    assert np.sign(ref.q[-1, THETA]) == (-1 if mirror else 1)
    _check_fall(got, ref, sc, 0.3)


def test_the_scenarios_own_fall_limit_applies_and_the_argument_overrides_it(thesis, engine,
                                                                          falling):
    """docs/engines.md: ``fall_limit`` (rad) is the run's, else the scenario's. The scenario's
    0.3 rad ends the run as above; fall_limit = 1.4 given with it lets the 0.6 s run complete
    (the reference, with 1.4, falls only at 1.04 s). Fails when the scenario's limit is
    ignored (the default used), or when the argument loses to it."""
    sc = dataclasses.replace(falling, fall_limit=0.3)
    got = engine.simulate(sc)
    _check_fall(got, ReferenceEngine(thesis).simulate(sc), sc, 0.3)
    whole = engine.simulate(sc, fall_limit=1.4)
    assert whole.status == "completed" and whole.t.size == 61
    assert whole.settings["fall_limit"] == 1.4


@pytest.mark.parametrize("limit, shown", [(0.1, "0.1000"), (np.pi / 16, "0.1963")],
                         ids=["below", "equal"])
def test_a_start_at_or_past_the_fall_limit_is_a_fall_at_the_first_sample(thesis, engine,
                                                                         falling, limit, shown):
    """The start leans pi/16 = 0.196 rad (the projection solves beta and the dependent rates
    and keeps theta as given): a limit of 0.1 rad is past at t = 0, and a limit of exactly
    pi/16 is reached there (Scenario.fall_limit: a run stops when |theta| *reaches* it; the
    reference's solver, too, calls |theta| >= limit at the start a fall). The run is its first
    row alone, the projected initial state, with no NaN (its ddq: no differences from one
    sample; zeros). Fails when the fall's row is cut away (an empty trajectory), when a lean
    equal to the limit is not a fall, or when one sample's ddq is differenced into NaN or an
    error."""
    start = initial_state(thesis, falling)
    assert start.q[THETA] == np.pi / 16
    got = engine.simulate(falling, fall_limit=limit)
    assert got.status == "fell" and got.t_end == 0.0 and np.array_equal(got.t, [0.0])
    assert got.message == (f"|theta| reached the fall limit {shown} rad by t = 0.000000 s "
                           "(first sample past it)")
    assert np.max(np.abs(got.q[0] - start.q)) < 1e-12
    assert np.max(np.abs(got.dq[0] - start.dq)) < 1e-12
    assert np.array_equal(got.ddq, np.zeros((1, 8)))
    assert got.C.shape == (1, 5) and np.array_equal(got.T, [[0.0, 1.0, 0.0]])


# -- failures and refusals ------------------------------------------------------------------

def test_a_failing_fmu_step_is_a_failed_run_holding_the_initial_state(thesis, engine):
    """A steering torque of 1e200 N m overflows the state within the first step: the FMU's
    fmi2DoStep returns fmi2Error (the wrapper: "singular system or non-finite state") and
    fmpy raises. The run is "failed" (the reference's solver fails on it too, at t = 0: "the
    required step size is less than spacing between numbers"), its message one line
    that starts with the module's prefix and names fmi2DoStep; the trajectory is the projected
    initial state alone, finite (docs/engines.md: a failed run's arrays hold no NaN). Fails
    when the exception escapes, when the partial result is NaN, or when the message spans
    fmpy's traceback."""
    sc = dataclasses.replace(get_scenario("stability-psid0"), grid=(0.0, 0.01, 11),
                             torques=(1e200, 0.0, 0.0))
    got = engine.simulate(sc)
    start = initial_state(thesis, sc)
    assert got.status == "failed"
    assert got.message.startswith(PREFIX) and "fmi2DoStep" in got.message
    assert "\n" not in got.message
    assert np.array_equal(got.t, [0.0]) and got.t_end == 0.0
    assert np.max(np.abs(got.q[0] - start.q)) < 1e-12
    assert np.max(np.abs(got.dq[0] - start.dq)) < 1e-12
    for a in (got.q, got.dq, got.ddq, got.C):
        assert np.all(np.isfinite(a))
    assert np.array_equal(got.T, [[1e200, 0.0, 0.0]])


def test_the_failure_message_is_the_first_line_of_fmpys_error(engine, monkeypatch):
    """fmpy's errors can span lines (a traceback, a log): the message keeps the first line, so
    the report's one line is the cause. Here simulate_fmu raises "fmi2DoStep failed at
    t = 0.42\\n<log>": the message is the prefix and that line exactly. Fails when the whole
    text is kept, or the last line instead of the first."""
    def fail(*args, **kwargs):
        raise RuntimeError("fmi2DoStep failed at t = 0.42\n[ERROR] the log that follows")
    monkeypatch.setattr(fmpy, "simulate_fmu", fail)
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 11))
    got = engine.simulate(sc)
    assert got.status == "failed"
    assert got.message == PREFIX + "fmi2DoStep failed at t = 0.42"


def test_an_inverse_scenario_is_refused_naming_it(engine):
    """An inverse scenario has no initial state to run from: the reference's one-line refusal
    (reference_model.scenarios.initial_state) naming the scenario, before the FMU is run."""
    with pytest.raises(ValueError) as err:
        engine.simulate(get_scenario("check"))
    assert str(err.value) == "scenario 'check' is an inverse scenario; it has no initial state"


# -- the input table ------------------------------------------------------------------------

def _fake_engine(model=None):
    """What `_inputs` reads of an engine: its model (for a torque history named by another
    scenario) and the mapping's torques, here under names of the FMU's own and with scales
    (thesis value in N m = scale * FMU value, mapping.py's `Ref`)."""
    torques = (Ref("u_steer", 2.0), Ref("u_pedal", 0.5), Ref("u_body", -4.0))
    return SimpleNamespace(model=model, mapping=SimpleNamespace(torques=torques))


def test_constant_torques_are_tabled_under_the_fmus_names_in_its_units():
    """(Mdir, Mped, Mvue) = (0.3, 1.0, -0.2) N m with scales 2, 0.5, -4: the FMU's values are
    0.15, 2.0 and 0.05 (value / scale, by hand) at every time; the table's first column is
    "time" (fmpy reads the first field as the time grid: fmpy.simulation.Input), then the
    mapping's torques in its order. Fails when the torques are permuted, multiplied by the
    scale instead of divided, or the time column is not first."""
    t = np.array([0.0, 0.25, 0.5, 1.0])
    sc = Scenario("const", "", "forward", torques=TORQUES)
    rows = _inputs(_fake_engine(), sc, t)
    assert rows.dtype.names == ("time", "u_steer", "u_pedal", "u_body")
    assert all(rows.dtype[n] == np.float64 for n in rows.dtype.names)
    assert rows.shape == (4,)
    assert np.array_equal(rows["time"], t)
    assert np.array_equal(rows["u_steer"], np.full(4, 0.15))
    assert np.array_equal(rows["u_pedal"], np.full(4, 2.0))
    assert np.array_equal(rows["u_body"], np.full(4, 0.05))


@pytest.mark.parametrize("interpolation, expected", [
    # samples at 0, 1, 2 s: (0, 0, 0), (1, 2, 3), (3, 2, 1) N m; read at 0, 0.5, 1, 1.5 s
    ("linear", [(0, 0, 0), (0.5, 1, 1.5), (1, 2, 3), (2, 2, 2)]),
    ("previous", [(0, 0, 0), (0, 0, 0), (1, 2, 3), (1, 2, 3)]),
], ids=["linear", "previous"])
def test_sampled_torques_are_tabled_at_each_time(interpolation, expected):
    """A scenario's sampled torques (TorqueSamples), linear and held: the values at each time
    are worked out by hand from the three samples (linear: halfway values; previous: the last
    sample at or before), then divided by the scales. Fails when every row gets the first
    time's torques (a function taken for a constant), when row and time are misaligned, or
    when a torque's column goes under another name."""
    samples = TorqueSamples(t=(0.0, 1.0, 2.0), T=((0, 0, 0), (1, 2, 3), (3, 2, 1)),
                            interpolation=interpolation)
    sc = Scenario("sampled", "", "forward", torques=samples)
    t = np.array([0.0, 0.5, 1.0, 1.5])
    rows = _inputs(_fake_engine(), sc, t)
    T = np.array(expected, dtype=float)
    assert np.array_equal(rows["time"], t)
    assert np.allclose(rows["u_steer"], T[:, 0] / 2.0, rtol=1e-15, atol=0)
    assert np.allclose(rows["u_pedal"], T[:, 1] / 0.5, rtol=1e-15, atol=0)
    assert np.allclose(rows["u_body"], T[:, 2] / -4.0, rtol=1e-15, atol=0)


def test_a_torque_history_named_by_another_scenario_is_its_spline_on_the_engines_model(thesis):
    """The replay's torques are the zigzag's inverse-dynamics spline computed on the engine's
    model (`torque_input(model, scenario)`, evaluated here at each time): the table holds it
    divided by the scales. Fails when the model used is not the engine's, or a time's torques
    land on another row."""
    sc = get_scenario("replay")
    t = np.linspace(0.0, 0.5, 11)
    rows = _inputs(_fake_engine(thesis), sc, t)
    spline = torque_input(thesis, sc)
    T = np.array([spline(tk) for tk in t])
    assert np.ptp(T, axis=0).min() > 0
    assert np.array_equal(rows["u_steer"], T[:, 0] / 2.0)
    assert np.array_equal(rows["u_pedal"], T[:, 1] / 0.5)
    assert np.array_equal(rows["u_body"], T[:, 2] / -4.0)


def test_a_fall_stops_the_master_so_a_later_failure_cannot_hide_it(thesis, engine):
    """stability-psid0 with torques that turn NaN from 0.5 s and a 0.3 rad fall limit: the
    reference falls at 0.379 s, before the NaN. The master stops at the first grid sample past
    the limit, so the FMU never meets the NaN and the run is the fall, its last sample past the
    limit and the one before not. Before, the master ran the whole grid, the NaN made a step
    fail and the fall was reported as 'failed' holding the start alone."""
    base = get_scenario("stability-psid0")
    nan_after = dataclasses.replace(base, torques=lambda tk: (0.0, 0.0, 0.0) if tk < 0.5
                                    else (float("nan"),) * 3)
    got = engine.simulate(nan_after, fall_limit=0.3)
    assert got.status == "fell", got.message
    assert abs(got.q[-1, THETA]) >= 0.3 > abs(got.q[-2, THETA])
    assert got.t[-1] < 0.5


def test_a_step_failing_midway_keeps_the_samples_before_it(thesis, engine):
    """Torques that turn NaN just after 0.1 s on a run that does not fall first: the FMU's
    step fails there, and the run is 'failed' with the grid's samples up to 0.1 s
    (docs/engines.md: a failed run holds what it computed), each finite."""
    base = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 31))
    nan_after = dataclasses.replace(base, torques=lambda tk: (0.0, 0.0, 0.0) if tk <= 0.1
                                    else (float("nan"),) * 3)
    got = engine.simulate(nan_after)
    assert got.status == "failed", got.message
    assert 2 < got.t.size <= 11 and got.t[-1] <= 0.1 + 1e-12
    assert np.all(np.isfinite(got.q)) and np.all(np.isfinite(got.dq))


@pytest.mark.parametrize("limit", [0.0, -1.0, float("nan"), True, "0.5"])
def test_the_fall_limit_follows_the_one_rule(engine, limit):
    """docs/engines.md: every time loop applies reference_model.solvers.checked_fall_limit: a
    real, finite, positive angle; the same one-line refusal. Before, 0 and -1 fell at t = 0,
    True and NaN were taken and '0.5' raised numpy's error after the whole run."""
    with pytest.raises(ValueError, match=r"fall_limit must be a positive angle in rad; got "):
        engine.simulate(get_scenario("stability-psid5"), fall_limit=limit)


def test_t_end_cuts_the_grid_and_other_options_are_refused(engine):
    """t_end (the convergence and soft-contact studies pass it) cuts the run at the last
    sample not after it; rtol and atol, options of the reference's integrator, are refused in
    one line naming them rather than dropped (the FMU integrates with its own method)."""
    sc = get_scenario("stability-psid5")
    got = engine.simulate(sc, t_end=0.05)
    assert got.status == "completed" and got.t[-1] == max(x for x in sc.t if x <= 0.05 + 1e-12)
    with pytest.raises(Exception, match=r"Co-Simulation run takes no atol, rtol \(the FMU "
                                        r"integrates with its own method and step\); fix: "):
        engine.simulate(sc, rtol=1e-9, atol=1e-12)


def _master_steps(monkeypatch) -> list:
    """The (time, go on?) of each step_finished call fmpy's master makes, collected by
    wrapping the callback the engine gives simulate_fmu."""
    calls = []
    real = fmpy.simulate_fmu

    def spy(*args, step_finished=None, **kw):
        def wrapped(now, recorder):
            go_on = step_finished(now, recorder)
            calls.append((now, go_on))
            return go_on
        return real(*args, step_finished=wrapped, **kw)
    monkeypatch.setattr(fmpy, "simulate_fmu", spy)
    return calls


@pytest.mark.parametrize("mirror", [False, True], ids=["theta>0", "theta<0"])
def test_the_master_stops_at_the_falls_grid_sample(engine, falling, monkeypatch, mirror):
    """fmpy's master is asked to stop (its step_finished callback returns False) on the
    communication step that lands on the run's last grid sample, the first past the limit,
    and on no earlier step: nothing after the fall is computed. Read from the callback fmpy
    calls, wrapped here. Fails when the stop is tested off the grid's samples, on another
    sample, on another row of the recorder, or never (the run then goes on to 0.6 s)."""
    calls = _master_steps(monkeypatch)
    sc = _mirrored(falling) if mirror else falling
    got = engine.simulate(sc, fall_limit=0.3)
    assert got.status == "fell"
    stops = [now for now, go_on in calls if not go_on]
    assert len(stops) == 1 and calls[-1][1] is False
    assert stops[0] == pytest.approx(got.t[-1], abs=1e-12)


def test_a_step_failing_before_the_first_sample_holds_the_start_alone(engine):
    """Torques NaN from 2 ms on a 10 ms grid: the FMU fails within the first grid interval,
    after a few communication steps; the run holds the start (the one grid sample reached),
    not a sample made up past the failure."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 11),
                             torques=lambda tk: (0.0, 0.0, 0.0) if tk < 0.002
                             else (float("nan"),) * 3)
    got = engine.simulate(sc)
    assert got.status == "failed"
    assert got.t.tolist() == [0.0] and got.q.shape == (1, 8)


def test_t_end_refusals_and_two_samples_whole(engine):
    """t_end leaving one sample is refused in one line naming the grid's start and the fix;
    leaving exactly two is a run of two samples, their ddq the first-order difference of dq
    (numpy's gradient on two points) and a three-sample run's middle row the central
    difference; an unknown constraint handling is refused naming the three."""
    sc = get_scenario("stability-psid5")
    with pytest.raises(ValueError, match=r"^t_end=0\.005 leaves fewer than two samples of the "
                                         r"scenario's grid \(from 0 s\); fix: a later t_end"):
        engine.simulate(sc, t_end=0.005)
    dt = sc.t[1] - sc.t[0]
    two = engine.simulate(sc, t_end=dt)
    assert two.t.size == 2
    first = (two.dq[1] - two.dq[0]) / (two.t[1] - two.t[0])
    assert np.array_equal(two.ddq, np.vstack([first, first]))
    three = engine.simulate(sc, t_end=2 * dt)
    assert three.t.size == 3
    central = (three.dq[2] - three.dq[0]) / (three.t[2] - three.t[0])
    assert np.max(np.abs(three.ddq[1] - central)) <= 1e-12 * max(1.0, np.max(np.abs(central)))
    assert 0.0 <= three.timing["wall_seconds"] < 60.0
    with pytest.raises(ValueError, match=r"^constraints='exact': fix: 'baumgarte', 'none' or "
                                         r"'projection'"):
        engine.simulate(sc, constraints="exact")
    with pytest.raises(Exception, match=r"fix: leave it out, or use the Model-Exchange "
                                        r"interface \(interface=me\)"):
        engine.simulate(sc, atol=1e-12)


def test_a_grid_from_a_later_start_stops_on_its_own_samples(engine, falling, monkeypatch):
    """The falling scenario's grid shifted to start at 0.105 s (its samples 0.105 + k 0.01): the
    master's stop lands on the run's last sample, a time of that grid, not of a grid from 0
    (the sample index is counted from the run's start)."""
    calls = _master_steps(monkeypatch)
    sc = dataclasses.replace(falling, grid=(0.105, 0.01, 60))
    got = engine.simulate(sc, fall_limit=0.3)
    assert got.status == "fell"
    stops = [now for now, go_on in calls if not go_on]
    assert len(stops) == 1 and stops[0] == pytest.approx(got.t[-1], abs=1e-12)
    assert round((got.t[-1] - 0.105) / 0.01, 9) % 1 == 0


def test_constraints_none_runs_without_baumgarte_and_says_so(engine):
    """constraints='none' (an option `run` passes) is taken, not refused: the FMU's Baumgarte
    parameters at 0 and the settings naming it."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 6))
    got = engine.simulate(sc, constraints="none")
    assert got.status == "completed" and got.settings["constraints"] == "none"


def test_a_long_error_line_is_cut_at_160_characters(engine, monkeypatch):
    """The failure message keeps at most 160 characters of fmpy's first line (the report's
    status column)."""
    def fail(*args, **kwargs):
        raise RuntimeError("x" * 300 + "\nmore")
    monkeypatch.setattr(fmpy, "simulate_fmu", fail)
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 11))
    assert engine.simulate(sc).message == PREFIX + "x" * 160


# -- grids off zero, a lean in other units, a grid of one communication step ----------------

def test_a_grid_starting_half_a_step_late_falls_at_its_own_sample(thesis, engine, falling,
                                                                  monkeypatch):
    """The falling scenario on a grid from t0 = 0.25 ms (half a communication step; its samples
    t0 + k 0.01 s): the torques are constant and the equations do not hold t, so the reference's
    run of this scenario locates the fall at t0 + 0.37935 s, between the fine steps
    t0 + 0.3790 and t0 + 0.3795 s, and the run must end as a fall at the first grid sample past
    it, t0 + 0.38 s, following the reference before it (`_check_fall`), with the master's one
    stop on that sample. The sample index is counted from the grid's first time; counted from
    -t0 instead (2 t0 = one fine step: every count one step late) the check falls on
    t0 + 0.3795 s, past the fall but before the sample, so the master stops there and the run
    loses its fall sample ('completed' at t0 + 0.37 s). (The 0.105 s and 0.2 s starts above
    cannot show this: 2 t0 is a whole number of samples there.)
    Planted: the sample index taken from now + t0 instead of now - t0."""
    calls = _master_steps(monkeypatch)
    sc = dataclasses.replace(falling, grid=(0.00025, 0.01, 61))
    got = engine.simulate(sc, fall_limit=0.3)
    ref = ReferenceEngine(thesis).simulate(sc, fall_limit=0.3)
    _check_fall(got, ref, sc, 0.3)
    assert got.t_end == pytest.approx(0.00025 + 0.38, abs=1e-12)
    stops = [now for now, go_on in calls if not go_on]
    assert len(stops) == 1 and stops[0] == pytest.approx(got.t[-1], abs=1e-12)


def test_a_lean_mapped_in_degrees_falls_at_the_same_sample(thesis, cs_fmu, engine, falling,
                                                           monkeypatch, tmp_path):
    """The thesis FMU read through a mapping that puts its lean and lean rate in degrees
    (docs/engines.md: SI = scale * FMU value, scale pi/180), with the run's initial state
    (`initial_state`, replaced here) the falling scenario's projected start with theta and
    theta_dot multiplied by pi/180: the start values, SI / scale, are then that projected start
    itself, so the FMU computes the unscaled run (the plain mapping's, limit 0.3 rad), and the
    lean in SI is its lean times pi/180. With the limit 0.3 pi/180 rad, |theta| * pi/180 reaches
    it at exactly the samples where the unscaled run's |theta| reaches 0.3 rad: the run falls
    at the same sample (0.38 s), its master stopping there, with the unscaled run's states
    (theta times pi/180; 1e-10, the runs differ only by the start's rounding). The master's
    stop reads the FMU's theta in SI (times the scale); read divided by it, the lean looks
    3283 times larger, past the limit at the first sample, and the run stops at 0.01 s
    'completed'. Planted: the master's fall check dividing theta by its scale."""
    from reference_model.exports import fmu as fmu_export
    deg = np.pi / 180
    text = (fmu_export.mapping_text(thesis)
            .replace('theta = "theta"', f'theta = {{ name = "theta", scale = {deg!r} }}')
            .replace('theta = "d_theta"', f'theta = {{ name = "d_theta", scale = {deg!r} }}'))
    assert text.count("{ name = ") == 2
    (tmp_path / "degrees.toml").write_text(text)
    eng = load_engine(SPEC, thesis, fmu=str(cs_fmu), mapping=str(tmp_path / "degrees.toml"),
                      interface="cs")
    plain = engine.simulate(falling, fall_limit=0.3)
    assert plain.status == "fell" and plain.t_end == pytest.approx(0.38, abs=1e-12)
    start = initial_state(thesis, falling)
    q0, dq0 = start.q.copy(), start.dq.copy()
    q0[THETA] *= deg
    dq0[THETA] *= deg
    monkeypatch.setattr(cosimulation, "initial_state",
                        lambda model, scenario: SimpleNamespace(q=q0, dq=dq0))
    calls = _master_steps(monkeypatch)
    got = eng.simulate(falling, fall_limit=0.3 * deg)
    assert got.status == "fell", got.message
    assert np.array_equal(got.t, plain.t)
    assert got.message == (f"|theta| reached the fall limit {0.3 * deg:.4f} rad by t = "
                           f"{plain.t[-1]:.6f} s (first sample past it)")
    scales = np.ones(8)
    scales[THETA] = deg
    assert np.max(np.abs(got.q - plain.q * scales)) < 1e-10
    assert np.max(np.abs(got.dq - plain.dq * scales)) < 1e-10
    stops = [now for now, go_on in calls if not go_on]
    assert len(stops) == 1 and stops[0] == pytest.approx(plain.t[-1], abs=1e-12)


def test_a_grid_of_one_communication_step_is_stepped_once_per_sample(thesis, engine,
                                                                     monkeypatch):
    """The replay (all three torques vary) on a grid of 0.5 ms = `COMMUNICATION_STEP`, 0.05 s:
    the fewest equal steps of at most 0.5 ms is one per sample (the module's docstring: the
    steps are the grid's divided down to at most that), so fmpy's master makes exactly one
    communication step per grid interval, landing on the grid's times (its step_finished
    calls, wrapped here), and holds each torque over 0.5 ms: the run follows the reference's
    solver from the same start with the torques delayed by h/2 = 0.25 ms (the law used above;
    measured 2.9e-9 in q and 7.5e-9 in dq, bound 3e-8 and 1e-7), whereas two steps of 0.25 ms
    per sample hold the torques over half as long and land 4e-7 and 1.7e-5 away.
    Planted: at least two communication steps per sample (max(2, ...))."""
    calls = _master_steps(monkeypatch)
    sc = dataclasses.replace(get_scenario("replay"), grid=(0.0, COMMUNICATION_STEP, 101))
    got = engine.simulate(sc)
    assert got.status == "completed", got.message
    assert np.array_equal(got.t, sc.t)
    assert len(calls) == 100
    assert np.allclose([now for now, _ in calls], sc.t[1:], rtol=0, atol=1e-12)
    spline = torque_input(thesis, sc)
    init = initial_state(thesis, sc)
    held = simulate(thesis, init.q, init.dq, sc.t, lambda t: spline(t - COMMUNICATION_STEP / 2),
                    constraints="baumgarte", baumgarte=sc.baumgarte)
    assert np.max(np.abs(got.q - held.q)) < 3e-8
    assert np.max(np.abs(got.dq - held.dq)) < 1e-7
