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
   dq, Qaero odd and ``S T`` linear in T) and checked against the reference's own term. Where
   an engine offers two ways (gravity() and generalized_forces), `localize` checks both ("Qgrav
   in F", "Qv in F": a mistake in F alone shows there), and it checks the engine's forward
   accelerations against the constrained solve of the engine's *own* terms ("ddq solve": a
   wrong solve shows there, wrong terms do not).
3. **Which cause, hence which body**: the discrepancy ``r = engine - model`` over all states and
   all compared terms (each entry divided by its tolerance's scale, so terms of different units
   weigh alike; agreeing terms stay in the fit, where they rule causes out) is compared with the
   effect ``s`` of each candidate cause on the model's terms (`candidate_causes`,
   `comparisons.judgments.causes`):

   * *continuous* causes, fitted by least squares: ``d(term)/d p_j`` for each of the 30
     parameters (central differences; one-sided where the parameter sits on a validity
     boundary, which happens only for inertias and masses, where the terms are linear and
     one-sided differences are exact), each parameter in one term only (D and dD dq built with
     different radii), the gyroscopic terms ``w x (I w)``, the other front-contact model, and
     on a model built from the benchmark's Table 1 each of its 26 inputs through the conversion
     (`reference_model.benchmark`). The share is ``(s . r)^2 / (|s|^2 |r|^2)`` and the fitted
     coefficient the estimated difference (engines' value minus the model's);
   * *discrete* mistakes, taken at full size: a term's sign flipped (``-2 T``) or the term
     missing (``-T``), in every copy or in generalized_forces only; a rider torque with the
     wrong sign, on the wrong body or two torques swapped; two coordinates swapped in a term's
     arguments (``T(P q) - T(q)``); a Table 1 slip (trail's sign, the head angle for lam, lam
     converted to radians twice); from the engine's own values, a non-symmetric M (a triangle
     mirrored undoes it) and a forward solve without the constraint rows. Their share is the
     part of ``|r|^2`` that undoing them removes, ``1 - |r - s|^2 / |r|^2``: a discrete cause
     cannot claim a small difference that merely points its way.

   The best cause must explain at least ``LOCALIZED`` (90 %) of the whole difference *and* of
   each differing term (one large difference would otherwise hide a second mistake); a tie is
   settled in the order of `KINDS` (the discrete mistake, then one parameter, a Table 1 input,
   a parameter in one term). When no single cause explains ``EXPLAINED`` of it, pairs of
   parameters (and the gyroscopic and contact terms) are tried (e.g. two swapped inertias).
   Otherwise diagnose says that no single cause explains it and lists the best candidates, and
   each differing term's own best cause.

The body follows from the parameter: ``I2*, m2, R_rear`` body 2 (rear wheel); ``x3, z3, m3,
I3*, cv`` body 3 (frame+rider; cv is its drag); ``xa, za, dx4, dz4, m4, I4*`` body 4
(fork/handlebar); ``x5, z5, m5, I5*, R_front`` and the front contact body 5 (front wheel);
``g`` and the gyroscopic terms belong to all bodies.

Command line: ``bicycle-xval diagnose FILE [--against MODEL] [--engines pinocchio,exudyn]
[--states N] [--json OUT]``; exit 0 when everything agrees, 1 when something differs.
"""

from __future__ import annotations

import dataclasses
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

from .causes import (KINDS, Cause, coordinate_swap_causes, parameter_evaluator,
                     parameter_term_causes, table1_causes, term_sign_causes, torque_causes)
from .term_checks import (SOLVE_NEEDS, SOURCE_LABEL, TERM_TOLERANCE, TERMS, Block, SolveValues,
                          TermCheck, check_block, check_terms, engine_terms, extract, model_terms,
                          solve_values, term_blocks)
from .terms import States, TermComparison, compare_terms, random_states
from .tolerances import Tolerance

__all__ = [   # the terms and their checks are `term_checks`', named here too (their old home)
    "DEFAULT_SEED", "DEFAULT_STATES", "EXPLAINED", "LOCALIZED", "SOLVE_NEEDS", "SOURCE_LABEL",
    "STRUCTURAL", "TERM_TOLERANCE", "TERMS", "Block", "Diagnosis", "Explanation", "Localization",
    "ModelCauses", "SolveValues", "TermCheck", "body_label", "candidate_causes", "cause_body",
    "cause_effects", "cause_label", "check_block", "check_terms", "diagnose", "engine_terms",
    "explain", "format_localization", "localize", "model_terms", "parameter_body",
    "solve_values", "term_blocks",
]

STRUCTURAL = ("gyroscopic", "contact")
EXPLAINED = 0.99          # fraction of the discrepancy a cause must explain to be named alone
LOCALIZED = 0.90          # below this share nothing is printed as localized: no single cause
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


def format_localization(terms: Sequence[str], causes: Sequence[str], body: int | None,
                        labels: Sequence[str] = (), body_text: str | None = None) -> str:
    """E.g. 'M, Qv via I3xz (body 3 frame+rider)'; ``labels`` name the causes (default:
    `cause_label`), ``body_text`` replaces the body's ' (...)' (`Explanation.body_text`)."""
    what = ", ".join(t for t in TERMS + ("ddq",) if t in terms) or "nothing"
    named = labels or [cause_label(c) for c in causes]
    tail = f" ({body_label(body)})" if body_text is None else body_text
    return f"{what} via {' + '.join(named)}{tail}"


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


def _value(model: Model, cause: str) -> float | str:
    if cause == "contact":
        return model.contact
    if cause == "gyroscopic":
        return "with" if model.gyroscopic else "without"
    return float(getattr(model.params, cause))


class ModelCauses:
    """The candidate causes that follow from the model alone (its parameters, terms, Table 1)
    at one set of states, built once per set of compared terms and shared by every engine
    compared with that model (the planted-bug suite and the fault suite compare many)."""

    def __init__(self, model: Model, states: States):
        self.model, self.states = model, states
        self._built: dict[tuple, list[Cause]] = {}

    def get(self, ref: Mapping[str, np.ndarray], terms: Sequence[str],
            sources: Mapping[str, tuple[str, ...]]) -> list[Cause]:
        key = (tuple(terms), tuple(sorted(sources.items())))
        if key not in self._built:
            self._built[key] = _model_causes(self.model, self.states, ref, terms, sources)
        return self._built[key]


def _model_causes(model: Model, states: States, ref: Mapping[str, np.ndarray],
                  terms: Sequence[str], sources: Mapping[str, tuple[str, ...]]) -> list[Cause]:
    effects = cause_effects(model, states, terms)
    out = [Cause(c, cause_label(c), cause_body(c), "structural" if c in STRUCTURAL else "parameter",
                 False, {(t, None): e for t, e in eff.items()},
                 PARAMETER_UNITS.get(c, ""), _value(model, c),
                 evaluate=None if c in STRUCTURAL else
                 parameter_evaluator(model, states, model_terms, terms, c))
           for c, eff in effects.items()]
    out += parameter_term_causes(effects, model, PARAMETER_UNITS, parameter_body, states,
                                 model_terms)
    out += term_sign_causes(ref, sources)
    if "S" in terms:
        out += torque_causes(ref["S"], states.q)
    out += coordinate_swap_causes(model_terms, model, states, ref, terms)
    out += table1_causes(model, states, model_terms, terms)
    return out


def candidate_causes(model: Model, states: States, ref: Mapping[str, np.ndarray],
                     blocks: Sequence[Block], solves: Mapping[str, SolveValues | None] | None = None,
                     shared: ModelCauses | None = None) -> list[Cause]:
    """Every candidate cause (`comparisons.judgments.causes`) for the blocks' terms: the 30
    parameters and the gyroscopic and contact terms (as before), each parameter in one term
    only, each term's sign flipped or the term missing, the rider torques' sign, columns and
    bodies, two coordinates swapped in a term's arguments, a model's Table 1 inputs and slips
    (these from the model alone: ``shared`` keeps them for the next engine), and from the
    engines' own values: a non-symmetric M, a forward solve without the constraint rows or
    with the bias's sign flipped."""
    terms = [t for t in TERMS if any(b.term == t for b in blocks)]
    sources = {t: tuple(dict.fromkeys(b.source for b in blocks if b.term == t)) for t in terms}
    out = list((shared or ModelCauses(model, states)).get(ref, terms, sources))
    for name in dict.fromkeys(b.engine for b in blocks):
        Ms = [b for b in blocks if b.engine == name and b.term == "M"]   # its M, in ID too
        for part, lower in (("upper", True), ("lower", False)) if Ms else ():
            out.append(Cause(f"triangle:M:{part}", f"M not symmetric: its "
                             f"{'lower' if lower else 'upper'} triangle is wrong (M with its "
                             f"{part} triangle mirrored agrees)", None, "structural", True,
                             {("M", b.source): b.value - _mirrored(b.value, lower) for b in Ms},
                             engine=name))
    for b in blocks:
        if b.term == "ddq":
            sv = solves[b.engine]
            out.append(Cause("solve:unconstrained", "forward_acceleration solves M ddq = F without "
                             "the constraint rows (D ddq = -dD dq left out)", None, "structural",
                             True, {("ddq", "solve"): sv.unconstrained - sv.own}, engine=b.engine))
            out.append(Cause("solve:bias-sign", "forward_acceleration solves with D ddq = +dD dq "
                             "(the constraint bias's sign flipped in the solve)", None,
                             "structural", True, {("ddq", "solve"): sv.bias_flipped - sv.own},
                             engine=b.engine))
    return out


def _mirrored(M: np.ndarray, from_upper: bool) -> np.ndarray:
    """M with one triangle copied onto the other (the diagonal kept)."""
    tri = np.triu(M) if from_upper else np.tril(M)
    return tri + np.swapaxes(tri, -1, -2) - M * np.eye(M.shape[-1])


@dataclass(frozen=True)
class Explanation:
    """The best explanation of a discrepancy by one cause (or a pair)."""

    causes: tuple[str, ...]       # cause ids: parameter names, 'gyroscopic', 'contact', or the
                                  # ids of `candidate_causes` (e.g. 'sign:Qgrav[F]', 'table1:lam')
    estimates: tuple[float, ...]  # fitted change (engines minus model): SI for a parameter; for a
                                  # structural cause the coefficient (1 = fully the other variant)
    explained: float              # fraction of the squared discrepancy explained by the fit
    body: int | None
    runner_up: tuple[str, float] | None = None   # next best single cause and its fraction
    model_values: tuple[float | str | None, ...] = ()   # the model's value of each cause
    labels: tuple[str, ...] = ()  # readable name of each cause
    kinds: tuple[str, ...] = ()   # `KINDS` of each cause
    units: tuple[str, ...] = ()   # unit of each estimate
    candidates: tuple[tuple[str, str, float, tuple[str, ...]], ...] = ()
    # the best single causes: (id, label, share, the differing terms it leaves unexplained)
    unexplained: tuple[str, ...] = ()   # differing terms (rows) the causes explain < LOCALIZED of
    per_term: tuple[tuple[str, str, float], ...] = ()
    # (differing row, the cause that best explains that row alone, its share of the row)

    def _labels(self) -> tuple[str, ...]:
        return self.labels or tuple(cause_label(c) for c in self.causes)

    def describe(self) -> str:
        parts = []
        kinds = self.kinds or tuple("structural" if c in STRUCTURAL else "parameter"
                                    for c in self.causes)
        units = self.units or tuple(PARAMETER_UNITS.get(c, "") for c in self.causes)
        for cause, est, value, kind, unit, label in zip(self.causes, self.estimates,
                                                         self.model_values, kinds, units,
                                                         self._labels()):
            if cause == "contact":
                parts.append(f"engines' front contact is the other model (coefficient {est:.3f}; "
                             f"the model under test: {value!r})")
            elif cause == "gyroscopic":
                parts.append("the model under test lacks the gyroscopic terms the engines have"
                             if value == "without" else
                             "the engines lack the gyroscopic terms the model under test has")
                parts[-1] += f" (coefficient {est:.3f})"
            elif kind == "structural":
                parts.append("undoing it removes that share (the whole mistake, no fitted "
                             "size)")
            elif kind == "term-parameter":
                name, term = cause.split("@")
                parts.append(f"d{name} = {est:+.5g} {unit} in {term} only (model {value:.6g}, "
                             f"that term's fit {value + est:.6g} {unit})")
                if term in ("D", "dD dq"):
                    parts[-1] += f": D and dD dq were built with different {name}"
            elif kind == "table1":
                name = cause.split(":", 1)[1]
                parts.append(f"d{name} = {est:+.5g} {unit} in Table 1 (model built from "
                             f"{name} = {value:.6g}, engines' fit {value + est:.6g} {unit})")
            else:
                parts.append(f"d{cause} = {est:+.5g} {unit} (model {value:.6g}, engines' fit "
                             f"{value + est:.6g} {unit})")
        text = (f"{' + '.join(self._labels())}{self.body_text} "
                f"explains {100 * self.explained:.2f}% of the difference: {'; '.join(parts)}")
        if self.explained < _EXACT:
            text += (f"; it leaves {100 * (1 - self.explained):.2g}% of the difference, more "
                     "than a linearization or round-off leaves: a near cause, perhaps not the "
                     "exact one")
        if len(self.causes) == 2 and _looks_swapped(self):
            text += f"; looks like {self.causes[0]} and {self.causes[1]} swapped"
        alike = self.equally_good
        if alike:
            text += (f"; {' and '.join(alike)} {'explains' if len(alike) == 1 else 'explain'} "
                     f"it as well: the compared terms cannot tell "
                     f"{'the two' if len(alike) == 1 else 'these'} apart, so check "
                     f"{'both' if len(alike) == 1 else 'each'}")
            return text
        if self.runner_up and self.runner_up[1] >= 0.005:   # a runner-up of nothing says nothing
            label = next((c[1] for c in self.candidates if c[0] == self.runner_up[0]),
                         cause_label(self.runner_up[0]))
            text += f"; next best single cause {label} ({100 * self.runner_up[1]:.1f}%)"
        return text

    @property
    def equally_good(self) -> tuple[str, ...]:
        """Labels of the other single causes that explain the difference as well as the one
        named (within `_TIE` of its share): e.g. the rear wheel's mass and the rear radius in
        Qgrav alone, whose effects are the same vector (both scale the hub's height term
        g R_rear cos(theta)). Empty for a pair, and when the named cause stands alone."""
        if len(self.causes) != 1:
            return ()
        return tuple(label for cid, label, share, _ in self.candidates
                     if cid != self.causes[0] and share >= self.explained - _TIE)

    @property
    def body_text(self) -> str:
        """' (body 3 frame+rider)', ' (all bodies)'; nothing for a mistake in a term's
        structure (a sign, a solve, a swap), which belongs to no body."""
        kinds = self.kinds or ("parameter",)
        if self.body is None and all(k == "structural" for k in kinds) and \
                not set(self.causes) & set(STRUCTURAL):
            return ""
        return f" ({body_label(self.body)})"

    def best_candidates(self, n: int = 3) -> str:
        """'label 45.1%, label 12.0%, ...': the best single causes and their shares."""
        return ", ".join(f"{lab} {100 * s:.1f}%" + (f" (leaves {', '.join(u)} unexplained)" if u else "")
                         for _, lab, s, u in self.candidates[:n]) or "none"

    def to_dict(self) -> dict:
        return {"causes": list(self.causes), "estimates": list(self.estimates),
                "explained": self.explained, "body": self.body,
                "runner_up": list(self.runner_up) if self.runner_up else None,
                "model_values": list(self.model_values), "labels": list(self._labels()),
                "localized": self.explained >= LOCALIZED and not self.unexplained,
                "unexplained": list(self.unexplained),
                "per_term": [{"term": t, "label": lab, "explained": x} for t, lab, x in self.per_term],
                "candidates": [{"cause": c, "label": lab, "explained": s, "unexplained": list(u)}
                               for c, lab, s, u in self.candidates]}


#: a true cause leaves round-off and a linearization's error (at most 1.4e-8 of the difference
#: measured over the planted bugs and the fault suite); more than this is said
_EXACT = 1.0 - 1e-6


def _looks_swapped(e: Explanation) -> bool:
    (a, b), (da, db) = e.causes, e.estimates
    if a not in PARAMETER_UNITS or b not in PARAMETER_UNITS or PARAMETER_UNITS[a] != PARAMETER_UNITS[b]:
        return False
    va, vb = e.model_values
    return abs(da + db) <= 0.05 * abs(da) and abs(va + da - vb) <= 0.05 * abs(da)


def _stack(blocks: Sequence[np.ndarray]) -> np.ndarray:
    return np.concatenate([np.ravel(b) for b in blocks]) if blocks else np.zeros(0)


def _effect_vector(cause: Cause, blocks: Sequence[Block]) -> np.ndarray:
    parts = []
    for b in blocks:
        e = cause.effect(b.term, b.source) if cause.engine in (None, b.engine) else None
        parts.append(b.weighted(e) if e is not None else np.zeros(b.value.shape))
    return _stack(parts)


#: two shares closer than this are a tie, settled by `KINDS` (e.g. 'sign of Qgrav flipped'
#: and g = -9.81 explain the same difference; the discrete mistake is the likelier)
_TIE = 1e-6
#: how many of the best fitted causes are checked at their fitted size
_VERIFIED = 8


def explain(model: Model, states: States, ref: Mapping[str, np.ndarray],
            engine_values: Mapping[str, Mapping[str, np.ndarray]],
            tolerances: Mapping[str, Tolerance],
            copies: Mapping[str, Mapping[str, np.ndarray]] | None = None,
            solves: Mapping[str, SolveValues | None] | None = None,
            shared: ModelCauses | None = None) -> Explanation | None:
    """Least-squares localization of ``engine - model`` onto the causes (see the module
    docstring); None when there is nothing to explain. ``copies``, ``solves``: `localize`'s
    second copies of terms and forward solves; ``shared``: the model's causes, kept for the
    next engine compared with the same model at the same states."""
    blocks = term_blocks(ref, engine_values, tolerances, copies, solves)
    r = _stack([b.weighted(b.value - b.reference) for b in blocks])
    rr = float(r @ r)
    if not np.isfinite(rr) or rr == 0.0:
        return None
    causes = candidate_causes(model, states, ref, blocks, solves, shared)
    S = np.stack([_effect_vector(c, blocks) for c in causes], axis=1)
    G = np.einsum("ij,ij->j", S, S)
    b = S.T @ r
    ok = (G > 0) & np.isfinite(G)
    fixed = np.array([c.fixed for c in causes])
    with np.errstate(all="ignore"):
        coef = np.where(fixed, 1.0, b / np.where(ok, G, 1.0))
    share = _share(coef, b, G, rr, ok)
    # each differing block must be explained too: a share is a sum of squares, so one large
    # difference would otherwise hide a second, smaller mistake in another term
    segments = _segments(blocks)
    worst = np.ones(len(causes))
    rank = [KINDS.index(c.kind) for c in causes]
    per_term = []     # each differing block's own best cause (its coefficient fitted there)
    for (lo, hi), label in segments:
        Sb = S[lo:hi]
        bb, Gb, rb = Sb.T @ r[lo:hi], np.einsum("ij,ij->j", Sb, Sb), float(r[lo:hi] @ r[lo:hi])
        worst = np.minimum(worst, _share(coef, bb, Gb, rb, ok, clip=False))
        okb = ok & (Gb > 0)
        with np.errstate(all="ignore"):
            own = _share(np.where(fixed, 1.0, bb / np.where(okb, Gb, 1.0)), bb, Gb, rb, okb)
        i = min(range(len(causes)), key=lambda i: (-round(float(own[i]), 6), rank[i]))
        if own[i] > 0.0:
            per_term.append((label, causes[i].label, float(own[i])))
    # the best fitted causes again at their fitted size: the model rebuilt with the value
    # changed (a sensitivity is a linearization, and the value may not even be valid)
    removed = {}
    for i in [i for i in np.argsort(-share) if not fixed[i] and causes[i].evaluate][:_VERIFIED]:
        if share[i] < 0.5 * LOCALIZED:
            break
        at = causes[i].evaluate(float(coef[i]))
        removed[i] = _effect_vector(dataclasses.replace(causes[i], effects=at), blocks) \
            if at is not None else None
        share[i], worst[i] = _removal(r, removed[i], segments)
    whole = [i for i in range(len(causes)) if share[i] >= LOCALIZED and worst[i] >= LOCALIZED]
    pool = whole or range(len(causes))
    top = max(share[i] for i in pool)
    best = min((i for i in pool if share[i] >= top - _TIE), key=lambda i: (rank[i], -share[i]))
    order = sorted(range(len(causes)), key=lambda i: (i != best, -share[i], rank[i]))

    def missed(coefs, idx):
        vec = removed.get(idx[0]) if len(idx) == 1 and idx[0] in removed else \
            S[:, list(idx)] @ np.asarray(coefs)
        if vec is None:
            return tuple(label for _, label in segments)
        return tuple(dict.fromkeys(label for (lo, hi), label in segments
                                   if not _removal(r[lo:hi], vec[lo:hi], [])[0] >= LOCALIZED))

    seen, listed = set(), []
    for i in order:
        if share[i] <= 0.0 or causes[i].label in seen:
            continue
        seen.add(causes[i].label)
        listed.append((causes[i].id, causes[i].label, float(share[i]), missed([coef[i]], [i])))
        if len(listed) == 5:
            break
    runner_i = next((i for i in order if i != best), None)
    chosen = ((best,), (float(coef[best]),), float(share[best]))
    runner = (causes[runner_i].id, float(share[runner_i])) if runner_i is not None else None
    classic = [i for i, c in enumerate(causes) if c.id in PARAMETER_NAMES or c.id in STRUCTURAL]
    if chosen[2] < EXPLAINED:
        Gc = S[:, classic].T @ S[:, classic]
        best_pair = None
        for a, c in itertools.combinations(range(len(classic)), 2):
            if not (ok[classic[a]] and ok[classic[c]]):
                continue
            A = Gc[np.ix_([a, c], [a, c])]
            det = A[0, 0] * A[1, 1] - A[0, 1] ** 2
            if det <= 1e-9 * A[0, 0] * A[1, 1]:
                continue   # (nearly) the same effect: the pair says nothing more than one
            rhs = b[[classic[a], classic[c]]]
            x = np.linalg.solve(A, rhs)
            frac = float(x @ rhs) / rr
            if best_pair is None or frac > best_pair[2]:
                best_pair = ((classic[a], classic[c]), (float(x[0]), float(x[1])), frac)
        if best_pair and best_pair[2] >= max(EXPLAINED, chosen[2] + 0.05):
            chosen = best_pair
            runner = (causes[best].id, float(share[best]))
    idx, est, frac = chosen
    picked = [causes[i] for i in idx]
    bodies = {c.body for c in picked}
    body = bodies.pop() if len(bodies) == 1 else None
    return Explanation(tuple(c.id for c in picked), est, min(frac, 1.0), body, runner,
                       tuple(c.value for c in picked), tuple(c.label for c in picked),
                       tuple(c.kind for c in picked), tuple(c.unit for c in picked),
                       tuple(listed), missed(est, idx), tuple(per_term))


def _share(coef, b, G, rr, ok, clip=True):
    """The fraction of ``rr`` each cause removes at its coefficient: ``2 x b - x^2 G`` over
    ``rr`` (the least-squares x gives ``b^2 / (G rr)``; a discrete cause's x is 1)."""
    with np.errstate(all="ignore"):
        out = (2.0 * coef * b - coef ** 2 * G) / rr
    out = np.where(ok & np.isfinite(out), out, 0.0 if clip else -np.inf)
    return np.clip(out, 0.0, 1.0) if clip else out


def _removal(r: np.ndarray, removed: np.ndarray | None, segments) -> tuple[float, float]:
    """(share of ``|r|^2`` that subtracting ``removed`` removes, the least such share over the
    differing blocks' ``segments``); (0, -inf) when there is nothing to subtract (the cause's
    value is not a valid parameter set)."""
    if removed is None:
        return 0.0, -np.inf
    left = r - removed
    whole = 1.0 - float(left @ left) / float(r @ r)
    parts = [1.0 - float(left[lo:hi] @ left[lo:hi]) / float(r[lo:hi] @ r[lo:hi])
             for (lo, hi), _ in segments]
    return max(0.0, min(whole, 1.0)), min(parts, default=1.0)


def _segments(blocks: Sequence[Block]) -> list[tuple[tuple[int, int], str]]:
    """((start, stop), label) in the stacked residual of each block that fails its tolerance."""
    out, lo = [], 0
    for b in blocks:
        hi = lo + b.value.size
        if not check_block(b).passed:
            out.append(((lo, hi), b.label))
        lo = hi
    return out


# -- localization ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Localization:
    """Where the model under test and the engines disagree."""

    quantities: tuple[TermComparison, ...]   # compare_terms, every engine
    checks: tuple[TermCheck, ...]            # term by term, every engine
    explanation: Explanation | None
    solve_checks: tuple[TermCheck, ...] = ()  # each engine's ddq against its own terms' solve

    @property
    def agrees(self) -> bool:
        return all(c.passed for c in self.quantities + self.checks + self.solve_checks)

    @property
    def detected(self) -> bool:
        """Some compared quantity fails its tolerance."""
        return not all(c.passed for c in self.quantities)

    @property
    def localized(self) -> bool:
        """A single cause (or pair) explains at least `LOCALIZED` of the difference."""
        e = self.explanation
        return e is not None and e.explained >= LOCALIZED and not e.unexplained

    @property
    def terms(self) -> tuple[str, ...]:
        """The terms that differ (any engine), in TERMS order, then 'ddq' for a forward solve
        that is not the solve of the engine's own terms."""
        bad = {c.term for c in self.checks + self.solve_checks if not c.passed}
        return tuple(t for t in TERMS + ("ddq",) if t in bad)

    @property
    def entries(self) -> tuple[str, ...]:
        """Worst entries of the failing compared quantities (compare_terms' worst_entry)."""
        return tuple(dict.fromkeys(c.worst_entry for c in self.quantities if not c.passed))

    @property
    def differing_entries(self) -> tuple[str, ...]:
        """The entries above tolerance of every differing term, then of the failing quantities."""
        return tuple(dict.fromkeys([e for c in self.checks + self.solve_checks if not c.passed
                                    for e in c.entries] + list(self.entries)))

    def describe(self) -> str:
        if self.agrees:
            return "everything agrees"
        what = ', '.join(self.terms) or 'a compared quantity'
        if self.explanation is None:
            return f"{what} differ(s); no cause found"
        if not self.localized:
            return (f"{what} differ(s); no single cause explains it (best: "
                    f"{self.explanation.best_candidates(2)})")
        text = format_localization(self.terms, self.explanation.causes, self.explanation.body,
                                   self.explanation.labels, self.explanation.body_text)
        if self.explanation.explained < EXPLAINED:
            text += (f", partly: it explains {100 * self.explanation.explained:.0f}% "
                     "(more than one cause?)")
        return text


def localize(model: Model, states: States, engines: Sequence[Engine],
             engine_values: Mapping[str, Mapping[str, np.ndarray]] | None = None,
             truth: Engine | None = None, shared: ModelCauses | None = None, *,
             tolerances: Mapping[str, Tolerance]) -> Localization:
    """Compare the model (as the reference engine) with each engine and localize any
    difference. ``engine_values`` (engine name -> `engine_terms`) can be passed in when the same
    engines are compared with many models (the fault suite); otherwise each engine's terms are
    also taken a second way where it offers one (Qgrav and Qv out of generalized_forces besides
    gravity() and inverse_dynamics()) and its forward accelerations are checked against the
    solve of its own terms. ``truth``: another engine to compare with instead of the model (its
    terms are the baseline; the causes are still fitted on the model's sensitivities, which is
    what an engine built from the same parameters shares). ``shared``: the model's candidate
    causes at these states (`ModelCauses`), kept across calls with the same model, states and
    no ``truth``. ``tolerances``: what every term is judged by (the run's, a value)."""
    tols = tolerances
    copies: dict[str, dict[str, np.ndarray]] = {}
    solves: dict[str, SolveValues | None] = {}
    if engine_values is not None:
        values = engine_values
    else:
        values = {}
        for e in engines:
            values[e.name], copies[e.name], solves[e.name] = extract(e, states, extras=True)
    ref_engine = truth if truth is not None else load_engine("reference", model)
    quantities = tuple(c for e in engines for c in compare_terms(ref_engine, e, states, tols))
    ref = model_terms(model, states)
    if truth is not None:
        ref = {**ref, **engine_terms(truth, states)}
    blocks = term_blocks(ref, values, tols, copies, solves)
    checks = tuple(check_block(b) for b in blocks if b.source != "solve")
    solve_checks = tuple(check_block(b) for b in blocks if b.source == "solve")
    failing = not all(c.passed for c in quantities + checks + solve_checks)
    explanation = explain(model, states, ref, values, tols, copies, solves, shared) if failing else None
    return Localization(quantities, checks, explanation, solve_checks)


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
    not_run: tuple[tuple[str, str], ...] = ()   # (engine, reason): cannot represent this model

    @property
    def agrees(self) -> bool:
        return self.localization.agrees

    def describe(self) -> str:
        """A short readable table and the verdict."""
        loc = self.localization
        width = max([10] + [len(c.engine) for c in loc.checks + loc.solve_checks])
        against = "engines built from the same file" if self.against is None else self.against
        lines = [f"diagnose {self.model} against {against} "
                 f"(engines: {', '.join(self.engines)}; {self.n_states} states)", "",
                 f"{'term':10s} {'engine':{width}s} {'max error':>9s} {'tolerance':>9s}  {'verdict':7s}  worst entries"]
        for c in loc.checks + loc.solve_checks:
            lines.append(f"{c.label:10s} {c.engine:{width}s} {c.max_error:9.1e} {c.tolerance:9.0e}  "
                         f"{'ok' if c.passed else 'DIFFERS':7s}  {', '.join(c.entries)}")
        rows = {c.source for c in loc.checks + loc.solve_checks}
        if "F" in rows:
            lines.append("  'in F': the term taken out of generalized_forces (F = Qv + Qgrav + Qaero "
                         "+ S T), the other row from gravity() / inverse_dynamics()")
        if "ID" in rows:
            lines.append("  'M in ID': M taken out of inverse_dynamics (column k: ID(q, 0, e_k) - "
                         "ID(q, 0, 0)), the other row from mass_matrix()")
        if "solve" in rows:
            lines.append("  'ddq solve': forward_acceleration against the constrained solve of the "
                         "engine's own M, F, D and dD dq")
        bad = [c for c in loc.quantities if not c.passed]
        lines.append("")
        lines.append(f"compared quantities (tolerances.toml): {len(loc.quantities) - len(bad)} of "
                     f"{len(loc.quantities)} within tolerance"
                     + ("" if not bad else "; failing: " + "; ".join(
                         f"{c.quantity} vs {c.engines[1]} {c.max_error:.1e} > {c.tolerance:.0e} "
                         f"at {c.worst_entry}" for c in bad)))
        exp = loc.explanation
        if exp is not None and loc.localized:
            lines.append(f"localized: {loc.describe()}")
            lines.append(f"  {exp.describe()}")
        elif not loc.agrees:
            lines.append(f"no single cause explains it: {', '.join(loc.terms) or 'a compared quantity'} "
                         f"differ(s) at {', '.join(loc.differing_entries[:6]) or 'no entry'}")
            lines.append(f"  best candidates (share of the difference each explains alone, "
                         f"{100 * LOCALIZED:.0f}% needed): "
                         + (exp.best_candidates(3) if exp is not None else "none"))
            if exp is not None and len(exp.per_term) > 1:
                lines.append("  term by term (more than one mistake?): " + "; ".join(
                    f"{t}: {lab} {100 * x:.1f}%" for t, lab, x in exp.per_term))
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
        for name, reason in self.not_run:
            lines.append(f"not run on this model: {name} ({reason})")
        lines.append(f"verdict: {'everything agrees' if self.agrees else 'DIFFERS'}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        loc = self.localization
        return {
            "model": self.model, "against": self.against, "engines": list(self.engines),
            "n_states": self.n_states, "agrees": self.agrees,
            "localized_to": None if loc.agrees else loc.describe(),
            "localized": loc.localized,
            "terms": [c.to_dict() for c in loc.checks + loc.solve_checks],
            "comparisons": [{"quantity": c.quantity, "engines": list(c.engines),
                             "max_error": c.max_error, "tolerance": c.tolerance,
                             "passed": c.passed, "worst_entry": c.worst_entry}
                            for c in loc.quantities],
            "explanation": loc.explanation.to_dict() if loc.explanation else None,
            "declared_differences": [list(d) for d in self.declared],
            "not_run": [{"engine": e, "reason": r} for e, r in self.not_run],
        }


def _declared(a: Model, b: Model) -> tuple[tuple[str, float | str, float | str], ...]:
    out = [(n, getattr(a.params, n), getattr(b.params, n)) for n in PARAMETER_NAMES
           if getattr(a.params, n) != getattr(b.params, n)]
    if a.contact != b.contact:
        out.append(("contact", a.contact, b.contact))
    return tuple(out)


def diagnose(params_file: str | Path, against: str | Path | None = None,
             engines: Sequence[str] = (), n_states: int = DEFAULT_STATES,
             seed: int = DEFAULT_SEED, options: Mapping[str, Mapping] | None = None, *,
             tolerances: Mapping[str, Tolerance]) -> Diagnosis:
    """The reference model of ``params_file`` (a .toml file or a named model) against the
    engines built from the same file (``against=None``: adapters and engines must agree) or
    from ``against`` (a named model or a file): which terms differ, at which entries, and the
    parameter (hence body) or structural cause that best explains it, with its estimated value
    difference, every term judged by ``tolerances``. ``engines``: the engines to check (names
    or specs, at least one; the caller chooses them, e.g. `engines.term_engines`). A bad file
    raises `ParameterError`; no engine, an unknown engine or too few states ValueError."""
    engines = tuple(engines)
    if not engines or "reference" in engines:
        raise ValueError("engines must name at least one engine other than the reference (the "
                         f"reference is the model under test); got {', '.join(engines) or 'none'}")
    if not isinstance(n_states, int) or n_states < 4:     # True and False too: < 4
        raise ValueError(f"n_states must be an integer >= 4; got {n_states!r}")
    model = Model(resolve_model(params_file))
    against_engine = _engine_named(against)
    truth = model if against is None or against_engine else Model(resolve_model(against))
    built, not_run = _build(engines, truth, options)
    engines = tuple(e for e in engines if e not in dict(not_run))
    states = random_states(n_states, seed=seed)
    if against_engine:   # the user's engine against another engine, same parameters
        other = load_engine(str(against), model)
        return Diagnosis(str(params_file), f"engine {against}", engines, n_states,
                         localize(model, states, built, truth=other,
                                          tolerances=tolerances), (), not_run)
    return Diagnosis(str(params_file), None if against is None else str(against), engines,
                     n_states, localize(model, states, built, tolerances=tolerances),
                     _declared(model, truth), not_run)


def _build(engines: Sequence[str], model: Model, options) -> tuple[list[Engine], tuple[tuple[str, str], ...]]:
    """The engines built from ``model``, and (name, reason) of those that declare they cannot
    represent it (`engines.UnsupportedModel`: e.g. MuJoCo and a measured inertia that breaks
    A + B >= C), left out as a run leaves them out; when none can, the first one's error."""
    from engines import UnsupportedModel
    built, not_run, first = [], [], None
    for e in engines:
        try:
            built.append(load_engine(e, model, **dict((options or {}).get(e, {}))))
        except UnsupportedModel as exc:
            not_run.append((e, str(exc)))
            first = first or exc
    if not built:
        raise first
    return built, tuple(not_run)


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
