"""Scenario files: a scenario as TOML, validated like parameter files, and the writer.

Format (every table but ``[scenario]`` optional where said)::

    [scenario]
    name = "my-run"                        # required
    description = "..."                    # required
    kind = "forward"                       # "forward" (initial state + torques) or "inverse"
    model = "thesis"                       # named model, or a parameter file (relative to
                                           # this file); default "thesis"
    claim = "..."                          # what should happen (the thesis's claim); optional
    tags = ["stability"]                   # optional
    compared = ["trajectory"]              # keys of scenarios.QUANTITIES; default by kind

    [grid]                                 # output grid t_k = start + k step, k < samples
    start = 0.0                            # s, default 0
    step = 0.01                            # s
    samples = 629                          # or: duration = 6.28 (s, a whole number of steps)

    [initial]                              # forward: independent coordinates and rates
    theta = 0.19634954084936207            # roll (rad); psi (rear wheel angle), gamma (steer)
    dtheta = 0.0                           # rad/s; dpsi, dgamma; all default 0
    beta = -0.3141592653589793             # optional starting guesses of the dependent
                                           # coordinates xc, yc, phi, beta, eps (re-solved
                                           # from the constraints), default 0

    [inputs]                               # forward: rider torques, one of
    torques = { Mdir = 0.0, Mped = 1.0, Mvue = 0.0 }   # constant, N m (missing ones 0)
    # torques = "zigzag"                   # a named function: the inverse-dynamics torques of
    #                                      # the built-in inverse scenario (cubic spline)
    # csv = "torques.csv"                  # samples: columns t, Mdir, Mped, Mvue (header);
    # interpolation = "cubic"              # "cubic" (not-a-knot), "linear", "previous"

    [motion]                               # inverse: a named independent motion
    function = "zigzag"                    # "check" or "zigzag" (scenarios.MOTIONS)

    [solver]                               # forward, optional
    constraints = "baumgarte"              # "baumgarte", "projection", "none"
    baumgarte = [10.0, 10.0]               # a1, a2
    fall_limit = 1.4                       # rad: the run stops when |theta| reaches it

    [[expected_differences]]               # optional, any number
    quantity = "..."; engines = "..."; expected = "..."; reason = "..."

Every problem raises one :class:`ScenarioFileError` (a ``ValueError``) whose one-line message
names the file, the key, the problem and the fix. The built-in scenarios are files of this
format in ``reference_model/scenario_data/`` (package data), loaded by
:func:`load_builtin_scenarios`.
"""

from __future__ import annotations

import csv
import difflib
import json
import math
import os
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from ..parameters.loading import NAMED_MODELS
from ..solvers import CONSTRAINT_HANDLING, DEFAULT_FALL_LIMIT, THESIS_BAUMGARTE
from .definition import (FORWARD_QUANTITIES, INVERSE_QUANTITIES, MOTIONS, QUANTITIES,
                         TORQUE_FUNCTIONS, ExpectedDifference, Scenario, TorqueSamples)

__all__ = ["BUILTIN_DIR", "ScenarioFileError", "load_builtin_scenarios", "load_scenario",
           "scenario_from_mapping", "scenario_toml_text"]

#: The built-in scenarios' files (package data, beside this package: ``reference_model/scenario_data/``).
BUILTIN_DIR = Path(__file__).resolve().parents[1] / "scenario_data"

INDEPENDENT_COORDINATES = ("theta", "psi", "gamma")
DEPENDENT_COORDINATES = ("xc", "yc", "phi", "beta", "eps")
COORDINATE_ORDER = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")
RATES = ("dtheta", "dpsi", "dgamma")
TORQUES = ("Mdir", "Mped", "Mvue")
INTERPOLATIONS = {"cubic": "not-a-knot cubic spline (MATLAB's spline)",
                  "linear": "piecewise linear", "previous": "zero-order hold (last sample)"}

_KEYS: dict[str, tuple[str, ...]] = {
    "scenario": ("name", "description", "kind", "model", "claim", "tags", "compared"),
    "grid": ("start", "step", "samples", "duration"),
    "initial": INDEPENDENT_COORDINATES + RATES + DEPENDENT_COORDINATES,
    "inputs": ("torques", "csv", "interpolation"),
    "motion": ("function",),
    "solver": ("constraints", "baumgarte", "fall_limit"),
    "expected_differences": ("quantity", "engines", "expected", "reason"),
}
_FORWARD_ONLY = ("initial", "inputs", "solver")
_INVERSE_ONLY = ("motion",)


class ScenarioFileError(ValueError):
    """An invalid scenario file: ``<file>: <key>: <problem>; fix: <fix>`` on one line."""

    def __init__(self, file: str, key: str, problem: str, fix: str) -> None:
        self.file, self.key, self.problem, self.fix = str(file), key, problem, fix
        super().__init__(" ".join(f"{self.file}: {key}: {problem}; fix: {fix}".split()))

    def __reduce__(self):
        return (type(self), (self.file, self.key, self.problem, self.fix))


def _closest(word: str, pool) -> str | None:
    match = difflib.get_close_matches(word, list(pool), n=1, cutoff=0.6)
    return match[0] if match else None


class _Reader:
    """Typed access to the parsed document, each error naming file and key."""

    def __init__(self, file: str, data: dict[str, Any]):
        self.file, self.data = file, data

    def fail(self, key: str, problem: str, fix: str):
        raise ScenarioFileError(self.file, key, problem, fix)

    def require(self, name: str) -> None:
        """Refuse a document without the table ``name`` (every table is a table here:
        `_check_keys` refused any other value first)."""
        if name not in self.data:
            self.fail(name, f"table [{name}] is missing",
                      f"add [{name}] with " + ", ".join(_KEYS[name][:3]))

    def string(self, table: str, key: str, choices=None, default=None) -> str:
        section = self.data.get(table, {})
        if key not in section:
            if default is not None:
                return default
            self.fail(f"{table}.{key}", f"required key {key!r} is missing",
                      f'add {key} = "..." to [{table}]')
        value = section[key]
        if not isinstance(value, str):
            self.fail(f"{table}.{key}", f"{value!r} is not a string", f'write {key} = "..."')
        if choices is not None and value not in choices:
            hint = _closest(value, choices)
            self.fail(f"{table}.{key}", f"unknown {key} {value!r}",
                      (f"did you mean {hint!r}? " if hint else "")
                      + "use one of " + ", ".join(repr(c) for c in choices))
        return value

    def number(self, table: str, key: str, default: float | None = None, *, unit: str,
               positive: bool = False) -> float:
        section = self.data.get(table, {})
        if key not in section:
            if default is not None:
                return default
            self.fail(f"{table}.{key}", f"required key {key!r} is missing",
                      f"add {key} = <number> ({unit}) to [{table}]")
        value = section[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(f"{table}.{key}", f"{value!r} is not a finite number",
                      f"write a number in {unit}")
        if positive and not value > 0:
            self.fail(f"{table}.{key}", f"{key} = {value!r} must be > 0",
                      f"use a positive value in {unit}")
        return float(value)

    def strings(self, table: str, key: str, choices=None) -> tuple[str, ...]:
        value = self.data[table].get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            self.fail(f"{table}.{key}", f"{value!r} is not a list of strings",
                      f'write {key} = ["...", "..."]')
        for v in value:
            if choices is not None and v not in choices:
                hint = _closest(v, choices)
                self.fail(f"{table}.{key}", f"unknown entry {v!r}",
                          (f"did you mean {hint!r}? " if hint else "")
                          + "use entries from " + ", ".join(choices))
        return tuple(value)


def _check_keys(r: _Reader) -> None:
    for table, value in r.data.items():
        if table not in _KEYS:
            hint = _closest(table, _KEYS)
            r.fail(table, f"unknown table [{table}]",
                   (f"did you mean [{hint}]? " if hint else "remove it; ")
                   + "valid tables are " + ", ".join(_KEYS))
        rows = value if table == "expected_differences" else [value]
        if table == "expected_differences" and not (
                isinstance(value, list) and all(isinstance(v, dict) for v in value)):
            r.fail(table, "expected_differences must be an array of tables",
                   "write each as [[expected_differences]]")
        for row in rows:
            if not isinstance(row, dict):
                r.fail(table, f"{table!r} must be a table", f"write it as [{table}]")
            for key in row:
                if key not in _KEYS[table]:
                    hint = _closest(key, _KEYS[table])
                    r.fail(f"{table}.{key}", f"unknown key {key!r} in [{table}]",
                           (f"did you mean {hint!r}? " if hint else "remove it; ")
                           + f"valid keys are {', '.join(_KEYS[table])}")


def _grid(r: _Reader) -> tuple[float, float, int]:
    r.require("grid")
    start = r.number("grid", "start", 0.0, unit="s")
    step = r.number("grid", "step", positive=True, unit="s")
    section = r.data["grid"]
    if ("samples" in section) == ("duration" in section):
        r.fail("grid.samples", "give exactly one of samples and duration",
               "write samples = <count> (e.g. 629) or duration = <seconds>")
    if "samples" in section:
        n = section["samples"]
        if isinstance(n, bool) or not isinstance(n, int) or n < 2:
            r.fail("grid.samples", f"{n!r} is not a whole number >= 2",
                   "write the number of output samples, e.g. samples = 629")
        return start, step, n
    duration = r.number("grid", "duration", positive=True, unit="s")
    n = round(duration / step)
    if abs(n * step - duration) > 1e-9 * max(1.0, duration):
        r.fail("grid.duration", f"duration {duration!r} s is not a whole number of steps "
               f"({duration / step!r} steps of {step!r} s)",
               f"use duration = {n * step!r} or samples = {n + 1}")
    return start, step, n + 1


def _torques(r: _Reader, base: Path, grid: tuple[float, float, int]):
    section = r.data["inputs"]
    given = [k for k in ("torques", "csv") if k in section]
    if len(given) != 1:
        r.fail("inputs.torques", "give exactly one of torques (constant or named function) "
               "and csv (samples)",
               'write torques = { Mdir = 0.0, Mped = 1.0, Mvue = 0.0 }, torques = "zigzag" '
               'or csv = "torques.csv" with interpolation = "cubic"')
    if "interpolation" in section and "csv" not in section:
        r.fail("inputs.interpolation", "interpolation applies to csv samples only",
               "remove it, or give csv = \"...\"")
    if "csv" in section:
        return _csv_torques(r, base, grid)
    value = section["torques"]
    if isinstance(value, str):
        return r.string("inputs", "torques", TORQUE_FUNCTIONS)
    if not isinstance(value, dict):
        r.fail("inputs.torques", f"{value!r} is neither a table of constant torques nor a "
               "function name", 'write torques = { Mdir = 0.0, Mped = 1.0, Mvue = 0.0 }')
    for key in value:
        if key not in TORQUES:
            hint = _closest(key, TORQUES)
            r.fail(f"inputs.torques.{key}", f"unknown torque {key!r}",
                   (f"did you mean {hint!r}? " if hint else "")
                   + "the rider torques are Mdir (steer), Mped (pedal), Mvue (roll)")
    sub = _Reader(r.file, {"inputs.torques": value})
    return tuple(sub.number("inputs.torques", k, 0.0, unit="N m") for k in TORQUES)


def _csv_torques(r: _Reader, base: Path, grid) -> TorqueSamples:
    name = r.string("inputs", "csv")
    interpolation = r.string("inputs", "interpolation", tuple(INTERPOLATIONS))
    path = base / name                   # an absolute name stays itself (pathlib's join)
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            reader = csv.reader(handle)      # blank lines skipped, each row with its line number
            rows = [(reader.line_num, row) for row in reader if any(c.strip() for c in row)]
    except OSError as exc:
        r.fail("inputs.csv", f"cannot read {str(path)!r}: {exc.strerror or exc}",
               "give the path of a CSV file relative to the scenario file")
    header = [c.strip() for c in rows[0][1]] if rows else []
    if header != ["t", *TORQUES]:
        r.fail("inputs.csv", f"{path.name}: header {header!r} is not t, Mdir, Mped, Mvue",
               "make the first line 't,Mdir,Mped,Mvue' (s, then N m)")
    data = []
    for number, row in rows[1:]:
        try:
            values = [float(c) for c in row]
        except ValueError:
            values = []
        if len(values) != 4 or not all(math.isfinite(v) for v in values):
            r.fail("inputs.csv", f"{path.name} line {number}: {row!r} is not four finite numbers",
                   "write t,Mdir,Mped,Mvue as numbers on every line")
        data.append(values)
    t = np.array([row[0] for row in data])
    if len(t) < (4 if interpolation == "cubic" else 2) or np.any(np.diff(t) <= 0):
        r.fail("inputs.csv", f"{path.name}: times must be strictly increasing, with at least "
               f"{4 if interpolation == 'cubic' else 2} samples for {interpolation!r}",
               "sort the rows by t and remove repeated times")
    start, step, n = grid
    end = start + step * (n - 1)
    if t[0] > start or t[-1] < end - 1e-12 * max(1.0, abs(end)):
        r.fail("inputs.csv", f"{path.name}: samples cover [{float(t[0])!r}, {float(t[-1])!r}] s, the run "
               f"[{start!r}, {end!r}] s", "give samples over the whole run (no extrapolation)")
    return TorqueSamples(t=tuple(float(x) for x in t),
                         T=tuple(tuple(float(x) for x in row[1:]) for row in data),
                         interpolation=interpolation, source=str(path))


def _model(r: _Reader, base: Path) -> str:
    model = r.string("scenario", "model", default="thesis")
    if model in NAMED_MODELS:
        return model
    path = base / model                  # an absolute path stays itself
    if not path.is_file():
        hint = _closest(model, NAMED_MODELS)
        r.fail("scenario.model", f"{model!r} is neither a named model nor an existing file "
               f"({path})", (f"did you mean {hint!r}? " if hint else "")
               + f"use one of {', '.join(NAMED_MODELS)} or a parameter file path relative to "
               "the scenario file")
    return str(path)


def scenario_from_mapping(data: dict[str, Any], *, source: str = "<memory>",
                          base: Path | None = None) -> Scenario:
    """Validate a parsed scenario document (format in the module docstring). Relative paths
    (model, csv) are taken from ``base`` (default: the current folder)."""
    r = _Reader(str(source), data)
    base = Path(".") if base is None else base
    _check_keys(r)
    r.require("scenario")
    kind = r.string("scenario", "kind", ("forward", "inverse"))
    wrong = _INVERSE_ONLY if kind == "forward" else _FORWARD_ONLY
    for table in wrong:
        if table in data:
            r.fail(table, f"[{table}] does not apply to {'an' if kind == 'inverse' else 'a'} "
                   f"{kind} scenario",
                   f"remove [{table}] or set kind = \"{'inverse' if kind == 'forward' else 'forward'}\"")
    grid = _grid(r)
    fields: dict[str, Any] = dict(
        name=r.string("scenario", "name"), description=r.string("scenario", "description"),
        kind=kind, model=_model(r, base), grid=grid,
        thesis_claim=r.string("scenario", "claim", default=""),
        tags=r.strings("scenario", "tags"),
        compared=r.strings("scenario", "compared", tuple(QUANTITIES)),
    )
    if kind == "inverse":
        r.require("motion")
        fields["motion"] = MOTIONS[r.string("motion", "function", tuple(MOTIONS))]
    else:
        r.require("initial")
        q = {c: r.number("initial", c, 0.0, unit="rad" if c not in ("xc", "yc") else "m")
             for c in COORDINATE_ORDER}
        fields["q0"] = tuple(q[c] for c in COORDINATE_ORDER)
        fields["dq_ind0"] = tuple(r.number("initial", k, 0.0, unit="rad/s") for k in RATES)
        r.require("inputs")
        fields["torques"] = _torques(r, base, grid)
        fields["constraints"] = r.string("solver", "constraints", CONSTRAINT_HANDLING,
                                         default="baumgarte")
        a = r.data.get("solver", {}).get("baumgarte", list(THESIS_BAUMGARTE))
        if not (isinstance(a, list) and len(a) == 2 and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                and x >= 0 for x in a)):
            r.fail("solver.baumgarte", f"{a!r} is not two non-negative numbers",
                   "write baumgarte = [10.0, 10.0] (a1, a2)")
        fields["baumgarte"] = (float(a[0]), float(a[1]))
        fields["fall_limit"] = r.number("solver", "fall_limit", DEFAULT_FALL_LIMIT,
                                        positive=True, unit="rad")
    rows = data.get("expected_differences", [])
    diffs = []
    for i, row in enumerate(rows):
        sub = _Reader(r.file, {f"expected_differences[{i}]": row})
        diffs.append(ExpectedDifference(*(sub.string(f"expected_differences[{i}]", k)
                                          for k in _KEYS["expected_differences"])))
    fields["expected_differences"] = tuple(diffs)
    return Scenario(**fields)                      # an empty `compared`: the kind's default


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and validate a scenario file (one :class:`ScenarioFileError` per problem)."""
    file = os.fspath(path)
    try:
        text = Path(file).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioFileError(file, "(file)", "no such file",
                                "give the path of an existing .toml scenario file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioFileError(file, "(file)", f"cannot read the file: {exc}",
                                "give a readable UTF-8 .toml file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioFileError(file, "(syntax)", f"invalid TOML: {exc}",
                                "correct the TOML syntax on that line") from None
    return scenario_from_mapping(data, source=file, base=Path(file).resolve().parent)


def load_builtin_scenarios() -> dict[str, Scenario]:
    """The built-in scenarios (package data), by name, in the order of their files' index."""
    order = json.loads((BUILTIN_DIR / "index.json").read_text(encoding="utf-8"))
    out = {}
    for stem in order:
        sc = load_scenario(BUILTIN_DIR / f"{stem}.toml")
        if sc.name != stem:
            raise ScenarioFileError(str(BUILTIN_DIR / f"{stem}.toml"), "scenario.name",
                                    f"name {sc.name!r} differs from the file name",
                                    "name the file after the scenario")
        out[sc.name] = sc
    return out


# -- writer ------------------------------------------------------------------------------------

def _s(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)


def _f(x: float) -> str:
    return repr(float(x))


def scenario_toml_text(sc: Scenario, *, comment: str = "") -> str:
    """The scenario as a file of this format (floats by repr: exact), headed by ``comment``
    lines. A scenario whose torques are samples refers to its CSV by the path it was read
    from."""
    default_compared = INVERSE_QUANTITIES if sc.kind == "inverse" else FORWARD_QUANTITIES
    lines = [f"# {line}".rstrip() for line in comment.splitlines()]
    lines += ["[scenario]", f"name = {_s(sc.name)}", f"description = {_s(sc.description)}",
             f"kind = {_s(sc.kind)}", f"model = {_s(sc.model)}"]
    if sc.thesis_claim:
        lines.append(f"claim = {_s(sc.thesis_claim)}")
    if sc.tags:
        lines.append(f"tags = [{', '.join(_s(t) for t in sc.tags)}]")
    if tuple(sc.compared) != tuple(default_compared):
        lines.append(f"compared = [{', '.join(_s(c) for c in sc.compared)}]")
    start, step, n = sc.grid
    lines += ["", "[grid]", f"start = {_f(start)}", f"step = {_f(step)}", f"samples = {int(n)}"]
    if sc.kind == "inverse":
        name = next((k for k, m in MOTIONS.items() if m == sc.motion), None)
        if name is None:
            raise ValueError(f"scenario {sc.name!r}: its motion is not a named one "
                             f"({', '.join(MOTIONS)}); it cannot be written")
        lines += ["", "[motion]", f"function = {_s(name)}   # {MOTIONS[name].description}"]
    else:
        lines += ["", "[initial]"]
        lines += [f"{c} = {_f(v)}" for c, v in zip(COORDINATE_ORDER, sc.q0)
                  if c in INDEPENDENT_COORDINATES or v != 0.0]
        lines += [f"{k} = {_f(v)}" for k, v in zip(RATES, sc.dq_ind0)]
        lines += ["", "[inputs]"]
        if isinstance(sc.torques, str):
            lines.append(f"torques = {_s(sc.torques)}")
        elif isinstance(sc.torques, TorqueSamples):
            lines += [f"csv = {_s(sc.torques.source)}",
                      f"interpolation = {_s(sc.torques.interpolation)}"]
        else:
            lines.append("torques = { " + ", ".join(f"{k} = {_f(v)}" for k, v in
                                                    zip(TORQUES, sc.torques)) + " }")
        lines += ["", "[solver]", f"constraints = {_s(sc.constraints)}",
                  f"baumgarte = [{_f(sc.baumgarte[0])}, {_f(sc.baumgarte[1])}]",
                  f"fall_limit = {_f(sc.fall_limit)}"]
    for d in sc.expected_differences:
        lines += ["", "[[expected_differences]]", f"quantity = {_s(d.quantity)}",
                  f"engines = {_s(d.engines)}", f"expected = {_s(d.expected)}",
                  f"reason = {_s(d.reason)}"]
    return "\n".join(lines) + "\n"
