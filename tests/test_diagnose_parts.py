"""The parts of `comparisons.judgments.diagnose` below `explain`, each on its own: the candidate
causes the model gives (`ModelCauses`, `_model_causes`) and those the engines' own values give
(`candidate_causes`: a non-symmetric M, a forward solve without the constraint rows or with the
bias's sign flipped), the stacking of blocks into one residual (`_stack`, `_effect_vector`,
`_segments`), the sharing of the model's causes across `localize` calls, and the lines a user
reads from `bicycle-xval diagnose` at their edges (`Localization.describe`,
`Diagnosis.describe`).

Expected values are worked out here, not read from the code: a parameter's effect on a term by a
difference of the reference model's own terms at two values of it (the terms are linear in the
masses and inertias, so that difference is exact), each parameter's body from the thesis's
naming (``m3``, ``I3xx``: body 3, the frame+rider; ``g`` all bodies), each unit from the
quantity (a mass in kg, an inertia in kg*m^2, the drag coefficient of ``cv v^2`` in kg/m), the
triangle causes from an M made non-symmetric by a known lower-triangle error, and the texts from
the forms docs/report.md ("Diagnose") and the neighbouring tests/test_diagnose_text.py give.
Each test names the planted bugs it was seen failing on."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from comparisons.judgments.causes import Cause
from comparisons.judgments.diagnose import (Block, Diagnosis, Explanation, Localization,
                                            ModelCauses, SolveValues, _effect_vector, _segments,
                                            _stack, candidate_causes, localize, model_terms)
from comparisons.judgments.term_checks import TermCheck
from comparisons.judgments.terms import TermComparison, random_states
from comparisons.judgments.tolerances import load_tolerances
from reference_model import load_model
from reference_model.params import PARAMETER_NAMES

TOLS = load_tolerances()

#: the unit of each parameter's fitted change, from what the quantity is (thesis symbols)
UNITS = {**{n: "m" for n in ("R_rear", "R_front", "x3", "z3", "xa", "za", "dx4", "dz4", "x5",
                               "z5")},
         **{f"m{b}": "kg" for b in (2, 3, 4, 5)},
         **{n: "kg*m^2" for n in ("I2xx", "I2yy", "I2zz", "I3xx", "I3yy", "I3zz", "I3xz",
                                  "I4xx", "I4yy", "I4zz", "I4xz", "I5xx", "I5yy", "I5zz")},
         "g": "m/s^2", "cv": "kg/m"}


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis")


@pytest.fixture(scope="module")
def states():
    return random_states(4, seed=3)


@pytest.fixture(scope="module")
def ref(thesis, states):
    return model_terms(thesis, states)


def _terms_at(model, states, **changes):
    return model_terms(model.with_params(model.params.replace(**changes)), states)


# -- the model's own causes --------------------------------------------------------------------

def test_the_models_causes_are_its_parameters_with_their_units_kinds_and_effects(thesis, states,
                                                                                 ref):
    """Each of the 30 parameters is a continuous cause (fixed False, kind 'parameter') with the
    unit of its quantity and the body of its thesis symbol; the gyroscopic terms and the front
    contact are 'structural' causes with no unit (''). m3's effect on Qgrav is the difference
    of Qgrav at m3 + 1 kg and at m3 (Qgrav is linear in the mass). Planted: the parameters'
    fixed flag None, their unit None or looked up under the wrong key, the structural causes'
    unit None or 'XXXX', gyroscopic and contact made 'parameter' causes."""
    causes = {c.id: c for c in ModelCauses(thesis, states).get(ref, ["M", "Qgrav"],
                                                                {"M": ("",), "Qgrav": ("",)})}
    assert set(UNITS) == set(PARAMETER_NAMES)
    for name, unit in UNITS.items():
        c = causes[name]
        assert (c.kind, c.fixed, c.unit) == ("parameter", False, unit), name
    for name in ("gyroscopic", "contact"):
        c = causes[name]
        assert (c.kind, c.unit) == ("structural", ""), name
        assert c.fixed is False, name      # its coefficient is fitted (1 = the other variant)
    m3 = causes["m3"]
    assert (m3.body, m3.value) == (3, thesis.params.m3)
    assert causes["g"].body is None and causes["contact"].body == 5
    up = _terms_at(thesis, states, m3=thesis.params.m3 + 1.0)
    np.testing.assert_allclose(m3.effect("Qgrav", ""), up["Qgrav"] - ref["Qgrav"],
                               rtol=1e-6, atol=1e-9)
    assert set(m3.effects) == {("M", None), ("Qgrav", None)}


def test_a_parameter_in_one_term_only_is_evaluated_at_its_fitted_size(thesis, states, ref):
    """'m3 in Qgrav only' (m3 reaches M, Qv and Qgrav, so each term has its own cause) is
    checked by explain at its fitted size: evaluate(x) is Qgrav with m3 + x taken off Qgrav
    at m3, in Qgrav alone. Expected: the model rebuilt here at m3 + 2 kg. Planted: the
    evaluator left out (model_terms None, or the states shifted into its place)."""
    causes = {c.id: c for c in ModelCauses(thesis, states).get(ref, ["M", "Qgrav"],
                                                                {"M": ("",), "Qgrav": ("",)})}
    c = causes["m3@Qgrav"]
    assert (c.kind, c.body, c.unit, c.label) == ("term-parameter", 3, "kg", "m3 in Qgrav only")
    assert c.evaluate is not None
    got = c.evaluate(2.0)
    up = _terms_at(thesis, states, m3=thesis.params.m3 + 2.0)
    assert set(got) == {("Qgrav", None)}
    np.testing.assert_allclose(got[("Qgrav", None)], up["Qgrav"] - ref["Qgrav"], rtol=1e-12,
                               atol=1e-12)
    assert causes["m3@M"].evaluate is not None


def test_the_models_causes_are_kept_per_set_of_terms(thesis, states, ref):
    """The same request gives the same (kept) list; another set of terms its own causes: m3's
    effect on Qgrav alone when only Qgrav is compared, I3xx then has none (the inertia does not
    enter the gravity). Planted: one key for every request (the first set of terms' causes
    handed out for the second)."""
    shared = ModelCauses(thesis, states)
    first = shared.get(ref, ["M"], {"M": ("",)})
    assert shared.get(ref, ["M"], {"M": ("",)}) is first
    second = {c.id: c for c in shared.get(ref, ["Qgrav"], {"Qgrav": ("",)})}
    assert set(second["m3"].effects) == {("Qgrav", None)}
    assert not np.any(second["I3xx"].effect("Qgrav", ""))
    assert {c for c in second if c.startswith(("sign:", "missing:"))} == \
        {"sign:Qgrav", "missing:Qgrav"}


# -- the causes from the engines' own values ---------------------------------------------------

def _block(engine, term, source, value, reference):
    return Block(engine, term, source, value, reference, np.ones(len(value)), 1e-9)


def test_the_engines_own_causes_belong_to_that_engine(thesis, states, ref):
    """Engine 'a' gives M (its own and out of inverse_dynamics), Qgrav and a forward solve,
    its M with a known error E below the diagonal; engine 'b' gives Qgrav alone. Then:

    * only M and Qgrav are compared, so the sign/missing causes are those of M (in every copy,
      in its own mass_matrix(), in inverse_dynamics) and of Qgrav (one copy per engine);
    * 'a' alone has the two triangle causes (b gives no M): mirroring the upper triangle
      removes E (effect E), mirroring the lower one -E^T; both taken whole (fixed), of 'a';
    * 'a's solve causes are the unconstrained and the bias-flipped solves minus its own.

    Planted: the terms taken as those some block does not have, triangle causes for an engine
    without M, any of these causes not fixed (None or False) or of no engine."""
    E = np.zeros_like(ref["M"])
    E[:, 3, 0], E[:, 6, 4] = 0.25, -0.5            # theta row, xc column; gamma row, psi column
    M_a = ref["M"] + E
    n = len(states.q)
    own, unc, flip = (np.full((n, 8), v) for v in (1.0, 1.5, 3.0))
    sv = SolveValues(own + 1e-3, own, unc, flip)
    blocks = [_block("a", "M", "", M_a, ref["M"]), _block("a", "M", "ID", M_a, ref["M"]),
              _block("a", "Qgrav", "", ref["Qgrav"], ref["Qgrav"]),
              _block("a", "ddq", "solve", sv.ddq, sv.own),
              _block("b", "Qgrav", "", 1.1 * ref["Qgrav"], ref["Qgrav"])]
    causes = candidate_causes(thesis, states, ref, blocks, {"a": sv, "b": None})
    by_id = {c.id: c for c in causes}
    assert {c.id for c in causes if c.id.startswith(("sign:", "missing:"))} == {
        "sign:M", "missing:M", "sign:M[own]", "missing:M[own]", "sign:M[ID]", "missing:M[ID]",
        "sign:Qgrav", "missing:Qgrav"}
    assert {t for c in causes if c.engine is None for t, _ in c.effects} == {"M", "Qgrav"}
    engine_own = [(c.id, c.engine, c.fixed, c.kind, c.body) for c in causes
                  if c.id.startswith(("triangle:", "solve:"))]
    assert engine_own == [("triangle:M:upper", "a", True, "structural", None),
                          ("triangle:M:lower", "a", True, "structural", None),
                          ("solve:unconstrained", "a", True, "structural", None),
                          ("solve:bias-sign", "a", True, "structural", None)]
    for src in ("", "ID"):
        np.testing.assert_allclose(by_id["triangle:M:upper"].effect("M", src), E, atol=1e-12)
        np.testing.assert_allclose(by_id["triangle:M:lower"].effect("M", src),
                                   -np.swapaxes(E, -1, -2), atol=1e-12)
    assert by_id["triangle:M:upper"].label == ("M not symmetric: its lower triangle is wrong "
                                               "(M with its upper triangle mirrored agrees)")
    np.testing.assert_array_equal(by_id["solve:unconstrained"].effect("ddq", "solve"),
                                  np.full((n, 8), 0.5))
    np.testing.assert_array_equal(by_id["solve:bias-sign"].effect("ddq", "solve"),
                                  np.full((n, 8), 2.0))


def test_an_engines_own_cause_has_no_effect_on_another_engines_blocks():
    """The effect vector of a cause seen in engine 'a's values (e.g. its M not symmetric) is
    its effect, divided by each block's scale, on 'a's blocks and zero on 'b's blocks of the
    same term; a cause of no engine reaches both. Planted: the engine test dropped (a's
    mistake laid onto b's M)."""
    ref = np.zeros((2, 2, 2))
    blocks = [Block("a", "M", "", ref, ref, np.array([1.0, 2.0]), 1e-9),
              Block("b", "M", "", ref, ref, np.array([1.0, 1.0]), 1e-9)]
    e = np.arange(8.0).reshape(2, 2, 2)
    mine = Cause("triangle:M:upper", "x", None, "structural", True, {("M", ""): e}, engine="a")
    np.testing.assert_array_equal(_effect_vector(mine, blocks),
                                  [0, 1, 2, 3, 2, 2.5, 3, 3.5] + [0] * 8)
    anyone = dataclasses.replace(mine, engine=None)
    np.testing.assert_array_equal(_effect_vector(anyone, blocks),
                                  [0, 1, 2, 3, 2, 2.5, 3, 3.5] + list(range(8)))


def test_stacking_and_the_differing_blocks_place_in_it():
    """_stack ravels and joins the blocks, nothing gives an empty vector; _segments gives each
    failing block's (start, stop) in that vector and its row label: a passing M of 2 x 2 x 2
    entries first, then a failing Qgrav 'in F' of 2 x 3 at 8..14. Planted: the empty case
    joined (an error) or given one entry, the first block starting at 1."""
    assert _stack([]).shape == (0,)
    np.testing.assert_array_equal(_stack([np.ones((1, 2)), np.zeros(1)]), [1.0, 1.0, 0.0])
    z = np.zeros((2, 2, 2))
    g = np.zeros((2, 3))
    blocks = [Block("a", "M", "", z, z, np.ones(2), 1e-9),
              Block("a", "Qgrav", "F", g + 1.0, g, np.ones(2), 1e-9)]
    assert _segments(blocks) == [((8, 14), "Qgrav in F")]
    assert _segments(blocks[::-1]) == [((0, 6), "Qgrav in F")]


def test_localize_keeps_the_models_causes_in_the_shared_store(thesis):
    """A port with gravity's sign flipped, localized with a shared `ModelCauses`: the causes are
    asked of that store (once), so the next engine compared with this model reuses them
    (docstring of `localize`). Planted: the store not passed on (each call rebuilding them)."""
    from planted.engines import GravitySign

    class Counting(ModelCauses):
        asked = 0

        def get(self, *args, **kwargs):
            type(self).asked += 1
            return super().get(*args, **kwargs)

    s = random_states(4, seed=11)
    shared = Counting(thesis, s)
    loc = localize(thesis, s, [GravitySign(thesis)], shared=shared, tolerances=TOLS)
    assert loc.explanation.causes == ("sign:Qgrav",)
    assert Counting.asked == 1


# -- what a user reads -------------------------------------------------------------------------

M_BAD = TermCheck("pinocchio", "M", 3.2e-3, 1.1e-2, 1e-9, False, 4, ("M[theta, theta]",))
MASS = TermComparison("mass_matrix", ("reference", "pinocchio"), 3.2e-3, 1.1e-2, 1e-9, False, 4,
                      "M[theta, theta]", 24)
I3XX = Explanation(causes=("I3xx",), estimates=(-1.5,), explained=1.0, body=3,
                   model_values=(20.213,), labels=("I3xx",), kinds=("parameter",),
                   units=("kg*m^2",))


def test_a_cause_explaining_exactly_the_share_needed_is_not_partly():
    """EXPLAINED (99 %) is what a cause must explain to be named alone: exactly 99 % is enough
    (no ', partly'), just below it is partly. Planted: the bound taken as 'at most'."""
    at = Localization((MASS,), (M_BAD,), dataclasses.replace(I3XX, explained=0.99))
    assert at.describe() == "M via I3xx (body 3 frame+rider)"
    below = Localization((MASS,), (M_BAD,), dataclasses.replace(I3XX, explained=0.985))
    assert below.describe() == ("M via I3xx (body 3 frame+rider), partly: it explains 98% (more "
                                "than one cause?)")


def test_nothing_localized_lists_three_candidates_and_no_entry_when_none_is_named():
    """Four candidates, none localized: the line lists the best three only. A failing term row
    that names no entry (and no failing quantity) reads 'no entry'. Planted: all candidates
    listed, or four, the 'no entry' text changed."""
    cands = (("I3xx", "I3xx", 0.5, ()), ("m3", "m3", 0.2, ()), ("cv", "cv", 0.1, ()),
             ("g", "g", 0.05, ()))
    e = dataclasses.replace(I3XX, explained=0.5, candidates=cands)
    bare = dataclasses.replace(M_BAD, entries=())
    ok = dataclasses.replace(MASS, max_error=1e-12, passed=True)
    d = Diagnosis("mine.toml", "their.toml", ("pinocchio",), 24, Localization((ok,), (bare,), e))
    lines = d.describe().split("\n")
    assert lines[5:8] == [
        "compared quantities (tolerances.toml): 1 of 1 within tolerance",
        "no single cause explains it: M differ(s) at no entry",
        "  best candidates (share of the difference each explains alone, 90% needed): I3xx "
        "50.0%, m3 20.0%, cv 10.0%"]
    assert lines[-1] == "verdict: DIFFERS"
