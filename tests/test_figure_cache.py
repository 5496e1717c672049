"""The cache of drawn figures (`comparisons.report.figure_cache`): a figure is read back only
when its drawing code and its data are those it was drawn from, and what is read back is the
PNG a fresh drawing gives. Costs about 1 s (matplotlib's import and three small figures)."""

import dataclasses
import shutil

import numpy as np
import pytest

from comparisons.report import figures
from comparisons.report.figure_cache import (PNG_SIGNATURE, FigureCache, data_key,
                                             drawing_key)
from comparisons.report.writer import draw_figures
from comparisons.stages.results import Figure, Section
from engines.runs import Run


def _curve(scale=1.0):
    t = np.linspace(0.0, 1.0, 11)
    return {"t": t, "theta": scale * 1e-9 * (1 + t), "xc": scale * 2e-9 * (1 + t)}


def _figure(name="a.png", scale=1.0):
    return Figure(name, "error_vs_time", {"curves": {"kane": _curve(scale)}, "horizon": 1.0,
                                          "threshold": 1e-6, "title": "t"})


@dataclasses.dataclass
class _Result:
    """What `draw_figures` reads of a `ComparisonResult`: its sections."""
    sections: list


def _result(*figs):
    return _Result([Section("s", blocks=list(figs))])


def _run(**change):
    fields = dict(engine="kane", scenario="replay", model="thesis", kind="forward",
                  status="completed", message="ok", seconds=1.0, t=np.arange(3.0),
                  q=np.zeros((3, 8)), dq=np.zeros((3, 8)))
    fields.update(change)
    return Run(**fields)


def test_the_key_follows_every_value_a_drawing_reads():
    """One element of one array, an array's dtype with the same values, the order of a dict
    (the order of the curves and of the legend), a list for a tuple, an int for a float: each
    gives another key. Planted: hashing arrays by their values' sum (or dicts sorted) fails."""
    a = np.linspace(0.0, 1.0, 5)
    base = data_key("k", {"x": a, "y": 1.0})
    b = a.copy()
    b[3] = np.nextafter(b[3], 2.0)                       # one ulp in one element
    assert data_key("k", {"x": b, "y": 1.0}) != base
    assert data_key("k", {"x": a[[1, 0, 2, 3, 4]], "y": 1.0}) != base   # same sum
    assert data_key("k", {"x": a.astype(np.float32).astype(np.float64) * 0 + a, "y": 1.0}) == base
    assert data_key("k", {"x": a.astype(np.longdouble), "y": 1.0}) != base
    assert data_key("k", {"y": 1.0, "x": a}) != base
    assert data_key("k", {"x": a, "y": 1}) != base
    assert data_key("other", {"x": a, "y": 1.0}) != base
    assert data_key("k", {"x": [1.0, 2.0]}) != data_key("k", {"x": (1.0, 2.0)})
    assert data_key("k", {"x": a, "y": 1.0}) == base    # and it is a function of the data


def test_a_run_is_keyed_by_what_is_drawn_of_it_not_by_its_timing():
    """A `Run`'s measured seconds and message never change the key (they would make every
    report a miss); its samples and status do."""
    base = data_key("k", {"runs": {"kane": _run()}})
    assert data_key("k", {"runs": {"kane": _run(seconds=9.0, message="other")}}) == base
    assert data_key("k", {"runs": {"kane": _run(status="fell")}}) != base
    q = np.zeros((3, 8))
    q[2, 3] = 1e-12
    assert data_key("k", {"runs": {"kane": _run(q=q)}}) != base


def test_data_without_a_canonical_key_is_drawn_not_cached(tmp_path):
    cache = FigureCache(tmp_path)
    assert cache.key(drawing_key(), "k", {"x": object()}) is None


def test_the_drawing_code_is_part_of_the_key(tmp_path):
    """An edit of figures.py (here a comment) changes the drawing key: a cached PNG of the old
    code is never read back. Planted: a key without the sources fails."""
    import comparisons.report as pkg
    from pathlib import Path
    src = Path(pkg.__file__).parent
    for name in ("figures.py", "styles.py"):
        shutil.copy(src / name, tmp_path / name)
    assert drawing_key(tmp_path) == drawing_key()
    with open(tmp_path / "styles.py", "a") as f:
        f.write("# an edit\n")
    assert drawing_key(tmp_path) != drawing_key()


def test_a_cached_figure_is_the_png_a_fresh_drawing_gives(tmp_path):
    """First run: both figures drawn and stored; second: none drawn, the bytes equal
    `figures.draw_png`'s own. A changed figure is drawn again, the unchanged one read back."""
    cache = FigureCache(tmp_path / "figures")
    one, two = _figure("a.png"), _figure("b.png", 2.0)
    pngs, drawn = draw_figures(_result(one, two), 1, cache)
    assert drawn == 2 and len(list(cache.root.glob("*/*.png"))) == 2
    again, drawn = draw_figures(_result(one, two), 1, cache)
    assert drawn == 0
    assert again == pngs
    assert again["a.png"] == figures.draw_png(one.kind, one.data)
    changed = _figure("b.png", 3.0)
    third, drawn = draw_figures(_result(one, changed), 1, cache)
    assert drawn == 1 and third["a.png"] == pngs["a.png"] and third["b.png"] != pngs["b.png"]


def test_a_damaged_file_is_drawn_again_and_redraw_reads_nothing(tmp_path):
    cache = FigureCache(tmp_path)
    fig = _figure()
    pngs, _ = draw_figures(_result(fig), 1, cache)
    (path,) = cache.root.glob("*/*.png")
    path.write_bytes(b"half a fi")
    again, drawn = draw_figures(_result(fig), 1, cache)
    assert drawn == 1 and again == pngs and path.read_bytes().startswith(PNG_SIGNATURE)
    _, drawn = draw_figures(_result(fig), 1, dataclasses.replace(cache, read=False))
    assert drawn == 1


def test_an_unwritable_cache_costs_the_drawing_only(tmp_path):
    """A cache folder that cannot be made (a file is in the way): every figure is drawn, the
    report gets them, and one line says why."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    lines = []
    pngs, drawn = draw_figures(_result(_figure("a.png"), _figure("b.png", 2.0)), 1,
                               FigureCache(blocker / "figures"), lines.append)
    assert drawn == 2 and set(pngs) == {"a.png", "b.png"}
    assert len(lines) == 1 and "cannot be written" in lines[0] and str(blocker) in lines[0]


def test_prune_keeps_the_most_recently_used(tmp_path):
    import os
    cache = FigureCache(tmp_path, max_files=2)
    for i, key in enumerate(("aa1", "bb2", "cc3")):
        cache.put(key, PNG_SIGNATURE + bytes([i]))
        os.utime(cache._path(key), (1000 + i, 1000 + i))
    cache.get("aa1")                     # used now: the newest
    assert cache.prune() == 1
    assert cache.get("bb2") is None and cache.get("aa1") is not None


def test_run_redraw_option(tmp_path):
    """``run --redraw`` is parsed, and it is the one switch that turns reading back off."""
    from comparisons.cli.main import build_parser
    args = build_parser().parse_args(["run", "--redraw"])
    assert args.redraw is True
    assert build_parser().parse_args(["run"]).redraw is False
    assert FigureCache.default(read=False).read is False


@pytest.mark.parametrize("value", [np.float64(1.5), np.int64(3), np.bool_(True)])
def test_numpy_scalars_key_as_their_python_values(value):
    assert data_key("k", {"v": value}) == data_key("k", {"v": value.item()})
