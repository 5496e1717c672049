"""Scenario files (issue 13): the built-in scenarios as TOML package data, loaded the same way
as a user's file (the registry is read from them), equal to the scenarios written in Python
(tests/python_scenarios.py) field by field; torque samples from a CSV with a named
interpolation; one-line errors naming key, problem and fix."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from python_scenarios import PYTHON_SCENARIOS
from scenario_text import FORWARD, write
from reference_model.scenario_files import (BUILTIN_DIR, ScenarioFileError, load_builtin_scenarios,
                                            load_scenario, scenario_toml_text)
from reference_model.scenarios import (SCENARIOS, MOTIONS, Scenario, TorqueSamples, run_forward,
                                       torque_input)


def test_builtin_files_equal_the_python_statement_field_by_field():
    """The registry is read from the files; the scenarios written in Python (the registry as it
    was, tests/python_scenarios.py) are the independent statement they must equal."""
    loaded = load_builtin_scenarios()
    assert list(loaded) == list(PYTHON_SCENARIOS)
    for name, sc in PYTHON_SCENARIOS.items():
        for f in dataclasses.fields(Scenario):
            assert getattr(loaded[name], f.name) == getattr(sc, f.name), (name, f.name)
    assert sorted(p.stem for p in BUILTIN_DIR.glob("*.toml")) == sorted(PYTHON_SCENARIOS)


def test_the_registry_is_the_files():
    assert SCENARIOS == load_builtin_scenarios()


def test_writer_and_loader_round_trip(tmp_path):
    for sc in SCENARIOS.values():
        assert load_scenario(write(tmp_path, scenario_toml_text(sc))) == sc


def test_a_user_scenario_defaults_and_runs(tmp_path, thesis):
    sc = load_scenario(write(tmp_path, FORWARD))
    assert sc.grid == (0.0, 0.01, 51) and sc.model == "thesis"
    assert sc.q0 == (0, 0, 0, 0.1, 0, 0, 0, 0) and sc.dq_ind0 == (0.0, 5.0, 0.0)
    assert sc.torques == (0.0, 1.0, 0.0) and sc.constraints == "baumgarte"
    assert sc.compared == ("mass_matrix", "trajectory", "constraint_residual")
    traj = run_forward(thesis, sc)
    assert traj.status == "completed" and traj.t[-1] == pytest.approx(0.5)
    # the fall limit is the file's: theta starts at 0.1 rad, a limit of 0.05 stops at once
    early = load_scenario(write(tmp_path, FORWARD + "\n[solver]\nfall_limit = 0.05\n"))
    assert early.fall_limit == 0.05 and run_forward(thesis, early).status == "fell"


def test_csv_samples_and_their_interpolation(tmp_path, thesis):
    t = [float(x) for x in np.linspace(0.0, 0.6, 7)]
    rows = ["t,Mdir,Mped,Mvue"] + [f"{x!r},{x**3!r},1.0,{-x!r}" for x in t]
    (tmp_path / "T.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    text = FORWARD.replace("torques = { Mped = 1.0 }", 'csv = "T.csv"\ninterpolation = "{}"')
    s = np.array([0.05, t[2], 0.23, t[5]])           # between samples and on them
    held = np.array([t[0], t[2], t[2], t[5]])         # the sample at or before each time
    expected = {                       # independent: the exact functions the samples come from
        "cubic": np.stack([s**3, 1 + 0 * s, -s], axis=-1),      # not-a-knot is exact on cubics
        "linear": np.stack([np.interp(s, t, np.array(t) ** 3), 1 + 0 * s, -s], axis=-1),
        "previous": np.stack([held**3, 1 + 0 * s, -held], axis=-1),
    }
    for kind, want in expected.items():
        sc = load_scenario(write(tmp_path, text.format(kind)))
        assert isinstance(sc.torques, TorqueSamples) and sc.torques.interpolation == kind
        got = torque_input(thesis, sc)(s)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13, err_msg=kind)
    # constant samples run exactly like the constant torques
    (tmp_path / "C.csv").write_text("t,Mdir,Mped,Mvue\n0,0,1,0\n1,0,1,0\n", encoding="utf-8")
    const = load_scenario(write(tmp_path, text.replace("T.csv", "C.csv").format("linear")))
    a, b = run_forward(thesis, const), run_forward(thesis, load_scenario(write(tmp_path, FORWARD)))
    np.testing.assert_array_equal(a.q, b.q)


@pytest.mark.parametrize("edit, pattern", [
    (lambda t: t.replace("[grid]", "[grd]"), r"grd: unknown table \[grd\]; fix: did you mean \[grid\]"),
    (lambda t: t.replace('name = "mine"\n', ""), r"scenario\.name: required key 'name' is missing"),
    (lambda t: t.replace('"forward"', '"froward"'), r"scenario\.kind: unknown kind 'froward'; fix: did you mean 'forward'"),
    (lambda t: t.replace("duration = 0.5", "duration = 0.505"), r"grid\.duration: .*not a whole number of steps"),
    (lambda t: t.replace("duration = 0.5", "duration = 0.5\nsamples = 10"), r"grid\.samples: give exactly one of samples and duration"),
    (lambda t: t.replace("step = 0.01", "step = 0"), r"grid\.step: step = 0 must be > 0"),
    (lambda t: t.replace("{ Mped = 1.0 }", "{ Mpde = 1.0 }"), r"inputs\.torques\.Mpde: unknown torque 'Mpde'; fix: did you mean 'Mped'"),
    (lambda t: t.replace("{ Mped = 1.0 }", '"zigzog"'), r"inputs\.torques: unknown torques 'zigzog'; fix: did you mean 'zigzag'"),
    (lambda t: t.replace("{ Mped = 1.0 }", '{ Mped = "1" }'), r"inputs\.torques\.Mped: '1' is not a finite number"),
    (lambda t: t + '\n[motion]\nfunction = "zigzag"\n', r"motion: \[motion\] does not apply to a forward scenario"),
    (lambda t: t.replace("theta = 0.1", "tehta = 0.1"), r"initial\.tehta: unknown key 'tehta'.*did you mean 'theta'"),
    (lambda t: t.replace('kind = "forward"', 'kind = "forward"\nmodel = "thesys"'), r"scenario\.model: 'thesys' is neither a named model.*did you mean 'thesis'"),
    (lambda t: t.replace('kind = "forward"', 'kind = "forward"\ncompared = ["trajectories"]'), r"scenario\.compared: unknown entry 'trajectories'.*did you mean 'trajectory'"),
    (lambda t: t.replace("torques = { Mped = 1.0 }", 'csv = "none.csv"\ninterpolation = "linear"'), r"inputs\.csv: cannot read"),
    (lambda t: t.replace("torques = { Mped = 1.0 }", 'csv = "short.csv"\ninterpolation = "linear"'), r"inputs\.csv: short\.csv: samples cover \[0\.0, 0\.2\] s, the run \[0\.0, 0\.5\] s"),
    (lambda t: t.replace("torques = { Mped = 1.0 }", 'csv = "short.csv"\ninterpolation = "spline"'), r"inputs\.interpolation: unknown interpolation 'spline'"),
    (lambda t: t + "\n[solver]\nbaumgarte = [10]\n", r"solver\.baumgarte: \[10\] is not two non-negative numbers"),
    (lambda t: t.replace("dpsi = 5.0", "dpsi = 5.0\ndpsi = 6.0"), r"\(syntax\): invalid TOML"),
])
def test_bad_scenario_files_are_one_line_errors(tmp_path, edit, pattern):
    (tmp_path / "short.csv").write_text("t,Mdir,Mped,Mvue\n0,0,0,0\n0.2,0,0,0\n", encoding="utf-8")
    with pytest.raises(ScenarioFileError, match=pattern) as info:
        load_scenario(write(tmp_path, edit(FORWARD)))
    assert "\n" not in str(info.value) and "; fix: " in str(info.value)


def test_inverse_scenario_file(tmp_path):
    text = ('[scenario]\nname = "z"\ndescription = "d"\nkind = "inverse"\n[grid]\nstep = 0.01\n'
            'samples = 629\n[motion]\nfunction = "zigzag"\n')
    sc = load_scenario(write(tmp_path, text))
    assert sc.motion is MOTIONS["zigzag"] and sc.compared == SCENARIOS["zigzag"].compared
    assert math.isclose(sc.duration, 6.28)
    with pytest.raises(ScenarioFileError, match=r"initial: \[initial\] does not apply to an? inverse"):
        load_scenario(write(tmp_path, text + "[initial]\ntheta = 0.1\n"))
