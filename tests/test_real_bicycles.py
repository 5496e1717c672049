"""The ten measured bicycles that BicycleParameters ships, end to end, as a user brings them.

Each ``<Name>Benchmark.txt`` goes through ``bicycle-xval import`` (``--allow-triangle-violation``
for the three whose measured inertias break the triangle inequality, which the import refuses
otherwise), then all ten through one ``bicycle-xval run --quick --model ...`` on every default
engine, and each through ``diagnose``. Expected, for every bicycle:

* a report, exit status 0 and ``passed: true``: the engines agree with the reference on real
  inputs, and the verdict is true (no false alarm from a declared difference or limitation);
* every section that applies: each engine term by term, fault injection, Exudyn's convergence,
  the energy drift, the soft-contact study (or, where MuJoCo cannot represent the bicycle, that
  limitation said in the section), the stability picture and the linearization against the
  closed form;
* its weave and capsize speeds equal to the ones computed here, independently of the project,
  from BicycleParameters' own canonical matrices (``bicycleparameters.bicycle.
  benchmark_par_to_canonical`` on the file's nominal values; eigenvalues of the 4x4 state
  matrix by numpy, sign changes found by brentq), to 1e-9 m/s: both are roots of the same
  analytic functions found to xtol ~1e-14, so 1e-9 is round-off of the matrices' entries
  (~1e-13 relative) times the roots' sensitivity, with margin, while a 1 mm change of the trail
  moves them by ~1e-3 m/s.

This is the heaviest study of the suite (about 450 stages, ~4 minutes on the 2-core machine),
so it is not part of ``make test`` (kept under 90 s): ``make test-bicycles`` runs it, and
``.ci/run`` runs both. The package's location is looked up, its data read from where pip put
it; nothing is copied into this repository.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from scipy.optimize import brentq

from comparisons.cli import main
from shipped_sets import SETS, file_values, shipped

pytestmark = pytest.mark.bicycles

TRIANGLE = ("Browser", "Yellow", "Yellowrev")      # refused by import without the flag
SPEED_TOL = 1e-9


def _canonical_speeds(values: dict[str, float]) -> dict[str, float]:
    """Weave and capsize speeds in 0-10 m/s from BicycleParameters' canonical matrices."""
    from bicycleparameters.bicycle import benchmark_par_to_canonical
    M, C1, K0, K2 = (np.asarray(x, dtype=float) for x in benchmark_par_to_canonical(dict(values)))
    g = values["g"]
    Minv = np.linalg.inv(M)

    def eig(v):
        A = np.block([[np.zeros((2, 2)), np.eye(2)],
                      [-Minv @ (g * K0 + v ** 2 * K2), -v * Minv @ C1]])
        return np.linalg.eigvals(A)

    def weave(v):            # the largest real part of an oscillatory pair (nan: none)
        lam = eig(v)
        osc = lam[np.abs(lam.imag) > 1e-9]
        return float(osc.real.max()) if osc.size else np.nan

    def capsize(v):          # the largest real eigenvalue (the capsize mode above weave)
        lam = eig(v)
        real = lam[np.abs(lam.imag) <= 1e-9]
        return float(real.real.max()) if real.size else np.nan

    grid = np.arange(0.0, 10.0 + 1e-12, 0.01)
    out = {}
    w = np.array([weave(v) for v in grid])
    k = np.flatnonzero((w[:-1] > 0) & (w[1:] <= 0))
    if k.size:
        out["weave"] = brentq(weave, grid[k[0]], grid[k[0] + 1], xtol=1e-14, rtol=1e-15)
        c = np.array([capsize(v) for v in grid])
        j = np.flatnonzero((c[:-1] < 0) & (c[1:] >= 0) & (grid[:-1] >= out["weave"]))
        if j.size:
            out["capsize"] = brentq(capsize, grid[j[0]], grid[j[0] + 1], xtol=1e-14, rtol=1e-15)
    return out


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """name -> the imported parameter file (``bicycle-xval import``)."""
    tmp = tmp_path_factory.mktemp("bicycles")
    out = {}
    for name in SETS:
        args = ["import", str(shipped(name)), "--from", "benchmark", "--out",
                str(tmp / f"{name}.toml")]
        if name in TRIANGLE:
            assert main(args) != 0, f"{name} breaks the triangle inequality: import must refuse"
            args.append("--allow-triangle-violation")
        assert main(args) == 0, name
        out[name] = tmp / f"{name}.toml"
    return out


@pytest.fixture(scope="module")
def report(imported, tmp_path_factory):
    """One ``run --quick`` with all ten as --model, every default engine and section."""
    out = tmp_path_factory.mktemp("bicycles-report") / "report"
    args = ["run", "--quick", "--out", str(out)]
    for path in imported.values():
        args += ["--model", str(path)]
    code = main(args)
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return {"code": code, "summary": summary, "report": (out / "report.md").read_text(),
            "names": {n: f"{n}Benchmark" for n in SETS}}


def test_every_bicycle_gives_a_true_passing_report(report):
    s = report["summary"]
    bad = [(c["quantity"], c["scenario"], c["engines"], c["max_error"], c["tolerance"])
           for c in s["comparisons"] if c["passed"] is False]
    faults = [f for f in s["faults"] if f["verdict"] not in ("localized", "not observable",
                                                             "not run")]
    assert bad == [] and faults == [], (bad, faults)
    assert report["code"] == 0 and s["passed"] is True
    assert s["dropped_engines"] == []
    assert {m["name"] for m in s["models"]} == set(report["names"].values())


@pytest.mark.parametrize("name", SETS)
def test_every_section_runs_on_each_bicycle(report, name):
    bike = report["names"][name]
    titles = set(re.findall(r"^## (.+)$", report["report"], flags=re.M))
    # each engine under its declared label (engines.facts), a plugin's the same way
    for engine in ("Pinocchio", "Exudyn", "Kane", "MuJoCo"):
        assert f"Reference vs {engine} on {bike}, term by term" in titles, (engine, name)
    for title in (f"Exudyn convergence on {bike}: integrator error or model difference?",
                  f"MuJoCo contact study on {bike}: soft contact against ideal rolling"):
        assert title in titles, title
    for start, end in (("Energy drift", f"on {bike}"), (f"Stability of {bike} (", f"{name}.toml)"),
                       (f"Linearization of {bike}", "")):
        assert any(t.startswith(start) and t.endswith(end) for t in titles), (start, end)
    faults = [f for f in report["summary"]["faults"] if f["model"] == bike]
    engines = {f["engine"] for f in faults}
    assert engines >= {"pinocchio", "exudyn", "kane", "mujoco"}, engines   # and any registered since
    term_rows = [c for c in report["summary"]["comparisons"]
                 if c["model"] == bike and c["scenario"].startswith("random-states")]
    assert {c["engines"][1] for c in term_rows} >= {"pinocchio", "exudyn", "kane"}
    conv = [c for c in report["summary"]["comparisons"]
            if c["quantity"] == "convergence order" and c["model"] == bike]
    assert [c["verdict"] for c in conv] == ["converges"]


@pytest.mark.parametrize("name", TRIANGLE)
def test_mujoco_s_limitation_is_declared_not_failed(report, name):
    """MuJoCo's compiler refuses principal moments that break A + B >= C: its runs, terms,
    faults and contact study on these bicycles say 'not run on this model' with the reason."""
    bike = report["names"][name]
    runs = [r for r in report["summary"]["engine_runs"]   # its forward runs (it has no inverse)
            if r["engine"] == "mujoco" and r["model"] == bike and "forward" in r["scenario"]
            or r["engine"] == "mujoco" and r["model"] == bike and "stability" in r["scenario"]]
    assert runs and all(r["status"] == "not run" and "A + B >= C" in r["message"] for r in runs)
    faults = [f for f in report["summary"]["faults"]
              if f["engine"] == "mujoco" and f["model"] == bike]
    assert [f["verdict"] for f in faults] == ["not run"]
    section = report["report"].split(f"## MuJoCo contact study on {bike}")[1].split("\n## ")[0]
    assert "Not run on this model" in section and "A + B >= C" in section


@pytest.mark.parametrize("name", [n for n in SETS if n not in TRIANGLE])
def test_soft_contact_is_a_declared_difference_on_every_bicycle(report, name):
    """MuJoCo's runs are measured against ideal rolling (slip, penetration, lift-off) and
    reported, never judged by the ideal-rolling tolerances."""
    bike = report["names"][name]
    rows = [c for c in report["summary"]["comparisons"]
            if c["engines"][-1] == "mujoco" and c["model"] == bike
            and c["quantity"] in ("trajectory", "constraint_residual",
                                  "contact fidelity (slip, penetration, trajectory)")]
    assert {c["quantity"] for c in rows} == {"trajectory", "constraint_residual",
                                             "contact fidelity (slip, penetration, trajectory)"}
    assert all(c["passed"] is None and c["tolerance"] is None
               and "declared model difference" in c["note"] for c in rows)
    fid = [c for c in rows if c["quantity"].startswith("contact fidelity")]
    assert all(c["slip_max"] > 0 and np.isfinite(c["penetration_max"]) for c in fid)


@pytest.mark.parametrize("name", SETS)
def test_critical_speeds_equal_bicycleparameters_canonical_ones(report, name):
    expected = _canonical_speeds(file_values(shipped(name)))
    got = report["summary"]["critical_speeds"][report["names"][name]]
    assert set(got) == set(expected), (got, expected)
    for mode, v in expected.items():
        assert abs(got[mode] - v) <= SPEED_TOL, (mode, got[mode], v)


@pytest.mark.parametrize("name", SETS)
def test_diagnose_finds_the_engines_agree_on_each_bicycle(imported, name, capsys):
    code = main(["diagnose", str(imported[name]), "--engines", "pinocchio,exudyn,kane,mujoco"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "verdict: everything agrees" in out
