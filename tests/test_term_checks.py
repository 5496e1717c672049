"""comparisons/judgments/term_checks.py on its own: the terms taken out of an engine through
the Engine interface, the forward solve they are checked against, and how a compared block is
judged and its worst entries named.

Expected values: the reference model's own methods (M, Qv, Qgrav, Qaero, S, D, dD dq called
directly; an engine built on them must give them back through the interface to round-off),
a 2-coordinate constrained solve worked out by hand, and blocks whose differences are placed
by hand. No localization runs; ~50 ms."""

import numpy as np
import pytest

from comparisons.judgments.term_checks import (COPY_SOURCE, TERM_TOLERANCE, Block, TermCheck,
                                               check_block, check_terms, engine_terms, extract,
                                               model_terms, solve_values, term_blocks)
from comparisons.judgments.terms import States, random_states
from comparisons.judgments.tolerances import Tolerance, load_tolerances
from engines import Engine, load_engine

STATES = random_states(4, seed=5)
TOLS = load_tolerances()


def _close(a, b):
    # 1e-9 relative to the largest entry: the interface's differences (F(q, dq) - F(q, 0))
    # lose ~1e-16 x |Qv| (~1e4 at these rates); anything wrong is O(1) of a term
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * max(1.0, np.abs(b).max()))


def test_model_terms_are_the_models_methods(thesis):
    s = STATES
    t = model_terms(thesis, s)
    assert list(t) == ["M", "Qv", "Qgrav", "Qaero", "S", "D", "dD dq"]
    for name, want in (("M", thesis.mass_matrix(s.q)), ("Qv", thesis.Qv(s.q, s.dq)),
                       ("Qgrav", thesis.Qgrav(s.q)), ("Qaero", thesis.Qaero(s.q, s.dq)),
                       ("S", thesis.S(s.q)), ("D", thesis.constraint_jacobian(s.q)),
                       ("dD dq", thesis.constraint_bias(s.q, s.dq))):
        np.testing.assert_array_equal(t[name], want)


def test_the_terms_come_back_through_the_interface(thesis):
    """The reference engine (every capability): each term, each copy (Qgrav and Qv out of
    generalized_forces, M out of inverse_dynamics) and the solve are the model's."""
    s = STATES
    terms, copies, solve = extract(load_engine("reference", thesis), s, extras=True)
    want = model_terms(thesis, s)
    assert list(terms) == list(want)
    for name in want:
        _close(terms[name], want[name])
    assert sorted(copies) == ["M", "Qgrav", "Qv"]
    _close(copies["Qgrav"], want["Qgrav"])
    _close(copies["Qv"], want["Qv"])
    _close(copies["M"], want["M"])
    ddq = thesis.forward_acceleration(s.q, s.dq, s.T)
    _close(solve.ddq, ddq)
    _close(solve.own, ddq)        # the engine's accelerations are its own terms' solve
    F = thesis.generalized_forces(s.q, s.dq, s.T)
    _close(solve.unconstrained, np.linalg.solve(want["M"], F[..., None])[..., 0])
    # without extras: no copies, no solve, the same terms
    t2, c2, s2 = extract(load_engine("reference", thesis), s, extras=False)
    assert c2 == {} and s2 is None and list(t2) == list(terms)
    assert list(engine_terms(load_engine("reference", thesis), s)) == list(terms)


class ForcesOnly(Engine):
    """generalized_forces and D alone: Qgrav is F at rest, Qv its even part, Qaero its odd
    part, S its torque columns."""

    name = "forces-only"
    capabilities = frozenset({"generalized_forces", "constraint_jacobian"})

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self.model.generalized_forces(q, dq, torques)

    def constraint_jacobian(self, q):
        return self.model.constraint_jacobian(q)


def test_an_engine_with_forces_alone_gives_them_split(thesis):
    s = STATES
    terms, copies, solve = extract(ForcesOnly(thesis), s, extras=True)
    want = model_terms(thesis, s)
    assert list(terms) == ["Qv", "Qgrav", "Qaero", "S", "D"]
    for name in terms:
        _close(terms[name], want[name])
    assert copies == {} and solve is None     # nothing to copy from, no M to solve with


def test_gravity_and_inverse_dynamics_give_qgrav_and_qv_and_f_their_copies(thesis):
    class GravID(ForcesOnly):
        name = "grav-id"
        capabilities = frozenset({"gravity", "inverse_dynamics", "generalized_forces"})

        def gravity(self, q):
            return self.model.Qgrav(q) + 1.0          # planted: Qgrav off by 1 N everywhere

        def inverse_dynamics(self, q, dq, ddq):
            return self.model.inverse_dynamics(q, dq, ddq)

    s = STATES
    terms, copies, _ = extract(GravID(thesis), s, extras=True)
    want = model_terms(thesis, s)
    _close(terms["Qgrav"], want["Qgrav"] + 1.0)       # gravity() is the term
    _close(copies["Qgrav"], want["Qgrav"])            # F at rest is its copy
    # Qv = -ID(q, dq, 0) - Qgrav with the engine's own (wrong) Qgrav: the 1 N shows there too
    _close(terms["Qv"], want["Qv"] - 1.0)
    _close(copies["Qv"], want["Qv"])                  # F's own Qv: its own gravity taken off
    _close(copies["M"], want["M"])


def test_the_constrained_solve_by_hand():
    """M = I (2x2), one constraint x1 + x2 with bias b, F = (1, 0):
    x1 + lambda = 1, x2 + lambda = 0, x1 + x2 = -b  ->  x = ((1 - b)/2, -(1 + b)/2);
    with the bias's sign flipped x = ((1 + b)/2, -(1 - b)/2); without the constraint x = F."""
    b = 0.5
    M, D = np.eye(2)[None], np.array([[[1.0, 1.0]]])
    F, bias = np.array([[1.0, 0.0]]), np.array([[b]])
    sv = solve_values(np.array([[9.0, 9.0]]), M, F, D, bias)
    np.testing.assert_allclose(sv.own, [[(1 - b) / 2, -(1 + b) / 2]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(sv.bias_flipped, [[(1 + b) / 2, -(1 - b) / 2]], rtol=0,
                               atol=1e-15)
    np.testing.assert_allclose(sv.unconstrained, F, rtol=0, atol=0)
    assert sv.ddq.tolist() == [[9.0, 9.0]]
    # M and D all zero: a singular system, no solve (None, not an exception)
    assert solve_values(F, np.zeros((1, 2, 2)), F, np.zeros((1, 1, 2)), bias) is None


def _tol(value, scale="absolute"):
    return Tolerance("x", value, scale, "test")


def test_blocks_carry_their_source_reference_scale_and_tolerance(thesis):
    s = STATES
    ref = model_terms(thesis, s)
    # a copy is always of a term the engine has (extract takes it beside the term)
    engine_values = {"e": {"M": ref["M"], "Qv": ref["Qv"] + 1e-3, "Qgrav": ref["Qgrav"]}}
    copies = {"e": {"Qgrav": ref["Qgrav"]}}
    tols = {"mass_matrix": _tol(1e-12, "max_abs"), "generalized_forces":
            _tol(1e-10, "largest_term"), "gravity": _tol(1e-11, "max_abs"),
            "forward_acceleration": _tol(1e-9, "max_abs_or_one")}
    own = np.ones((4, 8))
    solves = {"e": type("S", (), {"ddq": own * 2, "own": own * 3})()}
    blocks = term_blocks(ref, engine_values, tols, copies, solves)
    assert [(b.engine, b.term, b.source, b.label) for b in blocks] == [
        ("e", "M", "", "M"), ("e", "Qv", "", "Qv"), ("e", "Qgrav", "", "Qgrav"),
        ("e", "Qgrav", "F", "Qgrav in F"), ("e", "ddq", "solve", "ddq solve")]
    assert [b.tolerance for b in blocks] == [1e-12, 1e-10, 1e-11, 1e-11, 1e-9]
    blocks = blocks[:2] + blocks[3:]
    for k in range(4):
        # M: max |M|; Qv: the largest of |Qv| and |Qgrav| (its extraction involves both), at
        # least 1; Qgrav: max |Qgrav| (the copy shares its term's scale)
        assert blocks[0].scale[k] == np.abs(ref["M"][k]).max()
        assert blocks[1].scale[k] == max(1.0, np.abs(ref["Qv"][k]).max(),
                                         np.abs(ref["Qgrav"][k]).max())
        assert blocks[2].scale[k] == np.abs(ref["Qgrav"][k]).max()
    assert blocks[3].scale.tolist() == [3.0] * 4       # max(1, max |own|)
    assert (blocks[3].value == 2).all() and (blocks[3].reference == 3).all()
    np.testing.assert_array_equal(blocks[1].reference, ref["Qv"])
    w = blocks[1].weighted(np.ones((4, 8)))
    np.testing.assert_array_equal(w, 1.0 / blocks[1].scale[:, None] * np.ones((4, 8)))
    assert set(COPY_SOURCE) <= set(TERM_TOLERANCE)


def test_check_block_names_the_entries_above_tolerance_worst_first_at_most_three():
    ref = np.zeros((3, 8))
    value = ref.copy()
    value[1, 2] = 4e-6       # phi at state 1: the worst
    value[2, 5] = 3e-6       # beta
    value[0, 0] = 2e-6       # xc
    value[0, 7] = 1.5e-6     # eps: a fourth one, not named
    value[2, 3] = 0.5e-6     # theta: below tolerance, not named
    c = check_block(Block("e", "Qv", "F", value, ref, np.ones(3), 1e-6))
    assert c.entries == ("Qv[phi]", "Qv[beta]", "Qv[xc]")
    assert (c.worst_state, c.max_error, c.max_abs_error, c.passed) == (1, 4e-6, 4e-6, False)
    assert (c.engine, c.term, c.source, c.label, c.tolerance) == ("e", "Qv", "F", "Qv in F",
                                                                  1e-6)
    assert c.describe() == ("Qv in F vs e: DIFFERS, max error 4.00e-06 (tolerance 1e-06) at "
                            "Qv[phi], Qv[beta], Qv[xc]")
    assert c.to_dict() == {"engine": "e", "term": "Qv", "max_error": 4e-6,
                           "max_abs_error": 4e-6, "tolerance": 1e-6, "passed": False,
                           "worst_state": 1, "entries": ["Qv[phi]", "Qv[beta]", "Qv[xc]"],
                           "source": "F"}
    # the scale divides per state: state 0 at scale 10 drops xc and eps below tolerance
    c = check_block(Block("e", "Qv", "", value, ref, np.array([10.0, 1.0, 1.0]), 1e-6))
    assert c.entries == ("Qv[phi]", "Qv[beta]")
    # nothing above tolerance: the worst entry alone is named, and it passes
    small = ref.copy()
    small[2, 6] = 1e-7
    c = check_block(Block("e", "Qv", "", small, ref, np.ones(3), 1e-6))
    assert (c.entries, c.passed, c.worst_state) == (("Qv[gamma]",), True, 2)
    assert c.describe().startswith("Qv vs e: ok, ")
    # exactly at the tolerance passes (the largest accepted error)
    at = ref.copy()
    at[0, 1] = 1e-6
    assert check_block(Block("e", "Qv", "", at, ref, np.ones(3), 1e-6)).passed is True


def test_check_block_names_a_symmetric_difference_once_and_nonfinite_as_infinite():
    ref = np.tile(np.eye(8), (2, 1, 1))
    value = ref.copy()
    value[1, 3, 6] += 2e-6
    value[1, 6, 3] += 2e-6          # symmetric: M[theta, gamma] once, not its mirror too
    value[0, 0, 1] += 1e-6 * 1.5    # one-sided: named
    c = check_block(Block("e", "M", "", value, ref, np.ones(2), 1e-6))
    assert c.entries == ("M[theta, gamma]", "M[xc, yc]")
    # D (not M) keeps both of a mirrored pair: rows and columns are different things
    D = np.zeros((1, 5, 5))
    Dv = D.copy()
    Dv[0, 1, 2] = Dv[0, 2, 1] = 1.0
    assert len(check_block(Block("e", "D", "", Dv, D, np.ones(1), 1e-6)).entries) == 2
    bad = ref.copy()
    bad[1, 2, 2] = np.nan
    c = check_block(Block("e", "M", "", bad, ref, np.ones(2), 1e-6))
    assert c.max_error == np.inf and c.passed is False and c.worst_state == 1
    assert c.entries[0] == "M[phi, phi]"
    # the solve's block is named by coordinate
    dd = check_block(Block("e", "ddq", "solve", np.eye(8)[None, 6] * 1e-3, np.zeros((1, 8)),
                           np.ones(1), 1e-9))
    assert dd.entries == ("ddq[gamma]",) and dd.label == "ddq solve"


def test_check_terms_checks_every_term_of_every_engine(thesis):
    s = STATES
    ref = model_terms(thesis, s)
    vals = {"a": {"M": ref["M"]}, "b": {"Qgrav": ref["Qgrav"] * (1 + 1e-3)}}
    checks = check_terms(ref, vals, TOLS)
    assert [(c.engine, c.term, c.passed) for c in checks] == [("a", "M", True),
                                                              ("b", "Qgrav", False)]
    # Qgrav 1e-3 relative everywhere, judged relative to max |Qgrav| per state: 1e-3
    assert checks[1].max_error == pytest.approx(1e-3, rel=1e-9)
    assert checks[1].tolerance == TOLS["gravity"].tolerance


def test_what_an_engine_lacks_is_not_asked_and_a_copy_keeps_its_own_values(thesis):
    """An engine with M alone is asked for M alone (not generalized_forces, which would
    raise CapabilityError). A non-symmetric M from inverse_dynamics keeps its orientation in
    the copy: column k is ID(q, 0, e_k) - ID(q, 0, 0), not row k. Qgrav's scale at rest
    (dq = 0: no Qv) is its own largest entry, which also bounds Qv's (Qv's parts: Qv, Qgrav)."""
    class OnlyM(Engine):
        name = "only-m"
        capabilities = frozenset({"mass_matrix"})

        def mass_matrix(self, q):
            return self.model.mass_matrix(q)

    terms, copies, solve = extract(OnlyM(thesis), STATES, extras=True)
    assert list(terms) == ["M"] and copies == {} and solve is None

    U = np.triu(np.ones((8, 8)))                       # not symmetric

    class Skewed(Engine):
        name = "skewed"
        capabilities = frozenset({"inverse_dynamics"})

        def inverse_dynamics(self, q, dq, ddq):
            return np.einsum("ij,nj->ni", U, np.broadcast_to(ddq, (len(q), 8)))

    _, copies, _ = extract(Skewed(thesis), STATES, extras=True)
    np.testing.assert_array_equal(copies["M"], np.broadcast_to(U, (4, 8, 8)))
    rest = States(STATES.q, np.zeros_like(STATES.dq), STATES.ddq, STATES.T)
    ref = model_terms(thesis, rest)
    (qv,) = term_blocks(ref, {"e": {"Qv": ref["Qv"]}}, TOLS)
    for k in range(4):
        assert qv.scale[k] == max(1.0, np.abs(ref["Qgrav"][k]).max())
        assert np.abs(ref["Qv"][k]).max() < 1e-9 < np.abs(ref["Qgrav"][k]).max()


def test_a_copy_block_compares_the_copys_values_and_mirrors_with_other_errors_are_both_named(
        thesis):
    ref = model_terms(thesis, STATES)
    copy = ref["Qgrav"] + 1.0
    blocks = term_blocks(ref, {"e": {"Qgrav": ref["Qgrav"]}}, TOLS, {"e": {"Qgrav": copy}})
    assert blocks[1].value is copy and blocks[1].reference is ref["Qgrav"]
    M = np.tile(np.eye(8), (1, 1, 1))
    value = M.copy()
    value[0, 3, 6] += 3e-6
    value[0, 6, 3] += 2e-6          # a mirror with another error: a non-symmetric M, both named
    c = check_block(Block("e", "M", "", value, M, np.ones(1), 1e-6))
    assert c.entries == ("M[theta, gamma]", "M[gamma, theta]")
