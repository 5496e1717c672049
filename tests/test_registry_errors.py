"""Every refusal of the engine registry (engines/registry.py) as the user reads it, issue 24.

The registry's contract (its module docstring, docs/engines.md): each error says in one line
the engine, the spec and the cause or the fix; a usage error is `EngineSpecError`, an engine
that is named right but broken is `EngineLoadError`, a missing extra is `EngineNotInstalled`.
The expected messages are written out here from that contract, whole, so that a message that
loses its engine, its spec or its fix fails; and the behaviours behind them (which file a spec
loads, which module is missing, whose pyproject is read) are checked on files written here.
Planted bugs each test was seen failing on are named in its docstring.
"""

import os
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import pytest

from engines.base import EngineLoadError, EngineSpecError
from engines.registry import (EngineNotInstalled, _canonical, _engine_class,
                              _pyproject_registrations, missing_modules, resolve)

ENGINE = '''
from engines.base import Engine

class {cls}(Engine):
    name = "{name}"
    capabilities = frozenset({{"mass_matrix"}})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)
'''


@pytest.fixture(autouse=True)
def _modules_forgotten():
    """The modules these tests import from their temporary folders are forgotten after each
    (a second session in the same process, as mutmut runs, would find the first one's)."""
    import importlib
    before = set(sys.modules)
    yield
    for name in set(sys.modules) - before:
        if "_xyz" in name or name.startswith("bicycle_xval_engine_file_"):
            del sys.modules[name]
    importlib.invalidate_caches()


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text))
    return path


# -- specs: which file, which class -----------------------------------------------------------

def test_two_files_with_one_name_load_their_own_classes(tmp_path):
    """a/eng.py and b/eng.py are two engines: the module each is loaded as is keyed by its
    path. Planted: the path's digest left out of the module name (the second spec returned
    the first file's module)."""
    a = _write(tmp_path / "a" / "eng.py", ENGINE.format(cls="One", name="one"))
    b = _write(tmp_path / "b" / "eng.py", ENGINE.format(cls="One", name="other"))
    ca, la, wa = resolve(f"{a}:One")
    cb, lb, wb = resolve(f"{b}:One")
    assert (la, lb) == ("one", "other") and ca is not cb
    assert (wa, wb) == (str(a.resolve()), str(b.resolve()))


def test_a_path_with_a_colon_splits_at_the_last_one(tmp_path):
    """The class follows the last colon (a directory may hold one). Planted: split at the
    first colon, at most two splits."""
    f = _write(tmp_path / "run:2" / "eng.py", ENGINE.format(cls="Eng", name="colon"))
    cls, label, where = resolve(f"{f}:Eng")
    assert label == "colon" and where == str(f.resolve())


def test_a_module_spec_is_labelled_by_its_last_part_and_found_where_it_is():
    """engines.base:Nope: the label is 'base', the message names the module's file (and that
    it defines no Engine subclass: Engine itself is not one). Planted: the label from the first part (split), the
    spec left out of the message."""
    import engines.base
    with pytest.raises(EngineSpecError) as e:
        resolve("engines.base:Nope")
    assert str(e.value) == (f"engine 'base': no class 'Nope' in {engines.base.__file__} (spec "
                            f"'engines.base:Nope'); it defines no Engine subclass")


def test_a_found_module_spec_says_where_its_class_comes_from():
    """(class, label, the module's file). Planted: where = the spec's text."""
    import engines.reference
    cls, label, where = resolve("engines.reference:ReferenceEngine")
    assert cls is engines.reference.ReferenceEngine and where == engines.reference.__file__


def test_a_module_without_a_file_is_named_by_its_name():
    """A module with no __file__ (sys, built in): the message names it by its name. Planted:
    __file__ read without a default (AttributeError escaped), the name left out."""
    with pytest.raises(EngineSpecError) as e:
        resolve("sys:Engine")
    assert str(e.value) == ("engine 'sys': no class 'Engine' in sys (spec 'sys:Engine'); it "
                            "defines no Engine subclass")


def test_a_class_that_is_not_an_engine_says_how_to_make_it_one():
    with pytest.raises(EngineSpecError) as e:
        resolve("pathlib:Path")
    assert str(e.value) == ("engine 'pathlib': 'Path' in spec 'pathlib:Path' is not an "
                            "engines.base.Engine subclass; subclass Engine (see docs/engines.md)")


def test_the_listing_of_classes_names_every_engine_subclass_but_engine():
    mod = types.ModuleType("m")
    from engines.base import Engine
    mod.B = type("B", (Engine,), {})
    mod.A = type("A", (Engine,), {})
    mod.Engine, mod.other = Engine, int
    with pytest.raises(EngineSpecError, match=r"; it defines: A, B$"):
        _engine_class(mod, "C", "m", "m:C")


@pytest.mark.parametrize("spec, message", [
    (None, "engine spec None is empty; give a registered name, package.module:Class or "
           "path/to/file.py:Class"),
    ("   ", "engine spec '   ' is empty; give a registered name, package.module:Class or "
           "path/to/file.py:Class"),
    ("nofile.py:Eng", "engine 'nofile': no file 'nofile.py' for spec 'nofile.py:Eng'; check "
                      "the path (relative to the working directory {cwd!r})"),
    ("dir\\eng:Eng", f"engine {'dir' + chr(92) + 'eng'!r}: {'dir' + chr(92) + 'eng'!r} in spec "
                     f"{'dir' + chr(92) + 'eng:Eng'!r} is not a .py file; give path/to/file.py:Class"),
    ("eng.py", "engine spec 'eng.py' names no class: write eng.py:ClassName (the Engine "
               "subclass to load, after a colon)"),
    ("a.b.Cls", "unknown engine 'a.b.Cls'; a class in a module is written package.module:Class, "
                "e.g. a.b:Cls"),
    ("no_such_pkg_xyz.sub:Cls", "engine 'sub': no module 'no_such_pkg_xyz' for spec "
                                "'no_such_pkg_xyz.sub:Cls'; check the spelling or install the "
                                "package that provides it (a registered name, "
                                "package.module:Class or path/to/file.py:Class)"),
    ("a-b:Cls", "engine spec 'a-b:Cls' is malformed: 'a-b' is neither a dotted module name nor "
                "a path ending in .py"),
    (":Cls", "engine spec ':Cls' is malformed: expected package.module:Class or "
             "path/to/file.py:Class (Class a Python identifier)"),
])
def test_each_wrong_spec_is_one_line_naming_it_and_the_fix(spec, message):
    """Planted: '.py' read in upper case, the backslash not a path, rsplit for split in the
    hint, the missing package's dotted test (missing - '.'), a non-string spec checked with
    'and' (AttributeError escaped)."""
    with pytest.raises(EngineSpecError) as e:
        resolve(spec)
    assert str(e.value) == message.format(cwd=str(Path.cwd()))


# -- engines that are named right but do not import -------------------------------------------

@pytest.mark.parametrize("body, cause", [
    ("import no_such_dependency_xyz\n",
     "ModuleNotFoundError: No module named 'no_such_dependency_xyz'"),
    ("raise RuntimeError('licence server down\\nretry later')\n",
     "RuntimeError: licence server down"),
    ("raise RuntimeError()\n", "RuntimeError: RuntimeError()"),
])
def test_a_file_that_fails_to_import_names_the_engine_the_spec_and_the_first_line(tmp_path, body,
                                                                                   cause):
    """A missing dependency of the engine (not the engine's own module) is a load error, not
    a spelling error; the cause is its first line, or its repr when it has none. Planted:
    the spec dropped from the message, repr(None) for an empty message."""
    f = _write(tmp_path / "broken.py", body)
    spec = f"{f}:Eng"
    with pytest.raises(EngineLoadError) as e:
        resolve(spec)
    assert str(e.value) == f"engine 'broken' ({spec}) failed to import: {cause}"


@pytest.mark.parametrize("body, cause", [
    ("import no_such_dependency_xyz\n",
     "ModuleNotFoundError: No module named 'no_such_dependency_xyz'"),
    ("raise ValueError('bad table\\nline 2')\n", "ValueError: bad table"),
])
def test_a_module_that_fails_to_import_names_the_engine_the_spec_and_the_cause(tmp_path,
                                                                               monkeypatch, body,
                                                                               cause):
    """The same through a module spec: the engine's module exists, a module it imports does
    not (an extra's dependency) or it raises. Planted: any missing module taken for the
    spec's own (missing or ...), the message replaced by None."""
    _write(tmp_path / "pkg_reg_xyz" / "__init__.py", "")
    _write(tmp_path / "pkg_reg_xyz" / "eng.py", body)
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(EngineLoadError) as e:
        resolve("pkg_reg_xyz.eng:Eng")
    assert str(e.value) == f"engine 'eng' (pkg_reg_xyz.eng:Eng) failed to import: {cause}"


# -- what an engine declares it needs ----------------------------------------------------------

@pytest.mark.parametrize("requires, extra", [
    ('"numpy"', None),                 # a string, not a tuple of names
    ('("numpy", 3)', None),            # not every entry a name
    ('("not a module",)', None),       # a string that is no module name
    ('("numpy",)', '"bad extra!"'),    # an extra that is no extra's name
])
def test_a_malformed_declaration_is_the_engines_fault(tmp_path, requires, extra):
    """Planted: the three tests joined by 'and' where one is enough, 'or' inside the entries'
    test."""
    f = _write(tmp_path / "decl.py", f"REQUIRES = {requires}\nEXTRA = {extra}\n"
               + ENGINE.format(cls="Eng", name="decl"))
    spec = f"{f}:Eng"
    with pytest.raises(EngineLoadError) as e:
        resolve(spec)
    shown = ", ".join([requires.replace('"', "'"), (extra or "None").replace('"', "'")])
    assert str(e.value) == (f"engine 'decl' ({spec}): REQUIRES must be a tuple of module names "
                            f"and EXTRA an extra's name; got {shown}")


@pytest.mark.parametrize("requires, needs, pronoun", [
    ('("no_such_xyz.sub",)', "no_such_xyz", "it"),
    ('("no_such_xyz", "numpy", "no_such_abc")', "no_such_xyz, no_such_abc", "them"),
])
def test_a_file_engine_missing_what_it_requires_is_not_installed(tmp_path, requires, needs,
                                                                 pronoun):
    """Only the top-level module of a dotted requirement is looked up; one missing is 'it',
    more are 'them'; the engine is the file's label. A hyphen in EXTRA is allowed (an extra's
    name). Planted: the dotted name looked up whole, the pronoun's test, the label dropped."""
    f = _write(tmp_path / "needy.py", f"REQUIRES = {requires}\nEXTRA = 'my-extra'\n"
               + ENGINE.format(cls="Eng", name="needy"))
    with pytest.raises(EngineNotInstalled) as e:
        resolve(f"{f}:Eng")
    reason = f"not installed: it needs {needs} (install the package that provides {pronoun})"
    assert (e.value.engine, e.value.reason) == ("needy", reason)
    assert str(e.value) == f"engine 'needy' is {reason}"


def test_missing_modules_counts_a_refused_lookup_as_missing():
    """find_spec('') raises ValueError: missing, as an import hook's refusal is. Planted:
    found = True there."""
    assert missing_modules(["", "os", "no_such_xyz"]) == ("", "no_such_xyz")


# -- registered engines whose entry point is wrong ---------------------------------------------

def _registered(tmp_path, monkeypatch, name: str, target: str, module: str = "",
                dist: str = "third-xyz"):
    """A distribution ``dist`` 0.1 registering ``name = target`` (and a module file)."""
    from fake_dist import dist_info
    if module:
        _write(tmp_path / f"{target.split(':')[0].strip()}.py", module)
    dist_info(tmp_path, dist, "0.1", {name: target})
    monkeypatch.syspath_prepend(str(tmp_path))


def test_a_registered_target_that_is_no_module_and_class_is_broken_metadata(tmp_path, monkeypatch):
    """Planted: the target's two tests joined by 'and' (a module name with a space went on to
    import), the message replaced by None."""
    _registered(tmp_path, monkeypatch, "spaced", "not a module:Cls")
    with pytest.raises(EngineLoadError) as e:
        resolve("spaced")
    assert str(e.value) == ("engine 'spaced': its entry point 'not a module:Cls' (third-xyz 0.1) "
                            "is not package.module:Class; the package's metadata is broken")


def test_a_registered_engine_without_its_class_names_the_registration(tmp_path, monkeypatch):
    """The name and the target in the message, then who registered it. Planted: either
    dropped (None passed on)."""
    _registered(tmp_path, monkeypatch, "classless", "classless_xyz:Gone", module="X = 1\n")
    with pytest.raises(EngineLoadError) as e:
        resolve("classless")
    assert str(e.value) == (f"engine 'classless': no class 'Gone' in "
                            f"{tmp_path / 'classless_xyz.py'} (spec 'classless_xyz:Gone'); it "
                            f"defines no Engine subclass [registered by third-xyz 0.1]")


def test_a_registered_engine_whose_module_fails_names_its_target(tmp_path, monkeypatch):
    _registered(tmp_path, monkeypatch, "failing", "failing_xyz:Eng",
                module="raise ImportError('needs libfoo.so')\n")
    with pytest.raises(EngineLoadError) as e:
        resolve("failing")
    assert str(e.value) == ("engine 'failing' (failing_xyz:Eng) failed to import: ImportError: "
                            "needs libfoo.so")


def test_a_registered_engine_missing_its_extra_gives_the_pip_line(tmp_path, monkeypatch):
    """The registering distribution's extra, with the registered name. Planted: the name or
    the target dropped on the way to the check."""
    _registered(tmp_path, monkeypatch, "extra", "extra_xyz:Eng",
                module="REQUIRES = ('no_such_xyz',)\nEXTRA = 'gpu'\n"
                + ENGINE.format(cls="Eng", name="extra"))
    with pytest.raises(EngineNotInstalled) as e:
        resolve("extra")
    assert (e.value.engine, e.value.reason) == ("extra", "not installed: pip install "
                                                         "'third-xyz[gpu]'")


def test_with_nothing_registered_the_unknown_name_says_so(monkeypatch):
    from engines import registry
    monkeypatch.setattr(registry, "registrations", lambda: [])
    with pytest.raises(EngineSpecError) as e:
        resolve("anything")
    assert str(e.value) == ("unknown engine 'anything'; available: none registered (or give a "
                            "spec package.module:Class or path/to/file.py:Class)")


def test_a_name_registered_twice_lists_both_registrations(tmp_path, monkeypatch):
    _registered(tmp_path / "one", monkeypatch, "twice", "twice_a:Eng", dist="first-xyz")
    _registered(tmp_path / "two", monkeypatch, "twice", "twice_b:Eng", dist="second-xyz")
    with pytest.raises(EngineSpecError) as e:
        resolve("twice")
    assert str(e.value) == ("engine name 'twice' is registered more than once (twice_a:Eng from "
                            "first-xyz 0.1; twice_b:Eng from second-xyz 0.1); name one by its "
                            "spec package.module:Class")


# -- this project's own declaration in a source checkout ---------------------------------------

def _pyproject(tmp_path: Path, text: str) -> Path:
    return _write(tmp_path / "pyproject.toml", text)


def test_the_project_is_recognised_by_its_canonical_name(tmp_path):
    """PEP 503 names: 'Bicycle_XVal' is bicycle-xval. Planted: upper() for lower()."""
    assert _canonical("Bicycle_XVal..x") == "bicycle-xval-x"
    p = _pyproject(tmp_path, '[project]\nname = "Bicycle_XVal"\n'
                   '[project.entry-points."bicycle_xval.engines"]\nmine = "m:Eng"\n')
    assert [(r.name, r.target, r.distribution) for r in _pyproject_registrations(p)] == \
        [("mine", "m:Eng", None)]


@pytest.mark.parametrize("text", ["[tool.x]\ny = 1\n",                       # no [project]
                                  '[project]\nname = "bicycle-xval"\n',       # no entry points
                                  '[project]\nname = "bicycle-xval"\n'
                                  '[project.entry-points.other]\na = "b:C"\n'])  # not our group
def test_a_pyproject_without_the_group_registers_nothing(tmp_path, text):
    """Planted: each of the three lookups without its empty default (None, or no default)."""
    assert _pyproject_registrations(_pyproject(tmp_path, text)) == []


def test_the_pyproject_is_read_as_utf8_whatever_the_locale(tmp_path):
    """A maintainer's name with an accent, read under the C locale (ASCII): the file is UTF-8
    by the TOML standard. Planted: the locale's encoding (UnicodeDecodeError escaped)."""
    p = _pyproject(tmp_path, '[project]\nname = "bicycle-xval"\nauthors = [{name = "Gómez"}]\n'
                   '[project.entry-points."bicycle_xval.engines"]\nmine = "m:Eng"\n')
    env = {**os.environ, "LC_ALL": "C", "LANG": "C", "PYTHONCOERCECLOCALE": "0",
           "PYTHONUTF8": "0"}
    code = ("import sys; from engines.registry import _pyproject_registrations as r; "
            f"print([x.name for x in r(__import__('pathlib').Path({str(p)!r}))])")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          cwd=Path(__file__).resolve().parents[1], timeout=60)
    assert (done.returncode, done.stdout) == (0, "['mine']\n"), done.stderr[-500:]


def test_a_module_spec_three_deep_is_labelled_by_its_last_part():
    """reference_model.scenarios.files:Nope is engine 'files'. Planted: split at the first
    dot ('scenarios.files'). (Any split count from 1 on gives the same last part.)"""
    import reference_model.scenarios.files as files
    with pytest.raises(EngineSpecError) as e:
        resolve("reference_model.scenarios.files:Nope")
    assert str(e.value).startswith(f"engine 'files': no class 'Nope' in {files.__file__} ")


def test_a_registered_engine_with_a_malformed_declaration_names_itself(tmp_path, monkeypatch):
    """Planted: the registered name or its target dropped on the way to the check."""
    _registered(tmp_path, monkeypatch, "declared", "declared_xyz:Eng",
                module="REQUIRES = 'numpy'\n" + ENGINE.format(cls="Eng", name="declared"))
    with pytest.raises(EngineLoadError) as e:
        resolve("declared")
    assert str(e.value) == ("engine 'declared' (declared_xyz:Eng): REQUIRES must be a tuple of "
                            "module names and EXTRA an extra's name; got 'numpy', None")
