"""The exported FMU's directional derivatives (fmi2GetDirectionalDerivative by complex steps)
and the fmu engine's roll/steer eigenvalues (engines/fmu/linear.py), against independent
values: central differences of the FMU's own derivatives through fmpy, and the reference's
complex-step linearization (reference_model/linearize.py: its own generated numpy code, its
own reduced inverse dynamics). The FMUs are cached (tests/fmu_builds.py, ~3-5 s cold each); a
warm run of the fast tests here costs ~0.5 s (fmpy instances and a few hundred FMI calls).
The thesis-disc comparison and the rebuilt FMU's shifted weave speed are slow (a build each).

Planted and watched failing (then removed): in fmu_wrapper.c, the complex seed of d_q_i put on
d_q_(i+1) (the Jacobian test 9.2 off of 157, the eigenvalues 100% off) and the complex cos's
imaginary part given the wrong sign (the Jacobian test 60 off; the eigenvalues unmoved: at
upright every such sine is of a zero angle and beta's tangent is zero by symmetry, which is why
the Jacobian is checked at a random state); in linear.tangents, gamma's dependent rates taken
from D's theta column (both routes' eigenvalues 2.6e-2 off); FD_STEP at 1e-2 (the central
differences' eigenvalues 2.7e-5 off, over their 1e-9); pow left out of complex_source's
renaming (the complex-copy test); the central differences of D divided by h, not 2h (both
tests that take them, 0.24 off)."""

import ctypes

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

from fmu_builds import cached_fmu   # noqa: E402
from reference_model import linearize, load_model   # noqa: E402
from reference_model.linearize import LinearizationError   # noqa: E402
from reference_model.solvers import consistent_state   # noqa: E402

SPEC = "engines.fmu:FmuEngine"
#: away from the benchmark's double roots (0.68 m/s, where weave turns oscillatory), through
#: the weave (4.29 m/s) and capsize (6.02 m/s) speeds
SPEEDS = np.array([0.0, 0.3, 1.0, 2.5, 4.0, 4.3, 5.0, 6.0, 8.0, 10.0])


def _without_drag(name):
    m = load_model(name)
    return m.with_params(m.params.replace(cv=0.0))


@pytest.fixture(scope="module")
def benchmark():
    return load_model("benchmark")


@pytest.fixture(scope="module")
def benchmark_engine(benchmark):
    from engines import load_engine
    return load_engine(SPEC, benchmark, fmu=str(cached_fmu(benchmark)))


@pytest.fixture(scope="module")
def benchmark_fd_path(benchmark):
    return cached_fmu(benchmark, directional_derivatives=False)


def _instance(path):
    """One fmpy instance of the FMU in continuous-time mode, a1 = a2 = 0."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model
    md = read_model_description(str(path))
    fmu = FMU2Model(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.modelExchange.modelIdentifier, instanceName="test")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.setReal([vr["a1"], vr["a2"]], [0.0, 0.0])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    return md, fmu, vr


def _relative_error(got, ref):
    """Per speed: the largest eigenvalue error relative to the largest eigenvalue there (an
    eigenvalue's absolute error is bounded by the matrix's, ~ its largest eigenvalue times the
    relative error of A)."""
    return np.max(np.abs(got - ref), axis=1) / np.max(np.abs(ref), axis=1)


def test_the_fmu_declares_directional_derivatives_and_fmpy_validates_it(benchmark, benchmark_fd_path):
    """providesDirectionalDerivative and the Derivatives' dependencies (der(q_i): d_q_i, a
    constant factor; der(dq_i): the 16 states and 3 inputs); fmpy's validation passes with and
    without them."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu
    path = cached_fmu(benchmark)
    assert validate_fmu(str(path)) == [] and validate_fmu(str(benchmark_fd_path)) == []
    md = read_model_description(str(path))
    assert md.modelExchange.providesDirectionalDerivative
    assert not read_model_description(str(benchmark_fd_path)).modelExchange.providesDirectionalDerivative
    der = {d.variable.name: d for d in md.derivatives}
    assert [v.name for v in der["der(theta)"].dependencies] == ["d_theta"]
    assert der["der(theta)"].dependenciesKind == ["constant"]
    assert len(der["der(d_gamma)"].dependencies) == 19
    assert {v.causality for v in der["der(d_gamma)"].dependencies} == {"local", "input"}


def test_directional_derivatives_match_central_differences_of_fmpys_derivatives(thesis):
    """The 16x16 state Jacobian of (dq, ddq), the torques' columns, a parameter's column (m3)
    and the constraint outputs', each by fmi2GetDirectionalDerivative, against central
    differences of fmi2GetDerivatives / fmi2GetReal through fmpy at a random consistent state
    (thesis model, thesis contact). Central differences at h = 1e-6 (relative for m3) err by
    ~h^2 |f'''| ~ 1e-11 and ~1e-16 |f| / h times the KKT solve's amplification ~ 1e-8 of the
    largest entry: measured 3.6e-10 (states), 3.2e-9 (torques), 8.9e-10 (m3); bounded by 1e-7.
    A directional derivative along a random direction equals the Jacobian times it to 1e-12
    (measured 3e-15: linear in the seed, complex steps have no step error)."""
    md, fmu, vr = _instance(cached_fmu(thesis))
    rng = np.random.default_rng(2026)
    s = consistent_state(thesis, rng.normal(size=8) * 0.3, rng.normal(size=8))
    x0 = np.concatenate([s.q, s.dq])
    states = [d.variable.derivative.valueReference for d in md.derivatives]
    ders = [d.variable.valueReference for d in md.derivatives]
    outputs = [vr[f"C.{k}"] for k in ("rD_z", "vC_x", "vD_y")] + [vr["lambda.vD_x"]]
    torques = [vr[t] for t in ("Mdir", "Mped", "Mvue")]
    T0 = np.array([0.3, -0.2, 0.5])

    def at(x, T=T0, m3=thesis.params.m3):
        fmu.setReal(torques + [vr["m3"]], list(T) + [m3])
        fmu.setContinuousStates((ctypes.c_double * 16)(*x), 16)

    def values(x, T=T0, m3=thesis.params.m3):
        at(x, T, m3)
        dx = (ctypes.c_double * 16)()
        fmu.getDerivatives(dx, 16)
        return np.concatenate([np.array(dx), fmu.getReal(outputs)])

    unknowns = ders + outputs
    at(x0)
    J = np.array([fmu.getDirectionalDerivative(unknowns, states, list(e)) for e in np.eye(16)]).T
    JT = np.array([fmu.getDirectionalDerivative(unknowns, torques, list(e)) for e in np.eye(3)]).T
    Jm = np.array(fmu.getDirectionalDerivative(unknowns, [vr["m3"]], [1.0]))
    h = 1e-6
    fd = np.array([(values(x0 + h * e) - values(x0 - h * e)) / (2 * h) for e in np.eye(16)]).T
    fdT = np.array([(values(x0, T0 + h * e) - values(x0, T0 - h * e)) / (2 * h) for e in np.eye(3)]).T
    hm = h * thesis.params.m3      # a relative step on the mass
    fdm = (values(x0, m3=thesis.params.m3 + hm) - values(x0, m3=thesis.params.m3 - hm)) / (2 * hm)
    for got, ref in ((J, fd), (JT, fdT), (Jm, fdm)):
        assert np.max(np.abs(got - ref)) <= 1e-7 * np.max(np.abs(ref))
    assert np.max(np.abs(J[:8, 8:] - np.eye(8))) == 0.0      # der(q) = dq, exactly
    d = rng.normal(size=16)
    at(x0)
    along = np.array(fmu.getDirectionalDerivative(unknowns, states, list(d)))
    assert np.max(np.abs(along - J @ d)) <= 1e-12 * np.max(np.abs(J @ d))
    fmu.terminate()
    fmu.freeInstance()


def test_the_fmu_engines_eigenvalues_match_the_reference_linearization(benchmark, benchmark_engine):
    """Through the FMU's directional derivatives, the benchmark's roll/steer eigenvalues at
    nine speeds against reference_model.linearize's complex-step linearization (its own
    generated numpy code and reduced inverse dynamics, not the FMU's C). Both exact to
    rounding (different solves: a 13x13 KKT LU here, the eliminated reduced dynamics there, each
    ~1e2 eps, through eigenvalue problems of condition up to ~1e2 near the crossings): measured
    6.1e-16 of the largest eigenvalue at worst, bounded by 1e-12.
    Also Meijaard et al. (2007)'s weave speed, 4.29238 m/s, from the engine's eigenvalues."""
    from scipy.optimize import brentq
    assert benchmark_engine.directional
    got = benchmark_engine.eigenvalues(SPEEDS)
    assert got.shape == (SPEEDS.size, 4) and got.dtype == complex
    assert np.max(_relative_error(got, linearize.eigenvalues(benchmark, SPEEDS))) <= 1e-12
    weave = brentq(lambda v: benchmark_engine.eigenvalues(v)[0, 0].real, 4.0, 4.6, xtol=1e-13)
    assert abs(weave - 4.292382536) <= 1e-9      # Meijaard et al. 2007, Table 2: 4.292382536


def test_an_fmu_without_directional_derivatives_takes_central_differences(benchmark, benchmark_fd_path):
    """The same benchmark exported without directional derivatives: the engine differences
    fmi2GetDerivatives (step FD_STEP = 1e-6) and still agrees, looser: truncation ~h^2 = 1e-12
    and round-off ~1e-16 |f| / h ~ 1e-10 of an entry of A (times the eigenvalues' condition
    ~10): measured 2.7e-13 of the largest eigenvalue, bounded by 1e-9. The FMU's own
    fmi2GetDirectionalDerivative refuses."""
    from engines import load_engine
    from fmpy.fmi1 import FMICallException
    engine = load_engine(SPEC, benchmark, fmu=str(benchmark_fd_path))
    assert not engine.directional
    got = engine.eigenvalues(SPEEDS)
    assert np.max(_relative_error(got, linearize.eigenvalues(benchmark, SPEEDS))) <= 1e-9
    _, fmu, _ = _instance(benchmark_fd_path)
    with pytest.raises(FMICallException):
        fmu.getDirectionalDerivative([24], [0], [1.0])



def test_an_fmu_mapped_without_terms_takes_the_constraints_from_the_reference(benchmark, tmp_path):
    """The mapping of someone else's FMU: states, torques, Baumgarte and parameters only (no
    [terms], no [residual]). The contact height and D are then the thesis's constraints at the
    FMU's states and dD . dq central differences of D (step 1e-6: ~1e-10 of an entry); measured
    3.3e-14 of the largest eigenvalue with the FMU's directional derivatives, bounded by 1e-9."""
    from engines import load_engine
    from reference_model.exports.fmu import mapping_text
    text = mapping_text(benchmark)
    cut = text[:text.index("# optional: outputs holding the thesis's terms")] + \
        text[text.index("# optional: the FMU parameters"):]
    (tmp_path / "map.toml").write_text(cut, encoding="utf-8")
    engine = load_engine(SPEC, benchmark, fmu=str(cached_fmu(benchmark)),
                         mapping=str(tmp_path / "map.toml"))
    assert engine.directional and not engine.mapping.terms and engine.mapping.residual is None
    got = engine.eigenvalues(SPEEDS)
    assert np.max(_relative_error(got, linearize.eigenvalues(benchmark, SPEEDS))) <= 1e-9

def test_the_reduction_needs_the_rates_dependence_on_the_configuration(benchmark, benchmark_engine):
    """Leaving out the dependent rates' change with roll and steer (dD . dq along the tangent:
    the yaw rate a steered front wheel forces at speed) moves the eigenvalues by far more than
    the tolerances above: the comparison with the reference sees the reduction, not only the
    FMU's derivatives."""
    from engines.fmu import linear
    e = benchmark_engine
    q0, dq0 = linear.upright_state(lambda q, dq: np.asarray(e.constraint_residual(q, dq)),
                                   e._jacobian, 5.0, benchmark.params.R_rear)
    A = linear.state_matrix(e._jvp, e._jacobian, lambda q, d: np.zeros((5, 8)), q0, dq0)
    wrong = linearize.sort_eigenvalues(np.linalg.eigvals(A))
    assert np.max(np.abs(wrong - linearize.eigenvalues(benchmark, 5.0))) > 0.1


def test_eigenvalues_of_a_model_with_drag_are_refused(thesis):
    """With drag (the thesis's cv = 0.8 kg/m) upright running at constant speed is no steady
    motion: a LinearizationError naming cv, as the reference's own linearize raises."""
    from engines import load_engine
    engine = load_engine(SPEC, thesis, fmu=str(cached_fmu(thesis)))
    with pytest.raises(LinearizationError, match="cv"):
        engine.eigenvalues([4.0])
    with pytest.raises(LinearizationError, match="cv"):
        linearize.eigenvalues(thesis, 4.0)


@pytest.mark.slow
def test_thesis_disc_eigenvalues_through_the_fmu_match_the_reference():
    """thesis-disc without drag, both routes: measured 1.8e-15 (directional derivatives) and
    9.2e-14 (central differences) of the largest eigenvalue; bounded by 1e-12 and 1e-9 as above."""
    from engines import load_engine
    model = _without_drag("thesis-disc")
    ref = linearize.eigenvalues(model, SPEEDS)
    for dd, tol in ((True, 1e-12), (False, 1e-9)):
        engine = load_engine(SPEC, model, fmu=str(cached_fmu(model, directional_derivatives=dd)))
        assert engine.directional is dd
        assert np.max(_relative_error(engine.eigenvalues(SPEEDS), ref)) <= tol


@pytest.mark.slow
def test_a_rebuilt_fmu_with_a_heavier_fork_moves_the_weave_speed(benchmark, tmp_path):
    """The benchmark rebuilt with the front frame (fork, handlebar) 2 kg heavier, used with its
    own parameters: the weave speed from the engine's eigenvalues moves from 4.2924 to
    4.3365 m/s, the reference's weave speed of the changed model to 1e-9 m/s (brentq at
    xtol 1e-13 on eigenvalues exact to 1e-12)."""
    from scipy.optimize import brentq
    from engines import load_engine
    from reference_model.exports.fmu import write_fmu
    heavy = benchmark.with_params(benchmark.params.replace(m4=benchmark.params.m4 + 2.0))
    path = write_fmu(heavy, tmp_path / "heavy.fmu")
    engine = load_engine(SPEC, benchmark, fmu=str(path), parameters="fmu")
    weave = brentq(lambda v: engine.eigenvalues(v)[0, 0].real, 4.0, 4.6, xtol=1e-13)
    assert abs(weave - linearize.weave_speed(heavy)) <= 1e-9
    assert weave - linearize.weave_speed(benchmark) > 0.04
    assert np.max(_relative_error(engine.eigenvalues(SPEEDS), linearize.eigenvalues(heavy, SPEEDS))) <= 1e-12


def test_the_complex_copy_renames_every_kernel_and_refuses_an_unknown_function():
    """complex_source on a two-line kernel: double -> cplx, bx_ -> bxc_, the elementary
    functions to the wrapper's first-order ones, the runtime's include dropped; a function it
    has no complex version of (atan2) is a one-line FmuExportError naming it and the fix."""
    from reference_model.exports.fmu import FmuExportError, complex_source
    text = ('static void bx_k(const double *q, double *out)\n'
            '{ const double a = sin(q[0]); out[0] = pow(a, 2.0) + sqrt(cos(a)); }\n'
            '#include "runtime.c"\n')
    got = complex_source(text)
    assert got == ('static void bxc_k(const cplx *q, cplx *out)\n'
                   '{ const cplx a = c_sin(q[0]); out[0] = c_pow(a, 2.0) + c_sqrt(c_cos(a)); }\n\n')
    with pytest.raises(FmuExportError, match="atan2.*fix: export with directional_derivatives=False"):
        complex_source("static void bx_k(const double *q, double *out) { out[0] = atan2(q[0], q[1]); }")
