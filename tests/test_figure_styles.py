"""The figures name and draw runs from the engines' facts and their own data, never from a
list of names (issue 22): a run label's colour is its engine's declared ``colour``, its line
style its setup's place among the engine's setups; axis texts name the engine given to them.
Costs about 1 s (matplotlib's import and three small figures, never saved)."""

import numpy as np
import pytest

from comparisons.report import figures
from comparisons.report.styles import REFERENCE_STYLE, EngineStyle, style_of
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
    assert "color" not in style_of("foobar", styles)          # no engine: matplotlib's cycle
    assert style_of("reference", styles) == REFERENCE_STYLE


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
