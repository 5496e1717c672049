"""Model debugging: where the reference model and the engines disagree, and why.

The model under test is the reference model (the thesis's equations, generated C) built from a
parameter file; the engines (Pinocchio, Exudyn's kinematic tree) are built either from the same
file (a consistency check of adapters and engines: everything must agree) or from another model
(``against``), and then the difference is *localized*:

1. **Which quantity** fails its tolerance (`comparisons.terms.compare_terms`, tolerances from
   `tolerances.toml`) and at which entry.
2. **Which term** of the thesis's equations ``M ddq + D^T lambda = Qv + Qgrav + Qaero + S T``,
   ``D ddq + dD dq = 0``: each term is taken out of an engine through the Engine interface
   (`engine_terms`: e.g. ``Qv = -(M 0 - Qv - Qgrav) - Qgrav`` from inverse dynamics and gravity,
   or ``Qv = (F(dq) + F(-dq))/2 - F(0)`` from the generalized forces ``F``, since Qv is even in
   dq, Qaero odd and ``S T`` linear in T) and checked against the reference's own term.
3. **Which cause, hence which body**: the discrepancy ``r = engine - model`` over all states and
   all compared terms (each entry divided by its tolerance's scale, so terms of different units
   weigh alike; agreeing terms stay in the fit, where they rule causes out) is fitted by least
   squares onto the effect of each candidate cause on the model's terms:
   ``d(term)/d p_j`` for each of the 30 parameters (central differences; one-sided where the
   parameter sits on a validity boundary, which happens only for inertias and masses, where the
   terms are linear and one-sided differences are exact), the gyroscopic terms ``w x (I w)``,
   and the other front-contact model. The explained fraction of the single cause j is
   ``(s_j . r)^2 / (|s_j|^2 |r|^2)``; when no single cause explains at least
   ``EXPLAINED`` of it, pairs are tried (e.g. two swapped inertias). The fitted coefficient is
   the estimated parameter difference (engines' value minus the model's).

The body follows from the parameter: ``I2*, m2, R_rear`` body 2 (rear wheel); ``x3, z3, m3,
I3*, cv`` body 3 (frame+rider; cv is its drag); ``xa, za, dx4, dz4, m4, I4*`` body 4
(fork/handlebar); ``x5, z5, m5, I5*, R_front`` and the front contact body 5 (front wheel);
``g`` and the gyroscopic terms belong to all bodies.

Command line: ``bicycle-xval diagnose FILE [--against MODEL] [--engines pinocchio,exudyn]
[--states N] [--json OUT]``; exit 0 when everything agrees, 1 when something differs.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from engines import load_engine
from engines.base import Engine
from reference_model import Model, ParameterError
from reference_model.params import (BODY_NAMES, CONTACT_MODELS, PARAMETER_NAMES, PARAMETER_UNITS,
                                    resolve_model)

from .terms import States, TermComparison, compare_terms, entry_name, random_states
from .tolerances import Tolerance, load_tolerances

TERMS = ("M", "Qv", "Qgrav", "Qaero", "S", "D", "dD dq")
#: term -> (the tolerances.toml entry it is judged by, the terms its extraction from an engine
#: involves: the round-off of a difference is relative to the largest of them)
TERM_TOLERANCE: dict[str, tuple[str, tuple[str, ...]]] = {
    "M": ("mass_matrix", ("M",)),
    "Qv": ("generalized_forces", ("Qv", "Qgrav")),
    "Qgrav": ("gravity", ("Qgrav",)),
    "Qaero": ("generalized_forces", ("Qaero", "Qv", "Qgrav")),
    "S": ("generalized_forces", ("S", "Qgrav")),
    "D": ("constraint_jacobian", ("D",)),
    "dD dq": ("constraint_bias", ("dD dq",)),
}
STRUCTURAL = ("gyroscopic", "contact")
COMPARED_ENGINES = ("pinocchio", "exudyn")
EXPLAINED = 0.99          # fraction of the discrepancy a cause must explain to be named alone
DEFAULT_STATES = 24
DEFAULT_SEED = 11
_REL_STEP = 1e-5          # finite-difference step relative to the parameter
_ZERO_STEP = 1e-6         # step (SI) of a parameter whose value is 0


# -- causes and bodies -------------------------------------------------------------------------

def parameter_body(name: str) -> int | None:
    """The body (2..5) a parameter belongs to, None for g (all bodies)."""
    if name == "R_rear":
        return 2
    if name == "R_front":
        return 5
    if name == "cv":
        return 3
    if name in ("xa", "za"):
        return 4
    for body in (2, 3, 4, 5):
        if name in (f"x{body}", f"z{body}", f"dx{body}", f"dz{body}", f"m{body}") or \
                name.startswith(f"I{body}"):
            return body
    return None


def cause_body(cause: str) -> int | None:
    """The body of a cause (a parameter name, 'gyroscopic' or 'contact')."""
    if cause == "gyroscopic":
        return None
    if cause == "contact":
        return 5
    return parameter_body(cause)


def body_label(body: int | None) -> str:
    return "all bodies" if body is None else f"body {body} {BODY_NAMES[body]}"


def cause_label(cause: str) -> str:
    return {"gyroscopic": "gyroscopic terms w x (I w)",
            "contact": "front contact model"}.get(cause, cause)


def format_localization(terms: Sequence[str], causes: Sequence[str], body: int | None) -> str:
    """E.g. 'M, Qv via I3xz (body 3 frame+rider)'."""
    what = ", ".join(t for t in TERMS if t in terms) or "nothing"
    return f"{what} via {' + '.join(cause_label(c) for c in causes)} ({body_label(body)})"


# -- the terms of the equations of motion ------------------------------------------------------

def model_terms(model: Model, states: States) -> dict[str, np.ndarray]:
    """Every term of the reference model at the states (batch C calls)."""
    q, dq = states.q, states.dq
    return {"M": model.mass_matrix(q), "Qv": model.Qv(q, dq), "Qgrav": model.Qgrav(q),
            "Qaero": model.Qaero(q, dq), "S": model.S(q), "D": model.constraint_jacobian(q),
            "dD dq": model.constraint_bias(q, dq)}


def engine_terms(engine: Engine, states: States) -> dict[str, np.ndarray]:
    """The terms an engine provides, taken out through the Engine interface only.

    Qgrav is ``gravity`` or the generalized forces at rest, ``F(q, 0, 0)``; Qv is
    ``-inverse_dynamics(q, dq, 0) - Qgrav`` or ``(F(q, dq, 0) + F(q, -dq, 0))/2 - Qgrav`` (Qv is
    even in dq, Qaero odd); Qaero ``(F(q, dq, 0) - F(q, -dq, 0))/2``; column k of S
    ``F(q, 0, e_k) - F(q, 0, 0)``.
    """
    q, dq = states.q, states.dq
    n = len(states)
    zero3 = np.zeros((n, 3))
    out: dict[str, np.ndarray] = {}
    has = engine.supports
    if has("mass_matrix"):
        out["M"] = np.asarray(engine.mass_matrix(q), dtype=float)
    rest = np.asarray(engine.generalized_forces(q, np.zeros_like(dq), zero3), dtype=float) \
        if has("generalized_forces") else None
    if has("gravity"):
        out["Qgrav"] = np.asarray(engine.gravity(q), dtype=float)
    elif rest is not None:
        out["Qgrav"] = rest
    if has("inverse_dynamics") and "Qgrav" in out:
        out["Qv"] = -np.asarray(engine.inverse_dynamics(q, dq, np.zeros_like(dq)), dtype=float) \
            - out["Qgrav"]
    if rest is not None:
        plus = np.asarray(engine.generalized_forces(q, dq, zero3), dtype=float)
        minus = np.asarray(engine.generalized_forces(q, -dq, zero3), dtype=float)
        out.setdefault("Qv", 0.5 * (plus + minus) - out["Qgrav"])
        out["Qaero"] = 0.5 * (plus - minus)
        cols = []
        for k in range(3):
            T = zero3.copy()
            T[:, k] = 1.0
            cols.append(np.asarray(engine.generalized_forces(q, np.zeros_like(dq), T)) - rest)
        out["S"] = np.stack(cols, axis=-1)
    if has("constraint_jacobian"):
        out["D"] = np.asarray(engine.constraint_jacobian(q), dtype=float)
    if has("constraint_bias"):
        out["dD dq"] = np.asarray(engine.constraint_bias(q, dq), dtype=float)
    return {t: out[t] for t in TERMS if t in out}


def _scales(term: str, ref: Mapping[str, np.ndarray], tol: Tolerance) -> np.ndarray:
    """Per-state number the absolute error of ``term`` is divided by (the tolerance's scale)."""
    parts = TERM_TOLERANCE[term][1]
    n = ref[term].shape[0]
    return np.array([tol.normalizer(ref[term][k], [ref[p][k] for p in parts]) for k in range(n)])


@dataclass(frozen=True)
class TermCheck:
    """One term of the equations, the model under test against one engine."""

    engine: str
    term: str
    max_error: float          # relative to the tolerance's scale
    max_abs_error: float
    tolerance: float
    passed: bool
    worst_state: int
    entries: tuple[str, ...]  # the entries above tolerance, worst first (at most 3), else the worst

    def describe(self) -> str:
        verdict = "ok" if self.passed else "DIFFERS"
        return (f"{self.term} vs {self.engine}: {verdict}, max error {self.max_error:.2e} "
                f"(tolerance {self.tolerance:.0e}) at {', '.join(self.entries)}")

    def to_dict(self) -> dict:
        return {"engine": self.engine, "term": self.term, "max_error": self.max_error,
                "max_abs_error": self.max_abs_error, "tolerance": self.tolerance,
                "passed": self.passed, "worst_state": self.worst_state,
                "entries": list(self.entries)}


def check_terms(ref: Mapping[str, np.ndarray], engine_values: Mapping[str, Mapping[str, np.ndarray]],
                tolerances: Mapping[str, Tolerance] | None = None) -> list[TermCheck]:
    """Every term each engine provides against the model's (``ref`` from `model_terms`)."""
    tols = tolerances or load_tolerances()
    out = []
    for name, values in engine_values.items():
        for term, E in values.items():
            tol = tols[TERM_TOLERANCE[term][0]]
            diff = np.abs(E - ref[term])
            rel = diff / _scales(term, ref, tol).reshape((-1,) + (1,) * (diff.ndim - 1))
            rel = np.where(np.isfinite(rel), rel, np.inf)
            per_entry = rel.max(axis=0)
            if term == "M":   # symmetric: name each entry once, as M[row, col] with row <= col
                per_entry = np.where(np.tri(*per_entry.shape, -1, dtype=bool), -np.inf, per_entry)
            k = int(np.unravel_index(int(np.argmax(rel)), rel.shape)[0])
            order = np.argsort(per_entry, axis=None)[::-1]
            over = [i for i in order[:3] if per_entry.flat[i] > tol.tolerance] or [order[0]]
            entries = tuple(entry_name(term, tuple(int(j) for j in np.unravel_index(i, per_entry.shape)))
                            for i in over)
            err = float(rel.max())
            out.append(TermCheck(name, term, err, float(diff.max()), tol.tolerance,
                                 bool(err <= tol.tolerance), k, entries))
    return out


# -- causes: their effect on the model's terms -------------------------------------------------

def cause_effects(model: Model, states: States, terms: Sequence[str]) -> dict[str, dict[str, np.ndarray]]:
    """cause -> its effect on each term: ``d term / d p`` per unit of a parameter (central
    differences; one-sided where one side is not a valid parameter set: the terms are linear
    in the inertias and masses, where that happens, so the difference is exact), and, for the
    structural causes, the change when the gyroscopic terms are toggled or the front contact
    model is switched."""
    p = model.params
    base = model_terms(model, states)
    effects: dict[str, dict[str, np.ndarray]] = {}
    for name in PARAMETER_NAMES:
        value = getattr(p, name)
        h = _REL_STEP * abs(value) if value != 0.0 else _ZERO_STEP
        sides = {}
        for sign in (1.0, -1.0):
            try:
                sides[sign] = model.with_params(p.replace(**{name: value + sign * h}))
            except ParameterError:
                continue
        if len(sides) == 2:
            up = model_terms(sides[1.0], states)
            down = model_terms(sides[-1.0], states)
            effects[name] = {t: (up[t] - down[t]) / (2 * h) for t in terms}
        elif sides:
            (sign, changed), = sides.items()
            other = model_terms(changed, states)
            effects[name] = {t: (other[t] - base[t]) / (sign * h) for t in terms}
    # The gyroscopic terms are part of Qv only, which does not depend on the contact model, and
    # the contact model changes D and dD dq only: each structural effect is taken in the variant
    # that needs no further build (thesis contact for the gyroscopic terms, gyroscopic terms on
    # for the contact), so only the 'thesis-nogyro' library is ever needed besides the two models.
    on_thesis = p.with_contact("thesis")
    with_gyro = Model(on_thesis, gyroscopic=True)
    without = Model(on_thesis, gyroscopic=False)
    sign = 1.0 if model.gyroscopic else -1.0    # effect of toggling the model's variant
    a, b = model_terms(without, states), model_terms(with_gyro, states)
    effects["gyroscopic"] = {t: sign * (a[t] - b[t]) for t in terms}
    other = next(c for c in CONTACT_MODELS if c != model.contact)
    a, b = model_terms(Model(p.with_contact(other)), states), model_terms(Model(p), states)
    effects["contact"] = {t: a[t] - b[t] for t in terms}
    return effects


@dataclass(frozen=True)
class Explanation:
    """The best explanation of a discrepancy by one cause (or a pair)."""

    causes: tuple[str, ...]       # parameter names, 'gyroscopic' or 'contact'
    estimates: tuple[float, ...]  # fitted change (engines minus model): SI for a parameter; for a
                                  # structural cause the coefficient (1 = fully the other variant)
    explained: float              # fraction of the squared discrepancy explained by the fit
    body: int | None
    runner_up: tuple[str, float] | None = None   # next best single cause and its fraction
    model_values: tuple[float | str, ...] = ()   # the model's value of each cause

    def describe(self) -> str:
        parts = []
        for cause, est, value in zip(self.causes, self.estimates, self.model_values):
            if cause == "contact":
                parts.append(f"engines' front contact is the other model (coefficient {est:.3f}; "
                             f"the model under test: {value!r})")
            elif cause == "gyroscopic":
                parts.append("the model under test lacks the gyroscopic terms the engines have"
                             if value == "without" else
                             "the engines lack the gyroscopic terms the model under test has")
                parts[-1] += f" (coefficient {est:.3f})"
            else:
                unit = PARAMETER_UNITS[cause]
                parts.append(f"d{cause} = {est:+.5g} {unit} (model {value:.6g}, engines' fit "
                             f"{value + est:.6g} {unit})")
        text = (f"{' + '.join(cause_label(c) for c in self.causes)} ({body_label(self.body)}) "
                f"explains {100 * self.explained:.2f}% of the difference: {'; '.join(parts)}")
        if len(self.causes) == 2 and _looks_swapped(self):
            text += f"; looks like {self.causes[0]} and {self.causes[1]} swapped"
        if self.runner_up:
            text += f"; next best single cause {cause_label(self.runner_up[0])} " \
                    f"({100 * self.runner_up[1]:.1f}%)"
        return text

    def to_dict(self) -> dict:
        return {"causes": list(self.causes), "estimates": list(self.estimates),
                "explained": self.explained, "body": self.body,
                "runner_up": list(self.runner_up) if self.runner_up else None,
                "model_values": list(self.model_values)}


def _looks_swapped(e: Explanation) -> bool:
    (a, b), (da, db) = e.causes, e.estimates
    if a in STRUCTURAL or b in STRUCTURAL or PARAMETER_UNITS[a] != PARAMETER_UNITS[b]:
        return False
    va, vb = e.model_values
    return abs(da + db) <= 0.05 * abs(da) and abs(va + da - vb) <= 0.05 * abs(da)


def _stack(blocks: Sequence[np.ndarray]) -> np.ndarray:
    return np.concatenate([np.ravel(b) for b in blocks]) if blocks else np.zeros(0)


def explain(model: Model, states: States, ref: Mapping[str, np.ndarray],
            engine_values: Mapping[str, Mapping[str, np.ndarray]],
            tolerances: Mapping[str, Tolerance] | None = None) -> Explanation | None:
    """Least-squares localization of ``engine - model`` onto the causes (see the module
    docstring); None when there is nothing to explain."""
    tols = tolerances or load_tolerances()
    terms = sorted({t for v in engine_values.values() for t in v}, key=TERMS.index)
    scale = {t: _scales(t, ref, tols[TERM_TOLERANCE[t][0]]) for t in terms}

    def weigh(t, a):
        return a / scale[t].reshape((-1,) + (1,) * (a.ndim - 1))

    r = _stack([weigh(t, E - ref[t]) for v in engine_values.values() for t, E in v.items()])
    rr = float(r @ r)
    if not np.isfinite(rr) or rr == 0.0:
        return None
    effects = cause_effects(model, states, terms)
    causes = list(effects)
    S = np.stack([_stack([weigh(t, effects[c][t]) for v in engine_values.values() for t in v])
                  for c in causes], axis=1)
    G = S.T @ S
    b = S.T @ r
    g = np.diag(G)
    ok = g > 0
    single = np.where(ok, b ** 2 / np.where(ok, g, 1.0) / rr, 0.0)
    order = np.argsort(single)[::-1]
    best = int(order[0])

    def values(cs):
        out = []
        for c in cs:
            if c == "contact":
                out.append(model.contact)
            elif c == "gyroscopic":
                out.append("with" if model.gyroscopic else "without")
            else:
                out.append(float(getattr(model.params, c)))
        return tuple(out)

    chosen = ((causes[best],), (float(b[best] / G[best, best]),), float(single[best]))
    runner = (causes[int(order[1])], float(single[order[1]]))
    if chosen[2] < EXPLAINED:
        best_pair = None
        for i, j in itertools.combinations(np.flatnonzero(ok), 2):
            A = G[np.ix_([i, j], [i, j])]
            det = A[0, 0] * A[1, 1] - A[0, 1] ** 2
            if det <= 1e-9 * A[0, 0] * A[1, 1]:
                continue   # (nearly) the same effect: the pair says nothing more than one
            x = np.linalg.solve(A, b[[i, j]])
            frac = float(x @ b[[i, j]]) / rr
            if best_pair is None or frac > best_pair[2]:
                best_pair = ((causes[i], causes[j]), (float(x[0]), float(x[1])), frac)
        if best_pair and best_pair[2] >= max(EXPLAINED, chosen[2] + 0.05):
            chosen = best_pair
            runner = (causes[best], float(single[best]))
    cs, est, frac = chosen
    bodies = {cause_body(c) for c in cs}
    body = bodies.pop() if len(bodies) == 1 else None
    return Explanation(cs, est, min(frac, 1.0), body, runner, values(cs))


# -- localization ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Localization:
    """Where the model under test and the engines disagree."""

    quantities: tuple[TermComparison, ...]   # compare_terms, every engine
    checks: tuple[TermCheck, ...]            # term by term, every engine
    explanation: Explanation | None

    @property
    def agrees(self) -> bool:
        return all(c.passed for c in self.quantities) and all(c.passed for c in self.checks)

    @property
    def detected(self) -> bool:
        """Some compared quantity fails its tolerance."""
        return not all(c.passed for c in self.quantities)

    @property
    def terms(self) -> tuple[str, ...]:
        """The terms that differ (any engine), in TERMS order."""
        bad = {c.term for c in self.checks if not c.passed}
        return tuple(t for t in TERMS if t in bad)

    @property
    def entries(self) -> tuple[str, ...]:
        """Worst entries of the failing compared quantities (compare_terms' worst_entry)."""
        return tuple(dict.fromkeys(c.worst_entry for c in self.quantities if not c.passed))

    def describe(self) -> str:
        if self.agrees:
            return "everything agrees"
        if self.explanation is None:
            return f"{', '.join(self.terms) or 'a compared quantity'} differ(s); no cause found"
        text = format_localization(self.terms, self.explanation.causes, self.explanation.body)
        if self.explanation.explained < EXPLAINED:
            text += (f", partly: it explains {100 * self.explanation.explained:.0f}% "
                     "(more than one cause?)")
        return text


def localize(model: Model, states: States, engines: Sequence[Engine],
             engine_values: Mapping[str, Mapping[str, np.ndarray]] | None = None,
             truth: Engine | None = None) -> Localization:
    """Compare the model (as the reference engine) with each engine and localize any
    difference. ``engine_values`` (engine name -> `engine_terms`) can be passed in when the same
    engines are compared with many models (the fault suite). ``truth``: another engine to
    compare with instead of the model (its terms are the baseline; the causes are still fitted
    on the model's sensitivities, which is what an engine built from the same parameters
    shares)."""
    tols = load_tolerances()
    values = engine_values if engine_values is not None else \
        {e.name: engine_terms(e, states) for e in engines}
    ref_engine = truth if truth is not None else load_engine("reference", model)
    quantities = tuple(c for e in engines for c in compare_terms(ref_engine, e, states))
    ref = model_terms(model, states)
    if truth is not None:
        ref = {**ref, **engine_terms(truth, states)}
    checks = tuple(check_terms(ref, values, tols))
    failing = not all(c.passed for c in quantities) or not all(c.passed for c in checks)
    explanation = explain(model, states, ref, values, tols) if failing else None
    return Localization(quantities, checks, explanation)


# -- diagnose: the user's entry point ----------------------------------------------------------

@dataclass(frozen=True)
class Diagnosis:
    """The model of a parameter file against the engines (built from it, or from ``against``)."""

    model: str                      # the file (or named model) under test
    against: str | None             # what the engines were built from (None: the same file)
    engines: tuple[str, ...]
    n_states: int
    localization: Localization
    declared: tuple[tuple[str, float | str, float | str], ...] = field(default=())
    # (name, model's value, against's value) for every parameter that differs between the two

    @property
    def agrees(self) -> bool:
        return self.localization.agrees

    def describe(self) -> str:
        """A short readable table and the verdict."""
        loc = self.localization
        against = "engines built from the same file" if self.against is None else self.against
        lines = [f"diagnose {self.model} against {against} "
                 f"(engines: {', '.join(self.engines)}; {self.n_states} states)", "",
                 f"{'term':6s} {'engine':10s} {'max error':>9s} {'tolerance':>9s}  {'verdict':7s}  worst entries"]
        for c in loc.checks:
            lines.append(f"{c.term:6s} {c.engine:10s} {c.max_error:9.1e} {c.tolerance:9.0e}  "
                         f"{'ok' if c.passed else 'DIFFERS':7s}  {', '.join(c.entries)}")
        bad = [c for c in loc.quantities if not c.passed]
        lines.append("")
        lines.append(f"compared quantities (tolerances.toml): {len(loc.quantities) - len(bad)} of "
                     f"{len(loc.quantities)} within tolerance"
                     + ("" if not bad else "; failing: " + "; ".join(
                         f"{c.quantity} vs {c.engines[1]} {c.max_error:.1e} > {c.tolerance:.0e} "
                         f"at {c.worst_entry}" for c in bad)))
        if loc.explanation is not None:
            lines.append(f"localized: {loc.describe()}")
            lines.append(f"  {loc.explanation.describe()}")
        if self.against is None:
            lines.append(f"compared: engines built from {self.model} against the reference built "
                         f"from {self.model}" + (": the file is interpreted consistently" if
                                                 self.agrees else "")
                         + "; to see how it differs from another bicycle use --against NAME")
        if self.declared:
            theirs = Path(str(self.against)).stem
            shown = [f"{n}: {theirs} {b}, yours {a}" if isinstance(a, str) else
                     f"{n}: {theirs} {b:.6g}, yours {a:.6g} {PARAMETER_UNITS[n]}"
                     for n, a, b in self.declared]
            more = f" and {len(shown) - 6} more (see --json)" if len(shown) > 6 else ""
            lines.append(f"your file differs from {self.against} in: " + "; ".join(shown[:6]) + more)
        lines.append(f"verdict: {'everything agrees' if self.agrees else 'DIFFERS'}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        loc = self.localization
        return {
            "model": self.model, "against": self.against, "engines": list(self.engines),
            "n_states": self.n_states, "agrees": self.agrees,
            "localized_to": None if loc.agrees else loc.describe(),
            "terms": [c.to_dict() for c in loc.checks],
            "comparisons": [{"quantity": c.quantity, "engines": list(c.engines),
                             "max_error": c.max_error, "tolerance": c.tolerance,
                             "passed": c.passed, "worst_entry": c.worst_entry}
                            for c in loc.quantities],
            "explanation": loc.explanation.to_dict() if loc.explanation else None,
            "declared_differences": [list(d) for d in self.declared],
        }


def _declared(a: Model, b: Model) -> tuple[tuple[str, float | str, float | str], ...]:
    out = [(n, getattr(a.params, n), getattr(b.params, n)) for n in PARAMETER_NAMES
           if getattr(a.params, n) != getattr(b.params, n)]
    if a.contact != b.contact:
        out.append(("contact", a.contact, b.contact))
    return tuple(out)


def diagnose(params_file: str | Path, against: str | Path | None = None,
             engines: Sequence[str] = ("pinocchio",), n_states: int = DEFAULT_STATES,
             seed: int = DEFAULT_SEED, options: Mapping[str, Mapping] | None = None) -> Diagnosis:
    """The reference model of ``params_file`` (a .toml file or a named model) against the
    engines built from the same file (``against=None``: adapters and engines must agree) or
    from ``against`` (a named model or a file): which terms differ, at which entries, and the
    parameter (hence body) or structural cause that best explains it, with its estimated value
    difference. A bad file raises `ParameterError`; an unknown engine or too few states
    ValueError."""
    engines = tuple(engines)
    if not engines or "reference" in engines:
        raise ValueError("engines must name at least one engine other than the reference (the "
                         f"reference is the model under test); got {', '.join(engines) or 'none'}")
    if isinstance(n_states, bool) or not isinstance(n_states, int) or n_states < 4:
        raise ValueError(f"n_states must be an integer >= 4; got {n_states!r}")
    model = Model(resolve_model(params_file))
    against_engine = _engine_named(against)
    truth = model if against is None or against_engine else Model(resolve_model(against))
    built = [load_engine(e, truth, **dict((options or {}).get(e, {}))) for e in engines]
    states = random_states(n_states, seed=seed)
    if against_engine:   # the user's engine against another engine, same parameters
        other = load_engine(str(against), model)
        return Diagnosis(str(params_file), f"engine {against}", engines, n_states,
                         localize(model, states, built, truth=other), ())
    return Diagnosis(str(params_file), None if against is None else str(against), engines,
                     n_states, localize(model, states, built), _declared(model, truth))


def _engine_named(against) -> bool:
    """Whether ``--against`` names an engine (a registered name or a ``module:Class`` /
    ``file.py:Class`` spec) rather than a bicycle (a named model or a parameter file)."""
    if against is None:
        return False
    from engines import available_engines
    from reference_model import NAMED_MODELS
    text = str(against)
    if text in NAMED_MODELS or Path(text).is_file():
        return False
    return text in available_engines() or ":" in text
