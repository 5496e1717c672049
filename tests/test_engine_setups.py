"""An engine's setups and run costs (`comparisons.stages.runs`), on engines written here whose
declarations are known: declared setups labelled ``name-suffix`` (the name alone for no
suffix) with their options and settings line; an engine declaring none has one at its
defaults; command-line options replace the declared ones in one setup labelled by the name,
its settings line listing them sorted; the kinds of scenario follow the capabilities unless
declared (inverse only through ``run_inverse``); the costs come from the engine's `Costs`,
a measured scenario time replacing the rate, a case on another model costed as its scenario."""

from __future__ import annotations

import pytest

from comparisons.stages.runs import (EngineSetup, cost, engine_setups, label_of, run_one,
                                     setup_of, setups_for)

ENGINES = '''
from engines.base import Engine
from engines.facts import Costs, RunSetup


class Two(Engine):
    """Two declared setups."""
    name = "two"
    capabilities = frozenset({"mass_matrix", "simulate"})
    run_setups = (RunSetup("fine", (("step", 0.001),), kinds=("inverse", "forward"),
                           settings="step 1 ms"),
                  RunSetup("", (("step", 0.002),), kinds=("forward",)))
    costs = Costs(run_per_second=2.0, short_run=0.3, scenario_runs=(("replay", 9.0),))

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)


class Plain(Engine):
    """No setups, no simulate, inverse runs of its own."""
    name = "plain"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

    def run_inverse(self, scenario):
        raise NotImplementedError


class One(Engine):
    """One setup declaring forward runs only, though it could run inverse ones too."""
    name = "one"
    capabilities = frozenset({"mass_matrix", "simulate"})
    run_setups = (RunSetup(kinds=("forward",)),)

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

    def run_inverse(self, scenario):
        raise NotImplementedError


class DiscOnly(Engine):
    """Models the disc contact alone, and says why in its constructor."""
    name = "disc-only"
    capabilities = frozenset({"mass_matrix", "simulate"})
    contacts = ("disc",)

    def __init__(self, model, step=0.001):
        from engines import CapabilityError
        if model.contact != "disc":
            raise CapabilityError(f"disc-only cannot take the {model.contact}  contact   (step {step})")
        super().__init__(model)


class DiscQuiet(DiscOnly):
    """Models the disc contact alone, and builds on any model without saying so."""
    name = "disc-quiet"

    def __init__(self, model, step=0.001):
        Engine.__init__(self, model)


class Neither(Engine):
    """Terms only: no scenario of either kind."""
    name = "neither"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)
'''


@pytest.fixture(scope="module")
def specs(tmp_path_factory):
    path = tmp_path_factory.mktemp("setups") / "my_engines.py"
    path.write_text(ENGINES, "utf-8")
    return {n: f"{path}:{n}" for n in ("Two", "Plain", "One", "DiscOnly", "DiscQuiet", "Neither")}


def test_label_of_a_name_and_of_a_class_spec():
    assert label_of("pinocchio") == "pinocchio"
    assert label_of("my/engines.py:MyEngine") == "MyEngine"
    assert label_of("pkg.mod:Engine") == "Engine"


def test_declared_setups_are_labelled_by_suffix_with_their_options_and_settings(specs):
    spec = specs["Two"]
    fine, plain = engine_setups(spec)
    assert fine == EngineSetup("Two-fine", spec, (("step", 0.001),), ("inverse", "forward"),
                               "step 1 ms")
    assert plain == EngineSetup("Two", spec, (("step", 0.002),), ("forward",),
                                f"{spec} with its own defaults")
    assert setup_of(spec) == fine                    # the first: where its runs appear


def test_an_engine_declaring_no_setup_has_one_at_its_defaults(specs):
    spec = specs["Plain"]
    assert engine_setups(spec) == [EngineSetup("Plain", spec, (), ("inverse",),
                                               f"{spec} with its own defaults")]
    assert engine_setups(specs["Neither"])[0].kinds == ()


def test_command_line_options_make_one_setup_listing_them_sorted(specs):
    spec = specs["Plain"]
    [s] = engine_setups(spec, {"tol": 1e-9, "build": "tree"})
    assert s == EngineSetup("Plain", spec, (("build", "tree"), ("tol", 1e-9)), ("inverse",),
                            f"{spec} with build = tree, tol = 1e-09")
    [s] = engine_setups(specs["Two"], {"step": 0.005})   # two declared: kinds from capabilities
    assert (s.label, s.options, s.kinds) == ("Two", (("step", 0.005),), ("forward",))
    [s] = engine_setups(specs["One"], {"step": 0.005})   # one declared: its kinds kept
    assert s.kinds == ("forward",)
    assert engine_setups(specs["One"])[0].kinds == ("forward",)


def test_the_reference_runs_both_kinds_and_the_order_of_engines_is_kept(specs):
    setups = setups_for(["reference", specs["Plain"], specs["Two"]],
                        {specs["Two"]: {"step": 0.01}})
    assert [s.label for s in setups] == ["reference", "Plain", "Two"]
    assert setups[0].kinds == ("inverse", "forward")
    assert setups[2].options == (("step", 0.01),)


def test_costs_follow_the_engines_declaration(specs):
    two = setup_of(specs["Two"])
    assert cost(two, "replay") == 9.0                          # measured, declared
    assert cost(two, "replay-on-benchmark") == 9.0             # a case is its scenario
    assert cost(two, "zigzag") == 0.3 and cost(two, "check-on-mine") == 0.3
    assert cost(two, "check-forward") == pytest.approx(2.0 * 6.3)   # 6.3 s simulated
    assert cost(two, "stability-psid5") == pytest.approx(2.0 * 1.2)
    one = setup_of(specs["One"])                               # Costs' defaults: 1 s per s
    assert cost(one, "replay") == pytest.approx(6.3) and cost(one, "zigzag") == 0.8


def test_a_scenario_of_a_kind_the_setup_does_not_run_is_not_run_and_says_why(specs):
    setup = setup_of(specs["One"])                              # forward runs only
    run = run_one(setup, "zigzag")
    assert (run.engine, run.scenario, run.model, run.kind, run.status) == (
        "One", "zigzag", "thesis", "inverse", "not run")
    assert run.message == ("One has no constrained inverse dynamics (run_inverse: the rider's "
                           "torques and the contact forces of a prescribed motion)")


def test_an_engine_without_the_models_contact_is_not_run_with_its_own_reason(specs):
    """The loader refuses the contact before the constructor; the run then asks the
    constructor itself (with the setup's options) for its CapabilityError, else states it."""
    own = run_one(EngineSetup("DiscOnly", specs["DiscOnly"], (("step", 0.002),)), "stability-psid0")
    assert (own.status, own.model) == ("not run", "thesis")
    assert own.message == "CapabilityError: disc-only cannot take the thesis contact (step 0.002)"
    plain = run_one(setup_of(specs["DiscQuiet"]), "stability-psid0")
    assert plain.status == "not run"
    assert plain.message == ("DiscQuiet models the front contact(s) disc, not 'thesis' of model "
                             "'thesis'")
