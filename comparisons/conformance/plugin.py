"""pytest plugin of the conformance suite (entry point ``pytest11``: ``bicycle_xval``).

Options: ``--engine SPEC`` (repeatable: a registered name, ``package.module:Class`` or
``path/file.py:Class``), ``--engine-option key=value`` (repeatable, for every ``--engine``),
``--model NAME|FILE`` (repeatable), ``--xfails-file F``, ``--tolerances FILE`` (read once, in
`pytest_configure`, into the session's `Conformance.tolerances`; default the packaged
`comparisons/judgments/tolerances.toml`). The checks live in the test modules of
this package; `pytest_generate_tests` parametrizes them over (engine, model[, quantity]) for
what each engine can do, so a check the engine's capabilities do not allow is never collected
(and the header says which).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import pytest


@dataclass
class Candidate:
    """One engine built from one model, or the reason it could not be."""

    spec: str
    model_name: str
    engine: object = None
    reason: str = ""

    @property
    def id(self) -> str:
        from ..stages.runs import label_of
        return f"{label_of(self.spec)}-{self.model_name}"


@dataclass(frozen=True)
class Depth:
    """How many cases a session checks: ``examples`` hypothesis states per term check, the
    models of the forward runs (None: `models.DEFAULT_TRAJECTORY_MODELS`), the models of the
    eigenvalue check (None: every model) and whether it also finds the critical speeds (a
    dozen more calls of the capability: 0.03-0.24 s per engine)."""

    examples: int
    trajectory_models: tuple[str, ...] | None = None
    eigenvalue_models: tuple[str, ...] | None = None
    critical_speeds: bool = True


DEPTHS = {"full": Depth(25),
          "quick": Depth(5, ("thesis-disc",), ("benchmark",), critical_speeds=False)}


@dataclass
class Conformance:
    """What this session checks: the candidates (engine x model) and the expected failures."""

    specs: list[str]
    models: list[str]
    options: dict
    tolerances: object = None        # judgments.tolerances.Tolerances: what the checks judge by
    depth: Depth = DEPTHS["full"]
    candidates: list[Candidate] = field(default_factory=list)
    xfails: dict[str, str] = field(default_factory=dict)
    _models: dict = field(default_factory=dict)
    _references: dict = field(default_factory=dict)

    def model(self, name: str):
        if name not in self._models:
            from .models import conformance_model
            self._models[name] = conformance_model(name)
        return self._models[name]

    def reference(self, name: str):
        if name not in self._references:
            from engines import load_engine
            self._references[name] = load_engine("reference", self.model(name))
        return self._references[name]

    def usable(self) -> list[Candidate]:
        return [c for c in self.candidates if c.engine is not None]



def pytest_addoption(parser):
    g = parser.getgroup("bicycle-xval", "bicycle-xval engine conformance")
    g.addoption("--engine", dest="bx_engines", action="append", default=[], metavar="SPEC",
                help="engine to check: a registered name, package.module:Class or "
                     "path/file.py:Class (repeatable) [every registered engine but the reference: "
                     "'bicycle-xval engines' lists them]")
    g.addoption("--engine-option", dest="bx_options", action="append", default=[],
                metavar="KEY=VALUE", help="an option for every --engine (repeatable)")
    g.addoption("--model", dest="bx_models", action="append", default=[], metavar="NAME|FILE",
                help="model to check on: a named model or a parameter file (repeatable) "
                     "[thesis, thesis-disc, benchmark, general, general-disc]")
    g.addoption("--xfails-file", dest="bx_xfails", default=None, metavar="FILE",
                help="expected failures: one check id per line, '# reason' after it")
    g.addoption("--conformance-depth", dest="bx_depth", default="full",
                choices=tuple(DEPTHS), help="full: every check at its full count (an engine "
                "author's run) [full]; quick: each term at %d hypothesis states instead of %d and "
                "the forward runs on thesis-disc only (the project's own make test runs every "
                "engine so, make test-slow at full depth)" % (DEPTHS["quick"].examples,
                                                              DEPTHS["full"].examples))
    g.addoption("--tolerances", dest="bx_tolerances", default=None, metavar="FILE",
                help="a tolerance file replacing comparisons/judgments/tolerances.toml (same "
                     "tables)")


def default_engines() -> list[str]:
    """Every registered engine but the reference (which every check compares against): an
    engine whose extra is missing stays in the list, so the header says it was not checked and
    why; one that cannot be built without an option (a file) is left out."""
    from engines import available_engines
    from engines.defaults import REFERENCE
    from engines.registry import needs_options
    return [e for e in available_engines() if e != REFERENCE and not needs_options(e)]


def read_xfails(path: Path) -> dict[str, str]:
    """``{check id: reason}`` from an expected-failures file; a line without a reason is an
    error (an expected failure is a claim, and a claim states its reason)."""
    out = {}
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise pytest.UsageError(f"--xfails-file {path}: not UTF-8 text (byte {exc.start}); save "
                                "it as UTF-8") from None
    except OSError as exc:
        raise pytest.UsageError(f"--xfails-file {path}: cannot be read ({exc.strerror or exc})"
                                ) from None
    for k, line in enumerate(text.splitlines(), 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        check, _, reason = text.partition("#")
        if not reason.strip():
            raise pytest.UsageError(f"--xfails-file {path}, line {k}: {check.strip()!r} has no "
                                    "reason; write 'CHECK_ID  # why it is expected to fail'")
        out[check.strip()] = reason.strip()
    return out


def pytest_configure(config):
    specs = list(config.getoption("bx_engines")) or default_engines()
    from .models import DEFAULT_MODELS
    models = list(config.getoption("bx_models")) or list(DEFAULT_MODELS)
    options = {}
    if config.getoption("bx_options"):
        from engines import parse_engine_options
        for spec in specs:
            options[spec] = parse_engine_options(spec, config.getoption("bx_options"))
    xfails = {}
    if config.getoption("bx_xfails"):
        path = Path(config.getoption("bx_xfails"))
        if not path.is_file():
            raise pytest.UsageError(f"--xfails-file: no file {str(path)!r}")
        xfails = read_xfails(path)
    from ..judgments.tolerances import ToleranceError, load_complete, load_tolerances
    try:
        path = config.getoption("bx_tolerances")
        tolerances = load_tolerances() if path is None else load_complete(path)
    except ToleranceError as exc:
        raise pytest.UsageError(f"--tolerances: {exc}") from None
    config._bx_conformance = Conformance(specs, models, options, tolerances,
                                         DEPTHS[config.getoption("bx_depth")], xfails=xfails)
    config.addinivalue_line("markers", "conformance: a check of the engine conformance suite")


def _conformance(config) -> Conformance:
    conf = config._bx_conformance
    if not conf.candidates:          # built once, on first use (collection of a check)
        from engines import load_engine
        for spec in conf.specs:
            for name in conf.models:
                c = Candidate(spec, name)
                try:
                    c.engine = load_engine(spec, conf.model(name), **conf.options.get(spec, {}))
                except Exception as exc:   # noqa: BLE001 - reported in the header, not a crash
                    c.reason = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
                conf.candidates.append(c)
    return conf


def pytest_report_header(config):
    conf = config._bx_conformance
    if not conf.candidates:
        return None
    lines = ["bicycle-xval conformance:"]
    for c in conf.candidates:
        what = (", ".join(sorted(c.engine.capabilities)) if c.engine is not None
                else f"not checked: {c.reason}")
        lines.append(f"  {c.spec} on {c.model_name}: {what}")
    return lines


def pytest_generate_tests(metafunc):
    """``candidate`` (an engine on a model) and ``quantity`` are parametrized from what each
    engine declares; a test names what it needs with ``needs`` (a capability set)."""
    if "candidate" not in metafunc.fixturenames:
        return
    conf = _conformance(metafunc.config)
    needs = getattr(metafunc.module, "NEEDS", {}).get(metafunc.function.__name__, ())
    want = getattr(metafunc.function, "needs_method", None)
    cands = [c for c in conf.usable() if set(needs) <= set(c.engine.capabilities)
             and (want is None or callable(getattr(c.engine, want, None)))]
    if "simulate" in needs and not metafunc.config.getoption("bx_models"):
        from .models import DEFAULT_TRAJECTORY_MODELS   # forward runs are the costly checks
        keep = conf.depth.trajectory_models or DEFAULT_TRAJECTORY_MODELS
        cands = [c for c in cands if c.model_name in keep]
    if "eigenvalues" in needs and not metafunc.config.getoption("bx_models") \
            and conf.depth.eigenvalue_models is not None:
        cands = [c for c in cands if c.model_name in conf.depth.eigenvalue_models]
    # a check no engine of the session can take says why, instead of pytest's "got empty
    # parameter set"
    why = pytest.mark.skip(reason="not applicable: it needs "
                                  + ", ".join(sorted(set(needs) | ({want} if want else set())))
                                  + "; no engine of this session has them all"
                                  if needs or want else "no engine to check")
    if "quantity" in metafunc.fixturenames:
        from ..judgments.terms import QUANTITIES
        pairs = [(c, q) for c in cands for q in QUANTITIES if c.engine.supports(q)]
        metafunc.parametrize(("candidate", "quantity"),
                             pairs or [pytest.param(None, None, marks=why)], scope="session",
                             ids=[f"{c.id}-{q}" for c, q in pairs] or ["none"])
    else:
        metafunc.parametrize("candidate", cands or [pytest.param(None, marks=why)],
                             scope="session", ids=[c.id for c in cands] or ["none"])


@pytest.fixture(scope="session")
def conformance(request) -> Conformance:
    return _conformance(request.config)


@pytest.fixture(scope="session")
def tolerances(conformance):
    """The session's tolerances (``--tolerances``, read once in `pytest_configure`)."""
    return conformance.tolerances


@pytest.fixture(scope="session")
def reference(conformance, candidate):
    """The reference engine built from the candidate's model."""
    return conformance.reference(candidate.model_name)


def declared_xfails(engine) -> dict[str, str]:
    """The expected failures an engine declares itself: its ``conformance_xfails``, a mapping
    ``{check id pattern: reason}`` or the path of a file in the ``--xfails-file`` format.
    In a pattern ``*`` matches anything (nothing else is special) and ``{engine}`` stands for the engine's label in the ids,
    e.g. ``test_trajectory_to_the_meaningful_horizon[{engine}-*-stability-psid5]``."""
    from collections.abc import Mapping
    declared = getattr(engine, "conformance_xfails", None)
    who = f"engine {getattr(engine, 'name', '?')!r}: its conformance_xfails"
    if declared is None:
        return {}
    if isinstance(declared, (str, Path)):
        if not Path(declared).is_file():
            raise pytest.UsageError(f"{who} names no file: {str(declared)!r} (give the path of "
                                    "an expected-failures file, e.g. Path(__file__).parent / "
                                    "'conformance_xfails.txt')")
        try:
            return read_xfails(Path(declared))
        except pytest.UsageError as exc:
            raise pytest.UsageError(f"{who}: {str(exc).removeprefix('--xfails-file ')}") from None
    if not isinstance(declared, Mapping) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in declared.items()):
        raise pytest.UsageError(f"{who} is {type(declared).__name__} {str(declared)[:60]!r}; it "
                                "must be a mapping {check id pattern: reason} (both text) or "
                                "the path of an expected-failures file")
    return dict(declared)


def declared_reason(item) -> str | None:
    """The reason, if the candidate's engine declares this check an expected failure."""
    import re

    from ..stages.runs import label_of
    cand = getattr(getattr(item, "callspec", None), "params", {}).get("candidate")
    if not isinstance(cand, Candidate) or cand.engine is None:
        return None
    label = label_of(cand.spec)
    for pattern, reason in declared_xfails(cand.engine).items():
        # only * is special (ids hold brackets, which fnmatch would read as character sets)
        regex = ".*".join(re.escape(part) for part in pattern.replace("{engine}", label).split("*"))
        if re.fullmatch(regex, item.name):
            return f"declared by {label}: {reason}"
    return None


def pytest_collection_modifyitems(config, items):
    """Expected failures, strict (a listed check that passes fails the session, so no list
    goes stale): the ones each engine declares (`declared_xfails`), then ``--xfails-file``'s,
    which take precedence."""
    conf = getattr(config, "_bx_conformance", None)
    if conf is None:
        return
    seen = set()
    for item in items:
        reason = conf.xfails.get(item.name) or conf.xfails.get(item.nodeid)
        if reason is not None:
            seen.add(item.name if item.name in conf.xfails else item.nodeid)
        else:
            reason = declared_reason(item)
        if reason is not None:
            item.add_marker(pytest.mark.xfail(reason=reason, strict=True))
    unknown = sorted(set(conf.xfails) - seen)
    if unknown:
        warnings.warn(pytest.PytestConfigWarning(
            f"--xfails-file lists {len(unknown)} check id(s) that match no collected check, "
            f"e.g. {unknown[0]!r}"))


#: an exception text longer than this (characters) is reported as its one cut line instead
#: of whole (an engine that raises with a 10^6-character message would otherwise print it)
LONG_MESSAGE = 2000


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    exc = call.excinfo.value if call.excinfo is not None else None
    if rep.failed and exc is not None:
        try:
            long = len(str(exc)) > LONG_MESSAGE
        except Exception:   # noqa: BLE001 - a message that cannot be rendered: shorten too
            long = True
        if long:
            from engines.guard import describe
            where = call.excinfo.traceback[-1]
            rep.longrepr = (f"{where.path}:{where.lineno + 1}: {describe(exc)} (the message "
                            f"was cut to one line)")
