"""Candidate causes of a disagreement, beyond one parameter: what a port of the bicycle gets wrong.

A cause is described by what it does to the terms of the equations (`Cause` and its effect
per term, ``term -> array`` over the states, in the model's units). Two kinds of effect:

* **continuous** (``fixed=False``): the derivative of the terms with respect to a quantity
  (a model parameter in every term or in one term only; a Table 1 input of the benchmark
  through its conversion to the model, `reference_model.benchmark`). The fit scales it.
* **discrete** (``fixed=True``): the whole change the mistake makes, taken at full size (the
  sign of a term flipped: ``-2 T``; a term missing: ``-T``; a rider torque's column with the
  wrong sign or on the wrong body; two coordinates swapped in a term's arguments: ``T(P q) -
  T(q)``; a Table 1 slip such as the head angle converted to radians twice). Its share is the
  part of the discrepancy it *removes* when undone, never a scaled fit, so a discrete cause
  cannot explain a small difference that merely points the same way.

Each effect is keyed by ``(term, source)``: source None applies to every block of the term;
``""`` to the term as taken from the engine's own method (gravity, inverse_dynamics) and
``"F"`` to the copy taken out of ``generalized_forces`` (`comparisons.judgments.diagnose`).
Causes that need the engine's own values (a non-symmetric M, the forward solve) are built by
`diagnose` from them.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from reference_model import COORDINATES, TORQUE_NAMES, Model, ParameterError
from reference_model.params import BODY_NAMES, PARAMETER_NAMES, ParameterWarning

__all__ = [
    "KINDS", "Cause", "body_angular_jacobians", "changed_terms", "coordinate_swap_causes",
    "parameter_evaluator", "parameter_term_causes",
    "table1_causes", "table1_of", "term_sign_causes", "torque_causes",
]

#: kinds of cause, in the order a tie between equally good explanations is settled: the
#: discrete mistake first (it has no free coefficient), then the single parameter, then a Table
#: 1 input (it moves several parameters), then a parameter wrong in one term only
KINDS = ("structural", "parameter", "table1", "term-parameter")

Key = tuple[str, "str | None"]


@dataclass(frozen=True)
class Cause:
    """One candidate cause: an id (``Explanation.causes``), a readable label, its body (None:
    all or none), kind (`KINDS`), whether it is taken at full size, and its effect."""

    id: str
    label: str
    body: int | None
    kind: str
    fixed: bool
    effects: Mapping[Key, np.ndarray]
    unit: str = ""            # of the fitted coefficient (continuous causes)
    value: float | str | None = None  # the model's value of the quantity (continuous causes)
    engine: str | None = None  # a cause seen in one engine's own values only
    #: continuous causes: coefficient -> the whole effect at that size (the model rebuilt with
    #: the value changed), None when that value is not a valid model
    evaluate: Callable[[float], Mapping[Key, np.ndarray] | None] | None = \
        field(default=None, compare=False, repr=False)

    def effect(self, term: str, source: str) -> np.ndarray | None:
        """The effect on the block of ``term`` taken from ``source`` (None: none)."""
        got = self.effects.get((term, source))
        return got if got is not None else self.effects.get((term, None))


# -- a parameter wrong in one term only --------------------------------------------------------

def changed_terms(model: Model, states, model_terms: Callable, terms, **changes
                  ) -> Mapping[Key, np.ndarray] | None:
    """The change of the terms when the model's parameters take ``changes`` (None when that is
    not a valid parameter set; the triangle inequality is not insisted on)."""
    try:
        with warnings.catch_warnings():     # a candidate value may well be unusual
            warnings.simplefilter("ignore", ParameterWarning)
            other = model.with_params(model.params.replace(**changes, triangle="warn"))
    except (ParameterError, ValueError):
        return None
    new, base = model_terms(other, states), model_terms(model, states)
    return {(t, None): new[t] - base[t] for t in terms}


def parameter_evaluator(model: Model, states, model_terms: Callable, terms, name: str,
                        only: str | None = None) -> Callable[[float], Mapping[Key, np.ndarray] | None]:
    """`Cause.evaluate` of parameter ``name`` (in every term, or in term ``only``)."""
    value = float(getattr(model.params, name))

    def evaluate(x: float):
        return changed_terms(model, states, model_terms, terms if only is None else [only],
                             **{name: value + x})
    return evaluate


def parameter_term_causes(effects: Mapping[str, Mapping[str, np.ndarray]], model: Model,
                          units: Mapping[str, str], bodies: Callable[[str], int | None],
                          states=None, model_terms: Callable | None = None) -> list[Cause]:
    """'p differs in term t only' for each parameter p whose effect reaches more than one term
    (where it reaches one, this is the parameter itself): e.g. D and dD dq built with
    different wheel radii, or a mass typed wrong in the gravity alone."""
    out = []
    for name in PARAMETER_NAMES:
        if name not in effects:
            continue
        reached = [t for t, e in effects[name].items() if np.any(e != 0.0)]
        if len(reached) < 2:
            continue
        for t in reached:
            out.append(Cause(f"{name}@{t}", f"{name} in {t} only", bodies(name),
                             "term-parameter", False,
                             {(t, None): effects[name][t]}, units[name],
                             float(getattr(model.params, name)),
                             evaluate=None if model_terms is None else
                             parameter_evaluator(model, states, model_terms, [t], name, t)))
    return out


# -- a term's sign flipped or the term missing -------------------------------------------------

#: where a copy of a term comes from -> how a mistake there is named
_OWN = {"Qgrav": "gravity()", "Qv": "inverse_dynamics()"}


def _where(term: str, source: str | None) -> tuple[str, str]:
    """(id suffix, label suffix) of a mistake in one copy of a term (None: in every copy)."""
    if source is None:
        return "", ""
    if source == "F":
        return "[F]", " in generalized_forces"
    if source == "ID":
        return "[ID]", " in inverse_dynamics"
    return f"[{source or 'own'}]", f" in the engine's own {_OWN.get(term, term)}"


def term_sign_causes(ref: Mapping[str, np.ndarray], sources: Mapping[str, tuple[str, ...]]
                     ) -> list[Cause]:
    """For each term: its sign flipped (effect ``-2 T``) or the term missing (``-T``), in
    every copy of it and, where the engine gives two (gravity() and generalized_forces), in
    one only. ``sources``: term -> the sources its blocks come from."""
    out = []
    for t, src in sources.items():
        for s in [None] + (list(src) if len(src) > 1 else []):
            sid, tail = _where(t, s)
            out.append(Cause(f"sign:{t}{sid}", f"sign of {t} flipped{tail}", None, "structural",
                             True, {(t, s): -2.0 * ref[t]}))
            out.append(Cause(f"missing:{t}{sid}", f"{t} missing{tail}", None, "structural", True,
                             {(t, s): -ref[t]}))
    return out


# -- the rider torques: sign, columns swapped, wrong body --------------------------------------

#: torque -> (the body it acts on, the body-fixed axis it acts about), thesis section 2
TORQUE_BODY = {"Mdir": (4, 2), "Mped": (2, 1), "Mvue": (3, 0)}
_CHAIN = {2: (2, 3, 4), 3: (2, 3, 5), 4: (2, 3, 5, 6), 5: (2, 3, 5, 6, 7)}


def _rot(axis: int, a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    R = np.zeros(a.shape + (3, 3))
    i, j = [k for k in range(3) if k != axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = R[..., j, j] = c
    sign = -1.0 if axis == 1 else 1.0     # Ry's sine sits the other way round
    R[..., i, j], R[..., j, i] = -sign * s, sign * s
    return R


def body_angular_jacobians(q: np.ndarray) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray]]:
    """(A_b, Jw_b) of bodies 2..5 at states q (N, 8): rotation matrices body -> global (N, 3, 3)
    and angular-velocity Jacobians (N, 3, 8), from the thesis's chain of rotations (yaw phi
    about z, lean theta about x, then psi or beta about y, steer gamma about the frame's z,
    eps about the fork's y)."""
    q = np.asarray(q, dtype=float)
    yaw = _rot(2, q[:, 2])
    lean = yaw @ _rot(0, q[:, 3])
    A = {2: lean @ _rot(1, q[:, 4]), 3: lean @ _rot(1, q[:, 5])}
    A[4] = A[3] @ _rot(2, q[:, 6])
    A[5] = A[4] @ _rot(1, q[:, 7])
    axes = {2: np.broadcast_to([0.0, 0.0, 1.0], (len(q), 3)), 3: yaw[..., :, 0],
            4: lean[..., :, 1], 5: lean[..., :, 1], 6: A[3][..., :, 2], 7: A[4][..., :, 1]}
    J = {}
    for b, chain in _CHAIN.items():
        Jw = np.zeros((len(q), 3, len(COORDINATES)))
        for k in chain:
            Jw[:, :, k] = axes[k]
        J[b] = Jw
    return A, J


def torque_causes(S: np.ndarray, q: np.ndarray) -> list[Cause]:
    """Each rider torque's column of S with its sign flipped, two columns swapped, and each
    torque applied to another body (about that body's axis of the same name: Mped about the
    front wheel's axle, Mvue about the fork's x...)."""
    out = []
    A, J = body_angular_jacobians(q)
    for k, name in enumerate(TORQUE_NAMES):
        eff = np.zeros_like(S)
        eff[:, :, k] = -2.0 * S[:, :, k]
        body = TORQUE_BODY[name][0]
        out.append(Cause(f"sign:S[{name}]", f"rider torque {name} applied with the wrong sign",
                         body, "structural", True, {("S", None): eff}))
        axis = TORQUE_BODY[name][1]
        for b in (2, 3, 4, 5):
            if b == body:
                continue
            col = np.einsum("nik,ni->nk", J[b], A[b][:, :, axis])
            eff = np.zeros_like(S)
            eff[:, :, k] = col - S[:, :, k]
            out.append(Cause(f"body:S[{name}]->{b}",
                             f"rider torque {name} applied to the {BODY_NAMES[b]} instead of "
                             f"the {BODY_NAMES[body]}", b, "structural", True,
                             {("S", None): eff}))
    for i in range(3):
        for j in range(i + 1, 3):
            eff = np.zeros_like(S)
            eff[:, :, i] = S[:, :, j] - S[:, :, i]
            eff[:, :, j] = S[:, :, i] - S[:, :, j]
            a, b = TORQUE_NAMES[i], TORQUE_NAMES[j]
            out.append(Cause(f"swap:S[{a},{b}]", f"rider torques {a} and {b} swapped (columns "
                             "of S)", None, "structural", True, {("S", None): eff}))
    return out


# -- two coordinates swapped in a term's arguments --------------------------------------------

def coordinate_swap_causes(model_terms: Callable, model: Model, states, ref, terms
                           ) -> list[Cause]:
    """For each pair of coordinates (i, j): the terms evaluated with q_i and q_j (and dq_i,
    dq_j) swapped in their arguments, in one term or in all of them (effect ``T(P q) - T(q)``).
    A pair the term does not depend on has no effect and is no candidate."""
    out = []
    n = len(COORDINATES)
    for i in range(n):
        for j in range(i + 1, n):
            perm = list(range(n))
            perm[i], perm[j] = j, i
            swapped = type(states)(states.q[:, perm], states.dq[:, perm], states.ddq, states.T)
            other = model_terms(model, swapped)
            a, b = COORDINATES[i], COORDINATES[j]
            every = {}
            for t in terms:
                eff = other[t] - ref[t]
                if not np.any(np.abs(eff) > 1e-12 * max(1.0, float(np.abs(ref[t]).max()))):
                    continue
                every[(t, None)] = eff
                out.append(Cause(f"swap:{t}:{a},{b}", f"{a} and {b} swapped in the arguments of "
                                 f"{t}", None, "structural", True, {(t, None): eff}))
            if len(every) > 1:
                out.append(Cause(f"swap:all:{a},{b}", f"{a} and {b} swapped in the state (every "
                                 "term)", None, "structural", True, every))
    return out


# -- the benchmark's Table 1 inputs ------------------------------------------------------------

#: Table 1 name -> body (None: several)
_T1_BODY = {"R": 2, "B": 3, "H": 4, "F": 5}
#: Table 1 slips a port makes, each a whole change of one input: (id, label, input, new value)
_T1_SLIPS: tuple[tuple[str, str, str, Callable[[float], float]], ...] = (
    ("table1:c-sign", "trail c with its sign flipped (Table 1 input)", "c", lambda v: -v),
    ("table1:lam-deg2rad", "steer axis tilt lam converted to radians twice (Table 1 input)",
     "lam", math.radians),
    ("table1:lam-head-angle", "head angle pi/2 - lam used for the steer axis tilt lam "
     "(Table 1 input)", "lam", lambda v: math.pi / 2 - v),
    ("table1:lam-sign", "steer axis tilt lam with its sign flipped (Table 1 input)", "lam",
     lambda v: -v),
)


def table1_of(model: Model):
    """The Table 1 a model was built from or can be turned back into (`Parameters.benchmark`,
    else `reference_model.benchmark.to_benchmark`), or None."""
    from reference_model.benchmark import table1_from_mapping, to_benchmark
    p = model.params
    if p.benchmark is not None:
        return p.benchmark
    try:
        return table1_from_mapping(to_benchmark(p))
    except ParameterError:
        return None


def _table1_body(name: str) -> int | None:
    if name in ("rR",):
        return 2
    if name in ("rF",):
        return 5
    for letter, body in _T1_BODY.items():
        if len(name) > 1 and name[1] == letter and name[0] in "mxzI":
            return body
    return None


def table1_causes(model: Model, states, model_terms: Callable, terms) -> list[Cause]:
    """Each of Table 1's 26 inputs as a cause (the derivative of the terms through the
    conversion, central differences) and the slips of `_T1_SLIPS` at full size; nothing for a
    model without a Table 1 (`table1_of`)."""
    from reference_model.benchmark import BENCHMARK_DESCRIPTIONS, BENCHMARK_NAMES, parameters_from_benchmark
    table = table1_of(model)
    if table is None:
        return []
    base_values = table.as_dict()
    base = model_terms(model, states)

    def built(**change) -> Model | None:
        try:
            with warnings.catch_warnings():     # a slip's values may well be unusual
                warnings.simplefilter("ignore", ParameterWarning)
                conv = parameters_from_benchmark({**base_values, **change},
                                                 allow_triangle_violation=True)
                p = model.params.replace(**{n: getattr(conv, n) for n in PARAMETER_NAMES},
                                         triangle="warn")
            return model.with_params(p)
        except (ParameterError, ValueError):
            return None

    out = []
    for name in BENCHMARK_NAMES:
        value = base_values[name]
        h = 1e-6 * abs(value) if value != 0.0 else 1e-7
        sides = {s: built(**{name: value + s * h}) for s in (1.0, -1.0)}
        up, down = sides[1.0], sides[-1.0]
        if up is None and down is None:
            continue
        a = model_terms(up, states) if up is not None else base
        b = model_terms(down, states) if down is not None else base
        width = (h if up is not None else 0.0) + (h if down is not None else 0.0)
        unit = BENCHMARK_DESCRIPTIONS[name].rsplit(", ", 1)[-1] if ", " in BENCHMARK_DESCRIPTIONS[name] else ""
        out.append(Cause(f"table1:{name}", f"Table 1's {name} "
                         f"({BENCHMARK_DESCRIPTIONS[name].split(',')[0].split(' (')[0]})",
                         _table1_body(name),
                         "table1", False, {(t, None): (a[t] - b[t]) / width for t in terms},
                         unit, value, evaluate=lambda x, n=name, v=value: _slipped(
                             built(**{n: v + x}), states, model_terms, base, terms)))
    for cid, label, name, slip in _T1_SLIPS:
        changed = _slipped(built(**{name: slip(base_values[name])}), states, model_terms, base,
                           terms)
        if changed is not None:
            out.append(Cause(cid, label, None, "structural", True, changed))
    return out


def _slipped(other: Model | None, states, model_terms: Callable, base, terms):
    if other is None:
        return None
    new = model_terms(other, states)
    return {(t, None): new[t] - base[t] for t in terms}
