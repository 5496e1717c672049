"""The engines a command uses when the user names none: one declared place, read from the
registry and the engines' own facts (never a list of names).

    installed_engines()          # every registered engine that is installed, in registry order
    term_engines("thesis")       # those with terms (not the reference) that model that contact

`run`'s default is every registered engine (`engines.registry.default_engines`: one whose extra
is missing is listed as not run, with its pip line); `diagnose`'s and `sweep`'s the installed
engines with terms on the model's front contact (`term_engines`); the conformance suite's every
registered engine but the reference. An engine whose extra is missing, or that fails to
import, is left out here: the commands that list what did not run ask
`engines.registry.not_installed` why.
"""

from __future__ import annotations

from .base import EngineError
from .facts import EngineFacts, engine_facts
from .registry import available_engines, needs_options

__all__ = ["REFERENCE", "installed_engines", "installed_facts", "term_engines"]

#: the engine everything is compared against (the reference model itself)
REFERENCE = "reference"


def installed_facts() -> tuple[EngineFacts, ...]:
    """The facts of every registered engine that resolves (its declared ``REQUIRES`` are
    installed and its module imports), in the registry's order. Imports each engine's module
    (and so its library): the callers build the engines next."""
    out = []
    for name in available_engines():
        try:
            out.append(engine_facts(name))
        except EngineError:        # not installed, broken or registered twice: not a default
            continue
    return tuple(out)


def installed_engines() -> tuple[str, ...]:
    """Every registered engine that is installed (`installed_facts`), by name."""
    return tuple(f.name for f in installed_facts())


def term_engines(contact: str | None = None) -> tuple[str, ...]:
    """The installed engines other than the reference that compute terms (a capability beyond
    ``simulate``), and, given ``contact``, model that front contact; not those that cannot be
    built without an option (`registry.needs_options`)."""
    return tuple(f.name for f in installed_facts() if f.name != REFERENCE and f.has_terms
                 and (contact is None or contact in f.contacts) and not needs_options(f.name))
