"""The base class every engine subclasses (engines/base.py, docs/engines.md): an engine keeps
the model it was built for, names itself with its class, model and contact, supports exactly
the capabilities it declares, and each capability it does not provide raises CapabilityError
(a NotImplementedError) in one line naming the engine, what was asked and what it provides, in
CAPABILITIES' order ("nothing" for an engine that declares none). The messages are what the
harness prints for a capability an engine lacks. Each test names the planted bugs (mutmut's
mutants of the base class, which no fast test reached) it fails on. ~0.1 s."""

from __future__ import annotations

import pytest

from engines.base import CAPABILITIES, CapabilityError, Engine
from reference_model import load_model

CALLS = {
    "mass_matrix": lambda e: e.mass_matrix([0.0] * 8),
    "inverse_dynamics": lambda e: e.inverse_dynamics([0.0] * 8, [0.0] * 8, [0.0] * 8),
    "gravity": lambda e: e.gravity([0.0] * 8),
    "generalized_forces": lambda e: e.generalized_forces([0.0] * 8, [0.0] * 8),
    "constraint_jacobian": lambda e: e.constraint_jacobian([0.0] * 8),
    "constraint_bias": lambda e: e.constraint_bias([0.0] * 8, [0.0] * 8),
    "forward_acceleration": lambda e: e.forward_acceleration([0.0] * 8, [0.0] * 8),
    "simulate": lambda e: e.simulate(None),
    "eigenvalues": lambda e: e.eigenvalues([5.0]),
}


class Partial(Engine):
    name = "partial"
    # declared out of CAPABILITIES' order: the message lists them in that order
    capabilities = frozenset({"gravity", "mass_matrix"})


class Bare(Engine):
    name = "bare"
    capabilities = frozenset()


@pytest.fixture(scope="module")
def disc():
    return load_model("thesis-disc")


def test_every_capability_is_one_of_the_calls_checked():
    assert sorted(CALLS) == sorted(CAPABILITIES)


@pytest.mark.parametrize("capability", [c for c in CAPABILITIES if c not in Partial.capabilities])
def test_a_capability_not_provided_names_the_engine_what_was_asked_and_what_it_has(disc, capability):
    """Planted: the capability's name left out or replaced in the call to the refusal (None,
    'XX...XX', upper case), the list joined otherwise, the provided capabilities listed in the
    declared set's order."""
    with pytest.raises(CapabilityError) as err:
        CALLS[capability](Partial(disc))
    assert str(err.value) == (f"engine 'partial' cannot compute {capability}; it provides: "
                              "mass_matrix, gravity")
    assert isinstance(err.value, NotImplementedError)


def test_an_engine_providing_nothing_says_so(disc):
    """Every capability, gravity included (which the partial engine provides). Planted: the
    word 'nothing' changed or dropped, gravity's refusal naming another capability."""
    for capability, call in CALLS.items():
        with pytest.raises(CapabilityError) as err:
            call(Bare(disc))
        assert str(err.value) == f"engine 'bare' cannot compute {capability}; it provides: nothing"


def test_an_engine_keeps_its_model_names_itself_and_supports_what_it_declares(disc):
    """Planted: the model not stored (None), the repr's class, model or contact changed, the
    support test inverted."""
    e = Partial(disc)
    assert e.model is disc
    assert repr(e) == "Partial(model='thesis-disc', contact='disc')"
    assert [c for c in CAPABILITIES if e.supports(c)] == ["mass_matrix", "gravity"]
    assert not Bare(disc).supports("mass_matrix")
