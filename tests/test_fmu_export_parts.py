"""The FMU export's own pieces (reference_model/exports/fmu.py), each against the FMI 2.0
standard, the docs or the reference model itself rather than the export's output: the FMI
headers' and the C compiler's lookup and their one-line errors, the platform check, the
compile step's error line (a stand-in compiler script that fails as gcc does, with non-UTF-8
bytes), modelDescription.xml parsed with xml.etree (value references, causality / variability
/ initial, units and their SI base units, the derivatives' states, the ModelStructure's
indices and dependencies, no character data outside attributes), the GUID (FMI 2.0's
8-4-4-4-12 form, the same in the XML and the compiled wrapper, a hash of what the FMU holds),
the zip's layout (modelDescription.xml at the root, binaries/linux64/<modelIdentifier>.so,
sources/ that compile on their own), the wrapper shipped in sources/ (the template with each
@FIELD@ filled in), the binary's own values (fmpy instances: start values, derivatives
against the reference's `forward`, which interfaces it offers), the mapping template, and the
file writing (a temporary build folder that is removed, the FMU written atomically, never into
a folder that does not exist).

Two FMUs are built per module (`write_fmu`): the thesis with the defaults (Model Exchange,
directional derivatives; the binary comes from the code cache's fmu-binaries/, as the other
FMU tests build the same sources) and the thesis with Co-Simulation, no directional
derivatives and Baumgarte a1 = 2.5, a2 = 6 (one gcc run of ~2 s on a cold cache, then cached).
The GUID and file-writing tests replace the compile step with a stand-in that writes a
placeholder binary (~0.05 s an export). The file takes ~1.2 s with a warm cache (measured).

Each test names the planted bugs it was seen failing on (the export's surviving mutants of
`make mutants`, applied one at a time).
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
import tomllib
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

from engines.fmu.mapping import parse_mapping   # noqa: E402
from fmu_builds import cached_fmu   # noqa: E402
from reference_model.exports import fmu as fmu_export   # noqa: E402
from reference_model.exports.fmu import FmuExportError   # noqa: E402
from reference_model.parameters.schema import (PARAMETER_DESCRIPTIONS,   # noqa: E402
                                               PARAMETER_NAMES, PARAMETER_UNITS)

#: docs/model.md's coordinate order, the torques and the five constraints (docs/engines.md)
COORDS = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")
TORQUES = ("Mdir", "Mped", "Mvue")
RESIDUAL = ("rD_z", "vC_x", "vC_y", "vD_x", "vD_y")
#: the thesis's terms and their shapes (docs/engines.md, "The mapping file": M 8x8, F 8,
#: S 8x3, Qgrav 8, D 5x8, dD dq 5; 0 columns: a vector)
TERMS = (("M", 8, 8), ("F", 8, 0), ("S", 8, 3), ("Qgrav", 8, 0), ("D", 5, 8), ("dDdq", 5, 0))
#: FMI 2.0 unit names (Unit name="...") of the parameter schema's units
FMI_UNIT = {"m": "m", "kg": "kg", "kg*m^2": "kg.m2", "m/s^2": "m/s2", "kg/m": "kg/m"}
#: each unit's exponents of the SI base units (FMI 2.0 BaseUnit), by dimensional analysis
#: (N = kg m s^-2; the radian is FMI's own base unit "rad")
SI = {"m": {"m": 1}, "rad": {"rad": 1}, "m/s": {"m": 1, "s": -1}, "rad/s": {"rad": 1, "s": -1},
      "m/s2": {"m": 1, "s": -2}, "rad/s2": {"rad": 1, "s": -2}, "N.m": {"kg": 1, "m": 2, "s": -2},
      "N": {"kg": 1, "m": 1, "s": -2}, "kg": {"kg": 1}, "kg.m2": {"kg": 1, "m": 2},
      "kg/m": {"kg": 1, "m": -1}, "1/s": {"s": -1}}
#: the Co-Simulation FMU's Baumgarte parameters: distinct, so a1 and a2 cannot be swapped unseen
CS_BAUMGARTE = (2.5, 6.0)
#: FMI 2.0 section 2.2.1: guid "{8-4-4-4-12 hex digits}"
GUID = re.compile(r"^\{[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}\}$")
SO = f"binaries/linux64/{fmu_export.MODEL_IDENTIFIER}.so"


# -- the two FMUs and their parts -----------------------------------------------------------

class Built:
    """An exported FMU: its path, zip entries, parsed modelDescription.xml and variables."""

    def __init__(self, path: Path, baumgarte):
        self.path, self.baumgarte = path, baumgarte
        with zipfile.ZipFile(path) as z:
            self.infos = z.infolist()
            self.files = {i.filename: z.read(i) for i in self.infos}
        self.xml = self.files["modelDescription.xml"].decode("utf-8")
        self.root = ET.fromstring(self.xml)
        self.vars = self.root.find("ModelVariables").findall("ScalarVariable")
        #: FMI 2.0 indices: 1-based positions in ModelVariables
        self.index = {v.get("name"): i + 1 for i, v in enumerate(self.vars)}

    def var(self, name):
        return self.vars[self.index[name] - 1]

    def start(self, name):
        return float(self.var(name).find("Real").get("start"))


@pytest.fixture(scope="module")
def built(thesis, tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    me = cached_fmu(thesis)             # the defaults: the FMU the other FMU tests share
    cs = fmu_export.write_fmu(thesis, folder / "thesis-cs.fmu", CS_BAUMGARTE, co_simulation=True,
                              directional_derivatives=False)
    return {"me": Built(me, (10.0, 10.0)), "cs": Built(cs, CS_BAUMGARTE)}


def _instance(b: Built, folder: Path, cls_name: str = "FMU2Model"):
    from fmpy import extract
    from fmpy import fmi2
    unzipped = extract(str(b.path), unzipdir=str(folder))
    fmu = getattr(fmi2, cls_name)(guid=b.root.get("guid"), unzipDirectory=unzipped,
                                  modelIdentifier=fmu_export.MODEL_IDENTIFIER,
                                  instanceName="parts")
    return fmu


def _expected_variables(baumgarte):
    """(name, causality, variability, initial, unit, description) per value reference, as
    docs/engines.md and the wrapper's layout comment list them: q (8) | dq (8) | der(q) (8) |
    der(dq) (8) | T (3) | C (5) | lambda (5) | p (30) | a1, a2 | M, F, S, Qgrav, D, dD dq.
    Units from physics: xc, yc are lengths, the other six coordinates angles; a torque is N m,
    a multiplier of a contact constraint a force; the contact height residual is a length,
    the four contact velocities speeds; Baumgarte's a1, a2 are rates (1/s)."""
    def base(c):
        return "m" if c in ("xc", "yc") else "rad"
    rows = [(c, "local", "continuous", "exact", base(c), f"thesis coordinate {c}") for c in COORDS]
    rows += [(f"d_{c}", "local", "continuous", "exact", base(c) + "/s", f"rate of {c}")
             for c in COORDS]
    rows += [(f"der({c})", "local", "continuous", None, base(c) + "/s", None) for c in COORDS]
    rows += [(f"der(d_{c})", "local", "continuous", None, base(c) + "/s2", None) for c in COORDS]
    rows += [(t, "input", "continuous", None, "N.m", f"rider torque {t}") for t in TORQUES]
    rows += [(f"C.{k}", "output", "continuous", None, "m" if k == "rD_z" else "m/s",
              f"constraint residual {k}") for k in RESIDUAL]
    rows += [(f"lambda.{k}", "output", "continuous", None, "N", f"contact multiplier of {k}")
             for k in RESIDUAL]
    rows += [(p, "parameter", "fixed", "exact", FMI_UNIT[PARAMETER_UNITS[p]],
              PARAMETER_DESCRIPTIONS[p]) for p in PARAMETER_NAMES]
    rows += [(a, "parameter", "fixed", "exact", "1/s",
              f"Baumgarte {a}: D ddq = -dD dq - 2 a1 D dq - a2^2 C") for a in ("a1", "a2")]
    for block, n, m in TERMS:
        names = ([f"term.{block}[{i},{j}]" for i in range(1, n + 1) for j in range(1, m + 1)]
                 if m else [f"term.{block}[{i}]" for i in range(1, n + 1)])
        rows += [(name, "output", "continuous", None, None, f"the thesis's {block}")
                 for name in names]
    return rows


# -- modelDescription.xml -------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["me", "cs"])
def test_every_variable_has_its_reference_causality_initial_unit_and_description(built, kind):
    """Each ScalarVariable in order: valueReference 0, 1, 2, ... (its position, as the
    wrapper's layout), name, causality, variability, initial, the Real's unit and the
    description, against the documented layout (226 variables). Planted: any variable's unit
    or description dropped or misspelt (xc/yc's metre, rD_z's metre, the torques' N.m, the
    multipliers' N, the parameters' schema units, a1/a2's 1/s), the coordinates' unit taken
    for the rates or the accelerations', the angles in metres, a1/a2 misnamed, a term's row
    or column off by one, a parameter's initial dropped, the description or unit attributes
    looked up under another key."""
    b = built[kind]
    got = []
    for vr, v in enumerate(b.vars):
        assert v.get("valueReference") == str(vr)
        real = v.find("Real")
        got.append((v.get("name"), v.get("causality"), v.get("variability"), v.get("initial"),
                    real.get("unit"), v.get("description")))
    assert got == _expected_variables(b.baumgarte)
    assert len(got) == 226


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_start_values_are_the_models(built, thesis, kind):
    """The start values (FMI 2.0: every input, parameter and exact state has one; no output
    or derivative has): the torques 0; the thirty parameters the model's own, exactly; a1, a2
    the export's; the state upright and straight (roll, heading, steer 0) and on the rolling
    constraints (the reference's residual 0 at it), rolling at 4 m/s (d_xc = R_rear d_psi =
    R_front d_eps = 4, no steer or yaw rate), as the docstring says. Planted: a torque's
    start 1; the 4 m/s wheel rate put on the steer rate dq[6] (the export did so until
    2026-12-06: the FMU started at rest, steering at 12.5 rad/s)."""
    b = built[kind]
    for v in b.vars:
        has = v.find("Real").get("start") is not None
        assert has == (v.get("causality") in ("input", "parameter") or v.get("initial") == "exact")
    assert [b.start(t) for t in TORQUES] == [0.0, 0.0, 0.0]
    assert [b.start(p) for p in PARAMETER_NAMES] == list(thesis.params.vector())
    assert (b.start("a1"), b.start("a2")) == b.baumgarte
    q = np.array([b.start(c) for c in COORDS])
    dq = np.array([b.start(f"d_{c}") for c in COORDS])
    assert q[[2, 3, 6]].tolist() == [0.0, 0.0, 0.0]
    assert np.max(np.abs(thesis.constraint_residual(q, dq))) <= 1e-12
    # rolling straight at 4 m/s (the docstring): rolling without slip, upright and straight,
    # moves the rear contact forward at R_rear psi_dot = R_front eps_dot = d_xc, steering and
    # yawing not at all (1e-12: the projection onto the constraints is round-off)
    p = thesis.params
    assert dq[0] == pytest.approx(4.0, abs=1e-12) and abs(dq[1]) <= 1e-12
    assert p.R_rear * dq[4] == pytest.approx(4.0, abs=1e-12)
    assert p.R_front * dq[7] == pytest.approx(4.0, abs=1e-12)
    assert np.abs(dq[[2, 3, 5, 6]]).max() <= 1e-12


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_derivatives_and_model_structure_follow_fmi_2_0(built, kind):
    """FMI 2.0's ModelStructure by 1-based ScalarVariable index: der(q_i)'s derivative
    attribute is q_i's index and der(dq_i)'s is d_q_i's; Outputs lists every output in
    order; Derivatives every derivative, der(q_i) depending on d_q_i alone with a constant
    factor (der q = dq) and der(dq_i) on the 16 states and the 3 inputs, nonlinearly
    ("dependent"); InitialUnknowns the outputs and derivatives (the states are exact), sorted.
    Planted: der(dq_i) pointing at the next state or at q; the indices 2-based; the inputs
    counted 0-based or 2-based, or every non-input counted as one."""
    b = built[kind]
    for c in COORDS:
        assert b.var(f"der({c})").find("Real").get("derivative") == str(b.index[c])
        assert b.var(f"der(d_{c})").find("Real").get("derivative") == str(b.index[f"d_{c}"])
    ms = b.root.find("ModelStructure")
    outputs = [b.index[v.get("name")] for v in b.vars if v.get("causality") == "output"]
    derivs = [b.index[n] for n in [f"der({c})" for c in COORDS] + [f"der(d_{c})" for c in COORDS]]
    assert [int(u.get("index")) for u in ms.find("Outputs")] == outputs
    assert [int(u.get("index")) for u in ms.find("Derivatives")] == derivs
    assert [int(u.get("index")) for u in ms.find("InitialUnknowns")] == sorted(outputs + derivs)
    states = [b.index[c] for c in COORDS] + [b.index[f"d_{c}"] for c in COORDS]
    inputs = [b.index[t] for t in TORQUES]
    for u in ms.find("Derivatives"):
        name = b.vars[int(u.get("index")) - 1].get("name")
        deps = [int(i) for i in u.get("dependencies").split()]
        kinds = u.get("dependenciesKind").split()
        if name.startswith("der(d_"):
            assert deps == states + inputs and kinds == ["dependent"] * 19
        else:
            assert deps == [b.index["d_" + name[4:-1]]] and kinds == ["constant"]


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_each_unit_is_defined_once_by_its_si_base_units(built, kind):
    """UnitDefinitions: exactly the units the variables use, each once, its BaseUnit the SI
    exponents by dimensional analysis (N.m = kg m^2 s^-2, ...). Planted: a unit left out of
    the definitions while a variable uses it."""
    b = built[kind]
    defs = b.root.find("UnitDefinitions").findall("Unit")
    used = {v.find("Real").get("unit") for v in b.vars} - {None}
    assert sorted(u.get("name") for u in defs) == sorted(used)
    for u in defs:
        got = {k: int(x) for k, x in u.find("BaseUnit").attrib.items()}
        assert got == SI[u.get("name")], u.get("name")


def test_the_header_states_the_model_and_the_interfaces(built):
    """The root's and the interfaces' attributes (FMI 2.0: fmiVersion "2.0", a flat naming
    convention, no event indicators; the ModelExchange and CoSimulation elements each name
    the modelIdentifier, the binary's name, and fmu_wrapper.c as the source to compile, which
    sources/ holds), the description stating the model, its contact and the Baumgarte
    parameters it was exported with. Without co_simulation there is no CoSimulation element;
    providesDirectionalDerivative follows the option. Planted: the model name's prefix
    changed, the CoSimulation element replacing the header, its attributes or SourceFiles
    misspelt, the description's sentences re-cased, providesDirectionalDerivative "TRUE"."""
    for kind, cs, dd in (("me", False, "true"), ("cs", True, "false")):
        b = built[kind]
        r = b.root
        assert r.tag == "fmiModelDescription"
        assert {k: r.get(k) for k in ("fmiVersion", "modelName", "generationTool",
                                      "variableNamingConvention", "numberOfEventIndicators")} \
            == {"fmiVersion": "2.0", "modelName": "bicycle-xval thesis",
                "generationTool": "bicycle-xval export --format fmu",
                "variableNamingConvention": "flat", "numberOfEventIndicators": "0"}
        a1, a2 = ("10.0", "10.0") if kind == "me" else ("2.5", "6.0")
        assert r.get("description") == (
            "The bicycle-xval reference bicycle 'thesis' (thesis front contact), the thesis's "
            "minimal-coordinate four-body model. States q and dq; the rolling constraints by "
            "Baumgarte stabilisation D ddq = -dD dq - 2 a1 D dq - a2^2 C with "
            f"a1 = {a1}, a2 = {a2} (parameters; 0, 0: exact constrained accelerations). "
            "Mapping to the thesis's names: resources/bicycle-xval-mapping.toml.")
        interfaces = [e for e in r if e.tag in ("ModelExchange", "CoSimulation")]
        assert [e.tag for e in interfaces] == (["ModelExchange", "CoSimulation"] if cs
                                               else ["ModelExchange"])
        me = r.find("ModelExchange")
        assert dict(me.attrib) == {"modelIdentifier": "bicycle_xval",
                                   "canGetAndSetFMUstate": "false",
                                   "canSerializeFMUstate": "false",
                                   "providesDirectionalDerivative": dd,
                                   "completedIntegratorStepNotNeeded": "true"}
        for e in interfaces:
            files = [f.get("name") for f in e.find("SourceFiles").findall("File")]
            assert files == ["fmu_wrapper.c"] and "sources/fmu_wrapper.c" in b.files
        if cs:
            assert dict(r.find("CoSimulation").attrib) == {
                "modelIdentifier": "bicycle_xval", "canHandleVariableCommunicationStepSize": "true",
                "canGetAndSetFMUstate": "false", "canSerializeFMUstate": "false",
                "providesDirectionalDerivative": "false"}
        assert r.find("DefaultExperiment").attrib == {"startTime": "0", "stopTime": "1"}


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_no_character_data_outside_the_elements_and_fmpys_schema_check_passes(built, kind):
    """FMI 2.0's schema has no mixed content: every element's text and tail is whitespace;
    fmpy's validation (the XSD and its own rules) finds nothing. Planted: stray characters
    around the CoSimulation element's lines."""
    from fmpy.validation import validate_fmu
    b = built[kind]
    for e in b.root.iter():
        assert (e.text or "").strip() == "" and (e.tail or "").strip() == "", e.tag
    assert validate_fmu(str(b.path)) == []


def test_model_description_defaults_to_model_exchange_with_directional_derivatives(thesis):
    """model_description's defaults (as write_fmu's): no CoSimulation element, and
    providesDirectionalDerivative "true"; the guid given is the one written. Planted: either
    default flipped."""
    root = ET.fromstring(fmu_export.model_description(thesis, "{guid}"))
    assert root.find("CoSimulation") is None
    assert root.find("ModelExchange").get("providesDirectionalDerivative") == "true"
    assert root.get("guid") == "{guid}"


# -- the zip, the shipped sources and the GUID ----------------------------------------------

def test_the_zip_is_laid_out_as_fmi_2_0_says(built):
    """modelDescription.xml at the root, the binary at binaries/linux64/<modelIdentifier>.so
    (an ELF shared object), the sources under sources/ (the complex copy only with directional
    derivatives), the mapping under resources/; every entry deflated (the sources and the
    binary shrink ~5x). Planted: entries stored uncompressed; runtime.c left out of the
    zip."""
    common = {"modelDescription.xml", SO, "sources/fmu_wrapper.c", "sources/bicycle_generated.c",
              "sources/runtime.c", "resources/bicycle-xval-mapping.toml"}
    assert set(built["me"].files) == common | {"sources/bicycle_complex.c"}
    assert set(built["cs"].files) == common
    for b in built.values():
        assert b.files[SO][:4] == b"\x7fELF"
        assert b.root.find("ModelExchange").get("modelIdentifier") == Path(SO).stem
        assert {i.compress_type for i in b.infos} == {zipfile.ZIP_DEFLATED}


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_the_sources_include_only_what_sources_holds(built, kind):
    """The shipped sources compile on their own (FMI 2.0: sources/ with the FMI headers the
    importer has): every #include "..." of a shipped file is another shipped file or one of
    the three FMI 2.0 headers; every shipped source is plain ASCII (read as such here), so it
    reads the same in any locale. Planted: runtime.c (which bicycle_generated.c includes) left
    out of the zip."""
    b = built[kind]
    sources = {n.removeprefix("sources/") for n in b.files if n.startswith("sources/")}
    fmi = {"fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"}
    active = {"fmu_wrapper.c"}
    todo = ["fmu_wrapper.c"]
    while todo:
        text = b.files[f"sources/{todo.pop()}"].decode("ascii")
        if kind == "cs":    # DIRECTIONAL 0: the complex copy's include is compiled out
            text = re.sub(r"#if DIRECTIONAL\n.*?\n#endif\n#endif", "", text, flags=re.S)
        for inc in re.findall(r'#include "([^"]+)"', text):
            assert inc in sources | fmi, inc
            if inc in sources and inc not in active:
                active.add(inc)
                todo.append(inc)
    assert active == sources


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_the_shipped_wrapper_is_the_template_with_every_field_filled_in(built, thesis, kind):
    """sources/fmu_wrapper.c line by line against fmu_wrapper.c: the same wherever the
    template has no @FIELD@, and each field's value: the GUID of modelDescription.xml, N_P the
    thirty parameters (docs/engines.md), P_START the model's parameters and X_START the
    description's start state (exactly, as C doubles), A1 and A2 the export's Baumgarte
    parameters, COSIMULATION and DIRECTIONAL the options, CS_STEP 0.5 ms (docs/engines.md's
    RK4 step), the layout comment naming the file that fills it in. Planted: the GUID, the
    layout field left unfilled (its name re-cased); the layout text changed; a1 given a2's
    value."""
    b = built[kind]
    template = fmu_export.WRAPPER.read_text(encoding="utf-8").splitlines()
    shipped = b.files["sources/fmu_wrapper.c"].decode("ascii").splitlines()
    assert len(shipped) == len(template)
    fields: dict[str, str] = {}
    for t, s in zip(template, shipped):
        parts = re.split(r"@([A-Z0-9_]+)@", t)
        if len(parts) == 1:
            assert s == t
            continue
        pattern = "".join(re.escape(p) if i % 2 == 0 else "(.*)" for i, p in enumerate(parts))
        m = re.fullmatch(pattern, s)
        assert m is not None, t
        fields.update(zip(parts[1::2], m.groups()))
    assert "@" not in "".join(v for k, v in fields.items() if k != "NAME")
    assert fields.pop("NAME") == "@NAME@"      # the header comment's own mention of the fields
    doubles = {k: [float(x) for x in fields.pop(k).split(",")]
               for k in ("P_START", "X_START", "A1", "A2", "CS_STEP")}
    assert fields == {"LAYOUT": "filled in by reference_model/exports/fmu.py",
                      "DIRECTIONAL": "1" if kind == "me" else "0",
                      "GUID": b.root.get("guid"), "COSIMULATION": "0" if kind == "me" else "1",
                      "N_P": "30"}
    assert doubles["P_START"] == list(thesis.params.vector())
    assert doubles["X_START"] == ([b.start(c) for c in COORDS]
                                  + [b.start(f"d_{c}") for c in COORDS])
    assert (doubles["A1"][0], doubles["A2"][0]) == b.baumgarte
    assert doubles["CS_STEP"] == [5e-4]


def test_the_guid_has_fmis_form_and_is_a_hash_of_what_the_fmu_holds(thesis, tmp_path,
                                                                    stand_in_compiler):
    """The GUID is "{8-4-4-4-12}" lowercase hex (FMI 2.0), the same for the same FMU whether
    a1, a2 are given as ints or floats (the description is then byte for byte the same), and
    another for another Baumgarte pair, other parameters or other options. Planted: a group
    of the GUID one digit long or short; the Baumgarte pair left out of the hash or hashed as
    given (ints and floats differ); a None GUID in the description."""
    def guid(name, *args, model=thesis, **kw):
        path = fmu_export.write_fmu(model, tmp_path / f"{name}.fmu", *args, **kw)
        with zipfile.ZipFile(path) as z:
            md = z.read("modelDescription.xml")
        return ET.fromstring(md).get("guid"), md

    g_default, md_default = guid("default")
    g_ints, md_ints = guid("ints", (10, 10))
    assert GUID.match(g_default)
    assert md_ints == md_default
    heavy = thesis.with_params(thesis.params.replace(m3=thesis.params.m3 + 1.0))
    others = [guid("exact", (0.0, 0.0))[0], guid("a2", (10.0, 0.0))[0],
              guid("heavy", model=heavy)[0], guid("cs", co_simulation=True)[0],
              guid("fd", directional_derivatives=False)[0]]
    assert all(GUID.match(g) for g in others)
    assert len({g_default, *others}) == 6


def test_the_guid_in_the_description_is_the_binarys(built, tmp_path):
    """fmpy instantiates each FMU with the description's GUID (the wrapper refuses another:
    "GUID does not match the modelDescription"), and the GUID has FMI's form. Planted: the
    description's GUID None, or the wrapper's GUID field left unfilled."""
    for kind, b in built.items():
        assert GUID.match(b.root.get("guid"))
        fmu = _instance(b, tmp_path / kind)
        fmu.instantiate()
        fmu.freeInstance()


# -- the binary ----------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["me", "cs"])
def test_the_binary_starts_at_the_descriptions_start_values_and_computes_the_reference(
        built, thesis, tmp_path, kind):
    """An fmpy instance after initialization without any setReal: every variable with a
    start value reads it exactly (FMI 2.0: the start values are the FMU's initial values);
    its derivatives are (dq, ddq) with ddq the reference's `forward` at that state with the
    export's a1, a2, and its mass-matrix outputs the reference's, to 1e-12 of the largest
    entry (the same generated C compiled twice: round-off). Planted: a1 compiled with a2's
    value; a torque's start 1 in the description."""
    import ctypes
    b = built[kind]
    fmu = _instance(b, tmp_path)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    with_start = [v for v in b.vars if v.find("Real").get("start") is not None]
    got = fmu.getReal([int(v.get("valueReference")) for v in with_start])
    assert list(got) == [float(v.find("Real").get("start")) for v in with_start]
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    dx = (ctypes.c_double * 16)()
    fmu.getDerivatives(dx, 16)
    q = np.array([b.start(c) for c in COORDS])
    dq = np.array([b.start(f"d_{c}") for c in COORDS])
    ddq = thesis.forward(q, dq, (0.0, 0.0, 0.0), b.baumgarte).ddq
    assert np.array(dx)[:8].tolist() == dq.tolist()
    assert np.max(np.abs(np.array(dx)[8:] - ddq)) <= 1e-12 * np.max(np.abs(ddq))
    M = thesis.mass_matrix(q)
    vrM = [b.index[f"term.M[{i},{j}]"] - 1 for i in range(1, 9) for j in range(1, 9)]
    assert np.max(np.abs(np.array(fmu.getReal(vrM)).reshape(8, 8) - M)) <= 1e-12 * np.max(np.abs(M))
    fmu.terminate()
    fmu.freeInstance()


def test_directional_derivatives_are_there_only_when_exported(built, tmp_path):
    """With directional derivatives (the default), fmi2GetDirectionalDerivative of der(q)
    along dq is the identity, exactly (der q = dq); without them the call is fmi2Error (the
    docstring: "its function returns fmi2Error"). Planted: DIRECTIONAL compiled as 0 whatever
    the option."""
    from fmpy.fmi1 import FMICallException
    fmus = {}
    for kind, b in built.items():
        fmu = _instance(b, tmp_path / kind)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmus[kind] = fmu
    me = built["me"]
    ders = [me.index[f"der({c})"] - 1 for c in COORDS]
    rates = [me.index[f"d_{c}"] - 1 for c in COORDS]
    J = np.array([fmus["me"].getDirectionalDerivative(ders, rates, list(e)) for e in np.eye(8)])
    assert J.tolist() == np.eye(8).tolist()
    with pytest.raises(FMICallException):
        fmus["cs"].getDirectionalDerivative(ders[:1], rates[:1], [1.0])
    for fmu in fmus.values():
        fmu.terminate()
        fmu.freeInstance()


def test_only_the_co_simulation_export_offers_co_simulation(built, tmp_path):
    """The Co-Simulation FMU's binary takes a Co-Simulation instance and steps it (the state
    after one 0.5 ms step still on the constraints to 1e-9); the Model-Exchange-only binary
    refuses one ("this FMU does not provide that interface"). Planted: COSIMULATION compiled
    as 0 whatever the option."""
    cs = _instance(built["cs"], tmp_path / "cs", "FMU2Slave")
    cs.instantiate()
    cs.setupExperiment(startTime=0.0)
    cs.enterInitializationMode()
    cs.exitInitializationMode()
    cs.doStep(currentCommunicationPoint=0.0, communicationStepSize=5e-4)
    b = built["cs"]
    C = cs.getReal([b.index[f"C.{k}"] - 1 for k in RESIDUAL])
    assert np.max(np.abs(C)) <= 1e-9
    cs.terminate()
    cs.freeInstance()
    me = _instance(built["me"], tmp_path / "me", "FMU2Slave")
    with pytest.raises(Exception, match="Failed to instantiate"):
        me.instantiate()


# -- the mapping ---------------------------------------------------------------------------

TEMPLATE = '''\
# bicycle-xval mapping: FMU variable names -> the thesis's coordinates, torques and
# units (docs/engines.md, "The fmu engine"). A value is the FMU variable's name, or
# {name = "...", scale = s}: thesis value (SI) = s * FMU value.

contact = "disc"   # thesis or disc

[coordinates]   # the FMU's continuous states holding q (SI: m, rad)
xc = "xc"
yc = "yc"
phi = "phi"
theta = "theta"
psi = "psi"
beta = "beta"
gamma = "gamma"
eps = "eps"

[rates]         # the states holding dq (their derivatives are ddq)
xc = "d_xc"
yc = "d_yc"
phi = "d_phi"
theta = "d_theta"
psi = "d_psi"
beta = "d_beta"
gamma = "d_gamma"
eps = "d_eps"

[torques]       # inputs (N m)
Mdir = "Mdir"
Mped = "Mped"
Mvue = "Mvue"

# optional: the Baumgarte parameters (set to 0, 0 for exact accelerations and
# to a scenario's a1, a2 for its runs); leave out if the FMU has none
[baumgarte]
a1 = "a1"
a2 = "a2"

# optional: outputs holding the thesis's terms, {i} {j} 1-based row and column
[terms]
M = "term.M[{i},{j}]"
F = "term.F[{i}]"
S = "term.S[{i},{j}]"
Qgrav = "term.Qgrav[{i}]"
D = "term.D[{i},{j}]"
dDdq = "term.dDdq[{i}]"

# optional: outputs of the constraint residual C (the runs' C otherwise from the
# reference's constraints at the FMU's q, dq)
[residual]
rD_z = "C.rD_z"
vC_x = "C.vC_x"
vC_y = "C.vC_y"
vD_x = "C.vD_x"
vD_y = "C.vD_y"

# optional: the FMU parameters holding the thesis's (SI); the engine sets them from
# the model it is built for unless --engine-option parameters=fmu
[parameters]
''' + "".join(f'{p} = "{p}"\n' for p in PARAMETER_NAMES)


def test_the_mapping_template_reads_as_written_for_its_users(thesis):
    """`export --format fmu-mapping` writes mapping_text(None), the file a user edits for
    another tool's FMU: its comments (the value syntax of docs/engines.md, "thesis value (SI)
    = s * FMU value"; the torques in N m; what each optional table is for) and tables, word
    for word; for an exported model only the contact differs (the model's). The Baumgarte
    pair does not enter the mapping (it names the parameters, not their values). Planted:
    any comment re-cased, [terms] or [residual] upper-cased."""
    assert fmu_export.mapping_text(None) == TEMPLATE
    assert fmu_export.mapping_text(thesis) == TEMPLATE.replace('contact = "disc"',
                                                               'contact = "thesis"')
    assert fmu_export.mapping_text(thesis, (0.0, 0.0)) == fmu_export.mapping_text(thesis)
    assert tomllib.loads(TEMPLATE)["contact"] == "disc"


def test_the_fmus_own_mapping_names_its_variables_and_its_contact(built, thesis):
    """resources/bicycle-xval-mapping.toml inside each FMU, read by the fmu engine's parser
    against the FMU's own variables: the model's contact (thesis), every table there (a1, a2,
    the six terms, the five residuals, the thirty parameters). Planted: the template
    (contact "disc") written into the FMU instead of the model's mapping."""
    for b in built.values():
        text = b.files[fmu_export.MAPPING_FILE].decode("utf-8")
        got = parse_mapping(text, frozenset(b.index), "mapping")
        assert got.contact == thesis.contact == "thesis"
        assert got.baumgarte == ("a1", "a2")
        assert set(got.terms) == {t for t, _, _ in TERMS}
        assert got.residual == tuple(f"C.{k}" for k in RESIDUAL)
        assert list(got.parameters) == list(PARAMETER_NAMES)


# -- the compiler, the headers, the platform -----------------------------------------------

def _script(folder: Path, body: str) -> Path:
    """An executable stand-in for $CC: a /bin/sh script."""
    path = folder / "cc"
    path.write_bytes(b"#!/bin/sh\n" + body.encode("latin-1"))
    path.chmod(0o755)
    return path


def _build_tree(folder: Path) -> tuple[Path, Path]:
    build, headers = folder / "build", folder / "headers"
    build.mkdir()
    headers.mkdir()
    (build / "fmu_wrapper.c").write_text("int x;\n")
    (headers / "fmi2Functions.h").write_text("/* fmi2 */\n")
    return build, headers


@pytest.mark.parametrize("stderr, shown", [
    # gcc's last line, after an "In file included from" line and a blank one, with a byte
    # that is not UTF-8 (gcc prints the source's bytes as they are)
    ("printf 'In file included from x.c:1:\\n' >&2\n"
     "printf 'fmu_wrapper.c:5:1: error: stray \\377 in program\\n\\n  \\n' >&2\n",
     "fmu_wrapper.c:5:1: error: stray \ufffd in program"),
    ("", "no message"),
    ("printf '  \\n\\n' >&2\n", "no message"),
    (f"printf '%s\\n' '{'e' * 250}' >&2\n", "e" * 200),
])
def test_a_failing_compiler_is_one_line_with_its_last_line(tmp_path, monkeypatch, stderr, shown):
    """A compiler (a stand-in script as $CC) that exits 1: FmuExportError naming CC, its last
    non-blank stderr line (undecodable bytes replaced, cut at 200 characters; "no message"
    when it printed nothing) and the fix. Planted: stderr not captured, or decoded strictly
    (UnicodeDecodeError) or by an unknown error handler; the second-to-last line shown; the
    placeholder re-cased; the cut at 201."""
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(tmp_path / "cache"))
    cc = _script(tmp_path, stderr + "exit 1\n")
    build, headers = _build_tree(tmp_path)
    with pytest.raises(FmuExportError) as err:
        fmu_export._compile(build, headers, ("sh", str(cc)))
    assert str(err.value) == (f"C compiler 'sh {cc}' (CC) failed on the FMU wrapper: {shown}; "
                              "fix: set CC to a working C99 compiler")


def test_a_missing_compiler_is_named_with_the_fix(tmp_path, monkeypatch):
    """$CC naming no program: one line with the command and the fix (docs/engines.md:
    "without a compiler a one-line error"); gcc itself (CC unset) is the compiler returned.
    Planted: the compiler's problem ignored; the message None or re-cased."""
    missing = tmp_path / "no-such-cc"
    monkeypatch.setenv("CC", str(missing))
    with pytest.raises(FmuExportError) as err:
        fmu_export._compiler()
    assert str(err.value) == (f"export --format fmu needs a C compiler: C compiler '{missing}' "
                              "(CC) not found; fix: install gcc (Debian: apt-get install gcc) "
                              "or set CC to a C99 compiler")
    monkeypatch.delenv("CC")
    assert fmu_export._compiler() == ("gcc",)


HEADERS_MISSING = ("export --format fmu needs the FMI headers that fmpy ships; fix: "
                   "pip install 'bicycle-xval[fmu]'")


@pytest.mark.parametrize("spec", ["no fmpy", "no origin", "no headers"])
def test_without_fmpys_headers_the_error_names_the_extra(tmp_path, monkeypatch, spec):
    """fmpy not installed (no module spec), installed without a file origin (a namespace
    package), or without c-code/fmi2Functions.h: the same one line with the pip fix; the
    installed fmpy gives its c-code folder. Planted: the spec's checks joined by "or" or made
    always true, the folder's by "and"; the message None or re-cased."""
    import importlib.util
    real = fmu_export.fmi_headers()
    assert real.name == "c-code" and (real / "fmi2Functions.h").is_file()
    assert real.parent == Path(importlib.util.find_spec("fmpy").origin).parent
    fake = {"no fmpy": None, "no origin": SimpleNamespace(origin=None),
            "no headers": SimpleNamespace(origin=str(tmp_path / "fmpy" / "__init__.py"))}[spec]
    monkeypatch.setattr(fmu_export.importlib.util, "find_spec", lambda name: fake)
    with pytest.raises(FmuExportError) as err:
        fmu_export.fmi_headers()
    assert str(err.value) == HEADERS_MISSING


@pytest.mark.parametrize("system, machine", [("linux", "aarch64"), ("darwin", "x86_64"),
                                             ("win32", "AMD64")])
def test_off_linux_x86_64_the_export_refuses_naming_the_platform(monkeypatch, system, machine):
    """The binary is FMI's linux64: on another system or machine one line naming both and
    the fix; on Linux x86-64 the folder is linux64. Planted: the two checks joined by "or"
    (an aarch64 Linux binary labelled linux64); the message None or re-cased."""
    assert fmu_export._platform() == "linux64"
    monkeypatch.setattr(fmu_export, "sys", SimpleNamespace(platform=system))
    monkeypatch.setattr(fmu_export, "platform", SimpleNamespace(machine=lambda: machine))
    with pytest.raises(FmuExportError) as err:
        fmu_export._platform()
    assert str(err.value) == (f"export --format fmu builds a Linux x86-64 binary (FMI's linux64); "
                              f"this is {system} {machine}; fix: export on Linux x86-64, or "
                              "compile the FMU's sources/ with your tool")


def test_the_complex_copy_takes_loops_and_names_every_unknown_function():
    """complex_source: a `for(` loop is no function call (kept as it is); two functions it
    has no complex version of are both named, sorted, comma-separated, with the fix.
    Planted: "for" not excluded (a loop refused as an unknown function); another separator."""
    text = "void bx_k(double *x) { for(int i = 0; i < 2; i++) x[i] = sin(x[i]); }\n"
    assert fmu_export.complex_source(text) == \
        "void bxc_k(cplx *x) { for(int i = 0; i < 2; i++) x[i] = c_sin(x[i]); }\n"
    with pytest.raises(FmuExportError) as err:
        fmu_export.complex_source("double bx_k(double x) { return log(x) + exp(x); }")
    assert str(err.value) == ("the generated C calls exp, log, which the FMU's complex-step "
                              "derivatives do not cover; fix: export with "
                              "directional_derivatives=False, or add them to fmu_wrapper.c")


# -- writing the FMU -----------------------------------------------------------------------

@pytest.fixture()
def stand_in_compiler(monkeypatch):
    """`_compile` replaced: records the build folder and what it holds, writes a placeholder
    binary (the GUID and the file writing do not depend on gcc's output)."""
    seen = []

    def compile_(build, headers, cc):
        seen.append(SimpleNamespace(build=build, headers=headers, cc=cc, sources={
            p.name: p.read_text(encoding="utf-8") for p in build.iterdir()}))
        so = build / f"{fmu_export.MODEL_IDENTIFIER}.so"
        so.write_bytes(b"\x7fELF placeholder")
        return so

    monkeypatch.setattr(fmu_export, "_compile", compile_)
    return seen


def test_the_build_folder_is_a_named_temporary_removed_after_the_export(thesis, tmp_path,
                                                                         stand_in_compiler):
    """The compiler gets a fresh temporary folder named after the tool (bicycle-xval-fmu-*,
    the name a compiler error's path shows), holding exactly the sources the FMU ships under
    sources/, byte for byte; the folder is gone after the export. Planted: another prefix
    (upper-cased, "XX", or tempfile's default)."""
    out = fmu_export.write_fmu(thesis, tmp_path / "t.fmu")
    (call,) = stand_in_compiler
    assert call.build.parent == Path(tempfile.gettempdir())
    assert call.build.name.startswith("bicycle-xval-fmu-")
    assert not call.build.exists()
    with zipfile.ZipFile(out) as z:
        shipped = {n.removeprefix("sources/"): z.read(n).decode("utf-8")
                   for n in z.namelist() if n.startswith("sources/")}
    assert call.sources == shipped
    assert call.headers == fmu_export.fmi_headers() and call.cc == ("gcc",)


def test_the_export_builds_c_whatever_the_backend_setting(thesis, tmp_path, monkeypatch,
                                                          stand_in_compiler, built):
    """BICYCLE_XVAL_BACKEND=numpy (the user's choice for the reference's own evaluations)
    does not change the FMU: it needs the generated C, and ships the same
    bicycle_generated.c as the default export. Planted: the export's build without
    backend="c" (the numpy code, with no C file, is loaded)."""
    monkeypatch.setenv("BICYCLE_XVAL_BACKEND", "numpy")
    out = fmu_export.write_fmu(thesis, tmp_path / "t.fmu")
    with zipfile.ZipFile(out) as z:
        assert z.read("sources/bicycle_generated.c") == \
            built["me"].files["sources/bicycle_generated.c"]


def test_the_fmu_is_never_half_written_and_no_folder_is_made(thesis, tmp_path,
                                                             stand_in_compiler, monkeypatch):
    """The FMU replaces an existing file only when complete: a build that fails leaves the
    old file as it was and no temporary beside it; a successful one leaves the FMU alone in
    the folder, with a new file's mode (0666 less the umask, not a temporary's 0600). An
    output in a folder that does not exist is FileNotFoundError, and no folder is created (as
    every export: a mistyped folder is not made). Planted: the parent folders created."""
    out = tmp_path / "t.fmu"
    out.write_bytes(b"old")

    def failing(*args):
        raise FmuExportError("boom")

    with monkeypatch.context() as m:
        m.setattr(fmu_export, "_compile", failing)
        with pytest.raises(FmuExportError, match="^boom$"):
            fmu_export.write_fmu(thesis, out)
    assert out.read_bytes() == b"old" and os.listdir(tmp_path) == ["t.fmu"]
    fmu_export.write_fmu(thesis, out)
    assert os.listdir(tmp_path) == ["t.fmu"] and zipfile.is_zipfile(out)
    umask = os.umask(0o022)
    os.umask(umask)
    assert stat.S_IMODE(out.stat().st_mode) == 0o666 & ~umask
    with pytest.raises(FileNotFoundError):
        fmu_export.write_fmu(thesis, tmp_path / "missing" / "t.fmu")
    assert not (tmp_path / "missing").exists()
