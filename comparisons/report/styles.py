"""How the figures draw a run: its engine's declared colour, a line style per run setup.

    style_of("reference")      # black, solid, thick
    style_of(label)            # a registered engine's label, or ``name-suffix`` of one of its
                               # run setups or fixed-step variants: its colour, that setup's line

A run label is an engine's registered name, or that name, a ``-`` and a suffix naming one of
the engine's run setups or fixed-step variants (`engines.facts`). The colour is the engine's
declared ``colour``; the line style is the position of the suffix among the engine's own
(``LINESTYLES`` in turn), so an engine's setups are told apart by line and engines by colour.
Labels of no registered engine (a file spec's class name, a model) get matplotlib's cycle.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

__all__ = ["LINESTYLES", "REFERENCE_STYLE", "EngineStyle", "engine_styles", "style_of"]

#: the reference: what every other run is drawn against
REFERENCE_STYLE = {"color": "k", "ls": "-", "lw": 1.6}
#: an engine's setups in their declared order (the first is its plain name's or first setup's)
LINESTYLES = (("--", 1.3), (":", 1.5), ("-.", 1.1), ((0, (5, 1, 1, 1)), 1.1))


@dataclass(frozen=True)
class EngineStyle:
    """One engine's declarations the figures use: its name, colour and run-label suffixes."""

    name: str
    colour: str | None
    suffixes: tuple[str, ...]       # "" for the plain name, then its setups' and variants'


def _engine_style(facts) -> EngineStyle:
    suffixes = [s.suffix for s in facts.run_setups]
    if facts.fixed_step is not None:
        suffixes += list(facts.fixed_step.variant_names)
    return EngineStyle(facts.name, facts.colour, tuple(dict.fromkeys(suffixes)))


@lru_cache(maxsize=1)
def engine_styles() -> tuple[EngineStyle, ...]:
    """The styles of every installed registered engine. Read once per process: a figure worker
    draws many figures and the registered engines do not change while it does."""
    from engines.defaults import installed_facts
    return tuple(_engine_style(f) for f in installed_facts())


def _match(label: str, styles) -> tuple[EngineStyle, str] | None:
    """The engine whose name is ``label`` or ``label``'s ``name-`` prefix (the longest such
    name: a prefix never shadows a longer name), and the suffix."""
    for st in sorted(styles, key=lambda st: -len(st.name)):
        if label == st.name:
            return st, ""
        if label.startswith(st.name + "-"):
            return st, label[len(st.name) + 1:]
    return None


def style_of(label: str, styles: tuple[EngineStyle, ...] | None = None) -> dict:
    """matplotlib keyword arguments for the run labelled ``label`` (module docstring);
    ``styles``: the engines to match against (default `engine_styles`)."""
    from engines.defaults import REFERENCE
    if label == REFERENCE:
        return dict(REFERENCE_STYLE)
    found = _match(label, engine_styles() if styles is None else styles)
    if found is None:
        return {"lw": 1.0}
    st, suffix = found
    k = st.suffixes.index(suffix) if suffix in st.suffixes else len(st.suffixes)
    ls, lw = LINESTYLES[min(k, len(LINESTYLES) - 1)]
    out = {"ls": ls, "lw": lw}
    if st.colour is not None:
        out["color"] = st.colour
    return out
