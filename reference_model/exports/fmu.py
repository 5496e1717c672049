"""The reference bicycle as an FMI 2.0 Model-Exchange FMU: its generated C (`codegen.build`)
compiled with a small FMI wrapper (``fmu_wrapper.c``, filled in here, never committed filled
in) and the FMI headers that fmpy ships.

    from reference_model.exports.fmu import write_fmu
    write_fmu(load_model("thesis"), "thesis.fmu")

States q and dq (thesis coordinates, SI); the constraints by Baumgarte stabilisation,
``D ddq = -dD dq - 2 a1 D dq - a2^2 C`` with the parameters a1, a2 (default the thesis's
10, 10; a1 = a2 = 0 gives the exact constrained accelerations). Inputs Mdir, Mped, Mvue;
outputs the constraint residual ``C.*`` and the contact multipliers ``lambda.*``, and the
thesis's terms ``term.*`` (M, F = Qv + Qgrav + Qaero, S, Qgrav, D, dD dq), which the ``fmu``
engine reads when the mapping names them. The thirty parameters by their names and SI units.
Directional derivatives (``providesDirectionalDerivative="true"``, unless
``directional_derivatives=False``): ``fmi2GetDirectionalDerivative`` of any Real (derivatives,
outputs, terms) along any states, inputs and parameters, by a complex step through a complex
copy of the generated C (:func:`complex_source`): exact to rounding, no step-size error
(docs/engines.md, "The reference as an FMU").
``resources/bicycle-xval-mapping.toml`` maps the variables to the thesis's names
(:func:`mapping_text`; docs/engines.md, "The fmu engine"). The FMU file is written to a
temporary file beside ``out`` and renamed: never half-written.
"""

from __future__ import annotations

import hashlib
import importlib.util
import io
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from xml.sax.saxutils import quoteattr

import re

import numpy as np

from ..equations import codegen
from ..model import CONSTRAINT_NAMES, Model
from ..names import COORDINATES, TORQUE_NAMES
from ..parameters.benchmark_files import _write_atomically
from ..parameters.schema import PARAMETER_DESCRIPTIONS, PARAMETER_NAMES, PARAMETER_UNITS
from ..solvers import THESIS_BAUMGARTE, consistent_state
from .text import float_text

__all__ = ["FmuExportError", "MAPPING_FILE", "MODEL_IDENTIFIER", "TERM_BLOCKS", "CS_STEP",
           "binary_key", "complex_source", "fmi_headers", "mapping_text", "model_description", "write_fmu"]

MODEL_IDENTIFIER = "bicycle_xval"
MAPPING_FILE = "resources/bicycle-xval-mapping.toml"
WRAPPER = Path(__file__).with_name("fmu_wrapper.c")
#: the term outputs after a1, a2, in the wrapper's order: name, rows, columns (0: a vector)
TERM_BLOCKS = (("M", 8, 8), ("F", 8, 0), ("S", 8, 3), ("Qgrav", 8, 0), ("D", 5, 8),
               ("dDdq", 5, 0))
_UNITS = {"m": "m", "kg": "kg", "kg*m^2": "kg.m2", "m/s^2": "m/s2", "kg/m": "kg/m"}
_BASE = {"m": 'm="1"', "rad": 'rad="1"', "m/s": 'm="1" s="-1"', "rad/s": 'rad="1" s="-1"',
         "m/s2": 'm="1" s="-2"', "rad/s2": 'rad="1" s="-2"', "N.m": 'kg="1" m="2" s="-2"',
         "N": 'kg="1" m="1" s="-2"', "kg": 'kg="1"', "kg.m2": 'kg="1" m="2"',
         "kg/m": 'kg="1" m="-1"', "1/s": 's="-1"'}
_PLATFORM = "linux64"
_VR_P = 45
#: the Co-Simulation interface's largest RK4 step (s): Baumgarte's 10, 10 decay at 120 /s, and
#: RK4's error at h = 5e-4 s is ~(120 h)^4 ~ 1e-5 of a step's change per second of run
CS_STEP = 5e-4


class FmuExportError(RuntimeError):
    """The FMU cannot be built here (no C compiler, no FMI headers); one line with the fix."""


def fmi_headers() -> Path:
    """The folder of fmpy's copy of the FMI headers (fmi2Functions.h)."""
    spec = importlib.util.find_spec("fmpy")
    folder = Path(spec.origin).parent / "c-code" if spec and spec.origin else None
    if folder is None or not (folder / "fmi2Functions.h").is_file():
        raise FmuExportError("export --format fmu needs the FMI headers that fmpy ships; fix: "
                             "pip install 'bicycle-xval[fmu]'")
    return folder


def complex_source(generated: str) -> str:
    """The generated C (``bicycle_generated.c``) as complex-step code for the wrapper's
    directional derivatives: every ``double`` a ``cplx`` (double _Complex), the kernels
    ``bx_*`` renamed ``bxc_*``, sin/cos/sqrt/pow the wrapper's first-order complex versions,
    without the runtime (the wrapper solves the complex KKT system itself)."""
    text = generated.replace('#include "runtime.c"', "")
    unknown = sorted(set(re.findall(r"\b([a-z_][a-z0-9_]*)\(", text))
                     - {"sin", "cos", "sqrt", "pow", "for"} - set(re.findall(r"\b(bx_\w+)\(", text)))
    if unknown:
        raise FmuExportError(f"the generated C calls {', '.join(unknown)}, which the FMU's "
                             "complex-step derivatives do not cover; fix: export with "
                             "directional_derivatives=False, or add them to fmu_wrapper.c")
    text = re.sub(r"\bdouble\b", "cplx", text)
    text = re.sub(r"\bbx_", "bxc_", text)
    return re.sub(r"\b(sin|cos|sqrt|pow)\(", r"c_\1(", text)


def _coordinate_unit(name: str, order: int) -> str:
    base = "m" if name in ("xc", "yc") else "rad"
    return base + ("", "/s", "/s2")[order] if base == "rad" else ("m", "m/s", "m/s2")[order]


def _start_state(model: Model) -> np.ndarray:
    """Upright straight running: rear wheel rolling at 4 m/s, every constraint satisfied."""
    q = np.zeros(8)
    dq = np.zeros(8)
    dq[4] = 4.0 / model.params.R_rear          # psi_dot, the rear wheel rotation rate
    s = consistent_state(model, q, dq)
    return np.concatenate([s.q, s.dq])


def _variables(model: Model, baumgarte: tuple[float, float]) -> list[tuple[str, dict]]:
    """(name, attributes and a 'unit', 'start', 'derivative') per value reference, in order."""
    x0 = _start_state(model)
    out: list[tuple[str, dict]] = []
    for i, c in enumerate(COORDINATES):
        out.append((c, dict(causality="local", variability="continuous", initial="exact",
                            start=x0[i], unit=_coordinate_unit(c, 0),
                            description=f"thesis coordinate {c}")))
    for i, c in enumerate(COORDINATES):
        out.append((f"d_{c}", dict(causality="local", variability="continuous", initial="exact",
                                   start=x0[8 + i], unit=_coordinate_unit(c, 1),
                                   description=f"rate of {c}")))
    for i, c in enumerate(COORDINATES):
        out.append((f"der({c})", dict(causality="local", variability="continuous",
                                      unit=_coordinate_unit(c, 1), derivative=i + 1)))
    for i, c in enumerate(COORDINATES):
        out.append((f"der(d_{c})", dict(causality="local", variability="continuous",
                                        unit=_coordinate_unit(c, 2), derivative=9 + i)))
    for t in TORQUE_NAMES:
        out.append((t, dict(causality="input", variability="continuous", start=0.0, unit="N.m",
                            description=f"rider torque {t}")))
    for k in CONSTRAINT_NAMES:
        out.append((f"C.{k}", dict(causality="output", variability="continuous",
                                   description=f"constraint residual {k}",
                                   unit="m" if k == "rD_z" else "m/s")))
    for k in CONSTRAINT_NAMES:
        out.append((f"lambda.{k}", dict(causality="output", variability="continuous", unit="N",
                                        description=f"contact multiplier of {k}")))
    values = model.params.vector()
    assert len(out) == _VR_P
    for name, v in zip(PARAMETER_NAMES, values):
        unit = _UNITS.get(PARAMETER_UNITS[name])
        out.append((name, dict(causality="parameter", variability="fixed", initial="exact",
                               start=float(v), unit=unit, description=PARAMETER_DESCRIPTIONS[name])))
    for name, v in zip(("a1", "a2"), baumgarte):
        out.append((name, dict(causality="parameter", variability="fixed", initial="exact",
                               start=float(v), unit="1/s",
                               description=f"Baumgarte {name}: D ddq = -dD dq - 2 a1 D dq - a2^2 C")))
    for block, rows, cols in TERM_BLOCKS:
        for r in range(rows):
            for c in range(max(cols, 1)):
                name = f"term.{block}[{r + 1},{c + 1}]" if cols else f"term.{block}[{r + 1}]"
                out.append((name, dict(causality="output", variability="continuous",
                                       description=f"the thesis's {block}")))
    return out


def model_description(model: Model, guid: str, baumgarte=THESIS_BAUMGARTE,
                      co_simulation: bool = False, directional_derivatives: bool = True) -> str:
    """modelDescription.xml of the FMU of ``model`` (``guid`` written into it); with
    ``co_simulation`` also the Co-Simulation interface (fixed-step RK4, :data:`CS_STEP`);
    ``directional_derivatives``: whether it declares ``fmi2GetDirectionalDerivative``."""
    provides = "true" if directional_derivatives else "false"
    a1, a2 = baumgarte
    variables = _variables(model, (a1, a2))
    units = sorted({a["unit"] for _, a in variables if a.get("unit")})
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             '<fmiModelDescription fmiVersion="2.0" modelName='
             f'{quoteattr("bicycle-xval " + model.name)} guid="{guid}" '
             f'description={quoteattr(_description(model, (a1, a2)))} '
             'generationTool="bicycle-xval export --format fmu" '
             'variableNamingConvention="flat" numberOfEventIndicators="0">',
             f'  <ModelExchange modelIdentifier="{MODEL_IDENTIFIER}" '
             'canGetAndSetFMUstate="false" canSerializeFMUstate="false" '
             f'providesDirectionalDerivative="{provides}" completedIntegratorStepNotNeeded="true">',
             '    <SourceFiles>', '      <File name="fmu_wrapper.c"/>', '    </SourceFiles>',
             '  </ModelExchange>']
    if co_simulation:
        lines += [f'  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" '
                  'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="false" '
                  f'canSerializeFMUstate="false" providesDirectionalDerivative="{provides}">',
                  '    <SourceFiles>', '      <File name="fmu_wrapper.c"/>', '    </SourceFiles>',
                  '  </CoSimulation>']
    lines += ['  <UnitDefinitions>']
    lines += [f'    <Unit name="{u}"><BaseUnit {_BASE[u]}/></Unit>' for u in units]
    lines += ['  </UnitDefinitions>', '  <DefaultExperiment startTime="0" stopTime="1"/>',
              '  <ModelVariables>']
    for vr, (name, a) in enumerate(variables):
        head = (f'    <ScalarVariable name={quoteattr(name)} valueReference="{vr}" '
                f'causality="{a["causality"]}" variability="{a["variability"]}"')
        if "initial" in a:
            head += f' initial="{a["initial"]}"'
        if a.get("description"):
            head += f' description={quoteattr(a["description"])}'
        real = "<Real"
        if a.get("unit"):
            real += f' unit="{a["unit"]}"'
        if "derivative" in a:
            real += f' derivative="{a["derivative"]}"'
        if "start" in a:
            real += f' start="{float_text(float(a["start"]))}"'
        lines.append(f"{head}>{real}/></ScalarVariable>")
    lines.append('  </ModelVariables>')
    outputs = [vr + 1 for vr, (_, a) in enumerate(variables) if a["causality"] == "output"]
    derivs = [vr + 1 for vr, (_, a) in enumerate(variables) if "derivative" in a]
    lines += ['  <ModelStructure>', '    <Outputs>']
    lines += [f'      <Unknown index="{i}"/>' for i in outputs]
    lines += ['    </Outputs>', '    <Derivatives>']
    lines += [f'      <Unknown index="{i}"{_dependencies(variables, vr)}/>'
              for i, vr in ((i, i - 1) for i in derivs)]
    lines += ['    </Derivatives>', '    <InitialUnknowns>']
    lines += [f'      <Unknown index="{i}"/>' for i in sorted(outputs + derivs)]
    lines += ['    </InitialUnknowns>', '  </ModelStructure>', '</fmiModelDescription>', '']
    return "\n".join(lines)


def _dependencies(variables: list[tuple[str, dict]], vr: int) -> str:
    """The Derivatives entry's knowns (FMI 2.0 indices, 1-based): der(q_i) = dq_i, a constant
    factor 1; der(dq_i) depends on every state and input ("dependent": nonlinear)."""
    name = variables[vr][0]
    index = {n: i + 1 for i, (n, _) in enumerate(variables)}
    states = [index[c] for c in COORDINATES] + [index[f"d_{c}"] for c in COORDINATES]
    inputs = [i + 1 for i, (_, a) in enumerate(variables) if a["causality"] == "input"]
    if name.startswith("der(d_"):
        knowns = states + inputs
        return (f' dependencies="{" ".join(map(str, knowns))}" '
                f'dependenciesKind="{" ".join(["dependent"] * len(knowns))}"')
    return f' dependencies="{index["d_" + name[4:-1]]}" dependenciesKind="constant"'


def _description(model: Model, baumgarte) -> str:
    a1, a2 = baumgarte
    return (f"The bicycle-xval reference bicycle {model.name!r} ({model.contact} front contact), "
            "the thesis's minimal-coordinate four-body model. States q and dq; the rolling "
            "constraints by Baumgarte stabilisation D ddq = -dD dq - 2 a1 D dq - a2^2 C with "
            f"a1 = {float_text(a1)}, a2 = {float_text(a2)} (parameters; 0, 0: exact constrained "
            f"accelerations). Mapping to the thesis's names: {MAPPING_FILE}.")


def mapping_text(model: Model | None = None, baumgarte=THESIS_BAUMGARTE) -> str:
    """The mapping file (docs/engines.md, "The fmu engine") of an exported FMU; with
    ``model=None`` the template for someone else's FMU (the same names, to be edited)."""
    head = ["# bicycle-xval mapping: FMU variable names -> the thesis's coordinates, torques and",
            "# units (docs/engines.md, \"The fmu engine\"). A value is the FMU variable's name, or",
            "# {name = \"...\", scale = s}: thesis value (SI) = s * FMU value.",
            ""]
    head.append(f'contact = "{model.contact if model else "disc"}"   # thesis or disc')
    head += ["", "[coordinates]   # the FMU's continuous states holding q (SI: m, rad)"]
    head += [f'{c} = "{c}"' for c in COORDINATES]
    head += ["", "[rates]         # the states holding dq (their derivatives are ddq)"]
    head += [f'{c} = "d_{c}"' for c in COORDINATES]
    head += ["", "[torques]       # inputs (N m)"]
    head += [f'{t} = "{t}"' for t in TORQUE_NAMES]
    head += ["", "# optional: the Baumgarte parameters (set to 0, 0 for exact accelerations and",
             "# to a scenario's a1, a2 for its runs); leave out if the FMU has none",
             "[baumgarte]", 'a1 = "a1"', 'a2 = "a2"',
             "", "# optional: outputs holding the thesis's terms, {i} {j} 1-based row and column",
             "[terms]", 'M = "term.M[{i},{j}]"', 'F = "term.F[{i}]"', 'S = "term.S[{i},{j}]"',
             'Qgrav = "term.Qgrav[{i}]"', 'D = "term.D[{i},{j}]"', 'dDdq = "term.dDdq[{i}]"',
             "", "# optional: outputs of the constraint residual C (the runs' C otherwise from the",
             "# reference's constraints at the FMU's q, dq)", "[residual]"]
    head += [f'{k} = "C.{k}"' for k in CONSTRAINT_NAMES]
    head += ["", "# optional: the FMU parameters holding the thesis's (SI); the engine sets them from",
             "# the model it is built for unless --engine-option parameters=fmu", "[parameters]"]
    head += [f'{k} = "{k}"' for k in PARAMETER_NAMES]
    return "\n".join(head) + "\n"


def _platform() -> str:
    """The FMI 2.0 platform folder of the binary built here (Linux x86-64 only)."""
    if sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64"):
        return _PLATFORM
    raise FmuExportError(f"export --format fmu builds a Linux x86-64 binary (FMI's {_PLATFORM}); "
                         f"this is {sys.platform} {platform.machine()}; fix: export on Linux "
                         "x86-64, or compile the FMU's sources/ with your tool")


def _compiler() -> tuple[str, ...]:
    cc = codegen.compiler_command()
    problem = codegen.compiler_problem(cc)
    if problem is not None:
        raise FmuExportError(f"export --format fmu needs a C compiler: {problem}; fix: install "
                             "gcc (Debian: apt-get install gcc) or set CC to a C99 compiler")
    return cc


#: the compiler's flags after $CC (the source, the output and the include folders follow)
_FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fno-fast-math", "-fvisibility=default")


def binary_key(build: Path, headers: Path, cc: tuple[str, ...]) -> str:
    """The hash that names a compiled binary in the cache: the compiler command and its flags,
    and the name and bytes of every source in ``build`` and every header in ``headers`` (what
    the compiler reads; the folders' own paths, which are temporary, are left out)."""
    h = hashlib.sha256(repr((cc, _FLAGS)).encode())
    for folder in (build, headers):
        for path in sorted(folder.glob("*.[ch]")):
            h.update(f"\0{folder is build}:{path.name}\0".encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def _compile(build: Path, headers: Path, cc: tuple[str, ...]) -> Path:
    """The FMU's binary from the sources in ``build``: from the cache
    (``<cache>/fmu-binaries/<binary_key>.so``) when the same compiler has compiled the same
    sources before, else compiled now and cached (a read-only cache is only not written)."""
    so = build / f"{MODEL_IDENTIFIER}.so"
    cached = codegen.cache_root() / "fmu-binaries" / f"{binary_key(build, headers, cc)}.so"
    if cached.is_file():
        so.write_bytes(cached.read_bytes())
        so.chmod(0o755)     # as the compiler leaves it
        return so
    cmd = [*cc, *_FLAGS, f"-I{headers}", f"-I{build}", "-o", str(so),
           str(build / "fmu_wrapper.c"), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    if res.returncode != 0:
        last = [ln for ln in res.stderr.splitlines() if ln.strip()][-1:] or ["no message"]
        raise FmuExportError(f"C compiler {shlex.join(cc)!r} (CC) failed on the FMU wrapper: "
                             f"{last[0][:200]}; fix: set CC to a working C99 compiler")
    try:
        _write_atomically(cached, so.read_bytes())
    except OSError:     # a read-only cache: the binary is built, only not kept
        pass
    return so


def write_fmu(model: Model, out: str | os.PathLike[str], baumgarte=THESIS_BAUMGARTE, *,
              co_simulation: bool = False, directional_derivatives: bool = True) -> Path:
    """Build the FMU of ``model`` and write it to ``out`` atomically; returns the path.
    ``co_simulation``: also the Co-Simulation interface (fixed-step RK4 inside fmi2DoStep);
    ``directional_derivatives``: fmi2GetDirectionalDerivative by complex steps (False: an
    FMU without them, as many tools export; its function returns fmi2Error).
    Raises `FmuExportError` (no compiler, no headers) and `codegen.CodegenError`."""
    out = Path(out)
    headers = fmi_headers()
    binary = f"binaries/{_platform()}/{MODEL_IDENTIFIER}.so"
    cc = _compiler()
    library = codegen.build(model.contact, backend="c")
    generated = (library.path / codegen.C_FILES[0]).read_text(encoding="utf-8")
    key = hashlib.sha256(generated.encode() + model.params.vector().tobytes()
                         + np.asarray(baumgarte, dtype=float).tobytes()
                         + bytes([co_simulation, directional_derivatives])).hexdigest()
    guid = f"{{{key[:8]}-{key[8:12]}-{key[12:16]}-{key[16:20]}-{key[20:32]}}}"
    x0 = _start_state(model)
    wrapper = (WRAPPER.read_text(encoding="utf-8")
               .replace("@GUID@", guid).replace("@N_P@", str(len(PARAMETER_NAMES)))
               .replace("@P_START@", ", ".join(repr(float(v)) for v in model.params.vector()))
               .replace("@X_START@", ", ".join(repr(float(v)) for v in x0))
               .replace("@A1@", repr(float(baumgarte[0]))).replace("@A2@", repr(float(baumgarte[1])))
               .replace("@COSIMULATION@", "1" if co_simulation else "0")
               .replace("@DIRECTIONAL@", "1" if directional_derivatives else "0")
               .replace("@CS_STEP@", repr(CS_STEP))
               .replace("@LAYOUT@", "filled in by reference_model/exports/fmu.py"))
    with tempfile.TemporaryDirectory(prefix="bicycle-xval-fmu-") as tmp:
        build = Path(tmp)
        sources = {"fmu_wrapper.c": wrapper, "bicycle_generated.c": generated,
                   "runtime.c": codegen.RUNTIME_C.read_text(encoding="utf-8")}
        if directional_derivatives:
            sources["bicycle_complex.c"] = complex_source(generated)
        for name, text in sources.items():
            (build / name).write_text(text, encoding="utf-8")
        so = _compile(build, headers, cc)
        data = io.BytesIO()
        with zipfile.ZipFile(data, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", model_description(
                model, guid, baumgarte, co_simulation, directional_derivatives))
            z.write(so, binary)
            for name, text in sources.items():
                z.writestr(f"sources/{name}", text)
            z.writestr(MAPPING_FILE, mapping_text(model, baumgarte))
    _write_atomically(out, data.getvalue(), parents=False)
    return out
