"""The fmu engine itself (engines/fmu/engine.py) at its edges: the option and file refusals
whole, the terms a mapping names (gravity, D, dD dq, the residual: reached by no other fast
test), batches, torques and scales through the FMI calls, the failure statuses, its
Model-Exchange runs, the linearization's Jacobian-vector products and its clean-up.

Expected values: the reference model's own terms and runs (the FMU is built from the same
generated equations but read here through fmpy, the mapping and the FMI interface: round-off
apart, 1e-12 of the largest entry, as tests/test_fmu.py), central differences of the
reference's functions for the linearization's products, the documented contract (docs/engines.md,
"The fmu engine"; the module's docstrings: a mapped value is thesis = scale * FMU) and the
messages of fmpy, lxml and engines.base themselves. FMUs from tests/fmu_builds.cached_fmu
(cached, as every FMU test; edited copies of them in a temporary folder for an FMU without a
mapping, without Model Exchange, or declaring directional derivatives it lacks). Written from
the survivors of `make mutants` on the module; ~3 s warm.
"""

from __future__ import annotations

import dataclasses
import gc
import re
import shutil
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

from engines.base import CapabilityError, EngineSpecError, UnsupportedModel   # noqa: E402
from engines.fmu.engine import MAPPING_IN_FMU, FmuEngine   # noqa: E402
from engines.reference import ReferenceEngine   # noqa: E402
from fmu_builds import cached_fmu   # noqa: E402
from reference_model import load_model   # noqa: E402
from reference_model.exports.fmu import mapping_text   # noqa: E402
from reference_model.scenarios import get_scenario   # noqa: E402
from reference_model.solvers import consistent_state   # noqa: E402

#: docs/model.md's coordinate order
XC, YC, PHI, THETA, PSI, BETA, GAMMA, EPS = range(8)
TORQUES = (0.3, 1.0, -0.2)


def _close(got, ref, rel=1e-12):
    """Round-off agreement: within ``rel`` of the largest entry of ``ref``."""
    got, ref = np.asarray(got), np.asarray(ref)
    assert got.shape == ref.shape
    return np.max(np.abs(got - ref)) <= rel * max(np.max(np.abs(ref)), 1e-300)


@pytest.fixture(scope="module")
def thesis_fmu(thesis):
    return cached_fmu(thesis)


@pytest.fixture(scope="module")
def engine(thesis, thesis_fmu):
    return FmuEngine(thesis, fmu=str(thesis_fmu))


@pytest.fixture(scope="module")
def states(thesis):
    """Three random consistent states of the thesis bicycle (q, dq stacked: (3, 8) each)."""
    rng = np.random.default_rng(24)
    s = [consistent_state(thesis, rng.normal(size=8) * 0.3, rng.normal(size=8)) for _ in range(3)]
    return np.array([x.q for x in s]), np.array([x.dq for x in s])


@pytest.fixture(scope="module")
def benchmark():
    return load_model("benchmark")


def _edited(src: Path, out: Path, drop=(), xml=None) -> Path:
    """A copy of the FMU ``src`` without the members ``drop`` and with its modelDescription.xml
    passed through ``xml`` (text -> text)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(out, "w") as zout:
        for item in zin.infolist():
            if item.filename in drop:
                continue
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml" and xml is not None:
                data = xml(data.decode("utf-8")).encode("utf-8")
            zout.writestr(item, data)
    return out


def _mapping(tmp_path, model, edit=lambda t: t) -> str:
    path = tmp_path / "map.toml"
    path.write_text(edit(mapping_text(model)), encoding="utf-8")
    return str(path)


# -- the refusals, whole ------------------------------------------------------------------------

def test_the_file_refusals_are_whole_lines(thesis, thesis_fmu, tmp_path):
    """docs/engines.md's fmu options: no FMU, a file that is no zip, a zip without
    modelDescription.xml, an unreadable mapping file (the OS's own reason), and an FMU that
    carries no mapping when none is given: each the whole line with its fix. Planted: any of
    these lines lost or changed (XX-wrapped, upper-cased), strerror `and` exc."""
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis)
    assert str(err.value) == "engine fmu needs its FMU; fix: --engine-option fmu=PATH.fmu"
    missing = tmp_path / "none.fmu"
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(missing))
    assert str(err.value) == (f"engine option fmu={missing}: no such file; fix: give the path of a "
                              ".fmu file")
    zipped = tmp_path / "empty.fmu"
    with zipfile.ZipFile(zipped, "w") as z:
        z.writestr("other.txt", "x")
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(zipped))
    assert str(err.value) == (f"engine option fmu={zipped}: not an FMU (a zip file with a "
                              "modelDescription.xml); fix: give a .fmu file")
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(thesis_fmu), mapping=str(tmp_path / "none.toml"))
    assert str(err.value) == (f"engine option mapping={tmp_path / 'none.toml'}: No such file or "
                              "directory; fix: give a readable mapping .toml file")
    bare = _edited(thesis_fmu, tmp_path / "bare.fmu", drop=(MAPPING_IN_FMU,))
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(bare))
    assert str(err.value) == (f"engine option fmu={bare}: the FMU carries no {MAPPING_IN_FMU}; "
                              "fix: --engine-option mapping=PATH.toml (bicycle-xval export "
                              "--format fmu-mapping writes the template)")


def test_an_fmu_without_its_own_mapping_reads_the_one_given(thesis, thesis_fmu, tmp_path, states):
    """docs/engines.md: ``mapping=PATH.toml`` maps someone else's FMU, which carries none: the
    FMU is read (not refused as 'not an FMU') and agrees with the reference. Planted: the
    in-FMU mapping read whether or not the FMU has one (a KeyError, turned into 'not an FMU')."""
    bare = _edited(thesis_fmu, tmp_path / "bare.fmu", drop=(MAPPING_IN_FMU,))
    e = FmuEngine(thesis, fmu=str(bare), mapping=_mapping(tmp_path, thesis))
    q, dq = states
    assert _close(e.forward_acceleration(q[0], dq[0]), thesis.forward_acceleration(q[0], dq[0]))


def test_the_option_refusals_are_whole_lines(thesis, thesis_fmu):
    """interface and parameters outside their values: the line names the value and the values
    it takes (docs/engines.md). Planted: either line lost or changed; 'me' dropped from the
    accepted interfaces (then interface=me is refused)."""
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(thesis_fmu), interface="ME")
    assert str(err.value) == ("engine option interface=ME: fix: auto (Model Exchange when the "
                              "FMU has it), me or cs (Co-Simulation)")
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(thesis_fmu), parameters="both")
    assert str(err.value) == ("engine option parameters=both: fix: model (set the FMU's mapped "
                              "parameters from the model) or fmu (its own values)")
    assert FmuEngine(thesis, fmu=str(thesis_fmu), interface="me").interface == "me"


def test_a_model_description_that_does_not_read_quotes_lxmls_first_line(thesis, thesis_fmu, tmp_path):
    """A modelDescription.xml with a tag mismatch whose name is 200 characters long: the line
    quotes the first 160 characters of lxml's own message (its wording checked against lxml
    here: 33 characters of words, then the name) and nothing more, with the fix. Planted: the
    line lost, str(None), the second line (there is none), 161 characters, the fix changed."""
    import lxml.etree
    bad = "<fmiModelDescription><" + "b" * 200 + "></c></fmiModelDescription>"
    words = "Opening and ending tag mismatch: "
    with pytest.raises(lxml.etree.XMLSyntaxError) as lx:
        lxml.etree.fromstring(bad.encode())
    assert str(lx.value).startswith(words + "b" * 200 + " ")
    path = _edited(thesis_fmu, tmp_path / "badxml.fmu", xml=lambda t: bad)
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(path))
    assert str(err.value) == (f"engine option fmu={path}: its modelDescription.xml does not read "
                              f"({words}{'b' * (160 - len(words))}); fix: give a valid FMI 2.0 FMU")


def _without_model_exchange(text: str) -> str:
    return re.sub(r"<ModelExchange.*?</ModelExchange>", "", text, flags=re.S)


def test_the_interfaces_an_fmu_lacks_are_named(thesis, thesis_fmu, tmp_path):
    """A Co-Simulation-only FMU (the CS build with its ModelExchange element removed): auto
    picks Co-Simulation (runs only), me is refused naming Model-Exchange; the Model-Exchange
    FMU with cs is refused naming Co-Simulation. Planted: auto always Model Exchange, the
    interface word changed or swapped, the line lost."""
    cs = cached_fmu(thesis, co_simulation=True)
    only = _edited(cs, tmp_path / "cs-only.fmu", xml=_without_model_exchange)
    e = FmuEngine(thesis, fmu=str(only))
    assert e.interface == "cs" and e.capabilities == frozenset({"simulate"})
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(only), interface="me")
    assert str(err.value) == (f"engine option interface=me: the FMU {only} has no Model-Exchange "
                              "interface; fix: interface=auto")
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(thesis_fmu), interface="cs")
    assert str(err.value) == (f"engine option interface=cs: the FMU {thesis_fmu} has no "
                              "Co-Simulation interface; fix: interface=auto")


def test_mapping_refusals_start_with_where_the_mapping_came_from(thesis, thesis_fmu, tmp_path):
    """A mapping file naming a variable the FMU lacks: the engine's line starts with
    ``mapping=PATH`` (mapping.py's ``where``). Planted: where not passed on (None)."""
    path = _mapping(tmp_path, thesis, lambda t: t.replace('theta = "theta"', 'theta = "roll"'))
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(thesis_fmu), mapping=path)
    assert str(err.value).startswith(f"mapping={path}: coordinates.theta names 'roll'")


def test_an_fmu_of_the_other_contact_is_an_unsupported_model(disc, thesis_fmu):
    """The thesis-contact FMU on thesis-disc: a declared limitation (UnsupportedModel,
    docs/engines.md) naming both contacts. Planted: the line lost."""
    with pytest.raises(UnsupportedModel) as err:
        FmuEngine(disc, fmu=str(thesis_fmu))
    assert str(err.value) == ("the FMU models the thesis front contact, the model 'thesis-disc' "
                              "the disc one")


def test_mapped_variables_that_are_no_states_are_refused_for_model_exchange_only(thesis, tmp_path):
    """theta and its rate mapped to the parameters a1, a2 (variables, not continuous states):
    Model Exchange refuses naming both, comma-separated, with the fix; Co-Simulation steps the
    FMU and never sets states, so the same mapping is accepted there. Planted: the check
    dropped, inverted or applied to Co-Simulation, the line lost, the index built for
    Co-Simulation (a ValueError)."""
    cs = cached_fmu(thesis, co_simulation=True)
    path = _mapping(tmp_path, thesis, lambda t: t.replace('theta = "theta"', 'theta = "a1"')
                    .replace('theta = "d_theta"', 'theta = "a2"'))
    with pytest.raises(EngineSpecError) as err:
        FmuEngine(thesis, fmu=str(cs), mapping=path, interface="me")
    assert str(err.value) == (f"mapping={path}: a1, a2 are not continuous states of the FMU; "
                              "fix: map [coordinates] and [rates] to its states")
    assert FmuEngine(thesis, fmu=str(cs), mapping=path, interface="cs").interface == "cs"


# -- capabilities and their refusals ----------------------------------------------------------

def test_capabilities_follow_the_mapped_terms(thesis, thesis_fmu, tmp_path):
    """docs/engines.md: the class's forward_acceleration and simulate, plus the terms the
    mapping names (F and S together: generalized_forces), plus eigenvalues for 16 states;
    Co-Simulation narrows to simulate. Planted: the terms replacing the base set, F and S
    needing a third term, Co-Simulation keeping Model Exchange's set."""
    full = FmuEngine(thesis, fmu=str(thesis_fmu))
    assert full.capabilities == frozenset({"forward_acceleration", "simulate", "eigenvalues",
                                           "mass_matrix", "gravity", "generalized_forces",
                                           "constraint_jacobian", "constraint_bias"})

    def only_f_and_s(text):
        head, rest = text.split("[terms]", 1)
        tail = rest[rest.index("\n\n"):]
        return head + '[terms]\nF = "term.F[{i}]"\nS = "term.S[{i},{j}]"' + tail
    fs = FmuEngine(thesis, fmu=str(thesis_fmu), mapping=_mapping(tmp_path, thesis, only_f_and_s))
    assert fs.capabilities == frozenset({"forward_acceleration", "simulate", "eigenvalues",
                                         "generalized_forces"})
    cs = FmuEngine(thesis, fmu=str(cached_fmu(thesis, co_simulation=True)), interface="cs")
    assert cs.capabilities == frozenset({"simulate"})


def test_what_an_instance_lacks_is_a_capability_error_naming_it(thesis, thesis_fmu, tmp_path):
    """Without [terms] the terms are refused, and through Co-Simulation forward accelerations
    and eigenvalues: engines.base's line naming the call and what the engine provides (in
    CAPABILITIES' order). Planted: the capability's name lost or changed in the refusal;
    eigenvalues computed for a Co-Simulation engine (whose FMU has Model Exchange too)."""
    def no_terms(text):
        return text[:text.index("# optional: outputs holding")] + text[text.index("# optional: outputs of"):]
    e = FmuEngine(thesis, fmu=str(thesis_fmu), mapping=_mapping(tmp_path, thesis, no_terms))
    have = "forward_acceleration, simulate, eigenvalues"
    q = np.zeros(8)
    for call, args in (("mass_matrix", (q,)), ("gravity", (q,)), ("constraint_jacobian", (q,)),
                       ("constraint_bias", (q, q)), ("generalized_forces", (q, q))):
        with pytest.raises(CapabilityError) as err:
            getattr(e, call)(*args)
        assert str(err.value) == f"engine 'fmu' cannot compute {call}; it provides: {have}"
    cs = FmuEngine(thesis, fmu=str(cached_fmu(thesis, co_simulation=True)), interface="cs")
    for call, args in (("forward_acceleration", (q, q)), ("eigenvalues", ([4.0],))):
        with pytest.raises(CapabilityError) as err:
            getattr(cs, call)(*args)
        assert str(err.value) == f"engine 'fmu' cannot compute {call}; it provides: simulate"


# -- terms, batches, torques ------------------------------------------------------------------

def test_the_mapped_terms_are_the_references_for_a_state_and_a_batch(engine, thesis, states):
    """Gravity, D, dD dq, M and the residual outputs (C) at one state and at a batch of three,
    against the reference's terms (round-off, 1e-12 of the largest entry; the residual, ~1e-16
    on a consistent state, to 1e-12 absolute): a single state gives a single term, a batch a
    batch. Planted: a batch answered by its first state; these terms reached by no fast test."""
    q, dq = states
    for one in (0, slice(None)):
        assert _close(engine.gravity(q[one]), thesis.Qgrav(q[one]))
        assert _close(engine.constraint_jacobian(q[one]), thesis.constraint_jacobian(q[one]))
        assert _close(engine.constraint_bias(q[one], dq[one]), thesis.constraint_bias(q[one], dq[one]))
        assert _close(engine.mass_matrix(q[one]), thesis.mass_matrix(q[one]))
        C = np.asarray(engine.constraint_residual(q[one], dq[one]))
        assert C.shape == np.shape(thesis.constraint_residual(q[one], dq[one]))
    # off the constraints the residual is large and still the reference's
    rng = np.random.default_rng(5)
    qq, dd = rng.normal(size=(2, 8)) * 0.3, rng.normal(size=(2, 8))
    assert _close(engine.constraint_residual(qq, dd), thesis.constraint_residual(qq, dd))


def test_generalized_forces_of_a_batch_take_each_states_torques(engine, thesis, states):
    """F + S T with a torque row per state (a (2, 3) array) against the reference's batch:
    each state's own torques. Planted: S @ T for a 2-D T (a shape error, or rows mixed), the
    einsum's operands lost."""
    q, dq = states
    T = np.array([[0.3, 1.0, -0.2], [-0.5, 0.2, 0.7]])
    assert _close(engine.generalized_forces(q[:2], dq[:2], T), thesis.generalized_forces(q[:2], dq[:2], T))


def test_forward_follows_the_reference_contract_for_batches(engine, thesis, states):
    """Model.forward's contract: ddq (n, 8) with a torque row per state, lam zeros (n, 5) (not
    read), status an intc array like the reference's; a single state gives ddq (8,), lam (5,),
    status (1,). Planted: the torques broadcast to the wrong length (a (2, 3) torque array
    refused), status None or int64, lam None or (n, 6), a batch answered by its first row."""
    q, dq = states
    T = np.array([[0.3, 1.0, -0.2], [-0.5, 0.2, 0.7]])
    got = engine.forward(q[:2], dq[:2], T, (0.0, 0.0))
    ref = thesis.forward(q[:2], dq[:2], T, (0.0, 0.0))
    assert _close(got.ddq, ref.ddq, 1e-11)
    assert got.lam.shape == (2, 5) and not np.any(got.lam)
    assert got.status.dtype == ref.status.dtype == np.intc and np.array_equal(got.status, [0, 0])
    one = engine.forward(q[0], dq[0], TORQUES, (0.0, 0.0))
    assert one.ddq.shape == (8,) and one.lam.shape == (5,) and np.array_equal(one.status, [0])


def test_a_failed_fmi_call_is_status_one_and_forward_acceleration_refuses(engine, states):
    """The FMU refuses a non-finite state (fmi2Error, which fmpy raises): that row's ddq is
    zeros (8,) with status 1, the others computed; forward_acceleration raises ArithmeticError
    counting the failed states. Planted: the zeros' length, the status 1 -> 2, the refusal lost
    or its count."""
    q, dq = states
    bad = q.copy()
    bad[[0, 2], THETA] = np.nan
    got = engine.forward(bad, dq, TORQUES, (0.0, 0.0))
    assert np.array_equal(got.status, [1, 0, 1]) and got.ddq.shape == (3, 8)
    assert not np.any(got.ddq[[0, 2]]) and np.any(got.ddq[1])
    with pytest.raises(ArithmeticError) as err:
        engine.forward_acceleration(bad, dq)
    assert str(err.value) == "the FMU's derivatives failed (fmi2GetDerivatives) at 2 state(s)"


def test_scales_map_fmu_units_to_the_thesis(thesis, thesis_fmu, tmp_path, states):
    """docs/engines.md: thesis value (SI) = scale * FMU value. theta and its rate mapped with
    scale 2, Mdir with 4 and the parameter m3 with 0.5: the engine at (q, dq, T) is the SI FMU
    (the reference with m3 / 0.5 = 2 m3) at theta / 2, dtheta / 2, Mdir / 4, with theta's
    acceleration read back times 2; the linearization's products J ds and dD . v (by the FMU's
    directional derivatives) are those of that map, S f(x / S) and D(q / S), against
    fourth-order central differences of the reference (1e-9). Planted: the states, torques,
    accelerations or directional seeds multiplied where they divide (or the reverse)."""
    def scaled(t):
        return (t.replace('theta = "theta"', 'theta = {name = "theta", scale = 2.0}')
                .replace('theta = "d_theta"', 'theta = {name = "d_theta", scale = 2.0}')
                .replace('Mdir = "Mdir"', 'Mdir = {name = "Mdir", scale = 4.0}')
                .replace('m3 = "m3"', 'm3 = {name = "m3", scale = 0.5}'))
    e = FmuEngine(thesis, fmu=str(thesis_fmu), mapping=_mapping(tmp_path, thesis, scaled))
    heavy = thesis.with_params(thesis.params.replace(m3=2 * thesis.params.m3))
    q, dq = states
    S = np.ones(8)
    S[THETA] = 2.0
    T = np.array([0.8, 1.0, -0.2])
    want = heavy.forward_acceleration(q[0] / S, dq[0] / S, T / [4.0, 1.0, 1.0]) * S
    assert _close(e.forward_acceleration(q[0], dq[0], T), want, 1e-11)
    # the linearization's products in thesis units: f_thesis(x) = S2 f(x / S2), and D at q / S
    S2 = np.concatenate([S, S])

    def f(x):
        y = x / S2
        return np.concatenate([y[8:], heavy.forward_acceleration(y[:8], y[8:])]) * S2
    ds = np.random.default_rng(4).normal(size=16)
    x = np.concatenate([q[0], dq[0]])
    assert _close(e._jvp(q[0], dq[0], ds), _fd(f, x, ds), 1e-9)
    v = ds[8:]
    assert _close(e._along(q[0], v), _fd(lambda y: heavy.constraint_jacobian(y / S), q[0], v), 1e-9)


# -- runs ---------------------------------------------------------------------------------------

def test_a_model_exchange_run_is_the_references(engine, thesis):
    """stability-psid5 with constant torques and a fall limit of 0.2 rad (an option passed on;
    the lean starts at pi/16 = 0.196 rad and grows): the reference's DOP853 loop on the FMU's
    right-hand side at the scenario's Baumgarte a1, a2 follows the reference's own run to the
    same fall (same solver, derivatives equal to round-off: bounded by 1e-9 rad/m and 1e-8
    rad/s, and the fall time to 1e-9 s); T the scenario's torques, C the FMU's residual outputs
    (the thesis's constraints to round-off, 1e-12 m and m/s). Planted: the run's model, its
    scenario, its options or its torques lost; none of _FmuDynamics was reached before."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 11), torques=TORQUES)
    got = engine.simulate(sc, fall_limit=0.2)
    ref = ReferenceEngine(thesis).simulate(sc, fall_limit=0.2)
    assert got.status == ref.status == "fell" and abs(got.t_end - ref.t_end) < 1e-9
    assert np.array_equal(got.t[:-1], ref.t[:-1]) and got.t.size == ref.t.size == 8
    assert np.max(np.abs(got.q - ref.q)) < 1e-9 and np.max(np.abs(got.dq - ref.dq)) < 1e-8
    assert np.array_equal(got.T, np.tile(TORQUES, (8, 1)))
    assert np.max(np.abs(got.C - thesis.constraint_residual(got.q, got.dq))) < 1e-12


# -- the linearization's products ---------------------------------------------------------------

def _fd(f, x, d, h=1e-4):
    """Fourth-order central differences of f along d at x: error ~h^4 |f^(5)| ~ 1e-16 and
    round-off ~1e-16 |f| / h ~ 1e-12 of f's size."""
    return (8 * (f(x + h * d) - f(x - h * d)) - (f(x + 2 * h * d) - f(x - 2 * h * d))) / (12 * h)


def test_jacobian_vector_products_are_the_references_at_zero_torque(engine, thesis, states):
    """_jvp's docstring: J_f ds at a1 = a2 = 0 (exact accelerations) with no torque, even
    right after a call with torques. Against fourth-order central differences of the
    reference's (dq, ddq) (1e-9 of the product's size). Planted: the torques not reset before
    the directional derivatives (then the product is at the last call's 10 N m)."""
    q, dq = states
    engine.forward_acceleration(q[1], dq[1], (10.0, 10.0, 10.0))
    ds = np.random.default_rng(3).normal(size=16)

    def f(s):
        return np.concatenate([s[8:], thesis.forward_acceleration(s[:8], s[8:])])
    want = _fd(f, np.concatenate([q[0], dq[0]]), ds)
    assert _close(engine._jvp(q[0], dq[0], ds), want, 1e-9)


@pytest.fixture(scope="module")
def fd_engine(benchmark):
    return FmuEngine(benchmark, fmu=str(cached_fmu(benchmark, directional_derivatives=False)))


@pytest.mark.parametrize("size", [1e-6, 1e4])
def test_central_differences_scale_their_step_to_the_direction(fd_engine, benchmark, size):
    """Without directional derivatives, J ds and dD . dq_dir are central differences with a
    step FD_STEP = 1e-6 along the direction scaled to largest entry 1 (the module's
    docstring): a direction of size 1e-6 or 1e4 gives the same relative accuracy (~1e-9:
    round-off 1e-16 / 1e-6 times the KKT solve's amplification). Against fourth-order central
    differences of the reference; bounded by 1e-6. Planted: the step multiplied by the size
    (a step of 1e-2 x 1e4), or not scaled below size 1 (a step of 1e-12 in the state)."""
    rng = np.random.default_rng(8)
    s = consistent_state(benchmark, rng.normal(size=8) * 0.2, rng.normal(size=8))
    ds = rng.uniform(0.5, 1.0, size=16) * size

    def f(x):
        return np.concatenate([x[8:], benchmark.forward_acceleration(x[:8], x[8:])])
    x = np.concatenate([s.q, s.dq])
    assert _close(fd_engine._jvp(s.q, s.dq, ds), _fd(f, x, ds / size) * size, 1e-6)
    v = ds[:8]
    assert _close(fd_engine._along(s.q, v),
                  _fd(benchmark.constraint_jacobian, s.q, v / size) * size, 1e-6)


def test_eigenvalues_after_a_torqued_call_are_at_zero_torque(benchmark, tmp_path):
    """The linearization is about torque-free upright running whatever was asked before: after
    a forward acceleration at 5 N m, the eigenvalues at 5 m/s by central differences, on a
    mapping without [terms] and [residual] (so no FMU output call resets the torques in
    between), match the reference's linearization (1e-9 of the largest, as
    tests/test_fmu_linear.py). A state the FMU refuses near upright is one ArithmeticError line.
    Planted: the derivatives' torques not reset (then the upright state is not steady and it is
    refused); the refusal's line lost or changed."""
    from reference_model import linearize

    def states_only(text):
        return text[:text.index("# optional: outputs holding")] + text[text.index("# optional: the FMU parameters"):]
    e = FmuEngine(benchmark, fmu=str(cached_fmu(benchmark, directional_derivatives=False)),
                  mapping=_mapping(tmp_path, benchmark, states_only))
    assert not e.directional and e.mapping.residual is None
    e.forward_acceleration(np.zeros(8), np.zeros(8), (5.0, 5.0, 5.0))
    got = e.eigenvalues([5.0])
    ref = linearize.eigenvalues(benchmark, [5.0])
    assert np.max(np.abs(got - ref)) <= 1e-9 * np.max(np.abs(ref))
    with pytest.raises(ArithmeticError) as err:
        e._rates(np.full(16, np.nan))
    assert str(err.value) == "the FMU's derivatives failed (fmi2GetDerivatives) near upright"


def test_the_fmus_own_d_is_used_and_differentiated_exactly(thesis, thesis_fmu, states):
    """With parameters=fmu the FMU keeps the thesis's geometry while the engine's model has a
    front wheel 5 cm larger: D and dD . v then are the FMU's (the thesis's: round-off), not the
    model's, and dD . v is the FMU's directional derivative (exact), not central differences:
    against fourth-order central differences of the thesis's D at h = 3e-4 (truncation and
    round-off ~1e-13 of the largest entry, measured 2e-13), bounded by 2e-12, where D's own
    central differences at FD_STEP err by ~1e-10 (measured 6.8e-11). Planted: D taken from the
    model though mapped; dD . v by central differences though the FMU has directional
    derivatives."""
    other = thesis.with_params(thesis.params.replace(R_front=thesis.params.R_front + 0.05))
    e = FmuEngine(other, fmu=str(thesis_fmu), parameters="fmu")
    q, _ = states
    D = thesis.constraint_jacobian(q[0])
    assert _close(e._jacobian(q[0]), D)
    assert not _close(e._jacobian(q[0]), other.constraint_jacobian(q[0]), 1e-3)
    v = np.random.default_rng(9).normal(size=8)
    assert _close(e._along(q[0], v), _fd(thesis.constraint_jacobian, q[0], v, h=3e-4), 2e-12)


def test_a_directional_derivative_the_fmu_refuses_is_one_line(benchmark, tmp_path):
    """An FMU that declares providesDirectionalDerivative but refuses the call (the central-
    differences build with the flag set in its description): eigenvalues raise one
    ArithmeticError quoting fmpy's own message for that refusal (got here from fmpy). Planted:
    the line lost, its quote or its words changed."""
    from fmpy.fmi1 import FMICallException
    src = cached_fmu(benchmark, directional_derivatives=False)
    liar = _edited(src, tmp_path / "liar.fmu", xml=lambda t: t.replace(
        'providesDirectionalDerivative="false"', 'providesDirectionalDerivative="true"'))
    e = FmuEngine(benchmark, fmu=str(liar))
    assert e.directional
    inst = e._instance(None)
    with pytest.raises(FMICallException) as fmpy_err:
        inst.fmu.getDirectionalDerivative([0], [0], [1.0])
    with pytest.raises(ArithmeticError) as err:
        e.eigenvalues([4.0])
    assert str(err.value) == ("the FMU's fmi2GetDirectionalDerivative failed near upright "
                              f"({str(fmpy_err.value).splitlines()[0][:120]}), though it declares "
                              "providesDirectionalDerivative")


# -- clean-up -----------------------------------------------------------------------------------

def test_a_deleted_engine_frees_its_instances_and_its_folder(thesis, thesis_fmu, monkeypatch):
    """Deleting the engine terminates and frees each FMU instance (two here: two Baumgarte
    settings) and removes the extracted folder; a folder already gone is no error (nothing
    reaches sys.unraisablehook). Planted: the instances or the folder looked up under another
    name or on None, rmtree without its folder or raising on a missing one."""
    raised = []
    monkeypatch.setattr(sys, "unraisablehook", raised.append)
    calls = []
    e = FmuEngine(thesis, fmu=str(thesis_fmu))
    q = np.zeros(8)
    e.forward(q, q, TORQUES, (0.0, 0.0))
    e.forward(q, q, TORQUES, (10.0, 10.0))
    for key, inst in e._instances.items():
        for name in ("terminate", "freeInstance"):
            real = getattr(inst.fmu, name)
            setattr(inst.fmu, name, lambda real=real, name=name, key=key: (calls.append((key, name)), real())[1])
    folder = Path(e._unzipped)
    assert folder.is_dir()
    del e
    gc.collect()
    assert not folder.exists() and not raised
    assert sorted(calls) == [((0.0, 0.0), "freeInstance"), ((0.0, 0.0), "terminate"),
                             ((10.0, 10.0), "freeInstance"), ((10.0, 10.0), "terminate")]
    e = FmuEngine(thesis, fmu=str(thesis_fmu))
    shutil.rmtree(e._unzipped)
    del e
    gc.collect()
    assert not raised


def test_a_run_off_the_constraints_decays_by_the_scenarios_baumgarte_law(engine, thesis, monkeypatch):
    """A start off the constraints (the projected state with the rear contact's x rate 1e-2 m/s
    too large: the runs module's `initial_state` replaced so) shows which a1, a2 the FMU
    integrates with: Baumgarte's law makes each contact velocity decay as
    C_i' = -(2 a1 + a2^2) C_i (reference_model Model.forward), here a1 = 2, a2 = 6: exp(-40 t),
    solved in closed form; DOP853 at rtol 1e-10 follows it to ~1e-12 m/s, bounded by 1e-9.
    Planted: the scenario's a1, a2 not passed to the FMU (then the exact accelerations keep
    the velocity error constant)."""
    from types import SimpleNamespace

    from reference_model.scenarios import initial_state, runs
    sc = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 6),
                             baumgarte=(2.0, 6.0))
    start = initial_state(thesis, sc)
    q0, dq0 = start.q.copy(), start.dq.copy()
    dq0[XC] += 1e-2
    monkeypatch.setattr(runs, "initial_state", lambda model, scenario: SimpleNamespace(
        q=q0, dq=dq0, describe=lambda: "", beta_correction=0.0))
    got = engine.simulate(sc)
    C0 = thesis.constraint_residual(q0, dq0)
    assert abs(C0[1]) > 5e-3
    assert np.max(np.abs(got.C[:, 1:] - C0[1:] * np.exp(-40.0 * sc.t)[:, None])) < 1e-9
