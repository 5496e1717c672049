"""Tests of the `bicycle-xval` command line (comparisons/cli.py).

In-process through `comparisons.cli.main([...])` (output captured by capsys), and in a real
subprocess for the exit status the shell sees. Expected column names, scenario and model
names come from the model's description (docs/model.md) and the CLI's
documented contract, not from the code's own lists.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from comparisons.cli import main


ROOT = Path(__file__).resolve().parents[1]
COORDINATES = ["xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps"]   # thesis order
STATE_COLUMNS = (["t"] + COORDINATES + [f"d_{n}" for n in COORDINATES]
                 + [f"dd_{n}" for n in COORDINATES])
SCENARIO_NAMES = ["check", "zigzag", "replay", "stability-psid0", "stability-psid1",
                  "stability-psid5", "stability-psid10", "check-forward",
                  "benchmark-v4", "benchmark-v4.6", "benchmark-v8"]
THESIS_DPHI0 = -0.035520618556701   # the thesis's forward dq0[3] (listing, 15 decimals)


def run(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(err):
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("bicycle-xval: error: "), err
    return lines[0]


# --------------------------------------------------------------------------------------------
# data files
# --------------------------------------------------------------------------------------------
def test_inverse_dynamics_writes_the_documented_csv(tmp_path, capsys):
    out = tmp_path / "zigzag.csv"
    code, stdout, err = run(capsys, "inverse-dynamics", "--model", "thesis", "--scenario",
                            "zigzag", "--out", out)
    assert code == 0, err
    assert str(out) in stdout
    frame = pd.read_csv(out)
    expected = (STATE_COLUMNS + ["Mdir", "Mped", "Mvue"]
                + [f"lambda_{k}" for k in range(1, 6)])
    assert list(frame.columns) == expected
    assert len(frame) == 629                                  # t = 0:0.01:2*pi
    # 0.01 k written as its shortest exact decimal: exact to an ulp of 2 pi
    np.testing.assert_allclose(frame["t"], 0.01 * np.arange(629), rtol=0, atol=1e-15)
    assert np.all(np.isfinite(frame.to_numpy()))
    # full precision survives the file: the thesis's printed dphi(0) to its 15 decimals
    assert frame["d_phi"].iloc[0] == pytest.approx(THESIS_DPHI0, abs=1e-14)
    np.testing.assert_allclose(frame["theta"], -np.sin(frame["t"]) / 3, rtol=0, atol=1e-14)


def test_simulate_writes_the_documented_csv(tmp_path, capsys):
    out = tmp_path / "sub" / "psid10.csv"   # the folder is created
    code, stdout, err = run(capsys, "simulate", "--model", "thesis", "--scenario",
                            "stability-psid10", "--out", out)
    assert code == 0, err
    frame = pd.read_csv(out)
    assert list(frame.columns) == STATE_COLUMNS + [f"C_{k}" for k in range(1, 6)]
    assert len(frame) >= 2
    assert np.all(np.isfinite(frame.to_numpy()))
    t = frame["t"].to_numpy()
    # the scenario grid 0.01 k, possibly ending with the event (a fall) between grid points
    n = len(t) - 1
    np.testing.assert_allclose(t[:n], 0.01 * np.arange(n), rtol=0, atol=1e-15)
    assert t[-1] > t[-2]
    assert "stability-psid10" in stdout


# --------------------------------------------------------------------------------------------
# usage errors: exit 2, one line on stderr naming the problem
# --------------------------------------------------------------------------------------------
def _bad_parameter_file(tmp_path):
    text = (ROOT / "reference_model" / "parameters" / "thesis.toml").read_text()
    line = next(ln for ln in text.splitlines() if ln.startswith("m3 "))
    bad = tmp_path / "negative_mass.toml"
    bad.write_text(text.replace(line, 'm3 = { value = -77.391, unit = "kg" }'))
    return bad


USAGE_ERRORS = {
    "unknown scenario": (["simulate", "--scenario", "no-such-scenario", "--out", "{out}"],
                         ["no-such-scenario"]),
    "unknown scenario (inverse)": (["inverse-dynamics", "--scenario", "no-such-scenario",
                                    "--out", "{out}"], ["no-such-scenario"]),
    "unknown model": (["simulate", "--model", "no-such-model", "--scenario", "replay",
                       "--out", "{out}"], ["no-such-model"]),
    "inverse scenario to simulate": (["simulate", "--scenario", "zigzag", "--out", "{out}"],
                                     ["zigzag", "inverse"]),
    "forward scenario to inverse-dynamics": (["inverse-dynamics", "--scenario", "replay",
                                              "--out", "{out}"], ["replay", "forward"]),
    "rtol out of range": (["simulate", "--scenario", "replay", "--rtol", "2", "--out", "{out}"],
                          ["--rtol"]),
    "rtol zero": (["simulate", "--scenario", "replay", "--rtol", "0", "--out", "{out}"],
                  ["--rtol"]),
    "rtol not a number": (["simulate", "--scenario", "replay", "--rtol", "abc", "--out",
                           "{out}"], ["--rtol", "abc"]),
    "bad fall limit": (["simulate", "--scenario", "replay", "--fall-limit", "-1", "--out",
                        "{out}"], ["--fall-limit"]),
    "bad constraints": (["simulate", "--scenario", "replay", "--constraints", "magic", "--out",
                         "{out}"], ["--constraints", "magic"]),
    "missing --out (simulate)": (["simulate", "--scenario", "replay"], ["--out"]),
    "missing --out (inverse-dynamics)": (["inverse-dynamics", "--scenario", "zigzag"],
                                         ["--out"]),
    "bad parameter file": (["simulate", "--model", "{bad}", "--scenario", "replay", "--out",
                            "{out}"], ["m3", "negative_mass.toml"]),
    # --build and --step are a fixed-step integrator's (engines.facts.FixedStep), worded from the
    # engine's facts: the reference declares none, Exudyn's variants are its two builds
    "--build without a fixed-step integrator": (
        ["simulate", "--scenario", "replay", "--build", "tree", "--out", "{out}"],
        ["--build and --step", "fixed-step integrator", "'reference' declares none"]),
    "--step without a fixed-step integrator": (
        ["simulate", "--scenario", "replay", "--step", "1e-3", "--out", "{out}"],
        ["fixed-step integrator", "'reference' declares none"]),
    "unknown --build": (["simulate", "--engine", "exudyn", "--scenario", "replay", "--build",
                         "nope", "--out", "{out}"], ["--build nope", "tree, redundant"]),
    "unknown subcommand": (["frobnicate"], ["frobnicate"]),
    "unknown scenario in run": (["run", "--scenarios", "check,no-such-scenario", "--out",
                                 "{dir}"], ["no-such-scenario"]),
}


@pytest.mark.parametrize("case", list(USAGE_ERRORS))
def test_usage_errors_exit_2_with_one_line(tmp_path, capsys, case):
    template, words = USAGE_ERRORS[case]
    subst = {"{out}": str(tmp_path / "out.csv"), "{dir}": str(tmp_path / "report"),
             "{bad}": str(_bad_parameter_file(tmp_path)) if case == "bad parameter file" else ""}
    args = [subst.get(a, a) for a in template]
    code, stdout, err = run(capsys, *args)
    assert code == 2, (code, err)
    line = one_line_error(err)
    for word in words:
        assert word in line, (word, line)
    assert stdout == ""
    assert not (tmp_path / "out.csv").exists()   # nothing written on a usage error


def test_build_and_step_are_the_fixed_step_integrator_s_options():
    """``--build V --step h`` become the engine's declared variant's options and its step
    option (docs/engines.md: Exudyn's build='redundant', step=h). Planted: the step passed
    under any other name than the declared option fails."""
    import argparse

    from comparisons.cli.main import _fixed_step_options
    from engines.facts import engine_facts
    fixed = engine_facts("exudyn").fixed_step
    args = argparse.Namespace(engine="exudyn", build="redundant", step=2e-3)
    assert _fixed_step_options(args, fixed) == {"build": "redundant", "step": 2e-3}
    assert _fixed_step_options(argparse.Namespace(engine="x", build=None, step=None), None) == {}


def test_run_sections_help_lists_the_pipeline_s_sections():
    from comparisons.cli.main import build_parser
    from comparisons.stages.pipeline import SECTIONS
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["run"]
    help_text = " ".join(sub.format_help().split())
    assert ", ".join(SECTIONS) in help_text


# --------------------------------------------------------------------------------------------
# listings
# --------------------------------------------------------------------------------------------
def test_scenarios_lists_every_scenario(capsys):
    code, stdout, err = run(capsys, "scenarios")
    assert code == 0, err
    first_words = [ln.split()[0] for ln in stdout.strip().splitlines()]
    assert sorted(first_words) == sorted(SCENARIO_NAMES)
    kinds = {ln.split()[0]: ln.split()[1] for ln in stdout.strip().splitlines()}
    assert kinds["check"] == kinds["zigzag"] == "inverse"
    assert all(kinds[n] == "forward" for n in SCENARIO_NAMES[2:])


def test_models_lists_thesis_and_disc(capsys):
    code, stdout, err = run(capsys, "models")
    assert code == 0, err
    rows = {ln.split()[0]: ln for ln in stdout.strip().splitlines()}
    assert {"thesis", "thesis-disc", "benchmark"} <= set(rows)
    assert "contact=disc" in rows["benchmark"]
    assert "contact=thesis" in rows["thesis"]
    assert "contact=disc" in rows["thesis-disc"]


# --------------------------------------------------------------------------------------------
# the report
# --------------------------------------------------------------------------------------------
def test_run_quick_writes_the_report(quick_report):
    """The session's quick report (tests/conftest.py), run once for every report test."""
    out, code, _ = quick_report
    assert code == 0
    assert (out / "report.md").read_text().startswith("#")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenarios"] and all(s["status"] != "failed" for s in summary["scenarios"])
    csvs = sorted((out / "data").glob("*.csv"))
    pngs = sorted((out / "figures").glob("*.png"))
    assert csvs and pngs
    for f in csvs:
        frame = pd.read_csv(f)
        assert len(frame) >= 2 and list(frame.columns[:9]) == STATE_COLUMNS[:9], f.name
    for f in pngs:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f.name
    # every figure the report links exists
    report = (out / "report.md").read_text()
    for f in pngs:
        assert f"figures/{f.name}" in report


# --------------------------------------------------------------------------------------------
# a real process: the exit status the shell sees
# --------------------------------------------------------------------------------------------
def _command():
    exe = Path(sys.executable).parent / "bicycle-xval"
    if exe.exists():
        return [str(exe)]
    return [sys.executable, "-m", "comparisons.cli"]


@pytest.mark.parametrize("args, status", [
    (["scenarios"], 0),
    (["run", "--scenarios", "no-such-scenario", "--out", "{dir}"], 2),
])
def test_subprocess_exit_status(tmp_path, args, status):
    args = [str(tmp_path / "report") if a == "{dir}" else a for a in args]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    proc = subprocess.run(_command() + args, cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == status, proc.stderr
    if status == 0:
        names = [ln.split()[0] for ln in proc.stdout.strip().splitlines()]
        assert sorted(names) == sorted(SCENARIO_NAMES)
    else:
        line = one_line_error(proc.stderr)
        assert "no-such-scenario" in line
