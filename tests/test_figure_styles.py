"""The figures name and draw runs from the engines' facts and their own data, never from a
list of names (issue 22): a run label's colour is its engine's declared ``colour``, its line
style its setup's place among the engine's setups; axis texts name the engine given to them.
Every engine, declared or not, gets a colour and marker no other engine has (issue 25), with
eight engines in one figure. Costs about 1.3 s (matplotlib's import and four small figures,
never saved)."""

import numpy as np
import pytest

from comparisons.report import figures
from comparisons.report.styles import (REFERENCE_STYLE, EngineStyle, engine_styles,
                                       resolve_styles, style_of)
from engines.facts import engine_facts

FOO = EngineStyle("foo", "tab:red", ("", "a"))
FOO_BAR = EngineStyle("foo-bar", "tab:green", ("",))


def test_a_label_is_its_engine_s_colour_and_its_setup_s_line():
    """Matching: the name itself, or ``name-suffix``, the longest registered name first.
    Planted: matching in the given order (no longest-first) draws 'foo-bar' as foo's setup
    'bar' in red and fails."""
    styles = (FOO, FOO_BAR)
    assert style_of("foo", styles)["color"] == "tab:red"
    assert style_of("foo-a", styles)["color"] == "tab:red"
    assert style_of("foo", styles)["ls"] != style_of("foo-a", styles)["ls"]
    assert style_of("foo-bar", styles)["color"] == "tab:green"
    assert style_of("foobar", styles)["color"] not in ("tab:red", "tab:green")  # a fallback
    ref = style_of("reference", styles)
    assert {k: ref[k] for k in REFERENCE_STYLE} == REFERENCE_STYLE


def test_registered_engines_are_drawn_in_their_declared_colours():
    """A fixed-step engine's two variants share its colour and differ by line; two engines
    differ by colour (each as its class declares)."""
    tree, redundant = style_of("exudyn-tree"), style_of("exudyn-redundant")
    assert tree["color"] == redundant["color"] == engine_facts("exudyn").colour
    assert tree["ls"] != redundant["ls"]
    assert style_of("pinocchio")["color"] == engine_facts("pinocchio").colour != tree["color"]


@pytest.fixture
def curve():
    t = np.linspace(0.0, 1.0, 11)
    return {"t": t, "theta": 1e-9 * (1 + t), "xc": 1e-10 * (1 + t), "max": 2e-9 * (1 + t)}


def test_drawings_take_labels_and_axis_texts_from_their_data(curve):
    """error_vs_time, error_panels and contact_run name the engine from ``engine_label`` (a
    generic 'engine' by default) and the runs from the curves' keys. Planted: an axis text
    written out for one engine fails."""
    import matplotlib.pyplot as plt
    fig = figures.error_vs_time({"exudyn-tree": curve}, 1.0, 1e-6, "t", engine_label="Exudyn")
    ax = fig.axes[0]
    assert ax.get_ylabel() == "|Exudyn - reference| [rad or m]"
    assert ax.get_lines()[0].get_label() == "exudyn-tree: theta [rad]"
    assert ax.get_lines()[0].get_color() == engine_facts("exudyn").colour
    plt.close(fig)
    fig = figures.error_panels([{"title": "p", "curves": {"kane": curve}}], 1e-6)
    assert fig.axes[0].get_ylabel() == "|engine - ref|\n[rad or m]"
    plt.close(fig)
    t = curve["t"]
    wheels = {"rear": t, "front": t}
    fig = figures.contact_run(t, curve, 1.0, wheels, wheels, wheels,
                              {"t": t, "rear": t, "front": t}, "c", engine_label="MuJoCo")
    assert fig.axes[0].get_ylabel() == "|MuJoCo - ref|\n[rad or m]"
    assert "rear: MuJoCo" in [ln.get_label() for ln in fig.axes[3].get_lines()]
    plt.close(fig)


#: three plugins that declare neither colour nor marker, beside the installed engines: with the
#: five built-ins, eight engines (what the report must stay readable with)
PLUGINS = tuple(EngineStyle(n, None, ("",)) for n in ("plugin_a", "plugin_b", "plugin_c"))
#: colours kept for the engines being written: no fallback may take them
KEPT = {"tab:green", "tab:brown"}


def _pairs(styles):
    return [(st.colour, st.marker) for st in styles]


def test_installed_engines_declare_distinct_colours_and_markers():
    """Each installed engine's own declarations (not a fallback) differ from every other's, so
    a figure tells any two apart by colour and by marker alone; none takes a kept colour
    unless it is the engine it is kept for. Planted: MuJoCo declaring Pinocchio's
    tab:orange fails (the bug the issue saw: two engines in one colour)."""
    declared = [engine_facts(st.name) for st in engine_styles()]
    colours = [f.colour for f in declared]
    markers = [f.marker for f in declared]
    assert None not in colours and None not in markers, "a built-in declares both"
    assert len(set(colours)) == len(colours), colours
    assert len(set(markers)) == len(markers), markers
    assert not KEPT & set(colours)


def test_undeclared_engines_get_fallbacks_distinct_from_every_declared_one():
    """Eight engines, three declaring nothing: every (colour, marker) differs in both parts,
    the fallbacks come from neither a declared colour nor a kept one, and they are the same
    every time (a pure function of the engines). Planted: the old fallback, matplotlib's
    cycle (C0 is tab:blue, Exudyn's), fails; so does a fallback that ignores the declared."""
    from matplotlib.colors import to_hex
    eight = resolve_styles(engine_styles() + PLUGINS)
    n = len(engine_styles()) + len(PLUGINS)      # eight with the five built-ins of issue 25
    assert len(eight) == n >= 8
    colours, markers = zip(*_pairs(eight))
    # compared as drawn (hex), so 'C5' and 'tab:brown' are one colour
    assert len({to_hex(c) for c in colours}) == n and len(set(markers)) == n, _pairs(eight)
    declared = {to_hex(engine_facts(st.name).colour) for st in engine_styles()}
    fallbacks = {to_hex(st.colour) for st in eight[-3:]}
    assert not fallbacks & (declared | {to_hex(c) for c in KEPT})
    assert resolve_styles(engine_styles() + PLUGINS) == eight
    # an engine that declares a fallback's first colour pushes the fallback to the next one
    taken = resolve_styles((EngineStyle("x", "tab:pink", ("",), "X"),) + PLUGINS[:1])
    assert taken[1].colour != "tab:pink" and taken[1].marker != "X"


def test_an_unregistered_label_keeps_one_style_and_avoids_the_engines():
    """A file spec's class name (no registered engine): a colour and marker none of the
    engines has, the same on every call (a checksum, not ``hash``, which changes per process)."""
    styles = resolve_styles(engine_styles())
    a = style_of("MyEngine", styles)
    assert a == style_of("MyEngine", styles)
    assert (a["color"], a["marker"]) not in _pairs(styles)
    assert a["color"] not in {st.colour for st in styles} | KEPT
    assert a["marker"] not in {st.marker for st in styles}


def test_eight_engines_in_one_figure_are_eight_colours_and_eight_markers(monkeypatch):
    """The trajectory overlay of eight engines (the built-ins and three plugins): its lines in
    eight colours and eight markers, as drawn (read back from matplotlib). Planted: style_of
    returning no marker for an engine (as before the marker fact) fails."""
    import matplotlib.pyplot as plt

    from engines.runs import Run
    eight = resolve_styles(engine_styles() + PLUGINS)
    t = np.linspace(0.0, 1.0, 21)
    q = np.zeros((t.size, 8))
    runs = {st.name: Run(st.name, "s", "thesis", "forward", "completed", "", 1.0, t=t, q=q)
            for st in eight}
    # the figure matches its labels against these eight engines instead of the installed
    monkeypatch.setattr("comparisons.report.styles.engine_styles", lambda: eight)
    fig = figures.trajectory_overlay("s", runs, {}, 1.0, 1e-6)
    lines = [ln for ln in fig.axes[0].get_lines() if ln.get_label() != "_nolegend_"][:8]
    from matplotlib.colors import to_hex
    drawn = {(to_hex(ln.get_color()), ln.get_marker()) for ln in lines}
    plt.close(fig)
    assert len({c for c, _ in drawn}) == 8 and len({m for _, m in drawn}) == 8, drawn
    assert not {m for _, m in drawn} & {None, "None", "", " "}, "every line carries a marker"
