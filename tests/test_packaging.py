"""The built wheel carries what the installed package needs: every file the code opens at run
time, every module, the reading guides, and a declared dependency for every third-party
import (issue 21: a wheel without engines/mujoco/conformance_xfails.txt made
`pytest --pyargs comparisons.conformance --engine mujoco` end in INTERNALERROR).

What the wheel holds is what setuptools' ``build_py`` writes (``bdist_wheel`` runs it and
zips the result with the metadata; the two file lists were compared once, equal). It runs
with the virtualenv's own setuptools, no network, no build isolation, into a temporary
folder (about 1 s); ``egg_info`` writes the metadata (Requires-Dist) there too, never into
the source tree.

The files the code opens come from the code itself (the constants that name them), not from
a list here; the modules and data files from the source tree.
"""

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("comparisons", "engines", "reference_model")
#: pyproject.toml's package-dir: the repository folder -> where it lands in the wheel
MAPPED = {"docs": "comparisons/docs"}
#: the imports whose distribution is named otherwise (elsewhere the two names agree, as
#: numpy's; importlib.metadata.packages_distributions() would say so too, but takes 3.5 s
#: here and cannot name pin's, which installs pinocchio outside the usual layout);
#: distributed comes with dask[distributed]; pydrake is the module of the distribution drake
DISTRIBUTION_OF = {"PIL": "pillow", "markdown_it": "markdown-it-py", "pinocchio": "pin",
                   "pydrake": "drake",
                   "distributed": "dask"}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """(the wheel's files, relative to its root; the requirement names it declares)."""
    tmp = tmp_path_factory.mktemp("wheel")
    (tmp / "meta").mkdir()
    res = subprocess.run(
        [sys.executable, "-c", "from setuptools import setup; setup()", "-q",
         "egg_info", "--egg-base", str(tmp / "meta"), "build_py", "--build-lib", str(tmp / "lib")],
        cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    files = {p.relative_to(tmp / "lib").as_posix() for p in (tmp / "lib").rglob("*") if p.is_file()}
    requires = (next((tmp / "meta").glob("*.egg-info")) / "requires.txt").read_text()
    # the core, then the extras: the engines' and the sweep's count (issue 22: their imports
    # are declared there), the developers' ([test], [mutation]) do not
    base, *extras = requires.split("\n[")
    kept = [base] + [e.split("]", 1)[1] for e in extras if e.split("]")[0] not in ("test", "mutation")]
    names = {_canonical(line.split(";")[0].split("[")[0].split(">")[0].split("=")[0].split("<")[0])
             for part in kept for line in part.splitlines() if line.strip()}
    return files, names


def _canonical(name: str) -> str:
    return name.strip().lower().replace("_", "-").replace(".", "-")


def _in_wheel(path: Path) -> str:
    """Where a file of the source tree lands in the wheel."""
    rel = path.resolve().relative_to(ROOT).as_posix()
    for folder, target in MAPPED.items():
        if rel.startswith(folder + "/"):
            return target + rel[len(folder):]
    return rel


def _opened_at_run_time() -> list[Path]:
    """Every file the code opens at run time, as the code names it."""
    from comparisons.judgments.tolerances import TOLERANCES_FILE
    from comparisons.provenance import guide_path
    from engines.kane import codegen as kane_codegen
    from engines.mujoco.engine import MujocoEngine
    from reference_model import NAMED_MODELS, codegen
    from reference_model.scenario_files import BUILTIN_DIR
    files = [TOLERANCES_FILE, Path(MujocoEngine.conformance_xfails), codegen.RUNTIME_C,
             BUILTIN_DIR / "index.json", guide_path()]
    files += [codegen.PACKAGE_DIR / n for n in codegen.KEY_SOURCES]        # hashed for the cache
    files += [kane_codegen.HERE / n for n in kane_codegen.KEY_SOURCES]
    files += [path for path, _ in NAMED_MODELS.values()]
    files += [BUILTIN_DIR / f"{stem}.toml"                                 # as load_builtin_scenarios
              for stem in json.loads((BUILTIN_DIR / "index.json").read_text(encoding="utf-8"))]
    return files


def test_the_wheel_has_every_file_the_code_opens(built):
    """Planted: engines.mujoco's "*.txt" dropped from pyproject.toml's package-data fails
    this, naming engines/mujoco/conformance_xfails.txt."""
    files, _ = built
    opened = _opened_at_run_time()
    assert all(p is not None and p.is_file() for p in opened)     # the list itself is real
    missing = sorted({_in_wheel(p) for p in opened} - files)
    assert not missing, f"opened at run time but not in the wheel: {missing}"


def test_the_wheel_has_every_module_and_data_file_of_the_tree(built):
    """Every file of the three packages (a new subpackage not listed in pyproject.toml, a new
    data file not matched by package-data) and the docs. Planted: "comparisons.report" dropped
    from pyproject.toml's packages fails this, naming its modules."""
    files, _ = built
    tree = [p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*")
            if p.is_file() and "__pycache__" not in p.parts and p.suffix not in (".pyc", ".so")]
    tree += list((ROOT / "docs").glob("*.md"))
    missing = sorted({_in_wheel(p) for p in tree} - files)
    assert not missing, f"in the source tree but not in the wheel: {missing}"
    assert not {f for f in files if f.split("/")[0] not in PACKAGES}   # nothing else at the top


def _third_party_imports() -> dict[str, str]:
    """Top-level module -> a file importing it, over every import in the packages' code
    (function-local imports too: they run when a command needs them)."""
    found = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Import):
                    mods = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    mods = [node.module]
                else:
                    continue
                for m in mods:
                    top = m.split(".")[0]
                    if top not in sys.stdlib_module_names and top not in PACKAGES:
                        found.setdefault(top, path.relative_to(ROOT).as_posix())
    return found


def test_every_third_party_import_is_a_declared_dependency(built):
    """A plain install brings what the code imports: pytest and hypothesis for the
    conformance plugin (issue 21), Pillow for the figures. Planted: "hypothesis" removed from
    pyproject.toml's dependencies fails this, naming comparisons/conformance/test_conformance.py."""
    _, declared = built
    undeclared = {module: where for module, where in _third_party_imports().items()
                  if _canonical(DISTRIBUTION_OF.get(module, module)) not in declared}
    assert not undeclared, f"imported but not a dependency in pyproject.toml: {undeclared}"
    assert {"pytest", "hypothesis"} <= declared


# -- provenance: which code wrote a report --------------------------------------------------

def _git(cwd: Path, *args: str) -> str:
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True,
                          text=True).stdout.strip()


@pytest.fixture()
def checkout(tmp_path):
    """A git repository laid out as this one (a package at its top level), one commit."""
    repo = tmp_path / "repo"
    (repo / "comparisons").mkdir(parents=True)
    (repo / "reports").mkdir()
    (repo / "comparisons" / "x.py").write_text("a = 1\n")
    (repo / "reports" / "r.md").write_text("old\n")
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "one")
    return repo


def test_the_commit_is_the_checkouts_and_dirty_means_its_code(checkout):
    """Planted: dropping the pathspec of the dirty check (every tracked file counts) fails the
    report-folder case: a regenerated example report would flip the next run's record."""
    from comparisons.provenance import package_provenance
    p = package_provenance(checkout)
    assert p.commit == _git(checkout, "log", "-1", "--format=%H") and p.dirty is False
    (checkout / "reports" / "r.md").write_text("regenerated\n")   # a report is not the code
    assert package_provenance(checkout).dirty is False
    (checkout / "comparisons" / "x.py").write_text("a = 2\n")
    assert package_provenance(checkout).dirty is True


def test_no_commit_outside_a_checkout_or_inside_someone_elses(checkout, tmp_path, monkeypatch):
    """A folder that is no checkout, a package installed in a subfolder of another project's
    checkout (a virtualenv inside it), and no git at all: no commit, no error. Planted: not
    comparing the top level with the import root reports the other project's commit."""
    from comparisons.provenance import package_provenance, version_line
    plain = tmp_path / "plain"
    plain.mkdir()
    assert package_provenance(plain).commit is None
    inside = checkout / ".venv" / "site-packages"
    inside.mkdir(parents=True)
    assert (package_provenance(inside).commit, package_provenance(inside).dirty) == (None, None)
    monkeypatch.setenv("PATH", str(plain))                        # git cannot be found
    p = package_provenance(checkout)
    assert p.commit is None and version_line(p) == f"bicycle-xval {p.version}"


def test_version_flag_prints_the_version_and_the_guide(capsys):
    import importlib.metadata
    from comparisons.cli import main
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    out = capsys.readouterr().out.splitlines()
    assert exit_.value.code == 0
    assert out[0].startswith(f"bicycle-xval {importlib.metadata.version('bicycle-xval')}")
    assert out[1] == f"reading guide: {ROOT / 'docs' / 'report.md'}"
