"""Parameter validation under hostile input (issue 14, item 9): absurd magnitudes are errors
naming the range, unusual values warnings; the messages say what to do."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

from reference_model.params import (PARAMETER_BOUNDS, PARAMETER_GROUPS, PARAMETER_NAMES,
                                    THESIS_FILE, ParameterError, ParameterWarning,
                                    load_parameters, resolve_model)

THESIS_TEXT = THESIS_FILE.read_text(encoding="utf-8")


def _with_entry(tmp_path: Path, name: str, entry: str, *, key: str | None = None) -> Path:
    """The thesis file with parameter ``name``'s line replaced by ``key = entry``."""
    line = next(l for l in THESIS_TEXT.splitlines() if re.match(rf"{name}\s*=", l))
    path = tmp_path / "bad.toml"
    path.write_text(THESIS_TEXT.replace(line, f"{key or name} = {entry}"), encoding="utf-8")
    return path


def _one_line_error(path: Path) -> str:
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(f"{path}: ") and "; fix: " in text, text
    return text


def test_every_parameter_has_bounds():
    assert set(PARAMETER_BOUNDS) == set(PARAMETER_NAMES)


@pytest.mark.parametrize("name", PARAMETER_NAMES)
def test_absurd_magnitude_is_an_error_naming_the_range(tmp_path, name):
    """Issue 14: 1e300 kg passed validation and failed later with unrelated messages. No
    bicycle part, from a toy to a cargo bike, has any parameter of magnitude 1e300 SI."""
    text = _one_line_error(_with_entry(tmp_path, name, "1e300"))
    assert f"{PARAMETER_GROUPS[name]}.{name}" in text and "outside the range" in text, text
    assert f"{PARAMETER_BOUNDS[name].high:g}" in text, text     # the range is stated


def test_mass_range_is_stated(tmp_path):
    text = _one_line_error(_with_entry(tmp_path, "m3", '{ value = 1e300, unit = "kg" }'))
    assert "mass.m3" in text and "0.001 to 10000 kg" in text


def test_unusual_value_is_one_warning_not_an_error(tmp_path):
    """The Moon's gravity is a legitimate experiment, but worth a word."""
    path = _with_entry(tmp_path, "g", '{ value = 1.62, unit = "m/s^2" }')
    with pytest.warns(ParameterWarning) as record:
        p = load_parameters(path)
    assert p.g == 1.62
    messages = [str(w.message) for w in record if issubclass(w.category, ParameterWarning)]
    assert len(messages) == 1 and "\n" not in messages[0]
    assert messages[0].startswith(f"{path}: environment.g: ") and "usual: 9.7 to 9.9" in messages[0]


@pytest.mark.parametrize("model", ["thesis", "thesis-disc", "benchmark"])
def test_shipped_models_are_usual(model):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ParameterWarning)
        resolve_model(model)


def test_symmetric_tensor_entry_is_named(tmp_path):
    """Issue 14: I3zx was answered 'did you mean I3zz'; it is the symmetric entry I3xz."""
    text = _one_line_error(_with_entry(tmp_path, "I3xz", '{ value = -1.82, unit = "kg*m^2" }',
                                       key="I3zx"))
    assert "inertia.I3zx" in text and "I3xz" in text and "I3zz" not in text, text


@pytest.mark.parametrize("key, said", [("I2xz", "axisymmetric wheel"), ("I3xy", "only product of inertia is inertia.I3xz")])
def test_products_the_model_has_no_parameter_for(tmp_path, key, said):
    path = tmp_path / "extra.toml"
    path.write_text(THESIS_TEXT.replace("[inertia]\n", f"[inertia]\n{key} = 0.1\n"), encoding="utf-8")
    text = _one_line_error(path)
    assert f"inertia.{key}" in text and said in text, text


def test_utf8_bom_is_accepted(tmp_path):
    """A BOM (Windows editors) used to end in an 'invalid TOML at line 1' error."""
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + THESIS_TEXT.encode("utf-8"))
    assert load_parameters(path).vector().tolist() == load_parameters(THESIS_FILE).vector().tolist()
