"""Parts of parameter loading (reference_model/parameters/loading.py), issue 24: the named
models handed on with the triangle-inequality mode the caller asked for, and benchmark.toml
written and checked as UTF-8 whatever the process locale.

The contract is the module's docstring (named models, :func:`resolve_model`,
:func:`load_parameters`), the ``triangle`` mode of :class:`Parameters` ("strict" by default,
"warn" with ``allow_triangle_violation=True``) and docs/model.md: parameter files are UTF-8
text. The locale tests switch the process to the C locale (ASCII) so that a file opened with
the locale's encoding instead of UTF-8 fails. Planted bugs each test was seen failing on are
named in it.
"""

import locale

import pytest

from reference_model.parameters import loading
from reference_model.parameters.loading import NAMED_MODELS, named_model_text, resolve_model


@pytest.fixture
def ascii_locale():
    """The process's LC_CTYPE set to "C" (locale encoding ASCII), restored afterwards."""
    old = locale.setlocale(locale.LC_CTYPE)
    locale.setlocale(locale.LC_CTYPE, "C")
    try:
        yield
    finally:
        locale.setlocale(locale.LC_CTYPE, old)


# -- resolve_model: the triangle mode reaches the named models --------------------------------

@pytest.mark.parametrize("name", sorted(NAMED_MODELS))
def test_a_named_model_takes_the_callers_triangle_mode(name):
    """``resolve_model(name, allow_triangle_violation=True)`` loads the named model with the
    triangle-inequality check turned into a warning (mode "warn"); without it the mode is the
    default "strict". Planted: resolve_model dropping allow_triangle_violation (or passing
    None) for a named model."""
    assert resolve_model(name, allow_triangle_violation=True).triangle == "warn"
    assert resolve_model(name).triangle == "strict"


# -- benchmark.toml as UTF-8 ------------------------------------------------------------------

def test_check_reads_benchmark_toml_as_utf8_in_an_ascii_locale(tmp_path, monkeypatch, capsys,
                                                                ascii_locale):
    """``--check`` on a benchmark.toml holding Table 1 (the text main --write produces) and a
    non-ASCII comment reads it as UTF-8 under an ASCII locale: exit 0, "matches the formulas".
    Planted: _file_values reading the file with the locale's encoding (encoding=None)."""
    path = tmp_path / "benchmark.toml"
    path.write_text("# steer axis tilt \u03bb = \u03c0/10\n" + named_model_text(), encoding="utf-8")
    monkeypatch.setattr(loading, "BENCHMARK_FILE", path)
    assert loading.main(["--check"]) == 0
    assert capsys.readouterr().out == f"{path}: matches the formulas\n"


def test_write_saves_benchmark_toml_as_utf8_in_an_ascii_locale(tmp_path, monkeypatch, capsys,
                                                                ascii_locale):
    """``--write`` saves the generated text as UTF-8 (what load_parameters decodes), also
    under an ASCII locale and for a text with non-ASCII characters. Planted: main writing
    with the locale's encoding (encoding=None, or no encoding given)."""
    path = tmp_path / "benchmark.toml"
    text = "# \u03bb = \u03c0/10\n" + named_model_text()
    monkeypatch.setattr(loading, "BENCHMARK_FILE", path)
    monkeypatch.setattr(loading, "named_model_text", lambda: text)
    assert loading.main(["--write"]) == 0
    assert capsys.readouterr().out == f"wrote {path}\n"
    assert path.read_bytes() == text.encode("utf-8")
