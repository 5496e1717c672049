"""The linearization check (comparisons/judgments/linear_check.py) held to the parts of its
contract that tests/test_linear_closed_form.py leaves open: a model with drag is checked with
cv = 0 and the note says so in full (the module docstring: "it is checked with cv = 0, as the
stability section linearizes it, and the result says so"), and *any* refusal of
``to_benchmark`` makes the model not applicable with that refusal's reason, "never a failure"
(a reason without the "counterpart: " lead-in is given whole, not an IndexError). Each test
names the planted bugs (mutmut's survivors of the module's first measurement) it fails on.
~0.1 s: no linearization is computed (neither model reaches it).
"""

from __future__ import annotations

import reference_model.benchmark as benchmark_module
from comparisons.judgments.linear_check import linear_benchmark_check
from comparisons.judgments.tolerances import load_tolerances
from reference_model import load_model
from reference_model.params import ParameterError

TOLS = load_tolerances()   # the packaged tolerances.toml, read once


def test_a_model_with_drag_is_checked_without_it_and_the_note_says_so_in_full():
    """The thesis bicycle has drag (cv = 0.8 kg/m in its file) and the thesis contact. The note
    is the module's sentence, exactly, with the model's name and its cv; the drag is gone from
    what is checked: to_benchmark's reason names the contact and not environment.cv (which it
    would list, as one more blocker, for the model with its drag). Planted: the note's text
    wrapped in 'XX' (the neighbouring test reads only its start)."""
    model = load_model("thesis")
    assert model.params.cv == 0.8
    check = linear_benchmark_check(model, TOLS)
    assert check.note == ("thesis has drag (cv = 0.8 kg/m), so no steady upright motion: "
                          "checked with cv = 0, as the stability section linearizes it")
    assert check.reason.startswith("no benchmark counterpart: model.contact = 'thesis'")
    assert "environment.cv" not in check.reason
    assert (check.applicable, check.passed, check.matrices, check.speeds) == (False, None, (), ())


def test_any_refusal_of_to_benchmark_is_not_applicable_with_its_whole_reason(monkeypatch):
    """The docstring: any model without a counterpart is *not applicable* with to_benchmark's
    reason, never a failure. A refusal whose problem has no "counterpart: " lead-in to strip
    (one the check does not know the wording of) is given whole after the check's own "no
    benchmark counterpart: "; the drag-free benchmark needs no note; nothing is compared.
    Planted: the reason taken as the part *after* the lead-in ([+1] for [-1]), which raised
    IndexError on such a refusal instead of reporting it."""
    def refuse(params):
        raise ParameterError("square.toml", "(benchmark export)", "the wheels are square",
                             "make them round")

    monkeypatch.setattr(benchmark_module, "to_benchmark", refuse)
    check = linear_benchmark_check(load_model("benchmark"), TOLS, speeds=(1.0, 4.0))
    assert (check.model, check.reason, check.note, check.speeds_range) == \
        ("benchmark", "no benchmark counterpart: the wheels are square", "", (1.0, 4.0))
    assert (check.applicable, check.passed, check.matrices, check.speeds) == (False, None, (), ())



def test_a_model_named_like_the_lead_in_gets_the_reason_not_its_own_name():
    """A model's name is a free string from its file. Named "no counterpart: x", the thesis
    bicycle (no counterpart: its contact) is refused with to_benchmark's blockers after the
    check's lead-in, exactly as an ordinarily named model is; the name is not cut into the
    reason. Planted (found here, fixed): the reason taken after the *first* "counterpart: ",
    which lies inside the quoted name, gave "no benchmark counterpart: x' has no Meijaard ..."."""
    thesis = load_model("thesis")
    plain = linear_benchmark_check(thesis, TOLS)
    odd = linear_benchmark_check(thesis.with_params(thesis.params.replace(name="no counterpart: x")),
                                 TOLS)
    assert plain.reason.startswith("no benchmark counterpart: model.contact = 'thesis'")
    assert odd.reason == plain.reason
    assert odd.model == "no counterpart: x"
