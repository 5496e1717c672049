"""The core works without any engine library (issue 22: `pip install bicycle-xval` is the
reference model, the harness, the report and the conformance plugin; the engines and the sweep
are extras).

Each command runs in a fresh process where Exudyn, Pinocchio, MuJoCo, Dask and pyarrow cannot be
imported: a ``sitecustomize`` put first on PYTHONPATH puts a ``sys.meta_path`` finder in front
that raises ModuleNotFoundError for those top-level names (as a core-only install would; the
same finder refuses ``importlib.util.find_spec`` too). Then ``engines`` lists each engine whose
package declares a hidden module in ``REQUIRES`` as "not installed: pip install
'bicycle-xval[EXTRA]'"; ``run`` (its default engine list) runs the rest, lists those as not run
with the same line and exits 0; naming one in ``--engines`` is a one-line usage error; the
conformance suite runs on the third-party example engine; ``sweep`` says which extra it needs.
What is expected comes from the engine packages' own declarations and pyproject.toml's extras,
not from the code under test's output.

Planted once each (then reverted): ``import pinocchio`` at the top of engines/registry.py
failed every subprocess test here (the CLI ends in a traceback before anything runs);
engines/exudyn/__init__.py importing its engine unconditionally failed the listing test
("cannot be loaded" instead of "not installed") and the run test (exit 1, engine dropped);
the sweep's check of its modules removed failed the sweep test (a traceback from the import
of distributed, exit 1).

Cost: five fresh processes and the CSV check, about 10.5 s of CPU (20.7 s of wall time alone,
at load 7 on the 2-core machine): the run is the quick selection cut to one scenario, no
sections, no figures, no HTML; the conformance suite is one term of its sweep.
"""

import ast
import importlib.util
import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from engines.registry import DISTRIBUTION, EngineNotInstalled, registrations, resolve

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "numpy_engine"
FILE_SPEC = f"{EXAMPLE / 'numpy_bicycle' / 'engine.py'}:NumpyEngine"
#: the top-level modules a core-only install lacks: the engines' libraries and the sweep's
HIDDEN = ("exudyn", "pinocchio", "mujoco", "dartpy", "pydrake", "dask", "distributed", "pyarrow")

SITECUSTOMIZE = f'''
import sys

HIDDEN = {HIDDEN!r}


class _NotInstalled:
    """Refuses HIDDEN as if they were not installed."""

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None


sys.meta_path.insert(0, _NotInstalled())
'''


@pytest.fixture(scope="module")
def core_env(tmp_path_factory):
    """The environment of a core-only process: the hiding sitecustomize first, then this
    checkout (so its code runs, not another worktree's editable install)."""
    hook = tmp_path_factory.mktemp("core-only")
    (hook / "sitecustomize.py").write_text(SITECUSTOMIZE)
    return dict(os.environ, COLUMNS="400", PYTHONHASHSEED="0",
                PYTHONPATH=os.pathsep.join([str(hook), str(ROOT), os.environ.get("PYTHONPATH", "")]))


def _core(env, *args, cwd):
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


def _declaration(module: str) -> tuple[tuple[str, ...], str | None]:
    """(REQUIRES, EXTRA) as written in the module's source (read, not imported: importing the
    engines here would cost their libraries' import and trust the code under test)."""
    path = Path(importlib.util.find_spec(module).origin)
    found = {}
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                and getattr(node.targets[0], "id", None) in ("REQUIRES", "EXTRA"):
            found[node.targets[0].id] = ast.literal_eval(node.value)
    return tuple(found.get("REQUIRES", ())), found.get("EXTRA")


def _declared_missing() -> dict[str, str]:
    """Registered engine -> the listing's line, from each engine module's own REQUIRES and
    EXTRA and pyproject.toml's extras."""
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    out = {}
    for reg in registrations():
        requires, extra = _declaration(reg.target.partition(":")[0])
        if {r.split(".")[0] for r in requires} & set(HIDDEN):
            assert extra in extras, f"{reg.name}: EXTRA {extra!r} is not an extra of pyproject.toml"
            out[reg.name] = f"not installed: pip install '{DISTRIBUTION}[{extra}]'"
    return out


def test_the_engines_libraries_are_extras_not_core_dependencies():
    """Every engine's declared extra exists, `all` brings each of them and the sweep, and no
    core dependency is one of an extra's (the core stays light)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    missing = _declared_missing()
    assert len(missing) >= 3, missing          # the three engine libraries each declare one
    named = {line.split("[")[-1].rstrip("]'") for line in missing.values()}
    all_ = extras["all"][0].split("[")[1].rstrip("]").split(",")
    assert named | {"sweep"} <= set(all_)
    heavy = {r.split("[")[0].split(">")[0] for e in named | {"sweep"} for r in extras[e]}
    assert not heavy & {d.split("[")[0].split(">")[0] for d in project["dependencies"]}


@pytest.mark.slow
def test_engines_lists_each_missing_engine_with_its_pip_line(core_env, tmp_path):
    expected = _declared_missing()
    res = _core(core_env, "-m", "comparisons.cli", "engines", cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    lines = res.stdout.splitlines()
    for name, line in expected.items():
        at = next(i for i, t in enumerate(lines) if t.startswith(f"{name}  ("))
        assert lines[at + 1].strip() == line, res.stdout
    assert "cannot be loaded" not in res.stdout, res.stdout   # the rest load without them
    assert "capabilities:" in res.stdout


@pytest.mark.slow
def test_run_runs_the_installed_engines_and_lists_the_others(core_env, tmp_path):
    """The default engine list without the libraries: exit 0, each missing engine on stderr
    and in the report as not run with its line, nothing dropped; naming one is exit 2."""
    expected = _declared_missing()
    out = tmp_path / "r"
    res = _core(core_env, "-m", "comparisons.cli", "run", "--quick", "--scenarios", "check",
                "--sections", "none", "--figures", "none", "--no-html",
                "--out", str(out), cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["passed"] and not summary["dropped_engines"]
    assert {d["engine"]: d["reason"] for d in summary["not_installed_engines"]} == expected
    assert not set(expected) & set(summary["engines"]) and "reference" in summary["engines"]
    assert list((out / "data").glob("*.csv"))         # written without pyarrow
    report = (out / "report.md").read_text()
    for name, line in expected.items():
        assert f"engine {name} not run: {line}" in res.stderr
        assert f"Not run: engine `{name}`: {line}" in report
    name, line = next(iter(expected.items()))
    res = _core(core_env, "-m", "comparisons.cli", "run", "--quick", "--engines", name,
                "--out", str(out), cwd=tmp_path)
    err = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(err) == 1 and err[0].endswith(line), res.stderr[-2000:]


@pytest.mark.slow
def test_the_conformance_suite_runs_on_a_plugin_without_the_engine_libraries(core_env, tmp_path):
    res = _core(core_env, "-m", "pytest", "-p", "no:cacheprovider", "-q", "--pyargs",
                "comparisons.conformance", "--engine", FILE_SPEC, "--model", "thesis-disc",
                "-k", "sweep and mass_matrix", cwd=tmp_path)
    assert res.returncode == 0, res.stdout[-3000:]
    assert "1 passed" in res.stdout, res.stdout[-2000:]


@pytest.mark.slow
def test_sweep_without_dask_names_its_extra(core_env, tmp_path):
    """With an engine that is installed, so that Dask is the only thing missing."""
    installed = next(r.name for r in registrations()
                     if r.name != "reference" and r.name not in _declared_missing())
    res = _core(core_env, "-m", "comparisons.cli", "sweep", "--vary", "trail=0:0.2:3",
                "--engines", installed, "--out", str(tmp_path / "s"), cwd=tmp_path)
    err = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(err) == 1, res.stderr[-2000:]
    assert "dask" in err[0] and err[0].endswith(f"pip install '{DISTRIBUTION}[sweep]'")


def test_a_plugin_declares_its_own_extra(tmp_path, monkeypatch):
    """The registry reads REQUIRES/EXTRA generically: a third party's engine package whose
    library is missing is not installed with the pip line of *its* distribution and extra,
    found without importing the engine's module; by module spec (no distribution known) the
    line names the missing module."""
    pkg = tmp_path / "acme_heavy"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        "from engines.registry import missing_modules\n"
        "REQUIRES = ('acme_no_such_library',)\nEXTRA = 'heavy'\n"
        "if not missing_modules(REQUIRES):\n    from .engine import AcmeEngine\n")
    (pkg / "engine.py").write_text("raise AssertionError('the engine module was imported')\n")
    dist = tmp_path / "acme_bike-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: acme-bike\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[bicycle_xval.engines]\nacme = acme_heavy:AcmeEngine\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    from engines import engine_info, not_installed
    assert not_installed("acme") == "not installed: pip install 'acme-bike[heavy]'"
    [info] = engine_info("acme")
    assert info.not_installed == not_installed("acme") and info.error is None
    with pytest.raises(EngineNotInstalled, match="it needs acme_no_such_library"):
        resolve("acme_heavy:AcmeEngine")


def test_the_core_csv_writer_gives_arrows_bytes():
    """Without pyarrow (not in the core) the CSV files come from `plain_csv_rows`; the oracle is
    Arrow's own writer (double-conversion, C++): every double class (random bit patterns:
    subnormals, huge, NaN; random magnitudes 1e-12..1e14; the thresholds of its plain-decimal
    range 1e-6 and 1e10 and of repr's 1e-4 and 1e16), booleans, integers, text with quotes and
    commas, missing values. Planted: the plain range's lower end -6 -> -5 fails this (1e-6
    written 1e-6 where Arrow writes 0.000001). 30,000 rows of four columns: about 0.5 s."""
    import io

    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pa_csv

    from comparisons.stages.files import _arrow_column, plain_csv_rows
    rng = np.random.default_rng(22)
    edges = [0.0, -0.0, 1.0, 3.0, 100.0, 0.1, 1e-4, 9.9e-5, 1e-5, 1e-6, 9.99999e-7, 1e-7, 1e9,
             9999999999.0, 9999999999.5, 1e10, 1e15, 1e16, 1e21, 5e-324, 2.2250738585072014e-308,
             1.7976931348623157e308, np.inf, -np.inf, np.nan, -1e-6, -1e10]
    bits = rng.integers(0, np.iinfo(np.uint64).max, 15000, dtype=np.uint64, endpoint=True)
    floats = np.concatenate([bits.view(np.float64),
                             rng.normal(size=15000) * 10.0 ** rng.integers(-12, 15, 15000), edges])
    n = floats.size
    text = np.array([None if i % 7 == 0 else f'r{i},"q"' for i in range(n)], dtype=object)
    cols = {"x": floats, "ok": floats > 0, "i": np.arange(n) - n // 2, "s": text}
    table = pa.Table.from_arrays([_arrow_column(cols["x"]), pa.array(cols["ok"]),
                                  pa.array(cols["i"]), pa.array(list(text))], names=list(cols))
    buf = io.BytesIO()
    pa_csv.write_csv(table, buf, pa_csv.WriteOptions(include_header=False, quoting_style="needed"))
    arrow, plain = buf.getvalue().decode().splitlines(), plain_csv_rows(list(cols.values())).splitlines()
    assert len(plain) == len(arrow) == n
    differ = [(a, b) for a, b in zip(arrow, plain) if a != b]
    assert not differ, differ[:5]
