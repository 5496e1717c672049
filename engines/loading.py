"""Building engines from a name or spec: options, checks, several at once, and listing them.

`load_engine(spec, model, **options)` resolves ``spec`` (`engines.registry`), checks the options
against the class's ``__init__`` and the model's contact against its ``contacts``, builds it and
checks that every declared capability has its method. `load_engines` builds several and drops
the failures with their reasons; `parse_engine_options` types ``key=value`` strings;
`engine_info` describes what is registered.

Errors: `EngineSpecError` (usage, exit 2): a bad name/spec, an option the engine does not take,
a bad option value. `EngineLoadError` (exit 1): the engine does not import, lacks a declared
capability's method, does not support the model's contact, or raised while being built.

Every engine `load_engine` returns is guarded (`engines.guard`): what its methods return is
checked at the boundary, and it cannot end the process.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any, Mapping, NamedTuple, Sequence

from .base import (CAPABILITIES, Engine, EngineError, EngineLoadError, EngineSpecError,
                   UnsupportedModel)
from .guard import cut, engine_interrupt, guard, sigint_handler
from .registry import EngineNotInstalled, _one_line, _resolve_target, _who, registrations, resolve


@dataclass(frozen=True)
class EngineInfo:
    """What `bicycle-xval engines` lists for one engine.

    ``capabilities`` and ``contacts`` are the class's declarations (with default options);
    ``options`` the keyword arguments its ``__init__`` takes (``**`` means any); ``error`` is set
    (and the rest empty) when the engine could not be imported, ``not_installed`` instead when
    what it declares in ``REQUIRES`` is missing (the line with the pip command)."""

    name: str
    spec: str
    source: str
    capabilities: tuple[str, ...] = ()
    contacts: tuple[str, ...] = ()
    options: tuple[str, ...] = ()
    doc: str = ""
    error: str | None = None
    not_installed: str | None = None


class LoadedEngines(NamedTuple):
    """`load_engines`' result: the built engines by label, and the dropped ones with reasons
    (``engines, dropped = load_engines(...)``)."""

    engines: dict[str, Engine]
    dropped: list[tuple[str, str]]


# -- building --------------------------------------------------------------------------------

def _option_names(cls: type[Engine]) -> tuple[tuple[str, ...], bool]:
    """The keyword options of cls.__init__ after the model, and whether it takes **kwargs."""
    try:
        params = list(inspect.signature(cls.__init__).parameters.values())[2:]
    except (TypeError, ValueError):  # pragma: no cover - builtins without signatures
        return (), True
    names = tuple(p.name for p in params
                  if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY))
    return names, any(p.kind is p.VAR_KEYWORD for p in params)


def _check_options(cls, label: str, spec: str, options: Mapping[str, Any]) -> None:
    names, anything = _option_names(cls)
    unknown = sorted(set(options) - set(names))
    if unknown and not anything:
        if not names:
            raise EngineSpecError(f"{_who(label, spec)} takes no options; got "
                                  f"{', '.join(unknown)}")
        raise EngineSpecError(f"{_who(label, spec)} does not take option(s) "
                              f"{', '.join(unknown)}; it takes: {', '.join(names)}")


def _check_capabilities(engine: Engine, label: str, spec: str) -> None:
    caps = set(engine.capabilities)
    unknown = sorted(caps - set(CAPABILITIES))
    if unknown:
        raise EngineLoadError(f"{_who(label, spec)} declares unknown capabilities "
                              f"{', '.join(unknown)}; the capabilities are: {', '.join(CAPABILITIES)}")
    lacking = [c for c in CAPABILITIES if c in caps
               and getattr(type(engine), c, None) is getattr(Engine, c)]
    if lacking:
        raise EngineLoadError(f"{_who(label, spec)} declares {', '.join(lacking)} but does "
                              f"not implement {'it' if len(lacking) == 1 else 'them'} (override the "
                              f"method(s) of engines.base.Engine)")


def load_engine(spec: str, model, **options) -> Engine:
    """Build the engine named by ``spec`` (a registered name, ``package.module:Class`` or
    ``path/to/file.py:Class``) for a `reference_model.Model`; ``options`` go to its ``__init__``.

    Raises `EngineSpecError` (usage: unknown name, malformed spec, missing module/file/class, not
    an Engine, unknown option or bad option value) or `EngineLoadError` (the engine failed: does
    not import, lacks a declared capability's method, does not support the model's contact, or
    raised while being built)."""
    cls, label, where = resolve(spec)
    spec = spec.strip() if ":" in spec else where    # the messages name the class either way
    _check_options(cls, label, spec, options)
    contacts = tuple(getattr(cls, "contacts", ()) or ())
    contact = getattr(model, "contact", None)
    if contact not in contacts:
        raise UnsupportedModel(f"{_who(label, spec)} supports the front-contact models "
                              f"{', '.join(contacts) or 'none'}, not {contact!r} of model "
                              f"{getattr(model, 'name', '?')!r}")
    before = sigint_handler()
    try:
        engine = cls(model, **options)
    except EngineSpecError as exc:   # keep the class (EngineUsageError is one): callers match it
        raise type(exc)(f"{_who(label, spec)}: {exc}") from exc
    except UnsupportedModel as exc:   # a declared limitation, not a failure
        raise UnsupportedModel(f"{_who(label, spec)} cannot represent model "
                               f"{getattr(model, 'name', '?')!r}: {_one_line(exc)}") from exc
    except Exception as exc:  # noqa: BLE001 - report any failure of the engine's constructor
        raise EngineLoadError(f"{_who(label, spec)} raised while being built: "
                              f"{type(exc).__name__}: {cut(_one_line(exc))}") from exc
    except (SystemExit, KeyboardInterrupt) as exc:   # its own exit, never the harness's
        if not engine_interrupt(exc, before):
            raise
        raise EngineLoadError(f"{_who(label, spec)} raised {type(exc).__name__} while being "
                              "built (an engine must not end the process: raise an exception)"
                              ) from None
    _check_capabilities(engine, label, spec)
    return guard(engine)


def load_engines(specs: Sequence[str], model, options: Mapping[str, Mapping[str, Any]] | None = None
                 ) -> LoadedEngines:
    """Build several engines, dropping those that fail: ``engines, dropped = load_engines(...)``.

    ``options`` maps a spec (as given) to that engine's options. Returns the built engines by
    label (the registered name, or the class's ``name`` for a spec; the spec itself if two share
    a label) and ``dropped``: (label or spec, one-line reason) for each `EngineLoadError`. A bad
    spec or option (`EngineSpecError`) is a usage error and is raised, before anything is built.
    """
    options = dict(options or {})
    extra = sorted(set(options) - set(specs))
    if extra:
        raise EngineSpecError(f"options given for engine(s) {', '.join(extra)} that are not in the "
                              f"list {', '.join(specs)}")
    resolved: list[tuple[str, type[Engine] | None, str, str | None]] = []
    out = LoadedEngines({}, [])
    for spec in specs:     # first every name/spec and option, so a usage error stops the run early
        try:
            cls, label, _ = resolve(spec)
        except EngineLoadError as exc:
            resolved.append((spec, None, spec, str(exc)))
            continue
        _check_options(cls, label, spec, options.get(spec, {}))
        resolved.append((spec, cls, label, None))
    labels = [label for _, cls, label, _ in resolved if cls is not None]
    for spec, cls, label, failure in resolved:
        if failure is not None:
            out.dropped.append((spec, failure))
            continue
        key = label if labels.count(label) == 1 else spec
        try:
            out.engines[key] = load_engine(spec, model, **options.get(spec, {}))
        except EngineLoadError as exc:
            out.dropped.append((key, str(exc)))
    return out


_TRUE, _FALSE = ("true", "yes", "on", "1"), ("false", "no", "off", "0")


def _convert(text: str, default: Any, what: str) -> Any:
    """``text`` as the type of the option's default (bool, int, float, str); without a usable
    default: an int, a float, true/false, none, else the string."""
    low = text.strip().lower()
    try:
        if isinstance(default, bool):
            if low in _TRUE or low in _FALSE:
                return low in _TRUE
            raise ValueError
        if isinstance(default, int):
            return int(text)
        if isinstance(default, float):
            return float(text)
        if isinstance(default, str):
            return text
    except ValueError:
        kind = type(default).__name__
        raise EngineSpecError(f"{what}: {text!r} is not a {kind} (the default is {default!r})") from None
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    if low in ("true", "false"):
        return low == "true"
    return None if low in ("none", "null") else text


def parse_engine_options(spec: str, pairs: Sequence[str]) -> dict[str, Any]:
    """Options for engine ``spec`` from ``key=value`` strings (the CLI's ``--engine-option``),
    each converted to the type of that option's default in the engine's ``__init__``
    (``step=5e-4`` -> 0.0005, ``build=tree`` -> 'tree', a bool from true/false/yes/no/1/0).

    Raises `EngineSpecError` for a pair without '=', an empty or repeated key, an option the
    engine does not take, or a value of the wrong type; `EngineLoadError` if the engine itself
    cannot be imported."""
    cls, label, where = resolve(spec)
    desc = spec.strip() if ":" in spec else where
    try:
        params = dict(list(inspect.signature(cls.__init__).parameters.items())[2:])
    except (TypeError, ValueError):  # pragma: no cover
        params = {}
    out: dict[str, Any] = {}
    for pair in pairs:
        key, eq, value = pair.partition("=")
        key = key.strip()
        if not eq or not key:
            raise EngineSpecError(f"engine option {pair!r} for {_who(label, desc)} is not key=value "
                                  f"(e.g. step=5e-4)")
        if key in out:
            raise EngineSpecError(f"engine option {key!r} for {_who(label, desc)} is given twice")
        _check_options(cls, label, desc, {key: None})
        param = params.get(key)
        default = param.default if param is not None and param.default is not param.empty else None
        out[key] = _convert(value, default, f"option {key} of {_who(label, desc)}")
    return out


# -- listing ---------------------------------------------------------------------------------

def _info(cls: type[Engine], name: str, spec: str, source: str) -> EngineInfo:
    names, anything = _option_names(cls)
    # the class's own docstring: inspect.getdoc would give an engine without one the base
    # class's ("Base class: subclasses set name, ...") as its summary
    doc = inspect.cleandoc(cls.__doc__ or "").strip().splitlines()
    return EngineInfo(name=name, spec=spec, source=source,
                      capabilities=tuple(c for c in CAPABILITIES if c in set(cls.capabilities)),
                      contacts=tuple(getattr(cls, "contacts", ())),
                      options=names + (("**",) if anything else ()),
                      doc=doc[0] if doc else "")


def engine_info(spec: str | None = None) -> list[EngineInfo]:
    """What each registered engine is (or the one named by ``spec``): name, spec, source
    (distribution and version, or the file/module path), capabilities, contact models, options.

    An engine that fails to import is listed with ``error`` set rather than raised (a listing
    must show every registration); a bad ``spec`` raises `EngineSpecError` as in `load_engine`."""
    if spec is not None and ":" in spec:
        cls, label, where = resolve(spec)
        return [_info(cls, label, spec, where)]
    regs = registrations() if spec is None else [r for r in registrations() if r.name == spec]
    if spec is not None and not regs:
        resolve(spec)   # raises the unknown-engine error with the available names
    out = []
    for reg in regs:
        try:
            cls, _, _ = _resolve_target(reg)
        except EngineNotInstalled as exc:   # an extra not installed: not an error
            out.append(EngineInfo(name=reg.name, spec=reg.target, source=reg.source,
                                  not_installed=exc.reason))
            continue
        except EngineError as exc:
            out.append(EngineInfo(name=reg.name, spec=reg.target, source=reg.source, error=str(exc)))
            continue
        out.append(_info(cls, reg.name, reg.target, reg.source))
    return out


def split_options(method, options: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(the options ``method`` takes by keyword, the rest): e.g. for calling an engine's
    ``simulate`` with only the CLI settings it understands and telling the user which ones did
    not apply (never drop them silently). A method with ``**kwargs`` takes everything."""
    try:
        params = inspect.signature(method).parameters.values()
    except (TypeError, ValueError):  # pragma: no cover - builtins without signatures
        return dict(options), {}
    if any(p.kind is p.VAR_KEYWORD for p in params):
        return dict(options), {}
    names = {p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    taken = {k: v for k, v in options.items() if k in names}
    return taken, {k: v for k, v in options.items() if k not in names}
