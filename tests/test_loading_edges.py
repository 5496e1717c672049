"""Building and listing engines (engines/loading.py), issue 24: every refusal as the user reads
it, the typing of ``--engine-option key=value`` strings, and the bookkeeping of `load_engines`
and `engine_info`.

The contract is the module's docstring and docs/engines.md: a usage error (`EngineSpecError`,
exit 2) or an engine's failure (`EngineLoadError`, exit 1, or `UnsupportedModel` for a declared
limitation), each one line naming the engine, its spec and the fix; an option's text converted
to the type of its default. Expected messages are written out whole from that contract; the
engines are files written here. Planted bugs each test was seen failing on are named in it.
"""

import signal
import sys
import textwrap
from pathlib import Path

import pytest

from engines.base import EngineLoadError, EngineSpecError, UnsupportedModel
from engines.loading import (engine_info, load_engine, load_engines, parse_engine_options,
                             split_options)
from reference_model import load_model

ENGINES = '''
from engines.base import Engine, UnsupportedModel, EngineSpecError


class Typed(Engine):
    """Options of every type.

    More text that is not the summary."""
    name = "typed"
    capabilities = frozenset({"mass_matrix", "gravity"})
    contacts = ("thesis",)

    def __init__(self, model, flag=True, n=3, step=1e-3, build="tree", free=None):
        super().__init__(model)
        self.flag, self.n, self.step, self.build, self.free = flag, n, step, build, free

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

    def gravity(self, q):
        return self.model.gravity(q)


class Open(Engine):
    name = "open"
    capabilities = frozenset({"mass_matrix"})

    def __init__(self, model, **settings):
        super().__init__(model)
        self.settings = settings

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)


class Bare(Engine):
    name = "bare"
    capabilities = frozenset({"mass_matrix"})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)


class Declares(Engine):
    name = "declares"
    capabilities = frozenset({"mass_matrix", "gravity", "constraint_jacobian"})

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)


class Unknown(Engine):
    name = "unknown"
    capabilities = frozenset({"mass_matrix", "masmatrix", "gravty"})


class Refuses(Engine):
    name = "refuses"

    def __init__(self, model):
        raise UnsupportedModel("no rear wheel of radius 0.3 here\\n(second line)")


class Misused(Engine):
    name = "misused"

    def __init__(self, model, step=1e-3):
        raise EngineSpecError("step must be positive")


class Crashes(Engine):
    name = "crashes"

    def __init__(self, model):
        raise KeyError("licence")


class Interrupts(Engine):
    name = "interrupts"

    def __init__(self, model):
        raise KeyboardInterrupt


class Marks(Engine):
    """Records every build."""
    name = "marks"
    capabilities = frozenset({"mass_matrix"})
    built = []

    def __init__(self, model):
        super().__init__(model)
        Marks.built.append(model)

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)


class Exits(Engine):
    name = "exits"

    def __init__(self, model):
        raise SystemExit(3)
'''


@pytest.fixture(scope="module")
def eng(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("loading") / "eng.py"
    path.write_text(ENGINES)
    return path


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis")


def _spec(eng, cls):
    return f"{eng}:{cls}"


# -- typing option strings ---------------------------------------------------------------------

@pytest.mark.parametrize("pair, value", [
    ("flag=yes", True), ("flag=OFF", False), ("flag=1", True), ("flag=false", False),
    ("n=7", 7), ("step=2.5e-4", 2.5e-4), ("step=3", 3.0), ("build=a=b", "a=b"),
    ("build= Tree ", " Tree "),
    # no usable default (None): an int, a float, a truth value, none, else the text
    ("free=12", 12), ("free=1.5", 1.5), ("free=TRUE", True), ("free=False", False),
    ("free=None", None), ("free=null", None), ("free=redundant", "redundant"),
])
def test_an_option_is_typed_as_its_default(eng, pair, value):
    """Planted: a bool's truth and falsity swapped or joined by 'and', the text's case not
    folded, 'true' and 'false' read the other way round, 'none' not recognised (or everything
    taken for it), the value split at the last '=' (so 'build=a=b' set 'build=a')."""
    got = parse_engine_options(_spec(eng, "Typed"), [pair])
    key = pair.partition("=")[0]
    assert got == {key: value} and type(got[key]) is type(value)


@pytest.mark.parametrize("pair, kind, default", [
    ("flag=maybe", "bool", True), ("n=7.5", "int", 3), ("step=fast", "float", 0.001),
])
def test_an_option_of_the_wrong_type_names_it_its_type_and_default(eng, pair, kind, default):
    spec = _spec(eng, "Typed")
    key, _, text = pair.partition("=")
    with pytest.raises(EngineSpecError) as e:
        parse_engine_options(spec, [pair])
    assert str(e.value) == (f"option {key} of engine 'typed' ({spec}): {text!r} is not a {kind} "
                            f"(the default is {default!r})")


def test_an_engine_taking_any_option_gets_each_typed_without_a_default(eng):
    """Open(model, **settings): no parameter to read a default from. Planted: the default
    read from a parameter that does not exist (param is not None 'or' ...)."""
    assert parse_engine_options(_spec(eng, "Open"), ["k=1", "m=x", "z=0.5"]) == \
        {"k": 1, "m": "x", "z": 0.5}


@pytest.mark.parametrize("pairs, message", [
    (["step"], "engine option 'step' for engine 'typed' ({spec}) is not key=value (e.g. "
               "step=5e-4)"),
    (["=3"], "engine option '=3' for engine 'typed' ({spec}) is not key=value (e.g. step=5e-4)"),
    (["n=1", " n =2"], "engine option 'n' for engine 'typed' ({spec}) is given twice"),
    (["zzz=1"], "engine 'typed' ({spec}) does not take option(s) zzz; it takes: flag, n, step, "
                "build, free"),
])
def test_a_wrong_option_string_is_one_line_naming_the_engine_and_spec(eng, pairs, message):
    """Planted: the spec's description dropped or taken for a registered name's."""
    spec = _spec(eng, "Typed")
    with pytest.raises(EngineSpecError) as e:
        parse_engine_options(spec, pairs)
    assert str(e.value) == message.format(spec=spec)


def test_a_registered_engine_s_option_error_names_where_it_is_registered():
    """A registered name is described by its target and registration, not by the bare name.
    Planted: the description always the spec's text, or always the registration's."""
    with pytest.raises(EngineSpecError) as e:
        parse_engine_options("reference", ["zzz=1"])
    assert str(e.value).startswith("engine 'reference' (engines.reference:ReferenceEngine from ")


# -- building ----------------------------------------------------------------------------------

@pytest.mark.parametrize("cls, options, message", [
    ("Typed", {"zzz": 1, "aaa": 2}, "engine 'typed' ({spec}) does not take option(s) aaa, zzz; "
                                    "it takes: flag, n, step, build, free"),
    ("Bare", {"zzz": 1}, "engine 'bare' ({spec}) takes no options; got zzz"),
])
def test_an_option_the_engine_does_not_take_is_a_usage_error(eng, thesis, cls, options, message):
    """Planted: the spec dropped from the message (None), the class's name read from the
    resolved path instead of the spec."""
    spec = _spec(eng, cls)
    with pytest.raises(EngineSpecError) as e:
        load_engine(spec, thesis, **options)
    assert str(e.value) == message.format(spec=spec)


@pytest.mark.parametrize("cls, error, message", [
    ("Declares", EngineLoadError, "engine 'declares' ({spec}) declares gravity, "
                                  "constraint_jacobian but does not implement them (override the method(s) "
                                  "of engines.base.Engine)"),
    ("Unknown", EngineLoadError, "engine 'unknown' ({spec}) declares unknown capabilities "
                                 "gravty, masmatrix; the capabilities are: {caps}"),
    ("Refuses", UnsupportedModel, "engine 'refuses' ({spec}) cannot represent model 'thesis': "
                                  "no rear wheel of radius 0.3 here"),
    ("Misused", EngineSpecError, "engine 'misused' ({spec}): step must be positive"),
    ("Crashes", EngineLoadError, "engine 'crashes' ({spec}) raised while being built: KeyError: "
                                 "'licence'"),
    ("Exits", EngineLoadError, "engine 'exits' ({spec}) raised SystemExit while being built (an "
                               "engine must not end the process: raise an exception)"),
])
def test_an_engine_that_cannot_be_built_says_why_in_one_line(eng, thesis, cls, error, message):
    """Planted: 'it' for 'them', each message replaced or its parts dropped."""
    from engines.base import CAPABILITIES
    spec = _spec(eng, cls)
    with pytest.raises(error) as e:
        load_engine(spec, thesis)
    assert type(e.value) is error
    assert str(e.value) == message.format(spec=spec, caps=", ".join(CAPABILITIES))


def test_one_capability_declared_and_missing_is_it(eng, thesis, tmp_path):
    f = tmp_path / "one.py"
    f.write_text(ENGINES.replace('{"mass_matrix", "gravity", "constraint_jacobian"}',
                                 '{"mass_matrix", "gravity"}'))
    with pytest.raises(EngineLoadError, match=r" declares gravity but does not implement it "):
        load_engine(f"{f}:Declares", thesis)


def test_an_engine_s_own_keyboard_interrupt_while_built_is_its_failure(eng, thesis):
    """SIGINT's handler did not change during the build, so the KeyboardInterrupt is the
    engine's, not the user's Ctrl-C. Planted: the handler before the call not taken (None),
    so the interruption escaped as the user's."""
    handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(EngineLoadError) as e:
            load_engine(_spec(eng, "Interrupts"), thesis)
    finally:
        signal.signal(signal.SIGINT, handler)
    assert str(e.value).endswith("raised KeyboardInterrupt while being built (an engine must not "
                                 "end the process: raise an exception)")


def test_a_model_without_a_contact_is_not_supported(eng):
    """A duck-typed model that names no contact model. Planted: the contact read without a
    default (AttributeError escaped)."""
    class Model:
        name = "duck"
    with pytest.raises(UnsupportedModel) as e:
        load_engine(_spec(eng, "Typed"), Model())
    assert str(e.value) == (f"engine 'typed' ({_spec(eng, 'Typed')}) supports the front-contact "
                            f"models thesis, not None of model 'duck'")


def test_options_reach_the_engine_typed(eng, thesis):
    e = load_engine(_spec(eng, "Typed"), thesis,
                    **parse_engine_options(_spec(eng, "Typed"), ["n=9", "flag=no"]))
    assert (e.n, e.flag, e.step) == (9, False, 1e-3)


# -- several at once ---------------------------------------------------------------------------

def test_load_engines_keys_by_label_drops_failures_and_goes_on(eng, thesis, tmp_path):
    """A broken file first, then an engine that fails to build, then two good ones: the
    failures are dropped with their one-line reasons and the rest built, each keyed by its
    label. Planted: break for continue (the rest never built), the labels counted over the
    failures, the failure's text lost (str(None))."""
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('half-written file')\n")
    specs = [f"{broken}:X", _spec(eng, "Crashes"), _spec(eng, "Typed"), _spec(eng, "Bare")]
    built, dropped = load_engines(specs, thesis)
    assert sorted(built) == ["bare", "typed"]
    assert dropped == [(f"{broken}:X", f"engine 'broken' ({broken}:X) failed to import: "
                                       f"RuntimeError: half-written file"),
                       ("crashes", f"engine 'crashes' ({_spec(eng, 'Crashes')}) raised while "
                                   f"being built: KeyError: 'licence'")]


def test_two_engines_with_one_label_are_keyed_by_their_specs(eng, thesis, tmp_path):
    """Planted: the label kept for a shared one (the second overwrote the first), the count
    compared with 2."""
    other = tmp_path / "other.py"
    other.write_text(ENGINES)
    specs = [_spec(eng, "Typed"), _spec(other, "Typed"), _spec(eng, "Bare")]
    built, dropped = load_engines(specs, thesis)
    assert sorted(built) == sorted([specs[0], specs[1], "bare"]) and dropped == []


def test_load_engines_checks_every_option_before_building_any(eng, thesis):
    """Nothing is built when one engine's options are wrong, even those before it in the list.
    Planted: the options looked up under another key (checked only when that engine is
    built, after the first), the class or the spec dropped from the check."""
    from engines.registry import resolve
    spec = _spec(eng, "Typed")
    marks = resolve(_spec(eng, "Marks"))[0]
    marks.built.clear()
    with pytest.raises(EngineSpecError) as e:
        load_engines([_spec(eng, "Marks"), spec], thesis, {spec: {"zzz": 1}})
    assert marks.built == []
    assert str(e.value) == (f"engine 'typed' ({spec}) does not take option(s) zzz; it takes: "
                            f"flag, n, step, build, free")
    with pytest.raises(EngineSpecError) as e:
        load_engines([spec], thesis, {"elsewhere": {"n": 1}, "more": {}})
    assert str(e.value) == (f"options given for engine(s) elsewhere, more that are not in the "
                            f"list {spec}")


# -- listing -----------------------------------------------------------------------------------

def test_the_listing_of_a_spec_describes_its_class(eng):
    """An engine without a docstring has no summary (it showed the base class's, "Base class:
    subclasses set name, ..."). Planted: the spec, the doc's first line, the contacts or the
    '**' dropped."""
    (typed,) = engine_info(_spec(eng, "Typed"))
    assert (typed.name, typed.spec, typed.source) == ("typed", _spec(eng, "Typed"), str(eng))
    assert typed.capabilities == ("mass_matrix", "gravity")
    assert typed.contacts == ("thesis",) and typed.doc == "Options of every type."
    assert typed.options == ("flag", "n", "step", "build", "free")
    (open_,) = engine_info(_spec(eng, "Open"))
    assert open_.options == ("**",) and open_.doc == ""
    from engines.base import CONTACTS
    assert open_.contacts == tuple(CONTACTS)


def test_an_unknown_name_is_refused_with_the_available_ones():
    """Planted: the unknown name listed as nothing, the name lost on the way (None)."""
    with pytest.raises(EngineSpecError, match=r"^unknown engine 'no-such-engine'; available: "
                                              r"reference, "):
        engine_info("no-such-engine")


def test_the_listing_shows_every_registration_even_after_failures(tmp_path, monkeypatch):
    """Three registrations of a third party, in name order: one whose module is missing, one
    whose extra is not installed, one that works; each is listed with its name, target and
    source. Planted: break for continue (the rest not listed), a field dropped (None)."""
    from fake_dist import dist_info
    (tmp_path / "listing_ok_xyz.py").write_text(ENGINES)
    (tmp_path / "listing_extra_xyz.py").write_text("REQUIRES = ('no_such_xyz',)\nEXTRA = 'gpu'\n"
                                                   + ENGINES)
    dist_info(tmp_path, "listing-xyz", "0.1", {"zz-a": "listing_gone_xyz:Typed",
                                               "zz-b": "listing_extra_xyz:Typed",
                                               "zz-c": "listing_ok_xyz:Typed"})
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        listed = [i for i in engine_info() if i.name.startswith("zz-")]
    finally:
        for m in ("listing_ok_xyz", "listing_extra_xyz"):
            sys.modules.pop(m, None)
    assert [(i.name, i.spec, i.source) for i in listed] == [
        ("zz-a", "listing_gone_xyz:Typed", "listing-xyz 0.1"),
        ("zz-b", "listing_extra_xyz:Typed", "listing-xyz 0.1"),
        ("zz-c", "listing_ok_xyz:Typed", "listing-xyz 0.1")]
    gone, extra, ok = listed
    assert gone.error.startswith("engine 'zz-a': no module 'listing_gone_xyz'")
    assert extra.not_installed == "not installed: pip install 'listing-xyz[gpu]'"
    assert ok.error is None and ok.not_installed is None and ok.doc == "Options of every type."


def test_split_options_by_what_the_method_takes():
    def run(scenario, *, step=1e-3, method="x"):
        pass

    def anything(scenario, **kw):
        pass
    assert split_options(run, {"step": 1, "tol": 2}) == ({"step": 1}, {"tol": 2})
    assert split_options(anything, {"step": 1, "tol": 2}) == ({"step": 1, "tol": 2}, {})


def test_the_messages_list_every_item_and_name_an_unnamed_model(eng, tmp_path):
    """Two unknown options, two contact models, a model without a name, two specs: each
    listed with ', ', the nameless model as '?'. Planted: the separators and the '?'
    changed."""
    with pytest.raises(EngineSpecError, match=r"takes no options; got aaa, zzz$"):
        load_engine(_spec(eng, "Bare"), load_model("thesis"), zzz=1, aaa=2)
    f = tmp_path / "two.py"
    f.write_text(ENGINES.replace('contacts = ("thesis",)', 'contacts = ("thesis", "disc")')
                 .replace('name = "refuses"', 'name = "refuses"\n    contacts = ("thesis",)'))

    class Nameless:
        contact = "torus"
    with pytest.raises(UnsupportedModel) as e:
        load_engine(f"{f}:Typed", Nameless())
    assert str(e.value).endswith("supports the front-contact models thesis, disc, not 'torus' "
                                 "of model '?'")
    Nameless.contact = "thesis"
    with pytest.raises(UnsupportedModel) as e:
        load_engine(f"{f}:Refuses", Nameless())
    assert str(e.value).endswith("cannot represent model '?': no rear wheel of radius 0.3 here")
    g = tmp_path / "none.py"
    g.write_text(ENGINES.replace('contacts = ("thesis",)', 'contacts = ()'))
    with pytest.raises(UnsupportedModel, match=r"supports the front-contact models none, not "):
        load_engine(f"{g}:Typed", load_model("thesis"))
    with pytest.raises(EngineSpecError, match=r"that are not in the list a, b$"):
        load_engines(["a", "b"], None, {"c": {}})
