"""The SymBRiM engine's edges (engines/symbrim/engine.py, engines/symbrim/parameters.py), issue
24: the generated code's parameter vector with and without a front-tyre crown, which generated
variant a crown radius asks for, the parameter route an engine reports, the refusal of the
thesis's rim contact, and that a bicycle with Table 1 values gets BicycleParameters' own
numbers (not the project's map, which agrees with them only to rounding).

Expected values: the published benchmark (Meijaard et al. 2007, Table 1, as DynamicistToolKit
ships it, `dtk.bicycle.benchmark_parameters`) through BicycleParameters' own conversion called
here; the crown's geometry from the engine's and README's contract (a torus of major radius
R_front - c and crown c holds the upright hub at R_front); the variant from the engine's
docstring (0: the knife-edge disc, > 0: SymBRiM's ToroidalWheel); the general bicycle's wheel
moments from its own parameters. Each test names the planted bugs (mutmut's survivors) it was
seen failing on.

Cost: the knife-edge engines from the disk cache (~0.1 s each, module fixtures; the cold
derivation is `SymbrimEngine.prepare`'s, as in tests/test_symbrim.py). No test here builds the
toroidal variant (~65 s cold): where a crown is asked for, the loader is replaced by one that
records which variant was asked for (the toroidal equations themselves are
tests/test_symbrim.py's slow tests).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("symbrim")
pytest.importorskip("bicycleparameters")

from comparisons.conformance.models import conformance_model  # noqa: E402
from engines import CapabilityError  # noqa: E402
from engines.kane.names import MOORE_PARAMETERS  # noqa: E402
from engines.symbrim import SymbrimEngine, codegen  # noqa: E402
from engines.symbrim.engine import symbrim_parameters  # noqa: E402
from engines.symbrim.parameters import (BICYCLEPARAMETERS_ROUTE, moore_parameters,  # noqa: E402
                                        parameter_route)

RF = MOORE_PARAMETERS.index("rf")
#: Moore's names (the generated code's) -> BicycleParameters' Moore2012 names, written here from
#: Moore (2012)'s notation: wheels D (rear) and F (front), frame C, fork E; tensor entries 11,
#: 22, 33, 31 are xx, yy, zz, xz in Moore's body frames (not the module's MOORE2012_NAMES)
MOORE2012 = {"rr": "rr", "rf": "rf", "d1": "d1", "d2": "d2", "d3": "d3", "l1": "l1",
             "l2": "l2", "l3": "l3", "l4": "l4", "mc": "mc", "md": "md", "me": "me", "mf": "mf",
             "g": "g"}
MOORE2012.update({f"I{body}{axes}": f"i{body.lower()}{num}"
                  for body in "CDEF" for axes, num in (("xx", "11"), ("yy", "22"),
                                                        ("zz", "33"), ("xz", "31"))
                  if not (body in "DF" and axes == "xz")})


@pytest.fixture(scope="module")
def benchmark():
    return conformance_model("benchmark")


@pytest.fixture(scope="module")
def engines(benchmark):
    """The knife-edge engine on the benchmark (Table 1 values) and on the conformance suite's
    general bicycle (none), built once."""
    return {"benchmark": SymbrimEngine(benchmark),
            "general-disc": SymbrimEngine(conformance_model("general-disc"))}


@pytest.fixture
def asked(monkeypatch):
    """Replaces the generated-code loader by one that records the ``front_crown`` each engine
    asks for: the knife-edge module (cached) for a false one, a stand-in for a true one (the
    toroidal derivation is ~65 s cold, and only which variant is asked for is checked)."""
    calls: list = []
    real = codegen.load

    def load(front_crown=False):
        calls.append(front_crown)
        return object() if front_crown else real(False)

    monkeypatch.setattr(codegen, "load", load)
    return calls


# -- the parameter vector: Moore's, then the crown radius ---------------------------------

def test_without_a_crown_the_vector_is_moores_parameters_and_a_zero_crown(benchmark):
    """The default (no ``crown_radius``): Moore's parameters unchanged, rf = R_front (0.35 m,
    Table 1's rF: the knife-edge disc's radius), then a crown of exactly 0. Expected: Moore's
    parameters (`moore_parameters`, checked against BicycleParameters below) and the
    benchmark's R_front. Exact: nothing is subtracted from rf but 0.
    Fails when the default crown is not 0 (a 1 m default: rf = -0.65 m, a crown of 1 m)."""
    p = symbrim_parameters(benchmark.params)
    assert p.shape == (len(MOORE_PARAMETERS) + 1,)
    assert p[RF] == benchmark.params.R_front == 0.35
    assert p[-1] == 0.0
    assert np.array_equal(p[:-1], moore_parameters(benchmark.params))


@pytest.mark.parametrize("c", (0.005, 0.03))
def test_a_crown_makes_rf_the_torus_major_radius(benchmark, c):
    """With a crown c the front wheel is a torus of major radius R_front - c (engine docstring,
    README: so that the upright hub stands at R_front, the reference's): rf = R_front - c, the
    crown c last, every other Moore parameter unchanged. c: the crown study's smallest and
    largest values (5 and 30 mm). Tolerance 1e-15 m: one subtraction's rounding at 0.35 m.
    Fails when the crown is added to rf (a hub 2c too high) or not passed on."""
    p = symbrim_parameters(benchmark.params, c)
    base = moore_parameters(benchmark.params)
    assert abs(p[RF] - (benchmark.params.R_front - c)) < 1e-15
    assert p[-1] == c
    others = [k for k in range(len(MOORE_PARAMETERS)) if k != RF]
    assert np.array_equal(p[others], base[others])


@pytest.mark.parametrize("c, toroidal", ((0.0, False), (0.005, True), (0.03, True)))
def test_the_engine_asks_for_the_variant_its_crown_needs_and_passes_the_crown(benchmark, asked,
                                                                              c, toroidal):
    """``crown_radius`` 0 is the knife-edge disc, > 0 SymBRiM's ToroidalWheel (engine
    docstring): the engine asks the loader for that variant, and its parameter vector carries
    the crown (rf = R_front - c, the crown last). c: 0 and the crown study's smallest and
    largest values, all under 1 m. Tolerance as above (1e-15 m).
    Fails when the crown is not passed to the parameter vector (a torus evaluated at rf =
    R_front and crown 0), when the variant is chosen by crown >= 0 (the default engine would
    load, and on a new machine derive, the toroidal variant `prepare` did not warm), by
    crown > 1 m (a 3 cm crown evaluated by the knife-edge equations, which ignore it), or
    when no variant is given."""
    eng = SymbrimEngine(benchmark, crown_radius=c)
    assert len(asked) == 1 and bool(asked[0]) is toroidal and asked[0] in (True, False)
    assert eng.crown_radius == c and eng.p[-1] == c
    assert abs(eng.p[RF] - (benchmark.params.R_front - c)) < 1e-15


def test_the_default_engine_runs_on_the_code_prepare_warmed(benchmark):
    """`SymbrimEngine.prepare` derives (or loads) the knife-edge variant once before workers
    fork; an engine at the default crown must use exactly that module (the loader keeps one
    per variant in the process), not another variant that a worker would derive cold.
    Fails when crown 0 selects the toroidal variant (front_crown = crown >= 0) or no
    variant."""
    SymbrimEngine.prepare()
    assert SymbrimEngine(benchmark).code is codegen.load(front_crown=False)


# -- the parameter route ------------------------------------------------------------------

def test_the_engine_reports_its_parameter_route(engines):
    """The engine's ``parameter_route`` (engine docstring, README: "the engine's
    `parameter_route` says so") names BicycleParameters' conversion on the benchmark, which
    has Table 1 values, and the project's own on the general bicycle, which has none.
    Fails when the engine does not set it (None)."""
    assert engines["benchmark"].parameter_route == BICYCLEPARAMETERS_ROUTE
    assert engines["general-disc"].parameter_route.startswith("the project's own conversion")


def test_the_route_without_a_table1_counterpart_names_the_wheel_moments_on_one_line():
    """The general bicycle's wheels have Izz != Ixx (rear 0.125 against 0.1, front 0.115
    against 0.085 kg m^2: its own parameters), which Table 1's axisymmetric wheels cannot hold:
    the route says the project's conversion is taken and why, naming both moments of both
    wheels with their values, on one line with single spaces (a report's line).
    Fails when the reason is lost (the route says '(None)') or its words are run together
    with other text."""
    p = conformance_model("general-disc").params
    route = parameter_route(p)
    assert route.startswith("the project's own conversion: no Table 1 counterpart (")
    assert route.endswith(")") and "\n" not in route and "  " not in route
    assert f"inertia.I2zz = {p.I2zz} differs from inertia.I2xx = {p.I2xx}" in route
    assert f"inertia.I5zz = {p.I5zz} differs from inertia.I5xx = {p.I5xx}" in route


def test_a_table1_bicycle_gets_bicycleparameters_own_numbers_bit_for_bit(benchmark,
                                                                       monkeypatch):
    """The benchmark's Moore parameters are BicycleParameters' own: Meijaard et al.'s Table 1
    as DynamicistToolKit ships it (`dtk.bicycle.benchmark_parameters`, the same numbers as the
    model's Table 1 values) through ``Meijaard2007ParameterSet.to_parameterization('Moore2012')``
    called here, read with this file's own name map; cv the model's (0). Exact: the same
    numbers through the same function are the same bits, while the project's own map (an
    independent formulation) differs from them in 10 of the 29 entries by up to 9e-16, so only
    exact equality tells the two routes apart. The project's map is also made to fail here: a
    Table 1 bicycle must not reach it.
    Fails when a bicycle with Table 1 values takes the project's conversion (its table not
    consulted)."""
    from bicycleparameters.parameter_sets import Meijaard2007ParameterSet
    from dtk.bicycle import benchmark_parameters

    import engines.symbrim.parameters as route_module

    table = {k: float(v) for k, v in benchmark_parameters().items() if k != "lambda"}
    table["v"] = 0.0
    theirs = Meijaard2007ParameterSet(table, True).to_parameterization("Moore2012").parameters
    expected = np.array([0.0 if k == "cv" else float(theirs[MOORE2012[k]])
                         for k in MOORE_PARAMETERS])
    assert benchmark.params.cv == 0.0

    def projects(params):
        raise AssertionError("a Table 1 bicycle reached the project's own conversion")

    monkeypatch.setattr(route_module, "project_moore_parameters", projects)
    got = moore_parameters(benchmark.params)
    assert np.array_equal(got, expected), [
        (k, g, e) for k, g, e in zip(MOORE_PARAMETERS, got, expected) if g != e]


# -- the refusal ---------------------------------------------------------------------------

def test_the_thesis_contact_is_refused_with_the_reason_and_the_fix(thesis):
    """A user who asks SymBRiM for the thesis's rim contact reads one sentence: the engine,
    the contact asked for, why (SymBRiM's knife edge touches at the disc's lowest point, the
    thesis's at its rim point along the fork's -z; module docstring) and the fix (a
    disc-contact model, named). Stated exactly: it is the whole of what the user is told.
    Fails when the reason or the fix is garbled or dropped."""
    with pytest.raises(CapabilityError) as info:
        SymbrimEngine(thesis)
    assert str(info.value) == (
        "engine 'symbrim' cannot use the front contact 'thesis': SymBRiM's knife-edge wheel "
        "touches the ground at the disc's lowest point, not at the thesis's rim point along "
        "the fork's -z; use a disc-contact model (e.g. thesis-disc)")
