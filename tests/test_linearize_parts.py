"""The parts of the reference linearization (reference_model/linearize.py) held to its module
docstring: the generated complex-capable numpy evaluator, its on-disk cache with its stamp,
the pitch solve, the complex-step Jacobian of the reduced inverse dynamics, and the weave and
capsize searches. Written from the survivors of the module's mutation measurement (each test
names the planted bugs it fails on).

The generator is tested directly: ``_module_source(contact)`` is executed into a fresh
namespace (the cached evaluator never shows what the generator of the code under test
produces). Expected values come from elsewhere:

* the generated functions against the reference Model's own compiled C terms (M, Qv, Qgrav,
  the constraint Jacobian D and bias dD dq, the front contact height [rD]_z), at random states,
  and their complex steps against the C code's D (a complex-step derivative of [rD]_z is the
  first row of D);
* the pitch solve: the front contact height of the C model at the solved pitch is zero, and the
  complex part carries d beta/d theta = -D[0, theta] / D[0, beta] (implicit function theorem);
* the Jacobian: the reduced forces written here as virtual power (F = N^T (M ddq - Qv - Qgrav),
  N = d dq / d dq_ind from the C model's D), central finite differences of it;
* the stamp: hashlib's own SHA-256 of the file's rest, the key in the file's name;
* the critical speeds: Meijaard et al. 2007's published values (comparisons/judgments/
  published.py), the exact scaling of both speeds with gravity (1/sqrt(k) for g/k), and
  synthetic spectra and determinants written out here whose crossings are known in closed form.

Tolerances: generated numpy vs compiled C of the same expressions, 1e-11 relative to each
array's largest entry (different CSE and operation order: ~1e-15 measured); complex step vs
the C code's D, 1e-12 relative (the complex step is exact to rounding); the Jacobian vs central
differences of step 1e-6, 1e-6 relative (the truncation error ~h^2 times third derivatives of
order 1-100). ~5 s, most of it the two symbolic derivations (shared by a module fixture).
"""

from __future__ import annotations

import hashlib
import warnings
from pathlib import Path

import numpy as np
import pytest

import reference_model.linearize as lz
from comparisons.judgments.published import (MEIJAARD_CAPSIZE_SPEED, MEIJAARD_TABLE2,
                                              MEIJAARD_WEAVE_SPEED)
from reference_model import load_model
from reference_model.equations import codegen
from reference_model.linearize import (CriticalSpeedError, LinearizationError, capsize_speed,
                                       eigenvalues, linearize, weave_speed)
from reference_model.params import ParameterWarning

COORDS = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")
IND = [COORDS.index(n) for n in ("theta", "psi", "gamma")]
DEP = [COORDS.index(n) for n in ("xc", "yc", "phi", "beta", "eps")]
THETA, BETA, GAMMA = COORDS.index("theta"), COORDS.index("beta"), COORDS.index("gamma")
EPS = np.finfo(float).eps
H = 1e-20
CONTACTS = {"thesis": "thesis", "disc": "thesis-disc"}   # contact -> model of that contact


def _close(got, want, rtol):
    """|got - want| <= rtol * max |want| (relative to the array's largest entry)."""
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, (got.shape, want.shape)
    scale = max(float(np.max(np.abs(want))), 1e-300)
    err = float(np.max(np.abs(got - want))) / scale
    assert err <= rtol, f"relative difference {err:.2e} > {rtol:.0e}"


@pytest.fixture(scope="module")
def generated():
    """contact -> (generated source, its namespace, the C model of that contact)."""
    out = {}
    for contact, name in CONTACTS.items():
        source = lz._module_source(contact)
        namespace: dict = {}
        exec(compile(source, f"<linearize-{contact}>", "exec"), namespace)
        out[contact] = (source, namespace, load_model(name))
    return out


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def _states(seed: int, k: int = 4):
    """k random states (q, dq) as (8, k) arrays: angles up to 0.6 rad, rates up to 3 /s."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-0.6, 0.6, (8, k))
    q[:2] = rng.uniform(-5.0, 5.0, (2, k))       # xc, yc (m)
    return q, rng.uniform(-3.0, 3.0, (8, k))


# -- the generated evaluator ---------------------------------------------------------------


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_the_generated_file_says_what_it_is_and_for_which_contact(generated, contact):
    """The head comment says the file is generated, by which file from which derivation, for
    which contact model, and that it is never hand-edited; then numpy is imported (the only
    name the code uses). Planted: the head's words lower-cased or upper-cased, the head
    replaced, the derivation of contact None."""
    source = generated[contact][0]
    lines = source.splitlines()
    assert lines[0] == ("# Generated by reference_model/linearize.py from "
                        f"reference_model/equations/derivation.py (contact {contact!r}).")
    assert lines[1] == ("# Complex-capable numpy evaluation for complex-step derivatives. "
                        "Never hand-edited.")
    assert lines[2] == "import numpy"
    assert [ln.split("(")[0] for ln in lines if ln.startswith("def ")] == [
        "def front_height", "def constraints", "def dynamics"]


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_the_generated_functions_are_the_models_terms(generated, contact):
    """At four random states (one batch of columns): front_height is ([rD]_z, d[rD]_z/dbeta),
    constraints is D (row-major 5x8) then dD dq, dynamics is M (row-major 8x8), Qv, Qgrav, each
    equal to the reference Model's compiled C terms of the same contact, as complex arrays of
    the documented shapes. Planted: a function or its outputs dropped or misnamed, the
    contact's other constraint row (C[1], D[1, beta]), the outputs written only where zero or
    skipped where exactly 1, the symbol unpacking or the placeholders' CSE broken, the printer
    without numpy's qualified names or with a bad setting."""
    _, ns, model = generated[contact]
    p = model.params.vector()
    q, dq = _states(11 + len(contact))
    k = q.shape[1]
    fh = ns["front_height"](q, dq, p)
    cons = ns["constraints"](q, dq, p)
    dyn = ns["dynamics"](q, dq, p)
    assert fh.shape == (2, k) and cons.shape == (45, k) and dyn.shape == (80, k)
    assert fh.dtype == cons.dtype == dyn.dtype == np.complex128
    qs, dqs = q.T.copy(), dq.T.copy()
    D = model.constraint_jacobian(qs)                                  # (k, 5, 8)
    _close(fh[0].real, model.constraint_residual(qs, dqs)[:, 0], 1e-11)
    _close(fh[1].real, D[:, 0, BETA], 1e-11)
    _close(cons[:40].real.reshape(5, 8, k).transpose(2, 0, 1), D, 1e-11)
    _close(cons[40:].real.T, model.constraint_bias(qs, dqs), 1e-11)
    _close(dyn[:64].real.reshape(8, 8, k).transpose(2, 0, 1), model.mass_matrix(qs), 1e-11)
    _close(dyn[64:72].real.T, model.Qv(qs, dqs), 1e-11)
    _close(dyn[72:80].real.T, model.Qgrav(qs), 1e-11)
    assert not np.any(fh.imag) and not np.any(cons.imag) and not np.any(dyn.imag)


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_the_generated_code_runs_on_complex_steps(generated, contact):
    """A complex step of each coordinate through front_height gives d[rD]_z/dq, the first row of
    the C model's D (the evaluator exists for complex-step derivatives: every operation must
    carry the imaginary part). Planted: the printer's functions not numpy's."""
    _, ns, model = generated[contact]
    p = model.params.vector()
    q0 = _states(5, 1)[0][:, 0]
    q = np.tile(q0.astype(complex)[:, None], (1, 8))
    q[np.arange(8), np.arange(8)] += 1j * H
    slope = ns["front_height"](q, np.zeros_like(q), p)[0].imag / H
    _close(slope, model.constraint_jacobian(q0)[0], 1e-12)


def test_the_evaluator_is_loaded_from_its_file_and_names_it(generated, tmp_path):
    """_load runs the text as the file it came from: the evaluator keeps the path, and the
    functions' code names it (a traceback in the evaluator points at the cached file).
    Planted: the path dropped from the evaluator or from compile."""
    path = tmp_path / "linearize-thesis-x.py"
    ev = lz._load(generated["thesis"][0], path)
    assert ev.path == path
    for f in (ev.front_height, ev.constraints, ev.dynamics):
        assert f.__code__.co_filename == str(path)


# -- the cache: key, stamp, verification --------------------------------------------------


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv(codegen.CACHE_ENV, str(folder))
    return folder


def _key_of(path: Path, contact: str) -> str:
    prefix = f"linearize-{contact}-"
    assert path.name.startswith(prefix) and path.suffix == ".py", path.name
    return path.name[len(prefix):-3]


def _fake_body(tag: str) -> str:
    return (f"def front_height(q, dq, p):\n    return {tag!r}\n"
            "constraints = dynamics = front_height\n")


def test_each_contact_has_its_own_key_of_the_code_generators_form(cache, monkeypatch):
    """The file name carries a key that depends on the contact model (the code generator's key
    does) and has the generator's own form (hex digits, as long as codegen.cache_key's); the
    evaluator is numpy, so the C compiler is not part of it (another CC keeps the key).
    Planted: the key of contact None (in _file_key or in the file name), 21 digits, the C
    backend's key (which hashes the compiler)."""
    thesis, disc = lz._cache_file("thesis"), lz._cache_file("disc")
    assert thesis.parent == disc.parent == cache
    kt, kd = _key_of(thesis, "thesis"), _key_of(disc, "disc")
    assert kt != kd
    assert len(kt) == len(codegen.cache_key("thesis")) and int(kt, 16) >= 0
    monkeypatch.setenv("CC", "some-other-compiler -O3")
    assert _key_of(lz._cache_file("thesis"), "thesis") == kt


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_the_stamp_names_the_contact_the_files_key_and_the_hash_of_the_rest(cache, contact):
    """The first line stamps the contact, the key (the one in the file's name) and the SHA-256
    of the rest (hashlib's, computed here). Planted: the digest None, the key of contact None."""
    body = _fake_body("x")
    stamp = lz._stamp(contact, body)
    assert stamp.endswith("\n") and stamp.count("\n") == 1
    fields = dict(f.split("=", 1) for f in stamp.split()[1:] if "=" in f)
    assert fields == {"contact": contact, "key": _key_of(lz._cache_file(contact), contact),
                      "sha256": hashlib.sha256(body.encode("utf-8")).hexdigest()}


def _no_generation(contact):
    raise AssertionError("the evaluator was generated although a verified file was there")


def test_a_matching_cached_file_is_used_as_it_is(cache, monkeypatch):
    """A file whose stamp matches (this contact, this key, the hash of its rest) is run, not
    regenerated: its functions are the evaluator's. Planted: the stamp compared against the
    last line (rpartition), a separator that never matches, the check inverted or made of
    contact None."""
    monkeypatch.setattr(lz, "_module_source", _no_generation)
    path = lz._cache_file("thesis")
    path.parent.mkdir(parents=True)
    body = _fake_body("cached")
    path.write_text(lz._stamp("thesis", body) + body, encoding="utf-8")
    assert lz._verified_text("thesis", path) == body
    ev = lz._evaluator.__wrapped__("thesis")
    assert ev.front_height(None, None, None) == "cached" and ev.path == path


def _damage(path: Path, how: str) -> None:
    text = path.read_text(encoding="utf-8")
    head, _, body = text.partition("\n")
    if how == "cut":
        path.write_text(text[: len(text) // 2], encoding="utf-8")
    elif how == "other contact":
        other = _fake_body("disc's")
        path.write_text(lz._stamp("disc", other) + other, encoding="utf-8")
    elif how == "changed body":
        path.write_text(head + "\n" + body.replace("stale", "stalE"), encoding="utf-8")
    elif how == "stamp only":
        path.write_text(head, encoding="utf-8")
    elif how == "other key":
        path.write_text(head.replace("key=", "key=0") + "\n" + body, encoding="utf-8")
    elif how == "not utf-8":
        path.write_bytes(b"\xff\xfe" + text.encode("utf-8"))


@pytest.mark.parametrize("how", ["cut", "other contact", "changed body", "stamp only",
                                 "other key", "not utf-8"])
def test_a_damaged_or_foreign_cached_file_is_refused_and_regenerated(cache, monkeypatch, how):
    """A file cut short, another contact's file copied over it, its body edited under the same
    stamp, a stamp without a body, another key's stamp, bytes that are not UTF-8: refused, the
    evaluator generated again and the file rewritten with a stamp that checks out (contact,
    key, hashlib's SHA-256 of the rest). Planted: the stamp check skipped when the file has a
    line break (`and` for `or`)."""
    monkeypatch.setattr(lz, "_module_source",
                        lambda contact: f"# fresh {contact}\n" + _fake_body(f"fresh {contact}"))
    path = lz._cache_file("thesis")
    path.parent.mkdir(parents=True)
    stale = _fake_body("stale")
    path.write_text(lz._stamp("thesis", stale) + stale, encoding="utf-8")
    _damage(path, how)
    assert lz._verified_text("thesis", path) is None
    ev = lz._evaluator.__wrapped__("thesis")
    assert ev.front_height(None, None, None) == "fresh thesis"
    head, _, rest = path.read_text(encoding="utf-8").partition("\n")
    assert rest == "# fresh thesis\n" + _fake_body("fresh thesis")
    assert f"contact=thesis key={_key_of(path, 'thesis')} " in head
    assert head.endswith(f"sha256={hashlib.sha256(rest.encode('utf-8')).hexdigest()}")


# -- the pitch solve ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def evaluators(generated):
    return {c: lz._load(generated[c][0], Path(f"linearize-{c}.py")) for c in CONTACTS}


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_the_solved_pitch_puts_the_front_wheel_on_the_ground(generated, evaluators, contact):
    """For three (roll, steer) columns, one carrying a complex step in roll and one in steer:
    the C model's front contact height at the solved pitch is zero (1e-14 m), q's beta row holds
    the result, and the imaginary parts are d beta/d theta and d beta/d gamma of the implicit
    function theorem, -D[0, j] / D[0, beta], from the C model's D. Planted: the Newton step
    height * slope (a gradient step that diverges for the disc)."""
    model = generated[contact][2]
    p = model.params.vector()
    q = np.zeros((8, 3), dtype=complex)
    q[THETA] = [0.2, -0.1, 0.3]
    q[GAMMA] = [0.4, 0.2, -0.5]
    q[THETA, 0] += 1j * H
    q[GAMMA, 1] += 1j * H
    beta = lz._solve_beta(evaluators[contact], q, p, "test")
    np.testing.assert_array_equal(q[BETA], beta)
    qr = q.real.T.copy()
    height = model.constraint_residual(qr, np.zeros_like(qr))[:, 0]
    assert np.max(np.abs(height)) < 1e-14
    D = model.constraint_jacobian(qr)
    want = [-D[0, 0, THETA] / D[0, 0, BETA], -D[1, 0, GAMMA] / D[1, 0, BETA], 0.0]
    np.testing.assert_allclose(beta.imag / H, want, rtol=1e-12, atol=1e-15)


class _Height:
    """A front contact height of the pitch alone, for the Newton solve's logic."""

    def __init__(self, height, slope):
        self.height, self.slope, self.calls = height, slope, 0

    def __call__(self, q, dq, p):
        self.calls += 1
        b = q[BETA]
        return np.array([self.height(b), self.slope(b) + 0 * b])


def _fake(height, slope):
    f = _Height(height, slope)
    return lz._Evaluator(f, None, None, Path("fake.py")), f


def test_newton_finds_a_linear_heights_root_in_one_step_and_checks_once_more():
    """h(beta) = 3 (beta - 0.2): Newton's first step lands on 0.2; the docstring's "once more"
    after the step is below 1e-14 makes three evaluations. Planted: the step h * s (9 times too
    long: diverges)."""
    ev, f = _fake(lambda b: 3.0 * (b - 0.2), lambda b: 3.0)
    q = np.zeros((8, 1), dtype=complex)
    assert lz._solve_beta(ev, q, np.zeros(30), "x")[0] == 0.2 and f.calls == 3


def test_a_pitch_the_front_contact_does_not_fix_is_refused_in_one_line():
    """d[rD]_z/dbeta = 0: refused with the pitch it was at and the parameters to check; the
    reduced dynamics' solve is named "linearize". Planted: the check removed, the message None
    or with its words' case changed, the caller's name None or changed."""
    ev, _ = _fake(lambda b: 1.0 + 0 * b, lambda b: 0.0)
    msg = ("{}: d[rD]_z/dbeta vanishes at beta = [0.0]: the front contact does not fix the "
           "frame pitch; check the geometry (R_front, xa, za, x5, z5)")
    with pytest.raises(LinearizationError) as err:
        lz._solve_beta(ev, np.zeros((8, 1), dtype=complex), np.zeros(30), "model 'm' upright")
    assert str(err.value) == msg.format("model 'm' upright")
    with pytest.raises(LinearizationError) as err:
        lz._reduced_forces(ev, np.zeros(30), np.zeros((1, 9)), 0.0)
    assert str(err.value) == msg.format("linearize")


def test_a_pitch_that_does_not_converge_is_refused_with_its_last_step():
    """A height with no root (1 everywhere, slope 1): 50 Newton steps of 1 rad, then refused
    with the count and the last step. Planted: the message None, its last step of None, its
    words' case changed."""
    ev, f = _fake(lambda b: 1.0 + 0 * b, lambda b: 1.0)
    with pytest.raises(LinearizationError) as err:
        lz._solve_beta(ev, np.zeros((8, 1), dtype=complex), np.zeros(30), "m")
    assert str(err.value) == ("m: Newton on [rD]_z = 0 for the frame pitch beta did not converge "
                              "in 50 iterations (last step 1.00e+00 rad); check the geometry: "
                              "the front wheel must be able to touch the ground")
    assert f.calls == 50


# -- the complex-step Jacobian of the reduced inverse dynamics ------------------------------


def _pitched(model, q):
    """q with beta solving the C model's [rD]_z = 0 (Newton on its D[0, beta])."""
    q = q.copy()
    for _ in range(30):
        q[BETA] -= (model.constraint_residual(q, np.zeros(8))[0]
                    / model.constraint_jacobian(q)[0, BETA])
    return q


def _reduced_reference(model, x):
    """[F_theta, F_psi, F_gamma] by virtual power: dq = N dq_ind with N = d dq / d dq_ind from
    the C model's D (D N = 0, N's independent rows the identity), ddq = N ddq_ind plus the part
    that cancels dD dq, and F = N^T (M ddq - Qv - Qgrav)."""
    q = np.zeros(8)
    q[IND] = x[0:3]
    q = _pitched(model, q)
    D = model.constraint_jacobian(q)
    N = np.zeros((8, 3))
    N[IND] = np.eye(3)
    N[DEP] = -np.linalg.solve(D[:, DEP], D[:, IND])
    dq = N @ x[3:6]
    ddq = N @ x[6:9]
    ddq[DEP] -= np.linalg.solve(D[:, DEP], model.constraint_bias(q, dq))
    return N.T @ model.inverse_dynamics(q, dq, ddq)


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_the_jacobian_is_the_reduced_forces_derivative(generated, evaluators, contact):
    """At a state away from upright with every rate and acceleration non-zero: F and dF/dx
    (3 x 9: the three coordinates, rates and accelerations) equal the virtual-power reduced
    forces written here on the C model's terms and their central differences. Planted: the
    complex step replacing the state's value instead of adding to it (the rates' derivatives
    then taken at zero rate), one extra row in the batch (a tenth column)."""
    model = generated[contact][2]
    p = model.params.vector()
    x0 = np.array([0.05, 0.3, -0.1, 0.2, 3.0, -0.4, 0.5, -0.3, 0.7])
    F, J = lz._jacobian(evaluators[contact], p, x0, 0.0)
    assert F.shape == (3,) and J.shape == (3, 9)
    _close(F, _reduced_reference(model, x0), 1e-11)
    h = 1e-6
    fd = np.array([(_reduced_reference(model, x0 + h * e) - _reduced_reference(model, x0 - h * e))
                   / (2 * h) for e in np.eye(9)]).T
    _close(J, fd, 1e-6)


# -- linearization, eigenvalues, speeds ---------------------------------------------------


def test_the_linearizations_matrices_cannot_be_written(bench):
    """M, C1, K0, K2 (benchmark signs) are read-only like A. Planted: _read_only leaving the
    arrays writeable."""
    lin = linearize(bench, 5.0)
    for name in ("M", "C1", "K0", "K2", "A"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(lin, name)[0, 0] = 1.0


def test_the_eigenvalues_are_complex_even_when_all_are_real(bench):
    """At 0 m/s the benchmark's four roots are real (Table 2: 5.53, 3.13, -3.13, -5.53 /s):
    returned as complex numbers, in that order (the docstring: "(4,) complex"), while numpy
    returns a real array for them. Planted: the sort keeping the input's dtype."""
    lam = eigenvalues(bench, 0.0)
    assert lam.dtype == np.complex128
    np.testing.assert_allclose(lam, MEIJAARD_TABLE2[0], rtol=0, atol=1e-12)
    assert lz.sort_eigenvalues(np.array([3.0, -1.0, 2.0])).dtype == np.complex128


def test_a_speed_of_none_is_refused_as_not_a_finite_speed(bench):
    """None is not a speed: the documented ValueError, not numpy's TypeError. Planted: the
    speeds read without converting to float."""
    with pytest.raises(ValueError, match=r"^v must be a finite speed or a 1-D array of finite "
                                         r"speeds \(m/s\); got None$"):
        eigenvalues(bench, None)


def test_the_weave_real_part_is_the_pairs_or_nan(bench, monkeypatch):
    """At 5 m/s the weave pair's real part is Table 2's -0.77534188219585 /s; at 0 m/s all four
    roots are real: nan. Planted: the pair test always true, nan written as None or a bad
    string."""
    assert lz._weave_real(bench, 5.0) == pytest.approx(MEIJAARD_TABLE2[5][0], abs=1e-12)
    assert np.isnan(lz._weave_real(bench, 0.0))


def test_an_imaginary_part_of_exactly_one_is_a_weave_pair(bench, monkeypatch):
    """A pair 0.5 +- 1i is a pair like any other (as the sort treats it). Planted: the pair
    test `imag != 1`."""
    monkeypatch.setattr(lz, "eigenvalues", lambda model, v: np.array([0.5 + 1j, 0.5 - 1j, -1, -2]))
    assert lz._weave_real(bench, 1.0) == 0.5


def test_the_grid_has_the_step_asked_for_over_the_range_asked_for():
    """A grid of `step` over `speeds`: 5 to 10 m/s by 0.5 is eleven speeds; a range shorter than
    one step is its two ends. Planted: the count from hi + lo, at least two intervals, one point
    fewer or more, numpy's default 50 points."""
    np.testing.assert_allclose(lz._grid((5.0, 10.0), 0.5), np.arange(5.0, 10.01, 0.5),
                               rtol=0, atol=1e-15)
    np.testing.assert_array_equal(lz._grid((0.0, 0.005), 0.01), [0.0, 0.005])


def _synthetic(re_part):
    """eigenvalues() of a made-up bicycle: a weave pair re(v) +- 1i and two real roots."""
    def eig(model, v):
        v = np.asarray(v, dtype=float)
        r = re_part(v) + 0 * v
        return np.stack([r + 1j, r - 1j, -1.0 + 0 * r, -2.0 + 0 * r], axis=-1)
    return eig


def _no_weave(model, v):
    v = np.asarray(v, dtype=float)
    return np.zeros(v.shape + (4,), dtype=complex) + np.array([-1.0, -2.0, -3.0, -4.0])


@pytest.mark.parametrize("re_part, speeds, want", [
    (lambda v: 1.0 - v, (0.0, 2.0), 1.0),                   # crossing on a grid point
    (lambda v: v * (0.75 - v), (0.0, 2.0), 0.75),           # zero (not +) at the first point
    (lambda v: (0.25 - v) * (1.0 - v), (0.0, 1.0), 0.25),   # a zero two points after
    (lambda v: (0.7 - v) ** 3, (0.0, 2.0), 0.7),            # a flat (cubic) crossing
], ids=["on-grid", "zero-before", "zero-after", "cubic"])
def test_the_weave_speed_of_a_synthetic_spectrum(bench, monkeypatch, re_part, speeds, want):
    """The weave pair's real part crosses from + to - at a known speed, on a 0.5 m/s grid:
    exactly on a grid point (that point is the answer), with a zero at the grid point before
    the bracketing one or two after it (not a crossing: brentq finds the root), and a cubic
    root, flat enough that brentq needs 116 iterations to reach the documented xtol 1e-14
    (|x - root| <= 1e-14 + 4 eps |x|). Planted: a zero at the bracket's end missed (< 0),
    returned as None or as the next or previous grid point, the zero test looking at i - 1 or
    i + 2, brentq's bracket two steps wide, brentq at its default xtol (2e-12: 2.7e-13 off on
    the cubic) or iteration limit (100: no convergence)."""
    monkeypatch.setattr(lz, "eigenvalues", _synthetic(re_part))
    got = weave_speed(bench, speeds, step=0.5)
    assert abs(got - want) <= 1e-14 + 4 * EPS * want


def test_a_real_part_touching_zero_from_below_is_not_a_weave_speed(bench, monkeypatch):
    """-(v - 1)^2 is 0 at 1 m/s (a grid point) and negative around it: no crossing from + to -.
    Planted: `>=` for `>` on the grid's left point."""
    monkeypatch.setattr(lz, "eigenvalues", _synthetic(lambda v: -(v - 1.0) ** 2))
    with pytest.raises(CriticalSpeedError, match="no weave speed in"):
        weave_speed(bench, (0.0, 2.0), step=0.5)


def test_the_capsize_speed_in_the_ranges_last_step(bench):
    """Between 5 and 6.03 m/s there is no weave speed (4.29), so the search runs from 5 m/s; the
    capsize speed 6.02426 lies in the grid's last interval [6.02, 6.03]. Planted: brentq's
    bracket two grid steps wide (past the grid's end)."""
    assert abs(capsize_speed(bench, (5.0, 6.03)) - MEIJAARD_CAPSIZE_SPEED) < 5e-14


def test_the_default_capsize_search_starts_at_zero_and_ends_at_20(bench, monkeypatch):
    """The default range is 0 to 20 m/s. With g = 0.001 m/s^2 (g / k, k = 9810) both speeds
    scale by 1/sqrt(k) (the linearized equations divided by k): weave 0.0433, capsize 0.0608
    m/s, found from 0 m/s. With a determinant that never vanishes the message names the range
    searched, from the weave speed to 20 m/s. Planted: the default range (1, 20) or (0, 21)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ParameterWarning)
        low_g = bench.with_params(bench.params.replace(g=0.001))
    k = bench.params.g / 0.001
    assert capsize_speed(low_g) == pytest.approx(MEIJAARD_CAPSIZE_SPEED / np.sqrt(k), abs=1e-9)
    monkeypatch.setattr(lz, "_capsize_function", lambda model: (lambda v: 1.0))
    with pytest.raises(CriticalSpeedError, match=r"^model 'benchmark': no capsize speed in "
                                                 r"\[4\.29238, 20\] m/s"):
        capsize_speed(bench)
    assert weave_speed(bench) == pytest.approx(MEIJAARD_WEAVE_SPEED, abs=5e-14)


def test_the_default_capsize_grid_is_fine_enough_for_two_close_roots(bench, monkeypatch):
    """No weave pair; det = (v - 1.105)(v - 1.605) is positive on both sides of [1.105, 1.605]
    (roots between the 0.01 m/s grid's points): only a grid finer than 0.5 m/s sees the first
    root, 1.105. Planted: a default step of 1.01 m/s."""
    monkeypatch.setattr(lz, "eigenvalues", _no_weave)
    monkeypatch.setattr(lz, "_capsize_function",
                        lambda model: (lambda v: (v - 1.105) * (v - 1.605)))
    assert abs(capsize_speed(bench) - 1.105) <= 1e-14 + 4 * EPS * 1.105


def test_the_capsize_search_looks_for_the_weave_on_its_own_grid(bench, monkeypatch):
    """The weave pair's real part (v - 0.9)(1 - v) is positive only between 0.9 and 1 m/s: the
    0.5 m/s grid given does not see it (1 m/s is a zero, not after a positive value), so the
    capsize search starts at 0 m/s and finds det = 0.3 - v's root 0.3. Planted: the weave
    searched at the default 0.01 m/s step (it then starts the capsize search at 1 m/s)."""
    monkeypatch.setattr(lz, "eigenvalues", _synthetic(lambda v: (v - 0.9) * (1.0 - v)))
    monkeypatch.setattr(lz, "_capsize_function", lambda model: (lambda v: 0.3 - v))
    assert abs(capsize_speed(bench, (0.0, 2.0), step=0.5) - 0.3) <= 1e-14 + 4 * EPS * 0.3


def test_a_flat_capsize_crossing_is_found_to_the_documented_tolerance(bench, monkeypatch):
    """det = (0.7 - v)^3: brentq needs more than its default 100 iterations to reach xtol 1e-14
    (116). Planted: brentq's iteration limit at its default."""
    monkeypatch.setattr(lz, "eigenvalues", _no_weave)
    monkeypatch.setattr(lz, "_capsize_function", lambda model: (lambda v: (0.7 - v) ** 3))
    assert abs(capsize_speed(bench, (0.0, 2.0), step=0.5) - 0.7) <= 1e-14 + 4 * EPS * 0.7


@pytest.mark.parametrize("det, want", [(lambda v: 1.5 - v, 1.5), (lambda v: (v - 1.5) * (v - 1.9), 1.5),
                                       (lambda v: (v - 1.0) * (v - 1.5), 1.0)])
def test_a_capsize_root_exactly_on_a_grid_point_is_found(bench, monkeypatch, det, want):
    """No weave pair, a 0.25 m/s grid on [0, 2] (every point exact in binary) and a determinant
    that crosses zero exactly on a grid point: the capsize speed is that point, as the weave
    search already returns a root on its grid. The sign products on both sides of such a point
    are 0, not negative, so the search found no bracket ("no capsize speed in [0, 2] m/s") or
    went past it. Seen failing before the fix."""
    monkeypatch.setattr(lz, "eigenvalues", _no_weave)
    monkeypatch.setattr(lz, "_capsize_function", lambda model: det)
    assert capsize_speed(bench, (0.0, 2.0), step=0.25) == want


def test_a_capsize_determinant_touching_zero_on_a_grid_point_is_no_crossing(bench, monkeypatch):
    """det = (v - 1.5)^2 is zero at the grid point 1.5 but keeps its sign: no real eigenvalue
    crosses zero there, so there is no capsize speed in the range (the message names it)."""
    monkeypatch.setattr(lz, "eigenvalues", _no_weave)
    monkeypatch.setattr(lz, "_capsize_function", lambda model: (lambda v: (v - 1.5) ** 2))
    with pytest.raises(CriticalSpeedError, match=r"no capsize speed in \[0, 2\] m/s"):
        capsize_speed(bench, (0.0, 2.0), step=0.25)
