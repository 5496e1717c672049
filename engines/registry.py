"""Finding engines: entry points, ``module:Class`` and ``file.py:Class`` specs -> a class.

An engine is named in one of three ways (everywhere an engine is accepted):

* a registered name, e.g. ``pinocchio``: an entry point in the group ``bicycle_xval.engines``
  (``importlib.metadata``). The built-ins are registered in this project's ``pyproject.toml``
  exactly like a third party's::

      [project.entry-points."bicycle_xval.engines"]
      pinocchio = "engines.pinocchio:PinocchioEngine"

* ``package.module:Class``: an importable module and an `engines.base.Engine` subclass in it;
* ``path/to/file.py:Class``: a Python file, loaded by path (relative to the working directory).

Source checkouts: when bicycle-xval's own distribution is not installed, or is installed without
this group (an editable install made before the group existed), the built-ins are read from the
``pyproject.toml`` beside the package, so ``reference``, ``pinocchio`` and ``exudyn`` are found
either way and from the same single declaration. An installed entry point wins over that file.

What an engine needs beyond bicycle-xval's core is declared in the module its entry point names
(for a package, its ``__init__``), which must import without it::

    REQUIRES = ("exudyn",)   # top-level modules, looked up with importlib.util.find_spec
    EXTRA = "exudyn"         # the extra of the registering distribution that installs them

When one of ``REQUIRES`` cannot be found, the engine is `EngineNotInstalled` ("not installed:
pip install 'bicycle-xval[exudyn]'"): nothing heavy is imported to find that out, and no name
of an engine is known here (docs/engines.md, "An engine's heavy dependency").

Errors: `EngineSpecError` (a usage error, the CLI exits 2) when the name or spec is wrong;
`EngineLoadError` (exit 1) when a correctly named engine fails to import or its entry point is
broken. Both say in one line the engine, the spec and the cause or the fix. Building engines
from the classes found here is `engines.loading`.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.metadata as metadata
import importlib.util
import inspect
import re
import sys
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from .base import Engine, EngineError, EngineLoadError, EngineSpecError

__all__ = ["DISTRIBUTION", "GROUP", "SPEC_FORMS", "EngineNotInstalled", "Registration",
           "available_engines", "default_engines", "missing_modules", "needs_options", "not_installed", "registrations", "resolve"]

GROUP = "bicycle_xval.engines"
DISTRIBUTION = "bicycle-xval"
_PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_MODULE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")
SPEC_FORMS = "a registered name, package.module:Class or path/to/file.py:Class"


@dataclass(frozen=True)
class Registration:
    """One registered engine: its name, its ``module:Class`` target and where it comes from."""

    name: str
    target: str                 # "package.module:Class"
    distribution: str | None    # None: read from this project's pyproject.toml (not installed)
    version: str | None

    @property
    def source(self) -> str:
        if self.distribution is None:
            return f"{DISTRIBUTION} (its pyproject.toml; entry points not installed)"
        return f"{self.distribution} {self.version}"


# -- discovery -------------------------------------------------------------------------------

def _pyproject_registrations(path: Path = _PYPROJECT) -> list[Registration]:
    """The group as declared in this project's pyproject.toml (source checkouts only)."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError):
        return []
    project = data.get("project", {})
    if _canonical(project.get("name")) != _canonical(DISTRIBUTION):   # someone else's file
        return []
    group = project.get("entry-points", {}).get(GROUP, {})
    return [Registration(str(n), str(t), None, None) for n, t in group.items()]


def registrations() -> list[Registration]:
    """Every engine registered in the group, in a stable order (built-ins from the source tree
    if bicycle-xval's own entry points are not installed). A name registered twice appears
    twice; `load_engine` refuses it as ambiguous.

    Read once per import path (``sys.path`` as it is now): scanning the installed
    distributions' entry points and parsing their metadata costs ~40 ms, and every
    `load_engine` asks (a run builds engines a few hundred times). A distribution put on a
    new path entry is found; one installed into a path entry already read is found by the
    next process."""
    return list(_registrations(tuple(sys.path)))


@lru_cache(maxsize=8)
def _registrations(path: tuple[str, ...]) -> tuple[Registration, ...]:
    found: list[Registration] = []
    for ep in metadata.entry_points(group=GROUP):
        dist = getattr(ep, "dist", None)
        dname = dist.metadata["Name"] if dist is not None else "unknown distribution"
        version = dist.version if dist is not None else "?"
        found.append(Registration(ep.name, ep.value, dname, version))
    ours = {r.name for r in found if _canonical(r.distribution) == _canonical(DISTRIBUTION)}
    if not ours:
        found = _pyproject_registrations() + found
    # one entry per (name, target, distribution): the same dist-info on sys.path twice is one
    unique = {(r.name, r.target, r.distribution): r for r in found}
    regs = list(unique.values())
    mine = [r for r in regs if r.distribution is None
            or _canonical(r.distribution) == _canonical(DISTRIBUTION)]
    # ours in their pyproject order (installers write entry points sorted by name), then
    # third parties' by name
    declared = [r.name for r in _pyproject_registrations()]
    mine.sort(key=lambda r: (declared.index(r.name) if r.name in declared else len(declared), r.name))
    return tuple(mine + sorted((r for r in regs if r not in mine), key=lambda r: (r.name, r.target)))


def _canonical(dist: str | None) -> str:
    return re.sub(r"[-_.]+", "-", dist or "").lower()


def default_engines() -> tuple[str, ...]:
    """The engines a run compares when none is named: every registered engine (an engine whose
    extra is not installed is then listed as not run, with its pip line) but those that cannot
    be built without an option (`needs_options`). The one declared place of that default."""
    return tuple(e for e in available_engines() if not needs_options(e))


def needs_options(name: str) -> bool:
    """True when the registered engine ``name`` declares options it cannot be built without
    (``required_options``, e.g. a file): no default list includes it. An engine that does
    not import counts as not needing any (it is listed as not installed or failed)."""
    try:
        cls = resolve(name)[0]
    except EngineError:
        return False
    return bool(getattr(cls, "required_options", ()))


def available_engines() -> tuple[str, ...]:
    """The registered engine names (built-ins first, then third parties', each sorted)."""
    names: list[str] = []
    for r in registrations():
        if r.name not in names:
            names.append(r.name)
    return tuple(names)


# -- what an engine needs beyond the core ---------------------------------------------------

class EngineNotInstalled(EngineLoadError):
    """A registered engine whose declared ``REQUIRES`` are not installed: not a failure of the
    engine, an extra the user did not install. ``reason`` is the listing's line, e.g.
    "not installed: pip install 'bicycle-xval[exudyn]'"."""

    def __init__(self, engine: str, reason: str):
        super().__init__(f"engine {engine!r} is {reason}")
        self.engine, self.reason = engine, reason


def missing_modules(requires) -> tuple[str, ...]:
    """The top-level modules of ``requires`` that cannot be found (``find_spec``: nothing is
    imported). An import hook that refuses a name counts as missing."""
    out = []
    for name in requires:
        try:
            found = importlib.util.find_spec(name) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            out.append(name)
    return tuple(out)


def _requirements(module, engine: str, target: str, distribution: str | None) -> str | None:
    """The 'not installed: ...' line for ``module``'s ``REQUIRES``/``EXTRA``, or None when
    everything it declares is there."""
    requires = getattr(module, "REQUIRES", ())
    extra = getattr(module, "EXTRA", None)
    if isinstance(requires, str) or not all(isinstance(r, str) and _MODULE.match(r) for r in requires) \
            or not (extra is None or isinstance(extra, str) and _IDENT.match(extra.replace("-", "_"))):
        raise EngineLoadError(f"engine {engine!r} ({target}): REQUIRES must be a tuple of module "
                              f"names and EXTRA an extra's name; got {requires!r}, {extra!r}")
    gone = missing_modules(r.split(".")[0] for r in requires)
    if not gone:
        return None
    if extra and distribution:
        return f"not installed: pip install '{distribution}[{extra}]'"
    return f"not installed: it needs {', '.join(gone)} (install the package that provides " \
           f"{'it' if len(gone) == 1 else 'them'})"


def not_installed(name: str) -> str | None:
    """For a registered engine name: its 'not installed: pip install ...' line when a module it
    declares in ``REQUIRES`` is missing, else None (also for unknown names and specs; those are
    `resolve`'s errors). Imports only the light module the entry point names."""
    try:
        resolve(name)
    except EngineNotInstalled as exc:
        return exc.reason
    except (EngineLoadError, EngineSpecError):   # broken or unknown: not this question
        return None
    return None


# -- resolving a spec to a class -------------------------------------------------------------

def _is_file_spec(left: str) -> bool:
    return left.endswith(".py") or "/" in left or "\\" in left


def _import_module(module: str, engine: str, spec: str):
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        missing = exc.name or ""
        if missing and (module == missing or module.startswith(missing + ".")):
            raise EngineSpecError(
                f"engine {engine!r}: no module {missing!r} for spec {spec!r}; check the spelling "
                f"or install the package that provides it ({SPEC_FORMS})") from None
        raise EngineLoadError(f"{_who(engine, spec)} failed to import: "
                              f"{type(exc).__name__}: {exc}") from exc
    except EngineSpecError:
        raise
    except Exception as exc:  # noqa: BLE001 - any failure of a third party's module is reported
        raise EngineLoadError(f"{_who(engine, spec)} failed to import: "
                              f"{type(exc).__name__}: {_one_line(exc)}") from exc


def _import_file(path_text: str, engine: str, spec: str):
    path = Path(path_text).expanduser()
    if path.suffix != ".py":
        raise EngineSpecError(f"engine {engine!r}: {path_text!r} in spec {spec!r} is not a .py "
                              f"file; give path/to/file.py:Class")
    if not path.is_file():
        raise EngineSpecError(f"engine {engine!r}: no file {str(path)!r} for spec {spec!r}; check "
                              f"the path (relative to the working directory {str(Path.cwd())!r})")
    path = path.resolve()
    digest = hashlib.sha1(str(path).encode()).hexdigest()[:10]
    mod_name = f"bicycle_xval_engine_file_{_safe(path.stem)}_{digest}"
    if mod_name in sys.modules:
        return sys.modules[mod_name]
    mspec = importlib.util.spec_from_file_location(mod_name, path)
    if mspec is None or mspec.loader is None:  # pragma: no cover - .py files always have one
        raise EngineSpecError(f"engine {engine!r}: cannot load {str(path)!r} as Python ({spec!r})")
    module = importlib.util.module_from_spec(mspec)
    sys.modules[mod_name] = module   # dataclasses and pickling look classes up there
    try:
        mspec.loader.exec_module(module)
    except Exception as exc:  # noqa: BLE001
        del sys.modules[mod_name]
        raise EngineLoadError(f"{_who(engine, spec)} failed to import: "
                              f"{type(exc).__name__}: {_one_line(exc)}") from exc
    return module


def _who(label: str, spec: str) -> str:
    """"engine 'x' (spec)": every caller's spec holds a colon its label cannot."""
    return f"engine {label!r} ({spec})"


def _safe(text: str) -> str:
    return re.sub(r"\W", "_", text)


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else repr(exc)


def _engine_class(module, cls_name: str, engine: str, spec: str) -> type[Engine]:
    obj = getattr(module, cls_name, None)
    if obj is None:
        have = sorted(n for n, v in vars(module).items()
                      if inspect.isclass(v) and issubclass(v, Engine) and v is not Engine)
        hint = f"it defines: {', '.join(have)}" if have else "it defines no Engine subclass"
        raise EngineSpecError(f"engine {engine!r}: no class {cls_name!r} in "
                              f"{getattr(module, '__file__', module.__name__)} (spec {spec!r}); {hint}")
    if not (inspect.isclass(obj) and issubclass(obj, Engine)):
        raise EngineSpecError(f"engine {engine!r}: {cls_name!r} in spec {spec!r} is not an "
                              f"engines.base.Engine subclass; subclass Engine (see docs/engines.md)")
    return obj


def resolve(spec: str) -> tuple[type[Engine], str, str]:
    """(engine class, its label, where it comes from) for a name or spec; raises
    `EngineSpecError` / `EngineLoadError`. The label is the registered name, or for a spec the
    class's ``name`` attribute."""
    if not isinstance(spec, str) or not spec.strip():
        raise EngineSpecError(f"engine spec {spec!r} is empty; give {SPEC_FORMS}")
    spec = spec.strip()
    if ":" not in spec:
        return _resolve_name(spec)
    left, cls_name = spec.rsplit(":", 1)
    label = Path(left).stem if _is_file_spec(left) else left.rsplit(".", 1)[-1]
    if not left or not _IDENT.match(cls_name):
        raise EngineSpecError(f"engine spec {spec!r} is malformed: expected package.module:Class or "
                              f"path/to/file.py:Class (Class a Python identifier)")
    if _is_file_spec(left):
        module = _import_file(left, label, spec)
        where = str(Path(left).expanduser().resolve())
    else:
        if not _MODULE.match(left):
            raise EngineSpecError(f"engine spec {spec!r} is malformed: {left!r} is neither a dotted "
                                  f"module name nor a path ending in .py")
        module = _import_module(left, label, spec)
        where = getattr(module, "__file__", None) or left
    reason = _requirements(module, label, spec, None)
    if reason is not None:
        raise EngineNotInstalled(label, reason)
    cls = _engine_class(module, cls_name, label, spec)
    return cls, str(getattr(cls, "name", cls_name) or cls_name), where


def _resolve_name(name: str) -> tuple[type[Engine], str, str]:
    regs = [r for r in registrations() if r.name == name]
    if not regs and _is_file_spec(name):
        raise EngineSpecError(f"engine spec {name!r} names no class: write {name}:ClassName "
                              f"(the Engine subclass to load, after a colon)")
    if not regs and _MODULE.match(name) and "." in name:
        head, tail = name.rsplit(".", 1)
        raise EngineSpecError(f"unknown engine {name!r}; a class in a module is written "
                              f"package.module:Class, e.g. {head}:{tail}")
    if not regs:
        names = ", ".join(available_engines()) or "none registered"
        raise EngineSpecError(f"unknown engine {name!r}; available: {names} (or give a spec "
                              f"package.module:Class or path/to/file.py:Class)")
    if len(regs) > 1:
        who = "; ".join(f"{r.target} from {r.source}" for r in regs)
        raise EngineSpecError(f"engine name {name!r} is registered more than once ({who}); "
                              f"name one by its spec package.module:Class")
    return _resolve_target(regs[0])


def _resolve_target(reg: Registration) -> tuple[type[Engine], str, str]:
    """A registration's class by its target. The user named it right, so anything wrong here
    (a missing module or class, a malformed target) is the package's fault: `EngineLoadError`."""
    module_name, _, cls_name = (part.strip() for part in reg.target.partition(":"))
    if not cls_name or not _MODULE.match(module_name) or not _IDENT.match(cls_name):
        raise EngineLoadError(f"engine {reg.name!r}: its entry point {reg.target!r} ({reg.source}) "
                              f"is not package.module:Class; the package's metadata is broken")
    try:
        module = _import_module(module_name, reg.name, reg.target)
        reason = _requirements(module, reg.name, reg.target, reg.distribution or DISTRIBUTION)
        if reason is not None:
            raise EngineNotInstalled(reg.name, reason)
        cls = _engine_class(module, cls_name, reg.name, reg.target)
        return cls, reg.name, f"{reg.target} from {reg.source}"
    except EngineSpecError as exc:
        raise EngineLoadError(f"{exc} [registered by {reg.source}]") from None
