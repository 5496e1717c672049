"""The engine registry's reading of pyproject.toml in-process, where mutation testing sees it
(tests/test_registry_errors.py checks the same under a real C locale, in a child process that
mutmut's mutants never reach). ~0.1 s."""

from __future__ import annotations

import pathlib

from engines.registry import _pyproject_registrations


def test_the_pyproject_is_decoded_as_utf8_not_by_the_locale(tmp_path, monkeypatch):
    """TOML files are UTF-8 by the standard, so a maintainer's accented name must not depend on
    the machine's locale. Here a locale that can only read ASCII is stood in for by the text
    reader's default (a call that names no encoding gets ASCII): the file still registers its
    engine. Planted: read_text(encoding=None), the locale's encoding (UnicodeDecodeError on a
    Windows cp1252 or a C-locale machine)."""
    p = tmp_path / "pyproject.toml"
    p.write_text('[project]\nname = "bicycle-xval"\nauthors = [{name = "Gómez"}]\n'
                 '[project.entry-points."bicycle_xval.engines"]\nmine = "m:Eng"\n',
                 encoding="utf-8")
    read_text = pathlib.Path.read_text

    def ascii_locale(self, encoding=None, errors=None):
        return read_text(self, encoding=encoding or "ascii", errors=errors)

    monkeypatch.setattr(pathlib.Path, "read_text", ascii_locale)
    assert [(r.name, r.target) for r in _pyproject_registrations(p)] == [("mine", "m:Eng")]
