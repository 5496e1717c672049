"""A user's bicycle gets every section, and declared differences and limitations are never
failures (issue 21). The cheap parts, in ``make test``; the ten measured bicycles end to end are
tests/test_real_bicycles.py (``make test-bicycles``).

Expected values are independent of the code under test: the tasks a run with ``--model`` must
ask for are the issue's list; the soft-contact rows are judged on synthetic runs whose slip,
penetration, lift-off and error are set by construction; whether MuJoCo can represent a
bicycle follows from its principal moments, computed here with numpy, against MuJoCo's
documented compiler rule A + B >= C.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from comparisons.cli import main
from comparisons.judgments.contact import declared_difference_rows, lift_off_time
from comparisons.judgments.convergence import Horizon
from engines import UnsupportedModel, load_engine
from engines.runs import Run
from reference_model import load_model
from reference_model.solvers import Trajectory

DATA = Path(__file__).resolve().parent / "data" / "benchmark"


@pytest.fixture(scope="module")
def triangle(tmp_path_factory):
    """TriangleBenchmark (tests/data): measured-like inertias that break the triangle
    inequality, imported as a user does (with the flag)."""
    out = tmp_path_factory.mktemp("tri") / "tri.toml"
    assert main(["import", str(DATA / "TriangleBenchmark.txt"), "--from", "benchmark",
                 "--out", str(out), "--allow-triangle-violation"]) == 0
    return str(out)


def _breaks_triangle(model) -> bool:
    """Whether some body's principal moments break A + B >= C (numpy's eigenvalues)."""
    p = model.params
    for b in (2, 3, 4, 5):
        xz = getattr(p, f"I{b}xz", 0.0)      # the wheels have none
        I = np.array([[getattr(p, f"I{b}xx"), 0.0, xz],
                      [0.0, getattr(p, f"I{b}yy"), 0.0],
                      [xz, 0.0, getattr(p, f"I{b}zz")]])
        w = np.linalg.eigvalsh(I)
        if w[2] > w[0] + w[1]:
            return True
    return False


def test_a_model_run_asks_for_every_section(triangle):
    """The stages of ``run --quick --model`` on the default engines: each engine term by term,
    fault injection on every engine, Exudyn's convergence and energy, the soft-contact study,
    the stability picture and the linearization against the closed form, all on the model (planted: the model run returning before the
    engine sections, as it used to, fails this)."""
    from comparisons.stages.cases import build_cases, model_spec
    from comparisons.stages.pipeline import Options, _stage_tasks, select
    from comparisons.stages.runs import setups_for
    from comparisons.stages.stability import critical
    from comparisons.stages.stage import Plan
    from engines.facts import engine_facts
    base = select(None, True, None)
    m = model_spec(triangle)
    opts = Options(base.scenarios, base.engines, True, models=(m,))
    cases, _ = build_cases(opts.scenarios, opts.models, ())
    plan = Plan(opts, tuple(setups_for(opts.engines)), {e: engine_facts(e) for e in opts.engines},
                tuple(cases), {m.spec: critical(m.spec)})
    keys = {t.key for t in _stage_tasks(plan)}
    for engine in ("pinocchio", "exudyn", "kane", "mujoco"):
        assert ("terms", (engine, m.spec)) in keys, engine
        assert ("faults", (engine, m.spec)) in keys, engine
        if engine != "mujoco":   # a soft contact's energy is its study's, not conserved
            assert ("energy", (engine, m.spec)) in keys, engine
    for key in (("fixed-step", ("convergence", "exudyn", m.spec)),
                ("soft-contact", ("study", "mujoco", m.spec)),
                ("stability", ("curves", m.spec)), ("linear-check", m.spec)):
        assert key in keys, key


def test_mujoco_declares_the_bicycles_it_cannot_represent(triangle):
    model = load_model(triangle)
    assert _breaks_triangle(model)
    with pytest.raises(UnsupportedModel, match=r"A \+ B >= C"):
        load_engine("mujoco", model)
    # a bicycle whose bodies obey the rule builds (the control)
    ok = load_model("benchmark")
    assert not _breaks_triangle(ok)
    load_engine("mujoco", ok)


def test_a_declared_limitation_is_not_run_with_its_reason_everywhere(triangle):
    """The runs, the term section and the fault injection of MuJoCo on the triangle-breaking
    bicycle: 'not run on this model', with MuJoCo's reason; never a failure (planted: letting
    the loader's UnsupportedModel through run_one crashes the stage)."""
    from comparisons.stages.terms import plugin_terms
    from comparisons.stages.faults import fault_entries
    from comparisons.judgments.tolerances import load_tolerances
    from comparisons.stages.runs import run_one, setup_of
    from reference_model.scenarios import SCENARIOS
    run = run_one(setup_of("mujoco"), SCENARIOS["stability-psid10"], triangle)
    assert run.status == "not run" and "not run on this model" in run.message
    assert "A + B >= C" in run.message
    sec = plugin_terms(load_tolerances(), "mujoco", {}, 4, (triangle,))
    assert sec.comparisons == []            # nothing judged, nothing failed
    assert any("not run on this model" in str(b) for b in sec.blocks)
    entries = fault_entries(load_tolerances(), "mujoco", triangle)
    assert [e["verdict"] for e in entries] == ["not run"]
    assert "A + B >= C" in entries[0]["evidence"]


def _traj(t, theta, diagnostics=None):
    q = np.zeros((t.size, 8))
    q[:, 3] = theta
    z = np.zeros((t.size, 8))
    return Trajectory(t, q, z, z, np.zeros((t.size, 5)), np.zeros((t.size, 3)), "completed",
                      "synthetic", float(t[-1]), diagnostics=diagnostics or {})


def _run(engine, traj):
    return Run(engine, "synthetic", "M", "forward", traj.status, traj.message, 0.0,
               traj.t, traj.q, traj.dq, trajectory=traj)


def test_soft_contact_runs_are_measured_and_reported_never_judged():
    """A soft-contact engine's run 0.1 rad off in lean from t = 0.3 s, slipping at 0.02 m/s,
    sinking 1e-4 m, its front wheel unloaded from t = 0.5 s: the rows report exactly those
    numbers up to the meaningful horizon (0.8 s) and judge nothing (planted: judging them by
    [trajectory_conformance] makes passed False here)."""
    t = np.round(np.arange(0.0, 1.0001, 0.01), 10)
    off = np.where(t >= 0.3, 0.1, 0.0)
    front = np.where(t >= 0.5, 0.0, 100.0)
    diag = {"slip_speed_rear": np.full(t.size, 0.01), "slip_speed_front": np.full(t.size, 0.02),
            "penetration_rear": np.full(t.size, 1e-4), "penetration_front": np.full(t.size, 5e-5),
            "normal_force_rear": np.full(t.size, 200.0), "normal_force_front": front}
    ref, soft = _run("reference", _traj(t, 0.0 * t)), _run("soft", _traj(t, off, diag))
    hor = Horizon(0.8, "separation", 1e-6, 0.0, (1.0, 1.0), "synthetic")
    rows = declared_difference_rows(ref, soft, hor, "soft contact", 1.5, "C[vD_y] at t = 0.6 s")
    by = {r["quantity"]: r for r in rows}
    assert set(by) == {"constraint_residual", "trajectory",
                       "contact fidelity (slip, penetration, trajectory)"}
    assert all(r["passed"] is None and r["tolerance"] is None for r in rows)
    assert all("declared model difference (soft contact)" in r["note"] for r in rows)
    assert by["constraint_residual"]["max_error"] == 1.5
    assert by["trajectory"]["max_error"] == pytest.approx(0.1, abs=1e-15)
    assert by["trajectory"]["lift_off_s"] == pytest.approx(0.5)
    fid = by["contact fidelity (slip, penetration, trajectory)"]
    assert fid["slip_max"] == pytest.approx(0.02) and fid["penetration_max"] == pytest.approx(1e-4)
    assert fid["horizon"] == pytest.approx(0.8)


def test_lift_off_is_the_first_unloaded_sample_after_the_start():
    t = np.round(np.arange(0.0, 0.1001, 0.01), 10)
    d = {"normal_force_rear": np.r_[0.0, np.full(10, 5.0)],        # unloaded at t = 0 only
         "normal_force_front": np.r_[np.full(7, 5.0), np.zeros(4)]}
    assert lift_off_time(_traj(t, 0 * t, d)) == pytest.approx(0.07)
    assert lift_off_time(_traj(t, 0 * t)) is None                 # no forces recorded


BOOM = '''
from engines.base import Engine


class Boom(Engine):
    """An engine whose forward runs raise (a third party's solver that diverges)."""

    name = "boom"
    capabilities = frozenset({"simulate"})

    def simulate(self, scenario, **options):
        raise RuntimeError("solver diverged at t = 0.01 s")
'''


def test_an_engine_run_that_raises_is_its_failure_and_the_rest_is_written(tmp_path, capsys):
    """Asked to run and did not: the engine's failure, named in the verdict and in summary.json
    (passed false, exit 1), while the reference's results are all there (planted: dropping the
    'engine run' row gives passed true and exit 0)."""
    import json
    spec = tmp_path / "boom.py"
    spec.write_text(BOOM)
    out = tmp_path / "r"
    code = main(["run", "--quick", "--engines", f"reference,{spec}:Boom", "--scenarios",
                 "check-forward", "--sections", "terms", "--figures", "none", "--jobs", "1",
                 "--out", str(out)])
    capsys.readouterr()
    s = json.loads((out / "summary.json").read_text())
    assert code == 1 and s["passed"] is False
    bad = [c for c in s["comparisons"] if c["passed"] is False]
    assert [(c["quantity"], c["engines"]) for c in bad] == [("engine run", ["Boom"])]
    assert "solver diverged" in bad[0]["localized_to"]
    assert {r["engine"]: r["status"] for r in s["engine_runs"]} == {"reference": "completed",
                                                                    "Boom": "failed"}
    assert "solver diverged" in (out / "report.md").read_text().split("## Summary")[0]
