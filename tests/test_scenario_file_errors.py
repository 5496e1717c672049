"""Every refusal of a scenario file, as the user reads it, and the edges of what is accepted
(reference_model/scenarios/files.py), issue 24.

The format's contract (its module docstring, docs/robustness.md): one ScenarioFileError per
problem, on one line, ``<file>: <key>: <problem>; fix: <fix>``, where the key is the table or
``table.key`` the user wrote and the fix says what to write instead. The expected messages are
written out here, whole, from that contract, so a message that loses its file, its key, its
problem or its fix fails; the behaviours behind them (which path a relative name is taken from,
the bounds of each number, what the writer leaves out) are checked against values worked out by
hand. Planted bugs each test was seen failing on are named in its docstring.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from scenario_text import FORWARD, write
from reference_model.parameters.loading import NAMED_MODELS
from reference_model.scenarios.files import (ScenarioFileError, load_builtin_scenarios,
                                             load_scenario, scenario_from_mapping,
                                             scenario_toml_text)
from reference_model.scenarios import (FORWARD_QUANTITIES, INVERSE_QUANTITIES, MOTIONS,
                                       QUANTITIES, SCENARIOS, ExpectedDifference, TorqueSamples)
from reference_model.scenarios import files as scenario_files


TABLES = "scenario, grid, initial, inputs, motion, solver, expected_differences"
INITIAL_KEYS = "theta, psi, gamma, dtheta, dpsi, dgamma, xc, yc, phi, beta, eps"
TORQUES_FIX = ('write torques = { Mdir = 0.0, Mped = 1.0, Mvue = 0.0 }, torques = "zigzag" or '
               'csv = "torques.csv" with interpolation = "cubic"')
RIDER = "the rider torques are Mdir (steer), Mped (pedal), Mvue (roll)"
CSV = 'csv = "T.csv"\ninterpolation = "{}"'


def refusal(path: Path) -> str:
    with pytest.raises(ScenarioFileError) as info:
        load_scenario(path)
    return str(info.value)


def csv_file(folder: Path, *lines: str, name: str = "T.csv") -> Path:
    path = folder / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def with_csv(interpolation: str = "linear", grid: str | None = None) -> str:
    text = FORWARD.replace("torques = { Mped = 1.0 }", CSV.format(interpolation))
    return text if grid is None else text.replace("step = 0.01\nduration = 0.5", grid)


# -- the document's tables and keys ------------------------------------------------------------

@pytest.mark.parametrize("edit, key, problem, fix", [
    (lambda t: t.replace("[grid]", "[grd]"), "grd", "unknown table [grd]",
     f"did you mean [grid]? valid tables are {TABLES}"),
    (lambda t: t + "\n[zzzz]\nx = 1\n", "zzzz", "unknown table [zzzz]",
     f"remove it; valid tables are {TABLES}"),
    (lambda t: t + '\n[expected_differences]\nquantity = "x"\n', "expected_differences",
     "expected_differences must be an array of tables", "write each as [[expected_differences]]"),
    (lambda t: "expected_differences = [1]\n" + t, "expected_differences",
     "expected_differences must be an array of tables", "write each as [[expected_differences]]"),
    (lambda t: "solver = 5\n" + t, "solver", "'solver' must be a table", "write it as [solver]"),
    (lambda t: t.replace("theta = 0.1", "zzz = 0.1"), "initial.zzz", "unknown key 'zzz' in [initial]",
     f"remove it; valid keys are {INITIAL_KEYS}"),
    (lambda t: t.replace("theta = 0.1", "tehta = 0.1"), "initial.tehta",
     "unknown key 'tehta' in [initial]", f"did you mean 'theta'? valid keys are {INITIAL_KEYS}"),
    (lambda t: t[t.index("[grid]"):], "scenario",
     "table [scenario] is missing", "add [scenario] with name, description, kind"),
    (lambda t: t[:t.index("[grid]")] + t[t.index("[initial]"):], "grid",
     "table [grid] is missing", "add [grid] with start, step, samples"),
    (lambda t: t[:t.index("[initial]")] + t[t.index("[inputs]"):], "initial",
     "table [initial] is missing", "add [initial] with theta, psi, gamma"),
    (lambda t: t[:t.index("[inputs]")], "inputs",
     "table [inputs] is missing", "add [inputs] with torques, csv, interpolation"),
    (lambda t: t + '\n[motion]\nfunction = "zigzag"\n', "motion",
     "[motion] does not apply to a forward scenario", 'remove [motion] or set kind = "inverse"'),
])
def test_each_table_refusal_names_the_table_and_the_fix(tmp_path, edit, key, problem, fix):
    """Planted (mutmut): the key or fix dropped (None), the fix's hint given with no close
    match (IndexError), "remove it; " lost, the table list joined wrongly, `or` for `and` in
    the array-of-tables check ([1] then refused as "must be a table"), the missing table's
    example keys [:4]."""
    path = write(tmp_path, edit(FORWARD))
    assert refusal(path) == f"{path}: {key}: {problem}; fix: {fix}"


def test_an_inverse_scenario_refuses_the_forward_tables_and_needs_its_motion(tmp_path):
    """Planted: the kind the fix suggests the same kind ('inverse' if ... or True), the
    [motion] table optional (then MOTIONS[...] of a missing key is a KeyError), the motion's
    choices dropped (an unknown one then a KeyError)."""
    text = ('[scenario]\nname = "z"\ndescription = "d"\nkind = "inverse"\n[grid]\nstep = 0.01\n'
            'samples = 629\n')
    for table in ("initial", "inputs", "solver"):
        path = write(tmp_path, text + '[motion]\nfunction = "zigzag"\n' + f"[{table}]\n")
        assert refusal(path) == (f"{path}: {table}: [{table}] does not apply to an inverse "
                                 f'scenario; fix: remove [{table}] or set kind = "forward"')
    path = write(tmp_path, text)
    assert refusal(path) == f"{path}: motion: table [motion] is missing; fix: add [motion] with function"
    path = write(tmp_path, text + '[motion]\nfunction = "zigzog"\n')
    assert refusal(path) == (f"{path}: motion.function: unknown function 'zigzog'; fix: did you "
                             "mean 'zigzag'? use one of 'check', 'zigzag'")


# -- strings, numbers, lists -------------------------------------------------------------------

@pytest.mark.parametrize("edit, key, problem, fix", [
    (lambda t: t.replace('name = "mine"\n', ""), "scenario.name", "required key 'name' is missing",
     'add name = "..." to [scenario]'),
    (lambda t: t.replace('name = "mine"', "name = 3"), "scenario.name", "3 is not a string",
     'write name = "..."'),
    (lambda t: t.replace('"forward"', '"froward"'), "scenario.kind", "unknown kind 'froward'",
     "did you mean 'forward'? use one of 'forward', 'inverse'"),
    (lambda t: t.replace('"forward"', '"zz"'), "scenario.kind", "unknown kind 'zz'",
     "use one of 'forward', 'inverse'"),
    (lambda t: t.replace('kind = "forward"', 'kind = "forward"\ntags = "x"'), "scenario.tags",
     "'x' is not a list of strings", 'write tags = ["...", "..."]'),
    (lambda t: t.replace('kind = "forward"', 'kind = "forward"\ntags = [1]'), "scenario.tags",
     "[1] is not a list of strings", 'write tags = ["...", "..."]'),
    (lambda t: t.replace('kind = "forward"', 'kind = "forward"\ncompared = ["trajectories"]'),
     "scenario.compared", "unknown entry 'trajectories'",
     "did you mean 'trajectory'? use entries from " + ", ".join(QUANTITIES)),
    (lambda t: t.replace('kind = "forward"', 'kind = "forward"\ncompared = ["zz"]'),
     "scenario.compared", "unknown entry 'zz'", "use entries from " + ", ".join(QUANTITIES)),
    (lambda t: t.replace("step = 0.01\n", ""), "grid.step", "required key 'step' is missing",
     "add step = <number> (s) to [grid]"),
    (lambda t: t.replace("step = 0.01", 'step = "a"'), "grid.step", "'a' is not a finite number",
     "write a number in s"),
    (lambda t: t.replace("step = 0.01", "step = true"), "grid.step", "True is not a finite number",
     "write a number in s"),
    (lambda t: t.replace("step = 0.01", "step = nan"), "grid.step", "nan is not a finite number",
     "write a number in s"),
    (lambda t: t.replace("step = 0.01", "step = -0.01"), "grid.step", "step = -0.01 must be > 0",
     "use a positive value in s"),
    (lambda t: t.replace("step = 0.01", "step = 0.01\nstart = \"x\""), "grid.start",
     "'x' is not a finite number", "write a number in s"),
    (lambda t: t.replace("duration = 0.5", "duration = -1"), "grid.duration",
     "duration = -1 must be > 0", "use a positive value in s"),
    (lambda t: t.replace("theta = 0.1", 'theta = "a"'), "initial.theta",
     "'a' is not a finite number", "write a number in rad"),
    (lambda t: t.replace("theta = 0.1", 'xc = "a"'), "initial.xc", "'a' is not a finite number",
     "write a number in m"),
    (lambda t: t.replace("theta = 0.1", 'yc = "a"'), "initial.yc", "'a' is not a finite number",
     "write a number in m"),
    (lambda t: t.replace("theta = 0.1", 'dgamma = "a"'), "initial.dgamma",
     "'a' is not a finite number", "write a number in rad/s"),
    (lambda t: t + '\n[solver]\nconstraints = "projektion"\n', "solver.constraints",
     "unknown constraints 'projektion'",
     "did you mean 'projection'? use one of 'baumgarte', 'projection', 'none'"),
    (lambda t: t + "\n[solver]\nfall_limit = 0\n", "solver.fall_limit", "fall_limit = 0 must be > 0",
     "use a positive value in rad"),
    (lambda t: t + '\n[solver]\nfall_limit = "x"\n', "solver.fall_limit",
     "'x' is not a finite number", "write a number in rad"),
])
def test_each_value_refusal_names_the_key_and_the_fix(tmp_path, edit, key, problem, fix):
    """Planted: units dropped or upper-cased (s, rad, m, rad/s), xc/yc read in rad, the
    positive checks of duration and fall_limit turned off, `and` for `or` in the list check
    ("x" then read as the list ['x']), the choices' hint forced."""
    path = write(tmp_path, edit(FORWARD))
    assert refusal(path) == f"{path}: {key}: {problem}; fix: {fix}"


def test_a_document_from_memory_is_named_memory_and_paths_are_from_the_current_folder(
        tmp_path, monkeypatch):
    """scenario_from_mapping's defaults: source "<memory>", base the current folder.
    Planted: the source dropped (None), base never defaulted (None / name), Path(None)."""
    import tomllib
    data = tomllib.loads(with_csv())
    with pytest.raises(ScenarioFileError) as info:
        scenario_from_mapping({**data, "grid": {}})
    assert str(info.value).startswith("<memory>: grid.step: ")
    csv_file(tmp_path, "t,Mdir,Mped,Mvue", "0,0,1,0", "1,0,1,0")
    monkeypatch.chdir(tmp_path)
    sc = scenario_from_mapping(data)
    assert sc.torques.source == "T.csv" and sc.torques.T == ((0.0, 1.0, 0.0), (0.0, 1.0, 0.0))


# -- the grid ----------------------------------------------------------------------------------

@pytest.mark.parametrize("grid, problem, fix", [
    ("step = 0.01\nduration = 0.5\nsamples = 10", "give exactly one of samples and duration",
     "write samples = <count> (e.g. 629) or duration = <seconds>"),
    ("step = 0.01", "give exactly one of samples and duration",
     "write samples = <count> (e.g. 629) or duration = <seconds>"),
    ("step = 0.01\nsamples = 1", "1 is not a whole number >= 2",
     "write the number of output samples, e.g. samples = 629"),
    ("step = 0.01\nsamples = 2.5", "2.5 is not a whole number >= 2",
     "write the number of output samples, e.g. samples = 629"),
    ("step = 0.01\nsamples = false", "False is not a whole number >= 2",
     "write the number of output samples, e.g. samples = 629"),
])
def test_the_grid_count_refusals(tmp_path, grid, problem, fix):
    """Planted: `and` for the second `or` (2.5 samples accepted), the fix dropped."""
    path = write(tmp_path, FORWARD.replace("step = 0.01\nduration = 0.5", grid))
    assert refusal(path) == f"{path}: grid.samples: {problem}; fix: {fix}"


def test_two_samples_are_the_fewest_and_a_duration_is_a_whole_number_of_steps(tmp_path):
    """samples = 2 is a grid (one step); 0.125 s is 1.25 steps of 0.1 s: the fix offers the
    nearest whole grid, 1 step = 0.1 s or 2 samples. Planted: n <= 2, n < 3, the steps
    computed as duration * step, the fix's n / step, n - 1 and n + 2."""
    ok = load_scenario(write(tmp_path, FORWARD.replace("duration = 0.5", "samples = 2")))
    assert ok.grid == (0.0, 0.01, 2)
    path = write(tmp_path, FORWARD.replace("step = 0.01\nduration = 0.5", "step = 0.1\nduration = 0.125"))
    assert refusal(path) == (f"{path}: grid.duration: duration 0.125 s is not a whole number of "
                             "steps (1.25 steps of 0.1 s); fix: use duration = 0.1 or samples = 2")


@pytest.mark.parametrize("duration, step, accepted", [
    ("0.3", "0.1", True),                     # 0.3 / 0.1 = 2.9999999999999996: round-off only
    ("0.5000000015", "0.01", False),          # 1.5e-9 s off a whole grid of 0.5 s: refused
    ("100.000000005", "0.01", True),          # 5e-9 s off 100 s: 5e-11 of it, accepted
])
def test_a_duration_is_whole_to_a_relative_1e_9(tmp_path, duration, step, accepted):
    """The tolerance is 1e-9 of the duration (at least 1e-9 s): round-off of a decimal step is
    accepted, a duration off by more is not. Planted: max(2.0, duration) (1.5e-9 accepted),
    1e-9 / max(...) (100 s refused at 5e-9)."""
    text = FORWARD.replace("step = 0.01\nduration = 0.5", f"step = {step}\nduration = {duration}")
    path = write(tmp_path, text)
    if accepted:
        sc = load_scenario(path)
        assert sc.grid[2] == round(float(duration) / float(step)) + 1
    else:
        assert "is not a whole number of steps" in refusal(path)


# -- torques -----------------------------------------------------------------------------------

@pytest.mark.parametrize("inputs, key, problem, fix", [
    ('torques = { Mped = 1.0 }\ncsv = "T.csv"', "inputs.torques",
     "give exactly one of torques (constant or named function) and csv (samples)", TORQUES_FIX),
    ("", "inputs.torques",
     "give exactly one of torques (constant or named function) and csv (samples)", TORQUES_FIX),
    ('torques = { Mped = 1.0 }\ninterpolation = "linear"', "inputs.interpolation",
     "interpolation applies to csv samples only", 'remove it, or give csv = "..."'),
    ("torques = 5", "inputs.torques",
     "5 is neither a table of constant torques nor a function name",
     "write torques = { Mdir = 0.0, Mped = 1.0, Mvue = 0.0 }"),
    ("torques = { Zzz = 1.0 }", "inputs.torques.Zzz", "unknown torque 'Zzz'", RIDER),
    ("torques = { Mpde = 1.0 }", "inputs.torques.Mpde", "unknown torque 'Mpde'",
     f"did you mean 'Mped'? {RIDER}"),
    ('torques = { Mped = "1" }', "inputs.torques.Mped", "'1' is not a finite number",
     "write a number in N m"),
    ("csv = 3", "inputs.csv", "3 is not a string", 'write csv = "..."'),
    ('csv = "T.csv"', "inputs.interpolation", "required key 'interpolation' is missing",
     'add interpolation = "..." to [inputs]'),
])
def test_each_torque_refusal(tmp_path, inputs, key, problem, fix):
    """Planted: the torque names lower-cased in a fix, the sub-table's reader without the
    file (None: ...), the hint forced with no close match."""
    path = write(tmp_path, FORWARD.replace("torques = { Mped = 1.0 }", inputs))
    assert refusal(path) == f"{path}: {key}: {problem}; fix: {fix}"


def test_a_named_torque_function_and_constant_torques_with_defaults(tmp_path):
    sc = load_scenario(write(tmp_path, FORWARD.replace("{ Mped = 1.0 }", '"zigzag"')))
    assert sc.torques == "zigzag"
    sc = load_scenario(write(tmp_path, FORWARD.replace("{ Mped = 1.0 }", "{ Mvue = -2 }")))
    assert sc.torques == (0.0, 0.0, -2.0)


@pytest.mark.parametrize("lines, problem", [
    ((), "header [] is not t, Mdir, Mped, Mvue"),
    (("t,Mdir,Mped",), "header ['t', 'Mdir', 'Mped'] is not t, Mdir, Mped, Mvue"),
    (("t,Mdir,Mped,Mvue", "0,0,0,0", "0.1,x,0,0"),
     "line 3: ['0.1', 'x', '0', '0'] is not four finite numbers"),
    (("t,Mdir,Mped,Mvue", "0,0,0,0", "0.1,0,0"), "line 3: ['0.1', '0', '0'] is not four finite numbers"),
    (("t,Mdir,Mped,Mvue", "0,0,0,0", "0.1,inf,0,0"),
     "line 3: ['0.1', 'inf', '0', '0'] is not four finite numbers"),
    (("t,Mdir,Mped,Mvue", "", "0,0,0,0", "  ,  ", "0.1,0,0"),
     "line 5: ['0.1', '0', '0'] is not four finite numbers"),
])
def test_csv_content_refusals_name_the_line_as_the_user_counts_it(tmp_path, lines, problem):
    """A line number is the file's (blank lines counted), as an editor shows it. Planted: the
    numbering from 3, or from 0; `and` for `or` (a short or infinite row accepted); values
    None (TypeError); the header read from an empty file (IndexError). Found by this test:
    the line was counted among the non-blank rows only (line 3 for the file's line 5)."""
    csv_file(tmp_path, *lines)
    path = write(tmp_path, with_csv())
    fix = ("write t,Mdir,Mped,Mvue as numbers on every line" if "line" in problem
           else "make the first line 't,Mdir,Mped,Mvue' (s, then N m)")
    assert refusal(path) == f"{path}: inputs.csv: T.csv{':' if 'header' in problem else ''} {problem}; fix: {fix}"


@pytest.mark.parametrize("interpolation, times, accepted", [
    ("linear", ("0.6",), False),
    ("linear", ("0", "0.6"), True),
    ("previous", ("0", "0.6"), True),
    ("cubic", ("0", "0.2", "0.6"), False),
    ("cubic", ("0", "0.2", "0.4", "0.6"), True),
    ("linear", ("0", "0.3", "0.3", "0.6"), False),
    ("cubic", ("0", "0.4", "0.2", "0.5", "0.6"), False),
])
def test_csv_times_increase_with_enough_samples_for_the_interpolation(
        tmp_path, interpolation, times, accepted):
    """A cubic spline (not-a-knot) needs 4 samples, a linear or held one 2; repeated or
    decreasing times are refused. Planted: 5 for 4, 3 for 2, 'cubic' never matched, `<` for
    `<=` (repeated times accepted), `and` for `or`, np.any(None)."""
    csv_file(tmp_path, "t,Mdir,Mped,Mvue", *(f"{t},0,0,0" for t in times))
    path = write(tmp_path, with_csv(interpolation))
    if accepted:
        sc = load_scenario(path)
        assert sc.torques.t == tuple(float(t) for t in times)
        assert sc.torques.source == str(tmp_path.resolve() / "T.csv")
    else:
        need = 4 if interpolation == "cubic" else 2
        assert refusal(path) == (
            f"{path}: inputs.csv: T.csv: times must be strictly increasing, with at least {need} "
            f"samples for {interpolation!r}; fix: sort the rows by t and remove repeated times")


@pytest.mark.parametrize("grid, first, last, accepted", [
    ("step = 0.01\nduration = 0.5", 0.1, 1.0, False),        # starts after the run does
    ("step = 0.01\nduration = 0.5", 0.0, 0.5 - 1e-13, True),  # round-off short of the end
    ("step = 0.01\nduration = 0.5", 0.0, 0.5 - 1.5e-12, False),
    ("step = 1.0\nsamples = 101", 0.0, 100.0 - 5e-11, True),   # 5e-13 of a 100 s run
])
def test_csv_samples_cover_the_run_to_a_relative_1e_12(tmp_path, grid, first, last, accepted):
    """No extrapolation: the samples must cover [start, end], the end to 1e-12 of it (at least
    1e-12 s). Planted: end + 1e-12, 1e-12 / max(...), max(2.0, ...), t[+1] for t[-1] in the
    message (three samples here)."""
    mid = (first + last) / 2
    csv_file(tmp_path, "t,Mdir,Mped,Mvue", *(f"{t!r},0,0,0" for t in (first, mid, last)))
    path = write(tmp_path, with_csv(grid=grid))
    if accepted:
        assert load_scenario(path).torques.t == (first, mid, last)
    else:
        end = 0.5
        assert refusal(path) == (
            f"{path}: inputs.csv: T.csv: samples cover [{first!r}, {last!r}] s, the run "
            f"[0.0, {end!r}] s; fix: give samples over the whole run (no extrapolation)")


def test_csv_paths_relative_to_the_scenario_file_or_absolute(tmp_path):
    """Planted: an absolute path joined to the scenario's folder anyway (Path(None)), the
    reading error's strerror dropped (`and`), the source left out of the samples."""
    elsewhere = tmp_path / "data"
    elsewhere.mkdir()
    csv_path = csv_file(elsewhere, "t,Mdir,Mped,Mvue", "0,0,1,0", "1,0,1,0", name="abs.csv")
    sc_dir = tmp_path / "scenarios"
    sc_dir.mkdir()
    sc = load_scenario(write(sc_dir, with_csv().replace('"T.csv"', json.dumps(str(csv_path)))))
    assert isinstance(sc.torques, TorqueSamples) and sc.torques.source == str(csv_path)
    path = write(sc_dir, with_csv())
    assert refusal(path) == (f"{path}: inputs.csv: cannot read {str(sc_dir.resolve() / 'T.csv')!r}: "
                             "No such file or directory; fix: give the path of a CSV file "
                             "relative to the scenario file")


# -- model, solver, expected differences -------------------------------------------------------

def test_a_model_is_named_or_a_file_beside_the_scenario_or_absolute(tmp_path):
    """Planted: an absolute path joined to the folder (`or True`), the relative one taken
    as absolute (`and False` ... inverted), str(None) returned, the hint forced, the list of
    named models joined wrongly, the fix's tail upper-cased."""
    (tmp_path / "bike.toml").write_text("", encoding="utf-8")
    other = tmp_path / "other"
    other.mkdir()
    text = FORWARD.replace('kind = "forward"', 'kind = "forward"\nmodel = "MODEL"').replace
    assert load_scenario(write(tmp_path, text("MODEL", "bike.toml"))).model == str(tmp_path.resolve() / "bike.toml")
    absolute = str(tmp_path / "bike.toml")
    assert load_scenario(write(other, text("MODEL", absolute))).model == absolute
    assert load_scenario(write(tmp_path, text("MODEL", "benchmark"))).model == "benchmark"
    named = ", ".join(NAMED_MODELS)
    for given, hint in (("zzzz", ""), ("thesys", "did you mean 'thesis'? ")):
        path = write(tmp_path, text("MODEL", given))
        assert refusal(path) == (
            f"{path}: scenario.model: {given!r} is neither a named model nor an existing file "
            f"({tmp_path.resolve() / given}); fix: {hint}use one of {named} or a parameter file "
            "path relative to the scenario file")


@pytest.mark.parametrize("value, accepted", [
    ("[0, 0]", (0.0, 0.0)), ("[5.0, 20]", (5.0, 20.0)), ("[10]", None), ("[-1, 1]", None),
    ("[true, 1]", None), ("[inf, 1]", None), ('["a", 1]', None), ("10", None),
])
def test_baumgarte_gains_are_two_non_negative_finite_numbers_in_order(tmp_path, value, accepted):
    """a1, a2 >= 0 (zero turns the stabilization off), finite, not booleans, kept in order.
    Planted: x > 0, x >= 1, a[1] for a[0], each `and` of the check turned into `or`, the fix
    dropped."""
    path = write(tmp_path, FORWARD + f"\n[solver]\nbaumgarte = {value}\n")
    if accepted is not None:
        assert load_scenario(path).baumgarte == accepted
    else:
        shown = {"[true, 1]": "[True, 1]", "[inf, 1]": "[inf, 1]"}.get(value, value.replace('"', "'"))
        assert refusal(path) == (f"{path}: solver.baumgarte: {shown} is not two non-negative "
                                 "numbers; fix: write baumgarte = [10.0, 10.0] (a1, a2)")


def test_expected_differences_are_read_in_order_and_each_row_is_named_by_its_index(tmp_path):
    """Planted: the row's reader without the file (None: ...), an empty `compared` kept
    instead of the kind's default."""
    row = '\n[[expected_differences]]\nquantity = "q{0}"\nengines = "e{0}"\nexpected = "x{0}"\nreason = "r{0}"\n'
    text = FORWARD.replace('kind = "forward"', 'kind = "forward"\ncompared = []')
    sc = load_scenario(write(tmp_path, text + row.format(0) + row.format(1)))
    assert sc.expected_differences == (ExpectedDifference("q0", "e0", "x0", "r0"),
                                       ExpectedDifference("q1", "e1", "x1", "r1"))
    assert sc.compared == FORWARD_QUANTITIES
    path = write(tmp_path, text + row.format(0) + row.format(1).replace('reason = "r1"\n', ""))
    assert refusal(path) == (f"{path}: expected_differences[1].reason: required key 'reason' is "
                             'missing; fix: add reason = "..." to [expected_differences[1]]')


# -- the file ----------------------------------------------------------------------------------

def test_file_refusals(tmp_path):
    """Planted: each of the three messages' file, key, problem or fix dropped or changed."""
    missing = tmp_path / "nope.toml"
    assert refusal(missing) == (f"{missing}: (file): no such file; fix: give the path of an "
                                "existing .toml scenario file")
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe[scenario]\n")
    assert refusal(binary) == (f"{binary}: (file): cannot read the file: 'utf-8' codec can't "
                               "decode byte 0xff in position 0: invalid start byte; fix: give a "
                               "readable UTF-8 .toml file")
    folder = tmp_path / "dir.toml"
    folder.mkdir()
    assert refusal(folder).startswith(f"{folder}: (file): cannot read the file: [Errno 21] ")
    assert refusal(folder).endswith("; fix: give a readable UTF-8 .toml file")
    bad = write(tmp_path, FORWARD.replace("theta = 0.1", "theta = 0.1\ntheta = 0.2"))
    message = refusal(bad)
    assert message.startswith(f"{bad}: (syntax): invalid TOML: ") and "line 12" in message
    assert message.endswith("; fix: correct the TOML syntax on that line")


def test_builtin_scenarios_follow_their_index_and_a_misnamed_file_is_refused(tmp_path, monkeypatch):
    """Planted: each field of the misnamed file's error dropped, BUILTIN_DIR * name."""
    base = FORWARD.replace('name = "mine"', 'name = "NAME"').replace
    write(tmp_path, base("NAME", "second"), "second.toml")
    write(tmp_path, base("NAME", "first"), "first.toml")
    (tmp_path / "index.json").write_text('["second", "first"]', encoding="utf-8")
    monkeypatch.setattr(scenario_files, "BUILTIN_DIR", tmp_path)
    assert list(load_builtin_scenarios()) == ["second", "first"]
    write(tmp_path, base("NAME", "third"), "first.toml")
    with pytest.raises(ScenarioFileError) as info:
        load_builtin_scenarios()
    assert str(info.value) == (f"{tmp_path / 'first.toml'}: scenario.name: name 'third' differs "
                               "from the file name; fix: name the file after the scenario")


# -- the writer --------------------------------------------------------------------------------

def test_the_writer_heads_with_the_comment_and_leaves_defaults_out(tmp_path):
    """What the writer leaves out is what the loader defaults: `compared` when it is the
    kind's default, a dependent coordinate at 0. Planted: the comment dropped (lines = ...),
    a default comment "XXXX", lstrip for rstrip (a blank comment line "# "), the compared
    test inverted, every kind's default taken as the forward one, dependent coordinates
    always written or zeros written (!= 1.0)."""
    sc = SCENARIOS["check-forward"]
    text = scenario_toml_text(sc, comment="made by a test\n\nthird line")
    assert text.startswith("# made by a test\n#\n# third line\n[scenario]\n")
    assert scenario_toml_text(sc).startswith("[scenario]\n")
    for built in SCENARIOS.values():
        written = scenario_toml_text(built)
        default = INVERSE_QUANTITIES if built.kind == "inverse" else FORWARD_QUANTITIES
        assert ("compared = " in written) == (tuple(built.compared) != default), built.name
        if built.kind == "forward":
            initial = written.split("[initial]\n")[1].split("\n\n")[0].splitlines()
            keys = [line.split(" = ")[0] for line in initial]
            dependent = [c for c, v in zip(("xc", "yc", "phi", "beta", "eps"),
                                           (built.q0[0], built.q0[1], built.q0[2], built.q0[5],
                                            built.q0[7])) if v != 0.0]
            assert keys == sorted(["theta", "psi", "gamma", *dependent],
                                  key=["xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps"].index) \
                + ["dtheta", "dpsi", "dgamma"], built.name
    narrowed = SCENARIOS["zigzag"].__class__(**{**SCENARIOS["zigzag"].__dict__, "compared": ("torques", "multipliers")})
    assert 'compared = ["torques", "multipliers"]' in scenario_toml_text(narrowed)


def test_the_writer_keeps_text_unescaped_the_gains_in_order_and_the_samples_file(tmp_path):
    """Planted: ensure_ascii on (Á written as \\u00c1), baumgarte[1] twice, the csv lines
    replacing the document (lines = ...), the source or interpolation written as null."""
    import dataclasses
    csv_path = csv_file(tmp_path, "t,Mdir,Mped,Mvue", "0,0,1,0", "10,0,1,0")
    sc = dataclasses.replace(
        SCENARIOS["check-forward"], description="Ángulo de dirección", baumgarte=(5.0, 20.0),
        torques=TorqueSamples(t=(0.0, 10.0), T=((0.0, 1.0, 0.0),) * 2, interpolation="previous",
                              source=str(csv_path)))
    text = scenario_toml_text(sc)
    assert 'description = "Ángulo de dirección"' in text and "baumgarte = [5.0, 20.0]" in text
    assert f"[inputs]\ncsv = {json.dumps(str(csv_path))}\ninterpolation = \"previous\"\n" in text
    assert text.startswith("[scenario]\n")
    assert load_scenario(write(tmp_path, text)) == sc


def test_an_unnamed_motion_cannot_be_written():
    """Planted: next(...) without its default (StopIteration), the message dropped or its
    list of motions joined wrongly."""
    import dataclasses
    motion = dataclasses.replace(MOTIONS["zigzag"], description="a motion of my own")
    sc = dataclasses.replace(SCENARIOS["zigzag"], motion=motion)
    with pytest.raises(ValueError) as info:
        scenario_toml_text(sc)
    assert str(info.value) == ("scenario 'zigzag': its motion is not a named one (check, zigzag); "
                               "it cannot be written")
