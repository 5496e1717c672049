"""How the figures draw a run: its engine's colour and marker, a line style per run setup.

    style_of("reference")      # black, solid, thick, its marker
    style_of(label)            # a registered engine's label, or ``name-suffix`` of one of its
                               # run setups or fixed-step variants: its colour and marker,
                               # that setup's line
    mark_of(label)             # the colour and marker alone (for a drawing with its own lines)

A run label is an engine's registered name, or that name, a ``-`` and a suffix naming one of
the engine's run setups or fixed-step variants (`engines.facts`). The colour and marker are
the engine's declared ``colour`` and ``marker``; the line style is the position of the suffix
among the engine's own (``LINESTYLES`` in turn), so an engine's setups are told apart by line
and engines by colour and marker.

An engine that declares no colour or marker (a plugin) gets one of ``FALLBACK_COLOURS`` /
``FALLBACK_MARKERS`` that no installed engine declares: the registered ones in registry order
(so two of them never share one), then a label of no registered engine (a file spec's class
name) by a checksum of its name among those still free (the same label, the same style, in
every figure and every process). Why not matplotlib's colour cycle, as before: its first
colours are tab:blue and tab:orange, which Exudyn and Pinocchio declare, so an undeclared
engine was drawn in another engine's colour (and before the engines declared theirs, Kane and
MuJoCo came out blue and orange beside Exudyn and Pinocchio).
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, replace
from functools import lru_cache

__all__ = ["FALLBACK_COLOURS", "FALLBACK_MARKERS", "LINESTYLES", "REFERENCE_STYLE",
           "EngineStyle", "engine_styles", "mark_of", "resolve_styles", "style_of"]

#: the reference: what every other run is drawn against (its colour and marker: its facts')
REFERENCE_STYLE = {"color": "k", "ls": "-", "lw": 1.6}
#: an engine's setups in their declared order (the first is its plain name's or first setup's)
LINESTYLES = (("--", 1.3), (":", 1.5), ("-.", 1.1), ((0, (5, 1, 1, 1)), 1.1))
#: for engines that declare none, in this order (no colour or marker any engine declares)
FALLBACK_COLOURS = ("tab:pink", "tab:olive", "tab:cyan", "tab:gray", "navy", "darkgoldenrod",
                    "teal", "magenta", "lime", "maroon", "slateblue", "coral")
FALLBACK_MARKERS = ("X", "*", "h", "p", "<", ">", "d", "8", "H", "P", "1", "x")
#: markers along a line: one every tenth of the axes' diagonal, each engine's shifted by its
#: place so that the markers of lines drawn on top of each other stay visible
MARK_EVERY, MARKER_SIZE = 0.1, 4.0


@dataclass(frozen=True)
class EngineStyle:
    """One engine's declarations the figures use: its name, colour, marker and run-label
    suffixes (``place``: its position among the engines, which shifts its markers)."""

    name: str
    colour: str | None
    suffixes: tuple[str, ...]       # "" for the plain name, then its setups' and variants'
    marker: str | None = None
    place: int = 0


def _engine_style(facts) -> EngineStyle:
    suffixes = [s.suffix for s in facts.run_setups]
    if facts.fixed_step is not None:
        suffixes += list(facts.fixed_step.variant_names)
    return EngineStyle(facts.name, facts.colour, tuple(dict.fromkeys(suffixes)), facts.marker)


def _free(pool, taken) -> list[str]:
    return [x for x in pool if x not in taken]


def resolve_styles(styles) -> tuple[EngineStyle, ...]:
    """``styles`` with every missing colour and marker filled from the fallbacks that none of
    ``styles`` declares, in their order (the first undeclared engine gets the first free one),
    and each engine's ``place``. Pure: the same engines give the same styles."""
    colours = _free(FALLBACK_COLOURS, {s.colour for s in styles})
    markers = _free(FALLBACK_MARKERS, {s.marker for s in styles})
    out = []
    for k, st in enumerate(styles):
        colour = st.colour if st.colour is not None else colours.pop(0) if colours else "0.5"
        marker = st.marker if st.marker is not None else markers.pop(0) if markers else "."
        out.append(replace(st, colour=colour, marker=marker, place=k))
    return tuple(out)


@lru_cache(maxsize=1)
def engine_styles() -> tuple[EngineStyle, ...]:
    """The styles of every installed registered engine, fallbacks filled (`resolve_styles`).
    Read once per process: a figure worker draws many figures and the registered engines do
    not change while it does."""
    from engines.defaults import installed_facts
    return resolve_styles(tuple(_engine_style(f) for f in installed_facts()))


def _match(label: str, styles) -> tuple[EngineStyle, str] | None:
    """The engine whose name is ``label`` or ``label``'s ``name-`` prefix (the longest such
    name: a prefix never shadows a longer name), and the suffix."""
    for st in sorted(styles, key=lambda st: -len(st.name)):
        if label == st.name:
            return st, ""
        if label.startswith(st.name + "-"):
            return st, label[len(st.name) + 1:]
    return None


def _unregistered(label: str, styles) -> EngineStyle:
    """A label of no registered engine: a fallback colour and marker no engine of ``styles``
    uses, picked by the label's checksum (stable across processes, unlike ``hash``)."""
    colours = _free(FALLBACK_COLOURS, {s.colour for s in styles}) or ["0.5"]
    markers = _free(FALLBACK_MARKERS, {s.marker for s in styles}) or ["."]
    k = zlib.crc32(label.encode())
    return EngineStyle(label, colours[k % len(colours)], ("",), markers[k % len(markers)],
                       place=len(styles) + k % 7)


def _found(label: str, styles) -> tuple[EngineStyle, str]:
    styles = engine_styles() if styles is None else styles
    return _match(label, styles) or (_unregistered(label, styles), "")


def mark_of(label: str, styles: tuple[EngineStyle, ...] | None = None) -> dict:
    """matplotlib keyword arguments of the engine of run ``label``: colour, marker and where
    the markers go along the line (no line style: the drawing chooses it)."""
    st, _ = _found(label, styles)
    return {"color": st.colour, "marker": st.marker, "ms": MARKER_SIZE,
            "markevery": (MARK_EVERY * (st.place % 10) / 10, MARK_EVERY)}


def style_of(label: str, styles: tuple[EngineStyle, ...] | None = None) -> dict:
    """matplotlib keyword arguments for the run labelled ``label`` (module docstring);
    ``styles``: the engines to match against, fallbacks filled (default `engine_styles`)."""
    from engines.defaults import REFERENCE
    st, suffix = _found(label, styles)
    if label == REFERENCE:
        return {**REFERENCE_STYLE, **mark_of(label, styles), "color": REFERENCE_STYLE["color"]}
    k = st.suffixes.index(suffix) if suffix in st.suffixes else len(st.suffixes)
    ls, lw = LINESTYLES[min(k, len(LINESTYLES) - 1)]
    return {"ls": ls, "lw": lw, **mark_of(label, styles)}
