"""The reference as a Model-Exchange FMU (export --format fmu) and any such FMU as an engine
(engines/fmu). The FMU is built once per cache (gcc on the generated C, ~10 s cold) into the
code cache, as the generated code is, so a warm make test pays ~0.3 s for this file (fmpy's
validation, one instance, 12 states); the conformance suite on the FMU and the planted
parameter through diagnose are slow (subprocess / a second build)."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")

from engines.base import EngineSpecError   # noqa: E402
from fmu_builds import cached_fmu   # noqa: E402
from reference_model import load_model   # noqa: E402
from reference_model.exports import fmu as fmu_export   # noqa: E402
from reference_model.parameters.schema import PARAMETER_NAMES, PARAMETER_UNITS   # noqa: E402
from reference_model.solvers import consistent_state   # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: the engine by its module (the `fmu` name is its entry point, known once the package is
#: installed from this pyproject)
SPEC = "engines.fmu:FmuEngine"


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis")


@pytest.fixture(scope="module")
def thesis_fmu(thesis):
    return cached_fmu(thesis)


@pytest.fixture(scope="module")
def engine(thesis, thesis_fmu):
    from engines import load_engine
    return load_engine(SPEC, thesis, fmu=str(thesis_fmu))


def test_the_exported_fmu_passes_fmpys_validation_and_states_its_contract(thesis_fmu):
    """fmpy's own checks (schema, ModelStructure, start values, causality/variability, units)
    find nothing; the description states the Baumgarte constants; the thirty parameters are
    there by name and SI unit."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(thesis_fmu)) == []
    md = read_model_description(str(thesis_fmu))
    assert "Baumgarte" in md.description and "a1 = 10" in md.description
    assert md.modelExchange is not None and md.coSimulation is None
    variables = {v.name: v for v in md.modelVariables}
    si = {"m": "m", "kg": "kg", "kg*m^2": "kg.m2", "m/s^2": "m/s2", "kg/m": "kg/m"}
    for name in PARAMETER_NAMES:
        assert variables[name].causality == "parameter"
        assert variables[name].unit == si[PARAMETER_UNITS[name]], name
    assert [v.name for v in md.modelVariables if v.causality == "input"] == ["Mdir", "Mped", "Mvue"]
    assert len(md.derivatives) == 16
    with zipfile.ZipFile(thesis_fmu) as z:
        assert fmu_export.MAPPING_FILE in z.namelist()


def test_the_fmu_engine_agrees_with_the_reference_to_round_off(engine, thesis):
    """Forward accelerations and the thesis's terms at random consistent states, through the
    FMI calls, against the reference's ctypes calls. The same generated C, compiled twice
    (with the wrapper inlining differently): round-off only, 1e-12 relative to the largest
    entry (the terms' own tolerance in tolerances.toml). Planted and failing: the instance
    key ignored (every run at a1 = a2 = 0), caught by the Baumgarte comparison below."""
    rng = np.random.default_rng(26)
    for _ in range(6):
        s = consistent_state(thesis, rng.normal(size=8) * 0.3, rng.normal(size=8))
        T = rng.normal(size=3)
        ref = thesis.forward_acceleration(s.q, s.dq, T)
        assert np.max(np.abs(engine.forward_acceleration(s.q, s.dq, T) - ref)) <= 1e-12 * np.max(np.abs(ref))
        M = thesis.mass_matrix(s.q)
        assert np.max(np.abs(engine.mass_matrix(s.q) - M)) <= 1e-12 * np.max(np.abs(M))
        F = thesis.generalized_forces(s.q, s.dq, T)
        assert np.max(np.abs(engine.generalized_forces(s.q, s.dq, T) - F)) <= 1e-12 * np.max(np.abs(F))
    # off the constraint manifold the exact (a1 = a2 = 0) accelerations differ from Baumgarte's
    q, dq = rng.normal(size=8) * 0.3, rng.normal(size=8)
    exact = thesis.forward_acceleration(q, dq)
    assert np.max(np.abs(engine.forward_acceleration(q, dq) - exact)) <= 1e-12 * np.max(np.abs(exact))
    baum = thesis.forward(q, dq, (0, 0, 0), (10.0, 10.0)).ddq
    got = engine.forward(q, dq, (0, 0, 0), (10.0, 10.0)).ddq
    assert np.max(np.abs(got - baum)) <= 1e-12 * np.max(np.abs(baum))
    assert np.max(np.abs(baum - exact)) > 1e-3


def test_fmpy_simulates_the_fmu_on_the_constraints(thesis_fmu):
    """fmpy's own CVode run of the FMU from its start state (upright, 4 m/s): the rolling
    constraints stay satisfied to CVode's default tolerance (1e-4 relative on states of order
    1 to 10: measured 1.6e-6 m and 1.5e-5 m/s, bounded here by 1e-4 m and 1e-3 m/s) and the contact carries the weight (the vertical
    multiplier of order m g, 10^2 to 10^3 N)."""
    res = fmpy.simulate_fmu(str(thesis_fmu), stop_time=0.3,
                            output=["theta", "C.rD_z", "C.vC_x", "lambda.rD_z"])
    assert res["time"][-1] == pytest.approx(0.3)
    assert np.max(np.abs(res["C.rD_z"])) < 1e-4 and np.max(np.abs(res["C.vC_x"])) < 1e-3
    assert 50 < np.max(np.abs(res["lambda.rD_z"])) < 2000


@pytest.mark.parametrize("options, field", [
    ({}, "fmu=PATH.fmu"),
    ({"fmu": "/nonexistent/x.fmu"}, "fmu=/nonexistent/x.fmu: no such file"),
    ({"fmu": __file__}, "not an FMU"),
])
def test_bad_fmu_options_are_one_line_errors(thesis, options, field):
    from engines import load_engine
    with pytest.raises(EngineSpecError) as err:
        load_engine(SPEC, thesis, **options)
    assert field in str(err.value) and "fix:" in str(err.value) and "\n" not in str(err.value)


def test_a_mapping_naming_a_missing_variable_is_named(thesis, thesis_fmu, tmp_path):
    """The template with one coordinate renamed: the error names the field and the variable
    (planted and failing: the name check dropped)."""
    from engines import load_engine
    text = fmu_export.mapping_text(thesis).replace('theta = "theta"', 'theta = "roll"')
    path = tmp_path / "m.toml"
    path.write_text(text)
    with pytest.raises(EngineSpecError) as err:
        load_engine(SPEC, thesis, fmu=str(thesis_fmu), mapping=str(path))
    assert "coordinates.theta names 'roll'" in str(err.value)


def _env():
    return dict(os.environ, PYTHONHASHSEED="0", COLUMNS="400",
                PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))


@pytest.mark.slow
def test_the_exported_fmu_passes_the_conformance_suite(thesis_fmu, tmp_path):
    """The conformance plugin on the FMU, as a user runs it (a fresh pytest)."""
    res = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q",
                          "--pyargs", "comparisons.conformance", "--engine", SPEC,
                          "--engine-option", f"fmu={thesis_fmu}"],
                         cwd=tmp_path, env=_env(), capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]
    assert " passed" in res.stdout and "failed" not in res.stdout.splitlines()[-1]


@pytest.mark.slow
def test_diagnose_localizes_a_parameter_changed_in_a_rebuilt_fmu(thesis, tmp_path, capsys):
    """An FMU rebuilt with the frame's mass 2 kg heavier, checked against the thesis: diagnose
    names m3 and body 3 and fits the 2 kg."""
    from comparisons.cli import main
    bad = thesis.with_params(thesis.params.replace(m3=thesis.params.m3 + 2.0))
    path = fmu_export.write_fmu(bad, tmp_path / "bad.fmu")
    assert main(["diagnose", "--model", "thesis", "--engine", SPEC, "--engine-option",
                 f"fmu={path}", "--engine-option", "parameters=fmu"]) == 1
    out = capsys.readouterr().out
    assert "localized: M, Qv, Qgrav via m3 (body 3 frame+rider)" in out
    assert "dm3 = +2 kg" in out


@pytest.mark.slow
def test_a_co_simulation_fmu_gives_runs_only(thesis):
    """The FMU built with its Co-Simulation interface too (fixed-step RK4 inside fmi2DoStep),
    used through it: the engine offers runs only, and its run of stability-psid5 follows the
    reference's DOP853 run. RK4 at 5e-4 s on this smooth, constant-torque run: measured
    1.3e-13 at 0.12 s, 5.9e-13 at 0.6 s, 2e-8 at 0.96 s as the capsize grows; bounded by 1e-9
    up to 0.6 s (a thousand times the measurement, far below anything else this close to
    the reference). Planted and failing: the rates mapped onto the coordinates' start values
    (the run starts from dq = q)."""
    from engines import load_engine
    from engines.base import CapabilityError
    from engines.reference import ReferenceEngine
    from fmpy.validation import validate_fmu
    from reference_model.scenarios import get_scenario
    path = cached_fmu(thesis, co_simulation=True)
    assert validate_fmu(str(path)) == []
    engine = load_engine(SPEC, thesis, fmu=str(path), interface="cs")
    assert engine.capabilities == frozenset({"simulate"})
    with pytest.raises(CapabilityError):
        engine.forward_acceleration(np.zeros(8), np.zeros(8))
    sc = get_scenario("stability-psid5")
    got, ref = engine.simulate(sc), ReferenceEngine(thesis).simulate(sc)
    early = got.t <= 0.6
    assert np.array_equal(got.t[early], ref.t[:early.sum()])
    assert np.max(np.abs(got.q[early] - ref.q[:early.sum()])) < 1e-9
    assert np.max(np.abs(got.dq[early] - ref.dq[:early.sum()])) < 1e-8


@pytest.mark.slow
def test_run_with_the_fmu_engine_compares_terms_and_localizes_every_fault(thesis_fmu, tmp_path):
    """``run --quick`` with the FMU as an engine (its file as an engine option): its terms
    agree, the fault suite is built with that option and localizes all six faults, and the
    benchmark's terms (the disc contact, which a thesis-contact FMU does not model) list it
    as not run on this model. Failing before the stages passed the engine's options to the
    fault suite ('engine fmu needs its FMU') and before the benchmark's terms caught
    UnsupportedModel; ~15 s."""
    import json

    from comparisons.cli import main
    out = tmp_path / "r"
    assert main(["run", "--quick", "--scenarios", "check", "--engines", f"reference,{SPEC}",
                 "--engine-option", f"fmu={thesis_fmu}", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    mine = [c for c in summary["comparisons"] if c["engines"] == ["reference", "FmuEngine"]]
    assert {c["quantity"] for c in mine} >= {"mass_matrix", "forward_acceleration"}
    assert all(c["passed"] for c in mine)
    faults = [f for f in summary["faults"] if f["engine"] == "FmuEngine"]
    assert len(faults) == 6 and all(f["verdict"] == "localized" for f in faults), faults
    assert "FmuEngine: not run on this model" in (out / "report.md").read_text()
