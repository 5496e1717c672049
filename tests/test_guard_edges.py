"""The engine boundary's every refusal and pass-through, on engines written here
(engines/guard.py), issue 24.

The guard's contract (its module docstring, docs/robustness.md "Hostile engines"): a refused
value is one EngineCallError line naming the engine, the call and the cause; a trajectory's
optional arrays may be absent; arrays that are already float are kept (not copied); an
engine's own exception keeps its type and gets exactly one note naming the engine and the
call. The expected messages are written out here whole from that contract; numpy's own
messages, where one is quoted, come from numpy. Planted bugs each test was seen failing on are
named in its docstring.
"""

from __future__ import annotations

import dataclasses
import signal
import types

import numpy as np
import pytest

from engines.guard import (EngineCallError, check_trajectory, cut, describe, engine_interrupt,
                           guard, is_guarded, sigint_handler)

N = 3
T = np.array([0.0, 0.1, 0.2])


def trajectory(**given):
    """A trajectory as an engine could return it: t, q, dq, a status and a message; the
    optional arrays only when given."""
    fields = dict(t=T.copy(), q=np.zeros((N, 8)), dq=np.zeros((N, 8)), status="completed",
                  message="ok")
    fields.update(given)
    return types.SimpleNamespace(**{k: v for k, v in fields.items() if v is not ...})


def refused(traj) -> str:
    with pytest.raises(EngineCallError) as info:
        check_trajectory(traj)
    return str(info.value)


class Returns:
    """An engine whose every capability returns what it was built with."""

    name = "ret"

    def __init__(self, value, capabilities=("mass_matrix", "eigenvalues", "simulate")):
        self.value, self.capabilities = value, frozenset(capabilities)

    def mass_matrix(self, q):
        return self.value

    def gravity(self, q):
        return self.value

    def eigenvalues(self, speeds):
        return self.value

    def simulate(self, scenario):
        return self.value


def call_refused(engine, call, *args, **kwargs) -> str:
    with pytest.raises(EngineCallError) as info:
        getattr(guard(engine), call)(*args, **kwargs)
    return str(info.value)


# -- cut and describe --------------------------------------------------------------------------

def test_cut_keeps_exactly_the_limit_and_counts_what_it_left_out():
    """Planted: `<` for `<=` (a text of exactly the limit cut), len + limit in the count."""
    assert cut("a" * 300) == "a" * 300
    assert cut("a" * 301) == "a" * 300 + "... (1 more characters)"
    assert cut("x\n  y\tz", 10) == "x y z"
    assert cut("abcdefghij" * 2, 5) == "abcde... (15 more characters)"


class _Unprintable(Exception):
    def __str__(self):
        raise RuntimeError("no")


def test_describe_names_the_call_the_type_and_the_message():
    """Planted: the unprintable message's text dropped (None.strip()), the empty message
    rendered "ValueError: " (`or True`), type(None) for the type, the note ignored."""
    assert describe(ValueError("boom")) == "ValueError: boom"
    assert describe(ValueError("")) == "ValueError"
    assert describe(_Unprintable()) == "_Unprintable: (its message could not be rendered)"
    noted = KeyError("k")
    noted.add_note("in engine call: engine 'x': gravity")
    assert describe(noted) == "engine 'x': gravity: KeyError: 'k'"
    assert describe(EngineCallError("a\nb")) == "a b"


# -- values the terms return -------------------------------------------------------------------

def test_values_that_are_no_real_array_are_named_by_what_they_are():
    """Planted: `and` for `or` in the None check (None then read as an object array), the
    string's repr cut at 61 or not cut, the kind of None, numpy's reason dropped or cut at
    81, the complex and dtype messages changed."""
    q = np.zeros(8)
    what = "engine 'ret': mass_matrix"
    assert call_refused(Returns(None), "mass_matrix", q) == f"{what} returned None, not an array"
    text = "x" * 100
    assert call_refused(Returns(text), "mass_matrix", q) == (
        f"{what} returned a string ({repr(text)[:60]}... (42 more characters)), not an array")
    ragged = [[1.0], [1.0, 2.0]]
    try:
        np.asarray(ragged)
    except ValueError as exc:
        reason = " ".join(str(exc).split())
    assert call_refused(Returns(ragged), "mass_matrix", q) == (
        f"{what} returned a list that is not an array (ValueError: {reason[:80]}... "
        f"({len(reason) - 80} more characters))")
    assert call_refused(Returns(np.zeros((8, 8), complex)), "mass_matrix", q) == (
        f"{what} returned complex values (dtype complex128); refused, its imaginary part would "
        "be dropped: return real floats")
    assert call_refused(Returns(np.zeros((8, 8), bool)), "mass_matrix", q) == (
        f"{what} returned a ndarray of dtype bool, not real numbers")
    assert call_refused(Returns([object()]), "mass_matrix", q) == (
        f"{what} returned a list of dtype object, not real numbers")
    bad = np.eye(8)
    bad[2, 3] = np.nan
    assert call_refused(Returns(bad), "mass_matrix", q) == (
        f"{what} returned 1 non-finite value(s) (NaN or inf) of 64; raise instead when a state "
        "cannot be evaluated")


def test_a_term_keeps_float_arrays_and_reads_the_state_given_by_keyword():
    """The shape expected is that of the state asked about, passed by position or keyword.
    Planted: args[0] taken when there are none (`or True`: IndexError), the keyword's name
    ("q") changed (a batch then checked as one state), astype copying."""
    batch = np.zeros((4, 8))
    value = np.zeros((4, 8, 8))
    eng = guard(Returns(value))
    assert eng.mass_matrix(q=batch) is value and eng.mass_matrix(batch) is value
    assert call_refused(Returns(np.zeros((8, 8))), "mass_matrix", q=batch) == (
        "engine 'ret': mass_matrix returned shape (8, 8) for q of shape (4, 8); expected (4, 8, 8)")
    assert guard(Returns(np.eye(8, dtype=int))).mass_matrix(np.zeros(8)).dtype == np.float64


def test_eigenvalues_are_checked_against_the_speeds_asked_about():
    """By position or keyword, one speed as a scalar. Planted: the dispatch by name changed
    (eigenvalues checked as a term: KeyError), args[1], the keyword "speeds" changed, each
    argument of the check dropped."""
    three = np.zeros((3, 4), complex)
    eng = guard(Returns(three))
    assert eng.eigenvalues([1.0, 2.0, 3.0]).shape == (3, 4)
    assert eng.eigenvalues(speeds=[1.0, 2.0, 3.0]).shape == (3, 4)
    assert call_refused(Returns(three), "eigenvalues", speeds=[1.0, 2.0]) == (
        "engine 'ret': eigenvalues returned shape (3, 4) for 2 speed(s); expected (2, 4)")
    assert call_refused(Returns(three), "eigenvalues", 5.0) == (
        "engine 'ret': eigenvalues returned shape (3, 4) for 1 speed(s); expected (1, 4)")
    bad = np.zeros((1, 4), complex)
    bad[0, 1] = np.nan
    assert call_refused(Returns(bad), "eigenvalues", 5.0) == (
        "engine 'ret': eigenvalues returned 1 non-finite value(s) (NaN or inf) of 4; raise "
        "instead when a speed cannot be linearized")


# -- trajectories ------------------------------------------------------------------------------

def test_a_trajectory_needs_t_a_known_status_and_a_text_message():
    """Planted: the default call name changed, "T" for "t" (a trajectory without T refused),
    status or message read without a default (AttributeError), the status's repr cut at 61
    or not at all, the statuses joined wrongly."""
    assert refused(None) == "simulate returned None, not a reference_model.solvers.Trajectory"
    assert refused(object()) == "simulate returned an object, not a reference_model.solvers.Trajectory"
    assert refused(types.SimpleNamespace(T=np.zeros((N, 3)))) == (
        "simulate returned a SimpleNamespace, not a reference_model.solvers.Trajectory")
    assert refused(trajectory(status=...)) == (
        "simulate returned status None; expected one of completed, fell, failed")
    long = "s" * 100
    assert refused(trajectory(status=long)) == (
        f"simulate returned status {repr(long)[:60]}... (42 more characters); expected one of "
        "completed, fell, failed")
    assert refused(trajectory(message=...)) == "simulate returned a message that is None, not text"
    assert refused(trajectory(message=3)) == "simulate returned a message that is an int, not text"


def test_times_are_one_finite_non_decreasing_axis():
    """Repeated times are allowed (a solver's event), going back is not, from two samples.
    Planted: n > 2 (two samples never checked), `<=` (a repeated time refused), np.any(None),
    the (t) label dropped."""
    assert refused(trajectory(t=np.array([1.0, 0.0]), q=np.zeros((2, 8)), dq=np.zeros((2, 8)))) \
        == "simulate returned times that go backwards"
    assert refused(trajectory(t=np.array([0.0, 0.2, 0.1]))) == "simulate returned times that go backwards"
    same = trajectory(t=np.array([0.0, 0.1, 0.1]))
    assert check_trajectory(same) is same
    assert refused(trajectory(t=np.array([0.0, np.nan, 0.2]))) == (
        "simulate (t) returned 1 non-finite value(s) (NaN or inf) of 3; raise instead when a "
        "state cannot be evaluated")
    assert refused(trajectory(t="abc")) == "simulate (t) returned a string ('abc'), not an array"
    assert refused(trajectory(t=T.reshape(3, 1))) == "simulate returned t of shape (3, 1); expected (N,)"


@pytest.mark.parametrize("field, width", [("q", 8), ("dq", 8), ("ddq", 8), ("C", 5), ("T", 3)])
def test_every_array_of_a_trajectory_is_checked_where_given(field, width):
    """q and dq are required; ddq, C and T are checked when given (NaN, shape). Planted: each
    field's name changed ("XXddqXX", "c": never read), q or dq optional, `or` / `is not None`
    / `required` in the skip, `break` for `continue` (C and T unchecked after a missing ddq)."""
    nan = np.zeros((N, width))
    nan[1, 0] = np.nan
    assert refused(trajectory(**{field: nan})) == (
        f"simulate ({field}) returned 1 non-finite value(s) (NaN or inf) of {N * width}; raise "
        "instead when a state cannot be evaluated")
    assert refused(trajectory(**{field: np.zeros((N, width + 1))})) == (
        f"simulate returned {field} of shape ({N}, {width + 1}) for {N} samples; expected ({N}, {width})")
    if field in ("q", "dq"):
        assert refused(trajectory(**{field: None})) == f"simulate ({field}) returned None, not an array"
    else:
        assert check_trajectory(trajectory(**{field: None})).q.shape == (N, 8)


def test_optional_arrays_may_be_absent_and_float_arrays_are_kept_as_they_are():
    """The docstring's promise: arrays are replaced only when they were not float. Planted:
    getattr without a default (a trajectory with no ddq attribute: AttributeError), astype
    copying every array, "T" as t's key (T replaced by t), the replaced value None, `is` for
    `is not` (int arrays kept), each of setattr's arguments."""
    q, dq, big_t = np.zeros((N, 8)), np.ones((N, 8)), np.zeros((N, 3))
    traj = trajectory(q=q, dq=dq, T=big_t)
    out = check_trajectory(traj)
    assert out is traj and out.q is q and out.dq is dq and out.T is big_t and not hasattr(out, "ddq")
    ints = trajectory(t=np.array([0, 1, 2]), q=np.zeros((N, 8), dtype=int))
    out = check_trajectory(ints)
    assert out.t.dtype == np.float64 and out.q.dtype == np.float64
    np.testing.assert_array_equal(out.t, [0.0, 1.0, 2.0])


@dataclasses.dataclass(frozen=True)
class _Frozen:
    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    status: str = "completed"
    message: str = "ok\nsecond line"


def test_a_frozen_trajectory_is_checked_and_kept():
    frozen = _Frozen(np.array([0, 1, 2]), np.zeros((N, 8), int), np.zeros((N, 8)))
    assert check_trajectory(frozen) is frozen and frozen.q.dtype == int


def test_a_message_is_made_one_line_only_when_it_is_long_or_has_lines():
    """Planted: `and` for `or` (a long message kept), "\\n" not in (a short one rewritten:
    its double space lost), `>=` for `>` (one of exactly 300 characters rewritten), the cut
    message None or "None"."""
    assert check_trajectory(trajectory(message="a\nb")).message == "a b"
    assert check_trajectory(trajectory(message="x" * 400)).message == "x" * 300 + "... (100 more characters)"
    assert check_trajectory(trajectory(message="two  spaces")).message == "two  spaces"
    at_limit = "two  spaces" + "x" * 289                 # exactly MAX_MESSAGE characters
    assert check_trajectory(trajectory(message=at_limit)).message == at_limit


# -- the wrapper -------------------------------------------------------------------------------

class _Nameless:
    capabilities = frozenset({"mass_matrix", "gravity"})

    def mass_matrix(self, q):
        raise ValueError("inner")

    def gravity(self, q):
        return self.mass_matrix(q)          # an engine calling its own (guarded) capability


def test_an_engines_exception_keeps_its_type_and_gets_one_note():
    """Named by the class when the engine has no name; the inner call's note is the only one.
    Planted: getattr(engine, 'name', None) (engine None), type(None), `or` for `and` (a second
    note), each part of the note test (None, str(None), getattr(None, ...), "__NOTES__")."""
    eng = guard(_Nameless())
    with pytest.raises(ValueError) as info:
        eng.gravity(np.zeros(8))
    assert info.value.__notes__ == ["in engine call: engine '_Nameless': mass_matrix"]
    with pytest.raises(EngineCallError) as info:
        guard(Returns(None)).mass_matrix(np.zeros(8))
    assert not getattr(info.value, "__notes__", [])


class _Exits:
    name = "exits"
    capabilities = frozenset({"mass_matrix", "gravity"})

    def mass_matrix(self, q):
        raise SystemExit(3)

    def gravity(self, q):
        raise KeyboardInterrupt


def test_an_engine_that_ends_the_process_is_refused_in_one_line():
    """Planted: the code's placeholder "XXXX" for an interrupt, the fix upper-cased."""
    assert call_refused(_Exits(), "mass_matrix", np.zeros(8)) == (
        "engine 'exits': mass_matrix raised SystemExit 3 (an engine must not end the process: "
        "raise an exception)")
    assert call_refused(_Exits(), "gravity", np.zeros(8)) == (
        "engine 'exits': gravity raised KeyboardInterrupt (an engine must not end the process: "
        "raise an exception)")


class Terminated(KeyboardInterrupt):
    """Named like the harness's SIGTERM exception (comparisons' signals): matched by name."""


def test_only_the_engines_own_interrupt_is_its_doing():
    """Planted: `and` for `or`, the name "Terminated" changed or read from type(None),
    `return True` for the others."""
    now = sigint_handler()
    assert engine_interrupt(SystemExit(0), now) is True
    assert engine_interrupt(KeyboardInterrupt(), now) is True
    assert engine_interrupt(KeyboardInterrupt(), object()) is False   # the handler changed
    assert engine_interrupt(Terminated(), now) is False
    assert engine_interrupt(GeneratorExit(), now) is False
    assert now is signal.getsignal(signal.SIGINT)


def test_guard_wraps_the_declared_capabilities_once():
    """Planted: `or` for `and` (undeclared capabilities wrapped, and wrapped again)."""
    eng = Returns(np.zeros((8, 8)), capabilities=("mass_matrix",))
    guard(eng)
    first = vars(eng)["mass_matrix"]
    guard(eng)
    assert vars(eng)["mass_matrix"] is first and is_guarded(eng, "mass_matrix")
    assert not is_guarded(eng, "gravity") and "gravity" not in vars(eng)


def test_eigenvalues_called_directly_are_named_eigenvalues_and_need_numbers():
    """check_eigenvalues's own default name and its dtype refusal. Planted: the default name
    changed, the name not passed to the array check (None returned ...), the dtype message
    dropped or its kind read from None."""
    from engines.guard import check_eigenvalues
    with pytest.raises(EngineCallError) as info:
        check_eigenvalues("x", 1.0)
    assert str(info.value) == "eigenvalues returned a string ('x'), not an array"
    with pytest.raises(EngineCallError) as info:
        check_eigenvalues([object()] * 4, 1.0)
    assert str(info.value) == "eigenvalues returned a list of dtype object, not numbers"
