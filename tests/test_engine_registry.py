"""Engine discovery and loading: entry points, module and file specs, and their errors.

Third-party engines are simulated without installing anything: a `<dist>-<ver>.dist-info/`
folder with METADATA and entry_points.txt in a temporary directory on sys.path is exactly what
`importlib.metadata` reads for an installed distribution.
"""

import textwrap
from pathlib import Path

import numpy as np
import pytest

import engines
from engines import (EngineError, EngineLoadError, EngineSpecError, available_engines,
                     engine_info, load_engine, load_engines)
from engines.registry import _pyproject_registrations
from fake_dist import dist_info as _dist_info

BUILTINS = ("reference", "pinocchio", "exudyn")

FAKE_MODULE = '''
from engines.base import Engine

class FakeEngine(Engine):
    """A third party's engine: M only (from the model it was built from)."""
    name = "fake"
    capabilities = frozenset({"mass_matrix"})
    contacts = ("thesis",)

    def __init__(self, model, scale=1.0):
        super().__init__(model)
        self.scale = scale

    def mass_matrix(self, q):
        return self.scale * self.model.mass_matrix(q)

class Lazy(Engine):
    """Declares D without implementing it."""
    name = "lazy"
    capabilities = frozenset({"mass_matrix", "constraint_jacobian"})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

class Boom(Engine):
    name = "boom"
    def __init__(self, model):
        raise RuntimeError("no licence server")

class Typo(Engine):
    name = "typo"
    capabilities = frozenset({"mass_matrix", "masmatrix"})
    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

NOT_AN_ENGINE = object
'''




@pytest.fixture
def third_party(tmp_path, monkeypatch):
    """A fake installed distribution 'fake-engines 1.2.3' registering four engines."""
    (tmp_path / "fake_engine_mod.py").write_text(FAKE_MODULE)
    _dist_info(tmp_path, "fake-engines", "1.2.3", {
        "fake": "fake_engine_mod:FakeEngine", "lazy": "fake_engine_mod:Lazy",
        "boom": "fake_engine_mod:Boom", "ghost": "no_such_module_xyz:Ghost",
        "typo": "fake_engine_mod:Typo"})
    monkeypatch.syspath_prepend(str(tmp_path))
    return tmp_path


def test_builtins_are_discovered_in_declaration_order():
    assert available_engines()[:3] == BUILTINS


def test_builtins_come_from_the_pyproject_declaration():
    """The source-tree fallback reads the same table the installed entry points come from."""
    regs = {r.name: r.target for r in _pyproject_registrations()}
    assert regs == {"reference": "engines.reference:ReferenceEngine",
                    "pinocchio": "engines.pinocchio:PinocchioEngine",
                    "exudyn": "engines.exudyn:ExudynEngine",
                    "kane": "engines.kane:KaneEngine",
                    "fmu": "engines.fmu:FmuEngine",
                    "mujoco": "engines.mujoco:MujocoEngine",
                    "dart": "engines.dart:DartEngine",
                    "drake": "engines.drake:DrakeEngine",
                    "symbrim": "engines.symbrim:SymbrimEngine"}


def test_builtin_info_lists_capabilities_contacts_and_options():
    info = {i.name: i for i in engine_info()}
    assert set(BUILTINS) <= set(info)
    assert info["reference"].capabilities == engines.CAPABILITIES
    assert info["exudyn"].capabilities == ("mass_matrix", "generalized_forces", "simulate")
    assert "build" in info["exudyn"].options and info["pinocchio"].options == ()
    assert all(info[n].contacts == ("thesis", "disc") and info[n].error is None for n in BUILTINS)
    assert info["reference"].source.startswith("bicycle-xval")


def test_third_party_entry_point_is_discovered_and_built(third_party, thesis):
    assert {"fake", "lazy", "boom", "ghost"} <= set(available_engines())
    assert available_engines()[:3] == BUILTINS          # ours first, then theirs by name
    info = {i.name: i for i in engine_info()}
    assert info["fake"].source == "fake-engines 1.2.3"
    assert info["fake"].capabilities == ("mass_matrix",) and info["fake"].contacts == ("thesis",)
    assert info["fake"].options == ("scale",)
    assert "no module 'no_such_module_xyz'" in info["ghost"].error   # listed, not raised
    eng = load_engine("fake", thesis, scale=2.0)
    q = np.linspace(-1, 1, 8)
    np.testing.assert_array_equal(eng.mass_matrix(q), 2.0 * thesis.mass_matrix(q))


def test_module_and_file_specs(third_party, thesis):
    by_module = load_engine("fake_engine_mod:FakeEngine", thesis)
    by_file = load_engine(f"{third_party / 'fake_engine_mod.py'}:FakeEngine", thesis)
    assert type(by_module).__name__ == type(by_file).__name__ == "FakeEngine"
    [info] = engine_info(f"{third_party / 'fake_engine_mod.py'}:FakeEngine")
    assert info.name == "fake" and info.source == str(third_party / "fake_engine_mod.py")


@pytest.mark.parametrize("spec, message", [
    ("bullet", r"unknown engine 'bullet'; available: reference, pinocchio, exudyn.*spec"),
    ("fake_engine_mod:", r"malformed.*package.module:Class"),
    ("my/engine.py", r"'my/engine.py' names no class: write my/engine.py:ClassName"),
    ("fake_engine_mod.FakeEngine", r"package.module:Class, e.g. fake_engine_mod:FakeEngine"),
    ("fake_engine_mod:1x", r"malformed"),
    ("fake engine:Fake", r"malformed: 'fake engine' is neither a dotted module"),
    ("no_such_module_xyz:Ghost", r"no module 'no_such_module_xyz'.*install"),
    ("fake_engine_mod:Missing", r"no class 'Missing' in .*defines: Boom, FakeEngine, Lazy, Typo"),
    ("fake_engine_mod:NOT_AN_ENGINE", r"'NOT_AN_ENGINE' .* is not an engines.base.Engine subclass"),
    ("missing/dir/engine.py:X", r"no file 'missing/dir/engine.py'"),
    ("engine.txt/x:X", r"is not a .py file"),
])
def test_bad_spec_is_a_usage_error(third_party, thesis, spec, message):
    with pytest.raises(EngineSpecError, match=message) as err:
        load_engine(spec, thesis)
    assert "\n" not in str(err.value)


def test_bad_options_are_usage_errors(third_party, thesis):
    with pytest.raises(EngineSpecError, match=r"engine 'fake'.*does not take option\(s\) scal; it takes: scale"):
        load_engine("fake", thesis, scal=2)
    with pytest.raises(EngineSpecError, match="engine 'reference'.*takes no options; got build"):
        load_engine("reference", thesis, build="tree")
    with pytest.raises(EngineSpecError, match="engine 'exudyn'.*unknown Exudyn build 'x'"):
        load_engine("exudyn", thesis, build="x")


@pytest.mark.parametrize("spec, message", [
    ("lazy", r"engine 'lazy' \(fake_engine_mod:Lazy from fake-engines 1.2.3\) declares "
             r"constraint_jacobian but does not implement it"),
    ("boom", r"engine 'boom' \(fake_engine_mod:Boom .*\) raised while being built: RuntimeError: no licence server"),
    ("ghost", r"engine 'ghost'.*no module 'no_such_module_xyz'.*registered by fake-engines 1.2.3"),
    ("typo", r"declares unknown capabilities masmatrix"),
])
def test_engine_failure_is_a_load_error(third_party, thesis, spec, message):
    with pytest.raises(EngineLoadError, match=message) as err:
        load_engine(spec, thesis)
    assert "\n" not in str(err.value)


def test_unsupported_contact_and_import_failure(third_party, disc, tmp_path):
    with pytest.raises(EngineLoadError, match=r"engine 'fake'.*supports the front-contact models "
                                              r"thesis, not 'disc' of model 'thesis-disc'"):
        load_engine("fake", disc)
    broken = tmp_path / "broken_engine.py"
    broken.write_text("import numpy\nraise ImportError('needs libfoo.so')\n")
    with pytest.raises(EngineLoadError, match=r"engine 'broken_engine' .* failed to import: "
                                              r"ImportError: needs libfoo.so"):
        load_engine(f"{broken}:X", disc)
    missing_dep = tmp_path / "dep_engine.py"
    missing_dep.write_text("import no_such_dependency_xyz\n")
    # the file exists, its dependency does not: the engine failed, the spec is right
    with pytest.raises(EngineLoadError, match="No module named 'no_such_dependency_xyz'"):
        load_engine(f"{missing_dep}:X", disc)


def test_a_name_registered_twice_is_ambiguous(third_party, thesis, tmp_path_factory):
    other = tmp_path_factory.mktemp("other")
    _dist_info(other, "other-engines", "0.1", {"fake": "fake_engine_mod:Lazy"})
    import sys
    sys.path.insert(0, str(other))
    try:
        with pytest.raises(EngineSpecError, match=r"'fake' is registered more than once.*"
                                                  r"fake-engines 1.2.3.*other-engines 0.1"):
            load_engine("fake", thesis)
    finally:
        sys.path.remove(str(other))


def test_load_engines_drops_failures_and_continues(third_party, thesis):
    built, dropped = load_engines(["reference", "boom", "fake", "lazy", "ghost"], thesis,
                                  {"fake": {"scale": 3.0}})
    assert list(built) == ["reference", "fake"] and built["fake"].scale == 3.0
    assert [name for name, _ in dropped] == ["boom", "lazy", "ghost"]
    assert "no licence server" in dropped[0][1] and "constraint_jacobian" in dropped[1][1]
    # a usage error stops everything before anything is built
    with pytest.raises(EngineSpecError, match="unknown engine 'bulet'"):
        load_engines(["reference", "bulet"], thesis)
    with pytest.raises(EngineSpecError, match="does not take option"):
        load_engines(["boom", "fake"], thesis, {"fake": {"bad": 1}})
    with pytest.raises(EngineSpecError, match="options given for engine.*pinocchio"):
        load_engines(["fake"], thesis, {"pinocchio": {}})


def test_every_error_is_an_engine_error():
    """The CLI catches EngineSpecError (exit 2) before EngineError (exit 1)."""
    assert issubclass(EngineSpecError, EngineError) and issubclass(EngineLoadError, EngineError)
    assert not issubclass(EngineSpecError, EngineLoadError)


def test_installed_entry_points_win_over_the_source_tree(tmp_path, monkeypatch):
    """Once bicycle-xval's own distribution registers the group, the pyproject fallback is not
    read: every registration then comes from a distribution. Here an installed 'bicycle-xval
    9.9' registers an extra name (true whether or not the real install has entry points)."""
    _dist_info(tmp_path, "bicycle-xval", "9.9", {"ref-alias": "engines.reference:ReferenceEngine"})
    monkeypatch.syspath_prepend(str(tmp_path))
    from engines.registry import registrations
    regs = registrations()
    assert all(r.distribution is not None for r in regs)
    assert {r.name: r.source for r in regs}["ref-alias"] == "bicycle-xval 9.9"
    [info] = engine_info("ref-alias")
    assert info.source == "bicycle-xval 9.9" and info.error is None


def test_builtins_keep_their_declared_order_when_installed(tmp_path, monkeypatch):
    """Installers write entry_points.txt sorted by name (setuptools does); the listing keeps
    the pyproject's order all the same (the reference first)."""
    _dist_info(tmp_path, "bicycle-xval", "0.1.0", {
        "exudyn": "engines.exudyn:ExudynEngine", "pinocchio": "engines.pinocchio:PinocchioEngine",
        "reference": "engines.reference:ReferenceEngine"})
    monkeypatch.syspath_prepend(str(tmp_path))
    assert available_engines() == BUILTINS


def test_the_contract_documents_the_code_s_order():
    """docs/engines.md's coordinate and constraint tables follow the code's order, and every
    capability of the base class is documented."""
    import re

    from reference_model import CONSTRAINT_NAMES, COORDINATES
    text = (Path(__file__).resolve().parents[1] / "docs" / "engines.md").read_text()
    coords = re.findall(r"^\| (\d) \| `(\w+)` +\| (?:m|rad) ", text, flags=re.M)
    assert [name for _, name in coords] == list(COORDINATES)
    rows = re.findall(r"^\| (\d) \| `(\w+)` \| (?:holonomic|velocity)", text, flags=re.M)
    assert [name for _, name in rows] == list(CONSTRAINT_NAMES)
    for cap in engines.CAPABILITIES:
        assert f"| `{cap}` |" in text, cap


def test_engine_options_from_key_value_strings(third_party):
    from engines import parse_engine_options
    assert parse_engine_options("exudyn", ["build=redundant", "step=5e-4"]) == \
        {"build": "redundant", "step": 5e-4}
    assert parse_engine_options("fake", ["scale=2"]) == {"scale": 2.0}
    assert isinstance(parse_engine_options("fake", ["scale=2"])["scale"], float)  # default 1.0
    for pairs, message in ((["step"], r"'step' for engine 'exudyn' .* is not key=value"),
                           (["=1"], "is not key=value"),
                           (["step=1e-3", "step=2e-3"], "'step' .* given twice"),
                           (["stepp=1e-3"], r"does not take option\(s\) stepp; it takes: build, step"),
                           (["step=fast"], r"option step of engine 'exudyn' .*'fast' is not a float "
                                           r"\(the default is 0.001\)")):
        with pytest.raises(EngineSpecError, match=message):
            parse_engine_options("exudyn", pairs)
    with pytest.raises(EngineSpecError, match="takes no options; got build"):
        parse_engine_options("reference", ["build=tree"])


def test_fallback_reads_only_this_project_s_pyproject(tmp_path):
    other = tmp_path / "pyproject.toml"
    other.write_text('[project]\nname = "someone-else"\n'
                     '[project.entry-points."bicycle_xval.engines"]\nx = "a.b:C"\n')
    assert _pyproject_registrations(other) == []
    assert _pyproject_registrations(tmp_path / "missing.toml") == []


def test_split_options_by_a_method_s_signature():
    from engines import split_options

    def simulate(scenario, *, t_end=None, fall_limit=1.4):
        pass

    def anything(scenario, **kw):
        pass
    assert split_options(simulate, {"fall_limit": 0.4, "rtol": 1e-9}) == ({"fall_limit": 0.4},
                                                                         {"rtol": 1e-9})
    assert split_options(anything, {"rtol": 1e-9}) == ({"rtol": 1e-9}, {})


# -- the default engine lists, from the registry and the engines' facts ---------------------

def test_default_engines_are_the_installed_ones_with_terms_third_parties_included(third_party):
    """`engines.defaults`: a third party's engine is a default like a built-in. The fake's
    declarations decide: 'fake' has M and models the thesis contact only, 'boom' declares no
    capability, 'ghost' does not import; Kane's engine models the disc contact only
    (docs/engines.md). Planted: without the contact filter, 'fake' is a disc default and 'kane'
    a thesis one; without the terms filter, 'boom' is one: both fail here."""
    from engines import installed_engines, term_engines
    thesis, disc = term_engines("thesis"), term_engines("disc")
    assert "fake" in thesis and "fake" not in disc
    assert "kane" in disc and "kane" not in thesis
    assert "boom" in installed_engines() and "boom" not in term_engines()
    assert "ghost" not in installed_engines()
    assert "reference" in installed_engines() and "reference" not in term_engines()
    assert installed_engines()[:3] == BUILTINS              # the registry's order


def test_conformance_and_warm_imports_cover_a_third_party(third_party, tmp_path, monkeypatch):
    """The conformance suite's default list and the workers' warm imports come from the
    registry: the fake distribution's engines are in both (a broken one too: the suite's
    header says why it was not checked). ``warm_imports`` imports what a module declares in
    ``REQUIRES`` and skips what is not installed. Planted: warming without the ``REQUIRES``
    step leaves the declared library unimported and fails."""
    import sys

    from comparisons.conformance.plugin import default_engines
    from comparisons.stages.pool import engine_imports, warm_imports
    assert {"fake", "boom", "ghost"} <= set(default_engines())
    assert "reference" not in default_engines()
    assert "fake_engine_mod" in engine_imports() and "no_such_module_xyz" in engine_imports()
    assert engine_imports()[0] == "engines.reference"
    (tmp_path / "warm_probe_engine.py").write_text(
        "REQUIRES = ('warm_probe_library', 'warm_probe_absent')\n")
    (tmp_path / "warm_probe_library.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in ("warm_probe_engine", "warm_probe_library"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    warm_imports(("warm_probe_engine", "no_such_module_xyz"))
    assert "warm_probe_library" in sys.modules and "warm_probe_absent" not in sys.modules


def test_registrations_are_read_once_per_import_path(tmp_path, monkeypatch):
    """Scanning the installed distributions costs ~40 ms and every load_engine asks: it is
    read once per sys.path. A distribution on a new path entry is found (one scan), asked
    again it is not scanned again, and once the entry is gone so is the engine. Planted: the
    cache dropped fails the count; a cache not keyed on sys.path fails to find 'cached'."""
    import engines.registry as registry
    _dist_info(tmp_path, "cache-probe", "0.1", {"cached": "engines.reference:ReferenceEngine"})
    scans = []
    real = registry.metadata.entry_points
    monkeypatch.setattr(registry.metadata, "entry_points",
                        lambda **kw: scans.append(kw) or real(**kw))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "cached" in available_engines() and "cached" in available_engines()
    assert len(scans) == 1
    monkeypatch.undo()
    assert "cached" not in available_engines()


NEEDY_MODULE = '''
from engines.base import Engine
class Needy(Engine):
    """Cannot be built without its file (as the fmu engine without its FMU)."""
    name = "needy"
    capabilities = frozenset({"mass_matrix"})
    required_options = ("path",)
    def __init__(self, model, path=None):
        super().__init__(model)
        self.path = path
    def mass_matrix(self, q):
        return self.model.mass_matrix(q)
'''


def test_an_engine_that_needs_an_option_is_in_no_default_list(tmp_path, monkeypatch):
    """Registered, installed, with terms, but declaring required_options: run's default, the
    conformance suite's and diagnose's leave it out (built there without its file it would be
    dropped with a usage error, and a default run would say SOMETHING FAILED); named, it is
    still available. Planted and failing: default_engines returning every registered engine."""
    from comparisons.conformance.plugin import default_engines as conformance_defaults
    from engines import default_engines
    from engines.defaults import term_engines
    (tmp_path / "needy_mod.py").write_text(NEEDY_MODULE)
    _dist_info(tmp_path, "needy-engines", "1.0", {"needy": "needy_mod:Needy",
                                                   "fake": "fake_engine_mod:FakeEngine"})
    (tmp_path / "fake_engine_mod.py").write_text(FAKE_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "needy" in available_engines()
    assert "needy" not in default_engines() and "fake" in default_engines()
    assert "needy" not in conformance_defaults() and "fake" in conformance_defaults()
    assert "needy" not in term_engines("thesis") and "fake" in term_engines("thesis")
