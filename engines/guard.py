"""The engine boundary: every value an engine returns is checked once, where it leaves it.

`guard(engine)` (applied by `engines.loading.load_engine`, so every caller gets it, the
built-ins included) replaces each declared capability of the instance by a checked call:

* a term (``mass_matrix`` ... ``forward_acceleration``) must return a real float array of the
  shape the contract gives for the state(s) it was asked about (docs/engines.md,
  "The capabilities"), every entry finite; ``None``, a string, an object array, a complex
  array (its imaginary part would be dropped by the first ``float()``), the wrong shape or a
  NaN is refused;
* ``eigenvalues`` must return a finite complex (or real) array of shape (n, 4) for n speeds
  (one speed given as a scalar: (1, 4));
* ``simulate`` must return a `reference_model.solvers.Trajectory`-like object: ``t`` (N,),
  ``q`` and ``dq`` (N, 8) (and ``ddq`` (N, 8), ``C`` (N, 5), ``T`` (N, 3) where given), real
  and finite, a known status and a text message.

A refused value raises `EngineCallError` (an `EngineError`), one line naming the engine, the
call and the cause. ``SystemExit`` and a ``KeyboardInterrupt`` the engine raised itself (not a
signal delivered to this process) become `EngineCallError` too: an engine never ends the
harness. Any other exception keeps its type (callers match ``ValueError``, ``ArithmeticError``
...) and gets a note naming the engine and the call; `describe` renders any exception as
the one line the harness reports, cut to `MAX_MESSAGE` characters. `CapabilityError` (a
declared limitation) passes unchanged.

The engine's own calls to its methods (``self.mass_matrix`` inside its ``simulate``) go
through the same check; the hot paths of the solvers (``forward``, the duck-typed methods of
`reference_model.scenarios.run_forward`) are not capabilities and are not wrapped.
"""

from __future__ import annotations

import signal

import numpy as np

from .base import CAPABILITIES, CapabilityError, EngineError

__all__ = ["EngineCallError", "MAX_MESSAGE", "STATUSES", "check_eigenvalues", "check_term",
           "check_trajectory",
           "cut", "describe", "engine_interrupt", "guard", "is_guarded", "sigint_handler"]

#: characters of an engine's message kept in a report line (a 10^6-character message, or a
#: traceback pasted into one, would otherwise become the report)
MAX_MESSAGE = 300
STATUSES = ("completed", "fell", "failed")
N_Q, N_C = 8, 5
#: the shape of one state's value of each term (a batch prepends N)
TERM_SHAPES = {"mass_matrix": (N_Q, N_Q), "inverse_dynamics": (N_Q,), "gravity": (N_Q,),
               "generalized_forces": (N_Q,), "constraint_jacobian": (N_C, N_Q),
               "constraint_bias": (N_C,), "forward_acceleration": (N_Q,)}
_NOTE = "in engine call: "


class EngineCallError(EngineError):
    """An engine's method returned a value the contract refuses, or tried to end the process
    (``SystemExit``, its own ``KeyboardInterrupt``). The message is one line: engine, call,
    cause."""


def cut(text: str, limit: int = MAX_MESSAGE) -> str:
    """``text`` on one line, at most ``limit`` characters (with how much was left out)."""
    one = " ".join(str(text).split())
    if len(one) <= limit:
        return one
    return f"{one[:limit]}... ({len(one) - limit} more characters)"


def describe(exc: BaseException) -> str:
    """The one line the harness reports for ``exc``: the engine and call that raised it (when
    it came through a guarded call), its type and its message, cut."""
    where = [n[len(_NOTE):] for n in getattr(exc, "__notes__", ()) if str(n).startswith(_NOTE)]
    if isinstance(exc, EngineCallError):
        return cut(str(exc))
    try:
        text = str(exc)
    except Exception:   # noqa: BLE001 - an exception whose __str__ raises
        text = "(its message could not be rendered)"
    body = f"{type(exc).__name__}: {cut(text)}" if text.strip() else type(exc).__name__
    return f"{where[0]}: {body}" if where else body


def _who(engine) -> str:
    return f"engine {getattr(engine, 'name', type(engine).__name__)!r}"


def _kind(value) -> str:
    if value is None:
        return "None"
    if isinstance(value, (str, bytes)):
        return f"a string ({cut(repr(value), 60)})"
    kind = type(value).__name__
    return f"{'an' if kind[:1].lower() in 'aeiou' else 'a'} {kind}"


def _any_array(value, what: str) -> np.ndarray:
    """``value`` as a numpy array of any dtype, or `EngineCallError` saying why it is none."""
    if value is None or isinstance(value, (str, bytes)):
        raise EngineCallError(f"{what} returned {_kind(value)}, not an array")
    try:
        return np.asarray(value)
    except Exception as exc:   # noqa: BLE001 - ragged lists, objects that refuse
        raise EngineCallError(f"{what} returned {_kind(value)} that is not an array "
                              f"({type(exc).__name__}: {cut(exc, 80)})") from None


def _array(value, what: str) -> np.ndarray:
    """``value`` as a real float array, or `EngineCallError` saying why it is not one."""
    arr = _any_array(value, what)
    if arr.dtype.kind == "c":
        raise EngineCallError(f"{what} returned complex values (dtype {arr.dtype}); refused, "
                              "its imaginary part would be dropped: return real floats")
    if arr.dtype.kind not in "iuf":
        raise EngineCallError(f"{what} returned {_kind(value)} of dtype {arr.dtype}, not "
                              "real numbers")
    return arr.astype(np.float64, copy=False)


def _finite(arr: np.ndarray, what: str, cannot: str = "a state cannot be evaluated"
            ) -> np.ndarray:
    bad = ~np.isfinite(arr)
    if bad.any():
        raise EngineCallError(f"{what} returned {int(bad.sum())} non-finite value(s) (NaN or "
                              f"inf) of {arr.size}; raise instead when {cannot}")
    return arr


def check_term(name: str, value, q, what: str | None = None) -> np.ndarray:
    """``value``, returned by term ``name`` for state(s) ``q``, as a float array of the
    contract's shape; `EngineCallError` otherwise."""
    what = what or name
    arr = _array(value, what)
    shape = np.shape(q)
    want = ((shape[0],) if len(shape) == 2 else ()) + TERM_SHAPES[name]
    if arr.shape != want:
        raise EngineCallError(f"{what} returned shape {arr.shape} for q of shape {shape}; "
                              f"expected {want}")
    return _finite(arr, what)


def check_eigenvalues(value, speeds, what: str = "eigenvalues") -> np.ndarray:
    """``value``, returned by ``eigenvalues(speeds)``, as a complex (n, 4) array for the n
    speeds asked about; `EngineCallError` otherwise (None, text, the wrong shape, NaN)."""
    arr = _any_array(value, what)
    if arr.dtype.kind not in "iufc":
        raise EngineCallError(f"{what} returned {_kind(value)} of dtype {arr.dtype}, not numbers")
    want = (np.atleast_1d(np.asarray(speeds, dtype=float)).size, 4)
    if arr.shape != want:
        raise EngineCallError(f"{what} returned shape {arr.shape} for {want[0]} speed(s); "
                              f"expected {want}")
    return _finite(arr.astype(complex, copy=False), what, "a speed cannot be linearized")


def check_trajectory(traj, what: str = "simulate"):
    """``traj`` if it is a trajectory the harness can use (module docstring); else
    `EngineCallError`. Its arrays are replaced by float copies only when they were not float."""
    if not hasattr(traj, "t"):          # None and text have no t either
        raise EngineCallError(f"{what} returned {_kind(traj)}, not a "
                              "reference_model.solvers.Trajectory")
    status, message = getattr(traj, "status", None), getattr(traj, "message", None)
    if status not in STATUSES:
        raise EngineCallError(f"{what} returned status {cut(repr(status), 60)}; expected one "
                              f"of {', '.join(STATUSES)}")
    if not isinstance(message, str):
        raise EngineCallError(f"{what} returned a message that is {_kind(message)}, not text")
    t = _finite(_array(traj.t, f"{what} (t)"), f"{what} (t)")
    if t.ndim != 1:
        raise EngineCallError(f"{what} returned t of shape {t.shape}; expected (N,)")
    n = len(t)
    if np.any(np.diff(t) < 0):           # no difference for 0 or 1 sample
        raise EngineCallError(f"{what} returned times that go backwards")
    arrays = {"t": t}
    for field, width, required in (("q", N_Q, True), ("dq", N_Q, True), ("ddq", N_Q, False),
                                   ("C", N_C, False), ("T", 3, False)):
        value = getattr(traj, field, None)
        if value is None and not required:
            continue
        arr = _finite(_array(value, f"{what} ({field})"), f"{what} ({field})")
        if arr.shape != (n, width):
            raise EngineCallError(f"{what} returned {field} of shape {arr.shape} for {n} "
                                  f"samples; expected ({n}, {width})")
        arrays[field] = arr
    for field, arr in arrays.items():
        if getattr(traj, field) is not arr:
            try:
                setattr(traj, field, arr)
            except AttributeError:   # a frozen object: its values were checked, keep it
                pass
    if len(message) > MAX_MESSAGE or "\n" in message:
        try:
            traj.message = cut(message)
        except AttributeError:
            pass
    return traj


def sigint_handler():
    """SIGINT's handler now (None outside the main thread): taken before an engine call, for
    `engine_interrupt`."""
    try:
        return signal.getsignal(signal.SIGINT)
    except (ValueError, TypeError):   # pragma: no cover - not the main thread
        return None


def engine_interrupt(exc: BaseException, handler_before) -> bool:
    """Whether ``exc`` (a BaseException that is not an Exception) is the engine's own doing,
    rather than the user's Ctrl-C or SIGTERM reaching this process: ``SystemExit`` always; a
    ``KeyboardInterrupt`` unless it is the harness's `Terminated` (raised by its SIGTERM
    handler) or SIGINT's handler changed during the call (the harness's first-signal handler
    replaces itself when it fires). In a worker, SIGINT is ignored, so any
    ``KeyboardInterrupt`` is the engine's."""
    if isinstance(exc, SystemExit):
        return True
    if not isinstance(exc, KeyboardInterrupt) or type(exc).__name__ == "Terminated":
        return False
    return sigint_handler() is handler_before


class _Guarded:
    """One capability of one engine, checked (picklable: it holds the engine and the name)."""

    __slots__ = ("engine", "name")

    def __init__(self, engine, name: str):
        self.engine, self.name = engine, name

    def __reduce__(self):
        return (_Guarded, (self.engine, self.name))

    @property
    def __wrapped__(self):
        """The engine's own method (`inspect.signature` reads its parameters through this)."""
        return getattr(type(self.engine), self.name).__get__(self.engine)

    @property
    def __doc__(self):
        return getattr(type(self.engine), self.name).__doc__

    def __call__(self, *args, **kwargs):
        engine, name = self.engine, self.name
        what = f"{_who(engine)}: {name}"
        before = sigint_handler()
        try:
            value = getattr(type(engine), name)(engine, *args, **kwargs)
        except CapabilityError:
            raise
        except Exception as exc:
            if not isinstance(exc, EngineCallError) and not any(
                    str(n).startswith(_NOTE) for n in getattr(exc, "__notes__", ())):
                exc.add_note(f"{_NOTE}{what}")
            raise
        except BaseException as exc:
            if not engine_interrupt(exc, before):
                raise
            code = f" {exc.code!r}" if isinstance(exc, SystemExit) else ""
            raise EngineCallError(f"{what} raised {type(exc).__name__}{code} (an engine must "
                                  "not end the process: raise an exception)") from None
        if name == "simulate":
            return check_trajectory(value, what)
        if name == "eigenvalues":
            return check_eigenvalues(value, args[0] if args else kwargs.get("speeds"), what)
        return check_term(name, value, args[0] if args else kwargs.get("q"), what)


def guard(engine):
    """``engine`` with each of its declared capabilities checked (module docstring); the same
    object, returned for chaining. Idempotent."""
    for name in CAPABILITIES:
        if name in engine.capabilities and not isinstance(vars(engine).get(name), _Guarded):
            setattr(engine, name, _Guarded(engine, name))
    return engine


def is_guarded(engine, name: str) -> bool:
    return isinstance(vars(engine).get(name), _Guarded)
