"""`bicycle-xval sweep` (issue 16): spec errors, one tiny Dask sweep shared by the module
(columns, Table 1 speeds, resume, failures as rows, determinism), physical samples.

One in-process LocalCluster (processes=False, one worker) serves every sweep here: the module
costs a few seconds, not the spawn of worker processes.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from comparisons.cli.main import main
from comparisons.stages import sweep as sweep_stage
from comparisons.stages.sweep import chunk_path, plan, run_sweep
from comparisons.stages.sweep_spec import SpecError, make_spec, sample_parameters
from comparisons.stages.sweep_task import chunk_rows, columns
from reference_model import load_model
from reference_model.params import PARAMETER_NAMES
from sweep_engines import local_client

# Meijaard et al. (2007), section 5 / Table 2: the benchmark's weave and capsize speeds, 14
# significant digits; 1e-9 m/s is the bound (the critical speeds are root-found to
# xtol 1e-14 on the exact linearization, so only a wrong model or mapping misses it)
WEAVE, CAPSIZE = 4.2923825363411, 6.0242620153884
EXAMPLE_ENGINE = Path(__file__).parents[1] / "examples" / "numpy_engine" / "numpy_bicycle" / "engine.py"

BROKEN_ENGINE = '''
from engines.base import Engine
from reference_model import ModelEvaluationError

class Broken(Engine):
    """Pinocchio-like M for light riders; raises for a rider heavier than 90 kg."""
    name = "broken"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        if self.model.params.m3 > 90.0:
            raise ModelEvaluationError("singular mass matrix for this bicycle")
        return self.model.mass_matrix(q)
'''


@pytest.fixture(scope="module")
def benchmark_params():
    return load_model("benchmark").params


@pytest.fixture(scope="module")
def client():
    with local_client() as c:
        yield c


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, benchmark_params, client):
    """4 bicycles: rider mass 85 (Table 1) and 95 kg x trail 0.08 (Table 1) and 0.12 m, terms and
    eigen, Pinocchio and an engine that fails for riders above 90 kg."""
    d = tmp_path_factory.mktemp("sweep")
    (d / "broken.py").write_text(BROKEN_ENGINE)
    spec = make_spec(benchmark_params, varies=["m3=85:95:2", "trail=0.08:0.12:2"],
                     engines=("pinocchio", f"{d / 'broken.py'}:Broken"), checks=("terms", "eigen"),
                     n_states=4)
    out = d / "out"
    first = run_sweep(spec, out, client=client, progress=False)
    return spec, out, first


def _usage(capsys, out, *argv) -> str:
    assert main(["sweep", "--out", str(out), "--workers", "1", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


@pytest.mark.parametrize("argv, words", [
    (["--vary", "trial=0:0.2:41"], ["--vary", "unknown parameter 'trial'", "'trail'"]),
    (["--vary", "trail=0.2:0.1:5"], ["--vary", "empty range", "LOW < HIGH"]),
    (["--vary", "trail=0:0.2:0"], ["empty range"]),
    (["--vary", "trail=0:0.2"], ["LOW:HIGH:N"]),
    (["--sample", "10", "--spread", "-5"], ["--spread", "non-negative"]),
    (["--sample", "10"], ["--sample needs --spread"]),
    (["--vary", "I3xx=0.5:20:5"], ["--vary I3xx", "not physical", "narrow the range"]),
    (["--vary", "m3=80:90:3", "--sample", "4", "--spread", "10"], ["give one of them"]),
    (["--model", "thesis", "--vary", "m3=80:90:3"], ["--checks eigen", "thesis-disc"]),
    (["--vary", "m3=80:90:3", "--checks", "terms,wobble"], ["--checks", "choose from"]),
])
def test_bad_specs_are_one_line_naming_the_option(capsys, tmp_path, argv, words):
    err = _usage(capsys, tmp_path / "out", *argv)
    for w in words:
        assert w in err, err


def test_tiny_sweep_writes_the_documented_columns(tiny):
    spec, out, first = tiny
    frame = pd.read_parquet(out / "results.parquet")
    assert list(frame.columns) == columns(spec)
    assert list(frame["bicycle"]) == [0, 1, 2, 3]
    assert list(frame["vary.m3"]) == [85.0, 85.0, 95.0, 95.0]
    assert np.allclose(frame["vary.trail"], [0.08, 0.12, 0.08, 0.12], rtol=0, atol=1e-15)
    # the derived trail read back from the model through the reverse Table 1 formulas
    assert np.allclose(frame["trail"], frame["vary.trail"], rtol=0, atol=1e-12)
    for q in ("mass_matrix", "inverse_dynamics", "forward_acceleration"):
        assert {f"err.pinocchio.{q}", f"entry.pinocchio.{q}"} <= set(frame.columns)
    assert {"weave_speed", "capsize_speed", "failures", "status", "task_seconds",
            "localization"} <= set(frame.columns)
    assert {f"p.{n}" for n in PARAMETER_NAMES} <= set(frame.columns)
    light = frame[frame["vary.m3"] == 85.0]
    assert (light["status"] == "agree").all() and (light["err.pinocchio.mass_matrix"] < 1e-12).all()
    assert (frame["task_seconds"] > 0).all()


def test_table1_grid_point_reproduces_the_published_speeds(tiny):
    _, out, _ = tiny
    row = pd.read_parquet(out / "results.parquet").iloc[0]
    assert (row["vary.m3"], row["vary.trail"]) == (85.0, 0.08)
    assert abs(row["weave_speed"] - WEAVE) < 1e-9
    assert abs(row["capsize_speed"] - CAPSIZE) < 1e-9


def test_an_engine_failure_is_a_row_not_an_aborted_sweep(tiny):
    _, out, first = tiny
    frame = pd.read_parquet(out / "results.parquet")
    heavy = frame[frame["vary.m3"] == 95.0]
    assert len(heavy) == 2 and (heavy["status"] == "failed").all()
    assert heavy["failures"].str.contains("Broken mass_matrix: ModelEvaluationError: singular").all()
    # the other checks of the failing bicycle still ran
    assert heavy["weave_speed"].notna().all()
    assert (heavy["err.pinocchio.mass_matrix"] < 1e-12).all()
    assert first.failed_tasks == 0


def test_rerun_recomputes_nothing(tiny, client):
    spec, out, first = tiny
    files = [chunk_path(out, first.hash, i) for i in range(first.chunks)]
    before = [f.stat().st_mtime_ns for f in files]
    again = run_sweep(spec, out, client=client, progress=False)
    assert (again.computed, again.skipped) == (0, first.chunks)
    assert [f.stat().st_mtime_ns for f in files] == before


def test_identical_spec_identical_rows_in_any_order(tiny):
    spec, out, _ = tiny
    stored = pd.read_parquet(out / "results.parquet").drop(columns="task_seconds")
    rows = chunk_rows(spec, (3, 2, 1, 0))          # reverse order, this process
    again = sweep_stage.rows_frame(spec, rows).drop(columns="task_seconds")
    pd.testing.assert_frame_equal(stored, again)


def test_a_lost_task_becomes_a_failed_row_for_its_bicycle_only(tmp_path, benchmark_params,
                                                                client, monkeypatch):
    """A task whose worker dies (Dask gives up with KilledWorker, as measured with a real
    os._exit in a worker process: tests/test_sweep_processes.py) is split per bicycle, each run
    alone; only the bicycle that loses its task again is a failed row."""
    spec = make_spec(benchmark_params, varies=["m3=80:90:2"], engines=("pinocchio",),
                     checks=("eigen",))
    assert len(plan(spec)) == 1
    real = sweep_stage.limited_chunk_rows

    def dies_on_bicycle_1(spec, indices, limit):
        if 1 in indices:
            raise RuntimeError("worker tcp://127.0.0.1:1 died")
        return real(spec, indices, limit)
    monkeypatch.setattr(sweep_stage, "limited_chunk_rows", dies_on_bicycle_1)
    res = run_sweep(spec, tmp_path, client=client, progress=False)
    frame = pd.read_parquet(tmp_path / "results.parquet")
    assert res.failed_tasks == 2                   # the chunk, then bicycle 1 alone
    assert list(frame["status"]) == ["agree", "failed"]
    assert frame["failures"][1].startswith("task lost when run alone: RuntimeError: worker")
    assert list(frame["vary.m3"]) == [80.0, 90.0] and np.isfinite(frame["weave_speed"][0])


def test_samples_keep_inertias_physical_and_within_the_spread(benchmark_params):
    """50 % spread: independent factors on each inertia entry break the triangle inequality
    or positive definiteness of some of 300 bicycles; the congruence scaling never does."""
    spec = make_spec(benchmark_params, sample=300, spread=50.0, seed=3, checks=("terms",))
    base = dict(spec.base)
    for k in range(300):
        p = sample_parameters(spec, k)          # raises ParameterError if not physical
        for n in ("x3", "m3", "R_front"):
            assert 0.5 * abs(base[n]) - 1e-12 <= abs(getattr(p, n)) <= 1.5 * abs(base[n]) + 1e-12
        for body in (3, 4):   # every second moment (diagonal of S = tr(I)/2 - I) within +-50 %
            s0 = np.diag(np.trace(_tensor(base, body)) / 2 - _tensor(base, body))
            s1 = np.diag(np.trace(p.inertia(body)) / 2 - p.inertia(body))
            assert np.all(s1 >= 0.5 * s0 - 1e-12) and np.all(s1 <= 1.5 * s0 + 1e-12)
        assert p.I2xx == p.I2zz and p.g == base["g"]
    assert sample_parameters(spec, 7) == sample_parameters(spec, 7)
    # a sampled bicycle is the base's kind: its name, front contact and triangle rule (the
    # benchmark's disc, not Parameters' defaults 'custom', 'thesis', 'strict')
    loose = make_spec(benchmark_params.replace(triangle="warn"), sample=2, spread=10.0,
                      checks=("terms",))
    p = sample_parameters(loose, 1)
    assert (p.name, p.contact, p.triangle) == ("benchmark", "disc", "warn")
    with pytest.raises(SpecError, match="--spread"):
        make_spec(benchmark_params, sample=3, spread=-1.0)


def _tensor(values, body):
    xz = values.get(f"I{body}xz", 0.0)
    return np.array([[values[f"I{body}xx"], 0, xz], [0, values[f"I{body}yy"], 0],
                     [xz, 0, values[f"I{body}zz"]]])


def test_cli_sweep_writes_the_report(tmp_path, monkeypatch, capsys, tiny, client):
    """The command end to end on the tiny sweep's folder (all chunks done: nothing computed)."""
    spec, out, _ = tiny
    broken = spec.engines[1]
    rc = main(["sweep", "--vary", "m3=85:95:2", "--vary", "trail=0.08:0.12:2", "--states", "4",
               "--engines", f"pinocchio,{broken}", "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1, err                            # two bicycles failed
    assert "0 computed, 1 already done" in err and "2 agree" in err and "2 failed" in err
    report = (out / "report.md").read_text()
    assert "Broken mass_matrix" in report and (out / "stability.png").exists()
    assert os.path.getsize(out / "agreement.png") > 1000


# -- the tolerances travel with the tasks (issue 22) ---------------------------------------------

def _free_port() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def remote_scheduler(tmp_path):
    """A `dask scheduler` and one `dask worker` (no nanny, one thread) started as their own
    process groups on loopback in a clean environment: no variable of this process reaches the
    worker but PATH, the path to this checkout's code and its compiled-code cache. Both are ended (their process
    groups killed) whatever the test does. About 2-3 s to start on the 2-core machine."""
    import signal
    import subprocess
    import sys
    from pathlib import Path

    from reference_model.equations.codegen import CACHE_ENV, cache_root
    root = Path(__file__).resolve().parents[1]
    dask = Path(sys.executable).with_name("dask")
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(tmp_path),
           "PYTHONPATH": str(root), "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           CACHE_ENV: str(cache_root())}     # the compiled model this process uses (else ~40 s)
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = []

    def start(*argv):
        procs.append(subprocess.Popen([str(dask), *argv], cwd=root, env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
    try:
        start("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard")
        start("worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
              "--host", "127.0.0.1", "--death-timeout", "30")
        from distributed import Client
        with Client(address, timeout="30s") as c:     # waits for the scheduler
            c.wait_for_workers(1, timeout=30)
        yield address
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait(timeout=10)


@pytest.mark.slow
def test_a_remote_dask_worker_judges_by_the_given_tolerances(tmp_path, capsys, remote_scheduler,
                                                            failing_tolerances):
    """A sweep sent to a `dask worker` started in another environment, with a --tolerances file
    that makes every check fail, fails every bicycle (the tolerances are in each task's
    arguments, not in the worker's environment); the packaged tolerances agree on the same
    bicycles, under another spec hash (a resume never mixes the two). Two bicycles, Pinocchio's
    terms at 2 states: ~1 s of work on the worker besides its start."""
    import json
    failing = failing_tolerances
    argv = ["sweep", "--model", "benchmark", "--vary", "m3=80:90:2", "--checks", "terms",
            "--engines", "pinocchio", "--states", "2", "--scheduler", remote_scheduler,
            "--no-progress"]
    assert main([*argv, "--tolerances", str(failing), "--out", str(tmp_path / "fail")]) == 1
    bad = pd.read_parquet(tmp_path / "fail" / "results.parquet")
    assert list(bad["status"]) == ["disagree", "disagree"], bad["failures"].tolist()
    assert (bad["max_error"] > 1e-300).all()
    assert main([*argv, "--out", str(tmp_path / "ok")]) == 0
    good = pd.read_parquet(tmp_path / "ok" / "results.parquet")
    assert list(good["status"]) == ["agree", "agree"]
    # the same bicycles and states: the same errors, judged differently
    np.testing.assert_array_equal(bad["max_error"].to_numpy(), good["max_error"].to_numpy())
    hashes = [json.loads((tmp_path / d / "spec.json").read_text())["hash"] for d in ("fail", "ok")]
    assert hashes[0] != hashes[1]
    capsys.readouterr()


def test_the_spec_hash_covers_the_tolerance_values(tmp_path, benchmark_params, failing_tolerances):
    """Other tolerances, another hash; the same tables from another file name, the same hash
    (the hash is of the values, which spec.json lists)."""
    from comparisons.judgments.tolerances import TOLERANCES_FILE, load_tolerances
    from comparisons.stages.sweep_spec import spec_hash
    copy = tmp_path / "copy.toml"
    copy.write_text(TOLERANCES_FILE.read_text())

    def spec(tols=None):
        return make_spec(benchmark_params, varies=["m3=80:90:2"], checks=("terms",),
                         tolerances=tols)
    base = spec_hash(spec())
    assert spec_hash(spec(load_tolerances(copy))) == base
    failing = load_tolerances(failing_tolerances)
    assert spec_hash(spec(failing)) != base
    assert spec().as_json()["tolerances"]["mass_matrix"]["tolerance"] == 1e-12


def test_default_engines_and_the_runs_come_from_the_engines_facts(benchmark_params):
    """Without --engines a sweep compares every installed engine with terms on the base's
    contact (`engines.term_engines`), named in the spec and so in its hash; its runs are the
    reference's and those of every engine that declares a forward run on that contact with
    no model difference: Pinocchio's, Exudyn's kinematic tree at h = 1e-3 s (docs/engines.md)
    and Kane's, not MuJoCo's (a soft contact, a declared model difference). A plugin's
    forward runs count like a built-in's. Planted: run_options without the run-difference
    filter includes MuJoCo and fails."""
    from engines import term_engines
    from comparisons.stages.sweep_spec import spec_hash
    from comparisons.stages.sweep_task import run_options
    default = make_spec(benchmark_params, varies=["m3=80:90:2"], checks=("eigen", "runs"))
    named = make_spec(benchmark_params, varies=["m3=80:90:2"], checks=("eigen", "runs"),
                      engines=term_engines("disc"))
    assert default.engines == named.engines and spec_hash(default) == spec_hash(named)
    assert {"pinocchio", "exudyn", "kane", "mujoco"} <= set(default.engines)
    runs = run_options(default)
    assert list(runs)[0] == "reference" and "mujoco" not in runs
    assert (runs["exudyn"].engine, dict(runs["exudyn"].options)) == \
        ("exudyn", {"build": "tree", "step": 1e-3})
    assert runs["pinocchio"].options == () and "kane" in runs
    plugin = f"{EXAMPLE_ENGINE}:NumpyEngine"
    only = make_spec(benchmark_params, varies=["m3=80:90:2"], checks=("eigen", "runs"),
                     engines=(plugin,))
    assert list(run_options(only)) == ["reference", "NumpyEngine"]
    assert "run.weave.0.9.NumpyEngine" in columns(only)
    with pytest.raises(SpecError, match="--engines: give at least one engine"):
        make_spec(benchmark_params, varies=["m3=80:90:2"], engines=())


# -- issue 24: runs, the hash against every field, every column against its definition ---------

@pytest.mark.slow
def test_a_table1_sweep_with_runs_agrees_on_every_engine(tmp_path, benchmark_params, client):
    """The Table 1 bicycle alone with ``--checks runs`` (eigen added): the reference's and
    Pinocchio's runs at 0.9 and 1.1 x both critical speeds confirm the linear prediction
    (tests/test_stability_judge.py checks the judge itself against the closed form), so the
    row agrees. Eight 5 s runs, ~2 s."""
    spec = make_spec(benchmark_params, varies=["m3=85:85:1"], engines=("pinocchio",),
                     checks=("runs",))
    assert spec.checks == ("eigen", "runs")
    run_sweep(spec, tmp_path, client=client, progress=False)
    row = pd.read_parquet(tmp_path / "results.parquet").iloc[0]
    runs = [c for c in columns(spec) if c.startswith("run.")]
    assert len(runs) == 2 * 2 * 2                  # weave, capsize x 0.9, 1.1 x two engines
    assert {row[c] for c in runs} == {"confirmed"}, row[runs].to_dict()
    assert row["runs_confirmed"] and row["status"] == "agree" and row["failures"] == ""
    assert abs(row["weave_speed"] - WEAVE) < 1e-9 and abs(row["capsize_speed"] - CAPSIZE) < 1e-9


def test_the_sweep_runs_are_the_stability_stages_scenario(benchmark_params):
    """The sweep's in-memory scenario is `stages.stability.scenario` for the same model: the
    wheel rate is v / R_rear (the benchmark's wheels differ, 0.3 and 0.35 m, so a wrong radius
    is seen here), upright, the 0.05 rad/s roll-rate kick."""
    from comparisons.stages.stability import ROLL_RATE, scenario
    from comparisons.stages.sweep_task import _scenario
    model = load_model("benchmark")
    assert model.params.R_rear != model.params.R_front
    mine, stage = _scenario(model, 4.6), scenario("benchmark", 4.6)
    assert mine.dq_ind0 == pytest.approx((ROLL_RATE, 4.6 / 0.3, 0.0), rel=1e-15)
    for f in ("kind", "grid", "q0", "dq_ind0", "torques", "constraints"):
        assert getattr(mine, f) == getattr(stage, f), f


def _hash_variants(spec):
    """One spec per field of SweepSpec (and per part of a grid and of each tolerance), each
    differing from ``spec`` in that one place: field name -> list of variants."""
    import dataclasses

    from comparisons.judgments.tolerances import Tolerances
    from comparisons.stages.sweep_spec import Grid
    rep = dataclasses.replace
    g = spec.grids[0]
    base = dict(spec.base)
    tol = spec.tolerances.entries

    def tols(i, **kw):
        return Tolerances(tol[:i] + (rep(tol[i], **kw),) + tol[i + 1:], "other.toml")
    return {
        "base": [rep(spec, base=tuple((n, (v * 1.001 or 1e-3) if n == k else v) for n, v in spec.base))
                 for k in base],
        "base_name": [rep(spec, base_name="other")],
        "contact": [rep(spec, contact="thesis")],
        "triangle": [rep(spec, triangle="warn" if spec.triangle != "warn" else "error")],
        "grids": [rep(spec, grids=(Grid(g.name, g.low, g.high, g.n + 1),)),
                  rep(spec, grids=(Grid(g.name, g.low * 0.99, g.high, g.n),)),
                  rep(spec, grids=(Grid(g.name, g.low, g.high * 1.01, g.n),)),
                  rep(spec, grids=(Grid("m2", g.low, g.high, g.n),)),
                  rep(spec, grids=(g, Grid("trail", 0.08, 0.08, 1)))],
        "sample": [rep(spec, sample=spec.sample + 1)],
        "spread": [rep(spec, spread=spec.spread + 1.0)],
        "seed": [rep(spec, seed=spec.seed + 1)],
        "engines": [rep(spec, engines=spec.engines + ("kane",)), rep(spec, engines=spec.engines[:1])],
        "checks": [rep(spec, checks=("terms", "eigen"))],
        "n_states": [rep(spec, n_states=spec.n_states + 1)],
        "tolerances": ([tols(i, tolerance=t.tolerance * 2) for i, t in enumerate(tol)]
                       + [tols(i, scale="absolute" if t.scale != "absolute" else "max_abs")
                          for i, t in enumerate(tol)]
                       + [tols(i, quantity=t.quantity + "_x") for i, t in enumerate(tol)]),
    }


def test_the_spec_hash_changes_with_every_field(benchmark_params):
    """Every field of the spec (every base value, each part of a grid, each tolerance's value,
    scale and quantity) changes the hash on its own: the chunks live under it, so a field it
    missed would let a rerun reuse another spec's chunks. Introspected: a field added to
    SweepSpec without a variant here fails the test."""
    import dataclasses

    from comparisons.stages.sweep_spec import SweepSpec, spec_hash
    spec = make_spec(benchmark_params, varies=["m3=80:90:2"], engines=("pinocchio", "exudyn"),
                     checks=("terms",), n_states=3)
    variants = _hash_variants(spec)
    assert set(variants) == {f.name for f in dataclasses.fields(SweepSpec)}
    base = spec_hash(spec)
    hashes = {}
    for name, specs in variants.items():
        for s in specs:
            h = spec_hash(s)
            assert h != base, f"the hash ignores a change of {name}"
            hashes.setdefault(h, name)
    assert len(hashes) == sum(len(v) for v in variants.values())    # no two variants collide
    assert spec_hash(dataclasses.replace(spec)) == base               # and it is a function


def test_a_rerun_with_another_n_in_the_same_out_computes_every_row(tmp_path, benchmark_params,
                                                                    client):
    """The issue's case: m3 at 2 points, then at 3 in the same folder: 3 rows, the new ones
    computed (eigen only, ~0.1 s a bicycle)."""
    def sweep(n):
        spec = make_spec(benchmark_params, varies=[f"m3=80:90:{n}"], engines=("pinocchio",),
                         checks=("eigen",))
        return run_sweep(spec, tmp_path, client=client, progress=False)
    first, second = sweep(2), sweep(3)
    assert first.hash != second.hash and second.computed == second.chunks
    frame = pd.read_parquet(tmp_path / "results.parquet")
    assert list(frame["vary.m3"]) == [80.0, 85.0, 90.0]
    assert abs(frame["weave_speed"][1] - WEAVE) < 1e-9      # the middle one is Table 1's


def _error_by_definition(quantity, ref, other, states, tol):
    """tolerances.toml's definition, written out here: max over states of max |ref - other|
    divided by the scale (max_abs: max |ref|; max_abs_or_one: max(1, max |ref|);
    largest_term: max(1, the largest |entry| of the terms the quantity sums)); and the
    (state, index) of the largest |ref - other| of the worst state."""
    m = ref.model
    worst = (-1.0, None)
    for k in range(len(states)):
        q, dq, ddq, T = states.q[k], states.dq[k], states.ddq[k], states.T[k]
        if quantity == "mass_matrix":
            a, b = m.mass_matrix(q), other.mass_matrix(q[None])[0]
            terms = [a]
        elif quantity == "inverse_dynamics":
            a = m.mass_matrix(q) @ ddq - m.Qv(q, dq) - m.Qgrav(q)
            b = other.inverse_dynamics(q[None], dq[None], ddq[None])[0]
            terms = [m.mass_matrix(q) @ ddq, m.Qv(q, dq), m.Qgrav(q)]
        elif quantity == "forward_acceleration":
            a = ref.forward_acceleration(q[None], dq[None], T[None])[0]
            b = other.forward_acceleration(q[None], dq[None], T[None])[0]
            terms = [a]
        else:
            raise AssertionError(f"no definition written for {quantity}")
        diff = np.abs(np.asarray(a) - np.asarray(b))
        scale = {"max_abs": np.abs(a).max(), "max_abs_or_one": max(1.0, np.abs(a).max()),
                 "largest_term": max(1.0, max(np.abs(t).max() for t in terms))}[tol.scale]
        err = diff.max() / scale
        if err > worst[0]:
            worst = (err, (k, np.unravel_index(np.argmax(diff), diff.shape)))
    return worst


def test_every_column_is_what_its_definition_says(tiny):
    """Each column of the tiny sweep recomputed from its definition (sweep_task's docstring),
    not through the sweep's code: the parameters from the grid point; the derived trail from
    the model's geometry (Table 1's c); err.E.Q as tolerances.toml defines it, on the states of
    the row's seed, with the worst entry named; max_error the largest err; terms_passed and
    status from the tolerances; the critical speeds from Meijaard's closed form. The errors
    are ~1e-16 to 1e-13: the recomputation matches to 1e-3 relative plus 1e-18 (the same
    arithmetic, summed in another order), while an absolute error in place of a relative one
    moves them by the scale, >= 1e2 here."""
    from comparisons.judgments.meijaard import closed_form, closed_form_critical_speeds
    from comparisons.judgments.terms import COORDINATES, random_states
    from engines import load_engine
    from reference_model.benchmark import to_benchmark
    spec, out, _ = tiny
    # the rows recomputed in this process (test_identical_spec_identical_rows_in_any_order
    # shows they are the stored ones), so that a mutation run counts this test as one of
    # sweep_task's (the module's sweep runs once, in the first test that asks for it)
    frame = sweep_stage.rows_frame(spec, chunk_rows(spec, (0, 1, 2, 3)))
    tols = spec.tolerances
    for k, row in frame.iterrows():
        point = dict(zip(("m3", "trail"), (row["vary.m3"], row["vary.trail"])))
        assert row["p.m3"] == point["m3"]
        params = spec.base_parameters().replace(
            **{n: row[f"p.{n}"] for n in PARAMETER_NAMES})
        table = to_benchmark(params)
        assert row["trail"] == pytest.approx(table["c"], abs=1e-12)
        assert row["wheelbase"] == pytest.approx(table["w"], abs=1e-12)
        assert row["head_angle"] == pytest.approx(np.pi / 2 - table["lam"], abs=1e-12)
        weave, capsize = closed_form_critical_speeds(closed_form(table))
        assert abs(row["weave_speed"] - weave) < 1e-9 and abs(row["capsize_speed"] - capsize) < 1e-9
        model = load_model("benchmark").with_params(params)
        ref, pin = load_engine("reference", model), load_engine("pinocchio", model)
        states = random_states(spec.n_states, seed=int(row["seed"]))
        errs = []
        for q in ("mass_matrix", "inverse_dynamics", "forward_acceleration"):
            err, (state, idx) = _error_by_definition(q, ref, pin, states, tols[q])
            got = row[f"err.pinocchio.{q}"]
            assert got == pytest.approx(err, rel=1e-3, abs=1e-18), (k, q, got, err)
            if q == "mass_matrix" and err > 0:
                name = f"M[{COORDINATES[idx[0]]}, {COORDINATES[idx[1]]}] @ state {state}"
                assert row[f"entry.pinocchio.{q}"] == name
            errs.append(got)
        broken = row["err.Broken.mass_matrix"]
        if row["vary.m3"] < 90:         # the broken engine's M is the model's own: exactly 0
            assert broken == 0.0 and row["entry.Broken.mass_matrix"].endswith("@ state 0")
            errs.append(broken)
        else:
            assert np.isnan(broken) and row["status"] == "failed"
        assert row["max_error"] == max(errs)
        within = all(e <= tols[q].tolerance for e, q in
                     zip(errs, ("mass_matrix", "inverse_dynamics", "forward_acceleration")))
        assert row["terms_passed"] == (within and row["failures"] == "")
        if row["failures"] == "":
            assert row["status"] == ("agree" if within else "disagree")


def test_samples_spread_over_the_whole_range_and_keep_each_inertias_coupling(benchmark_params):
    """--spread 20 over 300 bicycles: every positive length, mass and radius, and every second
    moment, takes factors from the whole [0.8, 1.2] (the extremes of 300 uniform draws lie
    within 0.02 of the ends but for a chance of 2 x 0.95^300 = 4e-7, and those of all 3900
    length and mass draws within 0.001 but for 2 x 0.9975^3900 = 1e-4: a range of 19.8 %
    cannot reach that; seeds fixed, so the test is deterministic); g and cv stay; and each
    tensor's second-moment matrix moves by a congruence D S D, which leaves the
    coupling S_xz / sqrt(S_xx S_zz) exactly as it was (1e-12: round-off of the rebuild)."""
    from comparisons.stages.sweep_spec import ENVIRONMENT, INERTIAS, TENSORS
    spec = make_spec(benchmark_params, sample=300, spread=20.0, seed=5, checks=("terms",))
    base = dict(spec.base)
    samples = [sample_parameters(spec, k) for k in range(300)]

    def spans(factors):
        return min(factors) < 0.8 + 0.02 and max(factors) > 1.2 - 0.02

    pooled = []
    for n, v in base.items():
        if n in INERTIAS or v == 0.0:
            continue
        factors = [getattr(p, n) / v for p in samples]
        if n in ENVIRONMENT:
            assert set(factors) == {1.0}, n
        else:
            assert spans(factors), (n, min(factors), max(factors))
            pooled += factors
    assert len(pooled) >= 3000 and min(pooled) < 0.801 and max(pooled) > 1.199

    def second_moments(values, body):
        I = _tensor(values, body)
        return np.trace(I) / 2 * np.eye(3) - I
    for body in TENSORS:
        S0 = second_moments(base, body)
        S = [second_moments({n: getattr(p, n) for n in INERTIAS}, body) for p in samples]
        for i in range(3):
            assert spans([s[i, i] / S0[i, i] for s in S]), (body, i)
        if TENSORS[body][3]:
            c0 = S0[0, 2] / np.sqrt(S0[0, 0] * S0[2, 2])
            assert c0 != 0.0
            for s in S:
                assert s[0, 2] / np.sqrt(s[0, 0] * s[2, 2]) == pytest.approx(c0, abs=1e-12)
