"""The fmu engine (engines/fmu/engine.py) where an FMU or its surroundings differ from
bicycle-xval's own FMU in the usual case: a mapping file read under a non-UTF-8 locale, an FMU
that needs an event iteration at initialization, an FMU reporting non-finite derivatives
without an error status, an FMU with a forward push at upright running, the FMI arguments of
the directional derivative of D, and a replay's torques on an FMU that keeps its own
parameters.

Expected values: the documented contracts (docs/engines.md, "The fmu engine" and the forward
contract: status 0 ok, 1 singular, 2 the state or the result not finite; a torque history made
by another scenario's inverse dynamics is the reference model's, `run_forward(...,
torques_from=self.model)`), the FMI 2.0 standard (the event iteration at initialization calls
fmi2NewDiscreteStates until newDiscreteStatesNeeded is false; fmi2GetDirectionalDerivative's
nKnown is the number of seeds), TOML's own encoding (UTF-8), the reference model's own
functions and linear.py's documented refusal. The unusual FMUs are bicycle-xval's own FMU
(tests/fmu_builds.cached_fmu) with one of its fmpy calls wrapped to report what such an FMU
would (as tests/test_fmu_engine_edges.py wraps terminate and freeInstance). Each test names the
planted bugs (mutmut's survivors of the module) it fails on.
"""

from __future__ import annotations

import dataclasses
import locale

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

import fmpy.fmi2  # noqa: E402

from engines.fmu.engine import FmuEngine   # noqa: E402
from fmu_builds import cached_fmu   # noqa: E402
from reference_model import load_model   # noqa: E402
from reference_model.exports.fmu import mapping_text   # noqa: E402
from reference_model.linearize import LinearizationError   # noqa: E402
from reference_model.scenarios import get_scenario, torque_input   # noqa: E402
from test_fmu_engine_edges import engine, thesis_fmu   # noqa: E402,F401  (its fixtures)

#: docs/model.md's coordinate order
XC, THETA = 0, 3


@pytest.fixture(scope="module")
def benchmark():
    return load_model("benchmark")


@pytest.fixture(scope="module")
def benchmark_engine(benchmark):
    return FmuEngine(benchmark, fmu=str(cached_fmu(benchmark)))


def _derivative_slot(engine, state):
    """The position in the FMU's derivative vector of der(``state``), from its model
    description."""
    names = [d.variable.derivative.name for d in engine._description.derivatives]
    return names.index(state)


def test_a_mapping_file_is_read_as_utf8_whatever_the_locale(thesis, thesis_fmu, tmp_path):
    """A mapping is TOML, whose encoding is UTF-8: a mapping file with non-ASCII comments
    (units written as "°" and "µ", a dash) reads under the C locale, whose preferred encoding
    is ASCII (checked: the file does not read with it), and gives the mapping the template
    gives. Planted: the mapping file read with the locale's encoding."""
    template = mapping_text(thesis)
    path = tmp_path / "map.toml"
    path.write_text("# angles in rad (not °), lengths in m (not µm) — bicycle-xval\n" + template,
                    encoding="utf-8")
    plain = FmuEngine(thesis, fmu=str(thesis_fmu), mapping=str(_plain(tmp_path, template)))
    saved = locale.setlocale(locale.LC_CTYPE)
    try:
        locale.setlocale(locale.LC_CTYPE, "C")
        with pytest.raises(UnicodeDecodeError):
            path.read_text(encoding=locale.getencoding())
        e = FmuEngine(thesis, fmu=str(thesis_fmu), mapping=str(path))
    finally:
        locale.setlocale(locale.LC_CTYPE, saved)
    assert e.mapping == plain.mapping


def _plain(tmp_path, text):
    path = tmp_path / "plain.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_event_iteration_at_initialization_runs_until_no_new_discrete_states(
        thesis, thesis_fmu, monkeypatch):
    """FMI 2.0 (the event iteration after fmi2ExitInitializationMode): fmi2NewDiscreteStates
    is called until it reports newDiscreteStatesNeeded = false, then the FMU enters
    continuous-time mode. An FMU reporting that new discrete states are needed at its first
    call (and not at its second; terminateSimulation false throughout) is called twice before
    continuous-time mode, and its derivatives are then the reference's. Planted: the loop's
    test read from terminateSimulation (one call only)."""
    calls = []
    real_new, real_enter = fmpy.fmi2.FMU2Model.newDiscreteStates, \
        fmpy.fmi2.FMU2Model.enterContinuousTimeMode

    def new_discrete_states(fmu):
        info = real_new(fmu)
        calls.append("newDiscreteStates")
        first = calls.count("newDiscreteStates") == 1
        assert info[0] is False and info[1] is False        # the real FMU's own answer
        return (first,) + info[1:]

    def enter(fmu):
        calls.append("enterContinuousTimeMode")
        return real_enter(fmu)

    monkeypatch.setattr(fmpy.fmi2.FMU2Model, "newDiscreteStates", new_discrete_states)
    monkeypatch.setattr(fmpy.fmi2.FMU2Model, "enterContinuousTimeMode", enter)
    e = FmuEngine(thesis, fmu=str(thesis_fmu))
    q, dq = np.zeros(8), np.zeros(8)
    dq[4] = 5.0
    got = e.forward_acceleration(q, dq, (0.1, 0.2, 0.3))
    assert calls == ["newDiscreteStates", "newDiscreteStates", "enterContinuousTimeMode"]
    ref = thesis.forward(q, dq, (0.1, 0.2, 0.3), (0.0, 0.0)).ddq
    assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_non_finite_derivatives_reported_as_ok_are_status_two(engine, thesis, monkeypatch):
    """The forward contract (docs/engines.md): status 2 when the result is not finite. An FMU
    that returns fmi2OK with a NaN, or an infinite, acceleration (FMI lets it; bicycle-xval's
    own FMU refuses instead): the three states' statuses are 0, 2, 2, and forward_acceleration
    refuses, counting 2 states. Planted: the finiteness test always passing (status 0), the
    non-finite status 3."""
    inst = engine._instance((0.0, 0.0))
    slot = _derivative_slot(engine, engine.mapping.rates[THETA].name)
    real = inst.fmu.getDerivatives
    n = []

    def lenient(dx, nx):
        real(dx, nx)
        n.append(1)
        if len(n) % 3 == 2:
            dx[slot] = np.nan
        elif len(n) % 3 == 0:
            dx[slot] = np.inf

    monkeypatch.setattr(inst.fmu, "getDerivatives", lenient)
    q, dq = np.zeros((3, 8)), np.zeros((3, 8))
    dq[:, 4] = 5.0
    got = engine.forward(q, dq, (0.1, 0.2, 0.3), (0.0, 0.0))
    assert np.array_equal(got.status, [0, 2, 2])
    with pytest.raises(ArithmeticError) as err:
        engine.forward_acceleration(q, dq)
    assert str(err.value) == "the FMU's derivatives failed (fmi2GetDerivatives) at 2 state(s)"


def test_a_forward_push_at_upright_running_is_refused_by_the_linearization(
        benchmark_engine, benchmark, monkeypatch):
    """linear.py: the derivatives are checked to vanish at the steady motion (to 1e-8 of
    g + v^2 / R_rear), any force that keeps it from being one refused. The benchmark FMU with a
    forward push of 1e-3 m/s^2 on the rear contact (its der of the xc rate raised by that, as
    an FMU with a propulsive force would report; every other acceleration zero there) is
    refused at 5 m/s, quoting the push. Planted: the checked accelerations read from the yc
    rate on (the xc acceleration left out: no refusal)."""
    e = benchmark_engine
    inst = e._instance(None)
    rate = e.mapping.rates[XC]
    slot = _derivative_slot(e, rate.name)
    real = inst.fmu.getDerivatives

    def pushed(dx, nx):
        real(dx, nx)
        dx[slot] += 1e-3 / rate.scale

    monkeypatch.setattr(inst.fmu, "getDerivatives", pushed)
    with pytest.raises(LinearizationError) as err:
        e.eigenvalues([5.0])
    assert str(err.value) == (
        "upright straight running at 5 m/s is not a steady motion of this engine "
        "(accelerations up to 1.00e-03 there; drag cv > 0?); fix: linearize a model without "
        "drag, model.params.replace(cv=0.0)")


def test_the_directional_derivative_of_d_is_taken_along_the_eight_coordinates(
        engine, thesis, monkeypatch):
    """dD . v (the linearization's `_along`) from the FMU's fmi2GetDirectionalDerivative: the
    unknowns are the 40 outputs of the mapped D (rows in order), the knowns the 8 coordinate
    states (the mapping's [coordinates], value references from the model description) with
    one seed each (FMI 2.0: nKnown seeds; a ninth known makes the FMU read past the seeds),
    and the result is D's derivative along v (central differences of the reference's D,
    1e-8). Planted: the knowns taken from the first nine states (the eighth rate's state
    too)."""
    seen = []
    real = FmuEngine._directional

    def spy(inst, unknowns, knowns, seed):
        seen.append((list(unknowns), list(knowns), list(seed)))
        return real(inst, unknowns, knowns, seed)

    monkeypatch.setattr(FmuEngine, "_directional", staticmethod(spy))
    refs = {v.name: v.valueReference for v in engine._description.modelVariables}
    q = np.array([0.1, -0.2, 0.3, 0.05, 0.4, 0.02, 0.1, -0.3])
    v = np.array([0.3, -0.1, 0.2, 0.5, -0.4, 0.1, 0.6, 0.2])
    got = engine._along(q, v)
    ((unknowns, knowns, seed),) = seen
    assert knowns == [refs[r.name] for r in engine.mapping.coordinates]
    assert len(seed) == len(knowns) == 8
    assert unknowns == [refs[n] for row in engine.mapping.terms["D"] for n in row]
    h = 1e-5
    fd = (np.asarray(thesis.constraint_jacobian(q + h * v))
          - np.asarray(thesis.constraint_jacobian(q - h * v))) / (2 * h)
    assert got.shape == (5, 8)
    assert np.max(np.abs(got - fd)) <= 1e-8 * np.max(np.abs(fd))


def test_a_replays_torques_are_the_engine_models_inverse_dynamics(thesis, thesis_fmu):
    """docs/engines.md: a torque history made by another scenario's inverse dynamics (replay's
    zigzag) is the reference model's, `run_forward(..., torques_from=self.model)`. With
    parameters=fmu the FMU keeps the thesis's geometry while the engine's model has a front
    wheel 5 cm larger: the run's torques are the engine model's own zigzag torques
    (torque_input on that model, evaluated at the samples), exactly, not ones made with the
    FMU's constraint residual (7 N m off). Planted: torques_from dropped or None."""
    other = thesis.with_params(thesis.params.replace(R_front=thesis.params.R_front + 0.05))
    e = FmuEngine(other, fmu=str(thesis_fmu), parameters="fmu")
    sc = dataclasses.replace(get_scenario("replay"), grid=(0.0, 0.01, 3))
    run = e.simulate(sc)
    assert run.status == "completed"
    f = torque_input(other, sc)
    assert np.array_equal(run.T, np.array([np.asarray(f(t), dtype=float) for t in run.t]))
