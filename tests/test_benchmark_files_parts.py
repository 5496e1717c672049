"""The parts of reference_model/parameters/benchmark_files.py that the import round trips
(tests/test_import.py, tests/test_bicycleparameters.py, tests/test_cli_bicycles.py) leave open:
each refusal's one line (the file, the key or line, the problem and the fix: the module docstring
says every problem is one ParameterError naming them), BicycleParameters' three spellings of a
value with its uncertainty, the extras those files carry besides Table 1 (IRzz/IFzz, y of a
centre of mass, the handlebar G and fork S measured apart: checked, left out and said in
``notes``), and the atomic writer (the file appears whole or not at all, in folders it creates).

Expected values are the module docstring's contract, BicycleParameters' own shipped files (read
here by ``tests/shipped_sets.py``'s independent regex), hand arithmetic, and the messages of the
libraries the module defers to (``json``, ``tomllib``, ``os.strerror``). Each test names the
planted bugs (mutmut's survivors of the module's measurement) it fails on. ~0.5 s.
"""

from __future__ import annotations

import errno
import json
import locale
import os
import tomllib
from pathlib import Path

import pytest

from benchmark_sets import DATA
from reference_model.parameters import benchmark_files
from reference_model.parameters.benchmark import BENCHMARK_NAMES
from reference_model.parameters.benchmark_files import (_write_atomically, parse_benchmark_text,
                                                        read_benchmark_file, write_import)
from reference_model.parameters.schema import ParameterError
from shipped_sets import file_values, shipped

TXT_EXAMPLE = "w = 1.07+/-0.002"   # the module's example of a .txt line
FRONT_BODY = "the model's front body is their assembly H (mH, xH, zH, IHxx, IHyy, IHzz, IHxz)"


def _refusal(call, *args) -> ParameterError:
    """The ParameterError ``call(*args)`` raises; its message is one line of its four parts."""
    with pytest.raises(ParameterError) as info:
        call(*args)
    err = info.value
    assert str(err) == f"{err.file}: {err.key}: {err.problem}; fix: {err.fix}"
    assert "\n" not in str(err)
    return err


def _parts(err: ParameterError) -> tuple[str, str, str, str]:
    return err.file, err.key, err.problem, err.fix


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


# -- the file: its type, its reading ---------------------------------------------------------


@pytest.mark.parametrize(("name", "said"), [("bike.yaml", "'.yaml'"), ("bike", "'(none)'")])
def test_an_unknown_file_type_is_refused_before_the_file_is_opened(tmp_path, name, said):
    """A file whose suffix is none of .txt/.json/.toml is refused by its type, naming the
    suffix (or "(none)") and the three formats, even when the file does not exist (the type is
    checked first: "no such file" would send the user looking for the wrong mistake).
    Planted: the format not looked up before reading (``fmt = None``); the file, the key, the
    problem or the fix dropped or None; ``suffix and '(none)'``; the key, "(none)" or the fix's
    text altered or upper-cased."""
    path = tmp_path / name
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), "(file)", f"unknown benchmark file type {said}",
        "use a .txt (BicycleParameters' <Name>Benchmark.txt), .json or .toml file")


def test_a_missing_file_is_named_with_the_fix(tmp_path):
    """A .txt path that does not exist: "no such file", the fix to give an existing one.
    Planted: each of the four parts dropped or None; the key, the problem or the fix altered or
    upper-cased."""
    path = tmp_path / "NopeBenchmark.txt"
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), "(file)", "no such file",
        "give the path of an existing benchmark-parameter file")


def test_a_file_that_is_not_utf8_names_the_byte(tmp_path):
    """``w = 1.02`` then ``c = `` and the Latin-1 byte 0xE9: 9 + 4 bytes precede it, so the
    first undecodable byte is byte 13. Planted: each of the four parts dropped or None; the key
    or the fix altered, lower- or upper-cased."""
    path = tmp_path / "LatinBenchmark.txt"
    path.write_bytes(b"w = 1.02\nc = \xe9\n")
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), "(file)", "not UTF-8 text (byte 13)", "save the file as UTF-8")


def test_a_folder_in_place_of_the_file_is_a_read_error_in_the_systems_words(tmp_path):
    """A folder named like a benchmark file: the system's reason (``os.strerror(EISDIR)``),
    not Python's "[Errno 21] ...: '<path>'". Planted: each of the four parts dropped or None;
    ``exc.strerror and exc``; the key or the fix altered or upper-cased."""
    path = tmp_path / "FolderBenchmark.txt"
    path.mkdir()
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), "(file)", f"cannot read the file: {os.strerror(errno.EISDIR)}",
        "give the path of a readable file")


# -- JSON and TOML ---------------------------------------------------------------------------


def test_json_and_toml_files_are_read_as_given_and_name_their_source(tmp_path):
    """The docstring's JSON ``{"w": 1.02, ...}`` and TOML ``w = 1.02``: the numbers as given,
    no uncertainties, the path as the source. Planted: the source None for JSON and TOML."""
    for path in (_write(tmp_path / "b.json", '{"w": 1.02, "c": 0.08}'),
                 _write(tmp_path / "b.toml", "w = 1.02\nc = 0.08\n")):
        read = read_benchmark_file(path)
        assert (read.values, read.source, read.uncertainties, read.notes) == (
            {"w": 1.02, "c": 0.08}, str(path), {}, ())


def test_invalid_json_is_named_by_line_in_jsons_words(tmp_path):
    """A JSON object with a missing value on its third line: the line and ``json``'s own
    message, the fix showing an object of numbers. Planted: the file or the fix None; the
    fix's text altered or upper-cased."""
    text = '{\n  "w": 1.02,\n  "c": \n}\n'
    with pytest.raises(json.JSONDecodeError) as said:
        json.loads(text)
    path = _write(tmp_path / "bad.json", text)
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), f"line {said.value.lineno}", f"invalid JSON: {said.value.msg}",
        'write one object of numbers, e.g. {"w": 1.02, "c": 0.08, ...}')
    assert said.value.lineno == 4


def test_a_json_file_that_is_not_an_object_names_what_it_is(tmp_path):
    """``[1.02, 0.08]`` is a JSON list, not an object of Table 1 names. Planted: each of the
    four parts dropped or None; ``type(None)`` named instead of the list; the key or the fix
    altered or upper-cased."""
    path = _write(tmp_path / "list.json", "[1.02, 0.08]")
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), "(file)", "expected an object of Table 1 names, got list",
        'write {"w": 1.02, "c": 0.08, ...}')


def test_invalid_toml_is_one_line_in_tomllibs_words(tmp_path):
    """``w = `` (no value): "(syntax)", ``tomllib``'s own message, the fix showing a
    ``name = number`` line. Planted: each of the four parts dropped or None; the key or the
    fix altered or upper-cased."""
    text = "w = 1.02\nc =\n"
    with pytest.raises(tomllib.TOMLDecodeError) as said:
        tomllib.loads(text)
    path = _write(tmp_path / "bad.toml", text)
    assert _parts(_refusal(read_benchmark_file, path)) == (
        str(path), "(syntax)", f"invalid TOML: {said.value}",
        "write one 'name = number' per line, e.g. w = 1.02")


def test_an_unknown_format_name_is_a_value_error_naming_the_three():
    """``fmt`` given explicitly and none of txt/json/toml: a ValueError (a programming error,
    not a user's file) naming it and the three. Planted: the message None."""
    with pytest.raises(ValueError) as info:
        parse_benchmark_text("w = 1.02\n", "b.txt", "yaml")
    assert str(info.value) == "unknown benchmark format 'yaml'; use one of txt, json, toml"


# -- BicycleParameters' .txt -----------------------------------------------------------------


def test_the_three_spellings_of_a_value_and_its_uncertainty():
    """The docstring's ``1.07+/-0.002``, ``1.07 ± 0.002`` and ``(6.53+/-0.02)e-07``: the
    nominal values are the model's, the uncertainties (the exponent applied to both) kept."""
    read = parse_benchmark_text("w = 1.07+/-0.002\nc = 1.07 ± 0.002\nIHzz = (6.53+/-0.02)e-07\n",
                                "b.txt")
    assert read.values == {"w": 1.07, "c": 1.07, "IHzz": 6.53e-07}
    assert read.uncertainties["w"] == read.uncertainties["c"] == 0.002
    assert read.uncertainties["IHzz"] == pytest.approx(2e-09, rel=1e-15)


def test_a_comment_holding_a_hash_is_ignored_whole():
    """Everything after the first ``#`` is a comment, even one that holds another ``#``.
    Planted: the comment cut at the last ``#`` (``rsplit``), which leaves ``1.02 # measured``
    as the value."""
    read = parse_benchmark_text(
        "# BicycleParameters # export\nw = 1.02+/-0.01  # measured # twice\n", "b.txt")
    assert (read.values, read.uncertainties) == ({"w": 1.02}, {"w": 0.01})


def test_a_line_with_two_equals_signs_is_a_value_that_is_not_a_number():
    """``w = 1.02 = 3``: the name is what precedes the first ``=``, the rest the value, which is
    no number. Planted: the line split at every ``=`` (or two) and unpacked (a ValueError
    traceback), or at the last one (the name ``w = 1.02`` with the value 3, accepted); the
    file or the fix None."""
    err = _refusal(parse_benchmark_text, "c = 0.08\nw = 1.02 = 3\n", "b.txt")
    assert _parts(err) == ("b.txt", "line 2: w",
                           "value '1.02 = 3' is not a number or number+/-uncertainty",
                           f"write e.g. {TXT_EXAMPLE} (SI units, lam in rad)")


def test_a_line_without_equals_sign_is_quoted_as_written():
    """``  c 0.08 # cm`` on line 2: the line as written (stripped, its comment too) and the
    example line. Planted: the file or the fix None."""
    err = _refusal(parse_benchmark_text, "w = 1.02\n  c 0.08 # cm\n", "b.txt")
    assert _parts(err) == ("b.txt", "line 2", "expected 'name = value', got 'c 0.08 # cm'",
                           f"write one parameter per line, e.g. {TXT_EXAMPLE}")


def test_a_name_given_twice_names_both_lines():
    """``w`` on lines 1 and 3 (a comment between): both line numbers, the fix to keep one.
    Planted: the file, the key or the fix None; the fix altered or upper-cased."""
    err = _refusal(parse_benchmark_text, "w = 1.02\n# again\nw = 1.0\n", "b.txt")
    assert _parts(err) == ("b.txt", "line 3: w", "w is given twice (lines 1 and 3)",
                           "keep one of the two lines")


@pytest.mark.parametrize(("value", "said"), [
    ("1.07+/--0.002", "'-0.002'"), ("(6.53+/--0.02)e-07", "'-0.02'"),
    ("1.07+/-1e400", "'1e400'")])
def test_an_uncertainty_must_be_a_finite_non_negative_number(value, said):
    """A negative uncertainty (plain and in the factored-exponent spelling, quoted as written
    before the exponent) and one that overflows to infinity are refused on their line.
    Planted: ``isfinite or >= 0`` (both accepted); each of the four parts dropped or None; the
    exponent quoted in place of the uncertainty (``groups[2]``)."""
    err = _refusal(parse_benchmark_text, f"c = 0.08\nw = {value}\n", "b.txt")
    assert _parts(err) == ("b.txt", "line 2: w",
                           f"uncertainty {said} is not a non-negative number",
                           f"write e.g. {TXT_EXAMPLE}")


# -- the extras BicycleParameters writes -----------------------------------------------------


def _implied(key: str, value: str, why: str) -> str:
    return f"{key} = {value}: implied by Table 1 ({why}), checked and not stored"


SYMMETRIC = "the bicycle is symmetric about its xz plane: y of every centre of mass is 0"


def test_silvers_implied_values_are_checked_left_out_and_noted():
    """BicycleParameters' Silver carries IRzz = IRxx, IFzz = IFxx, yB = yH = 0 besides Table 1:
    the values read are Table 1's 26, the notes say each extra (wheels first, then the y's),
    and only Table 1's uncertainties are kept (all 0.0 in that file)."""
    path = shipped("Silver")
    extras = {k: v for k, v in file_values(path).items() if k not in BENCHMARK_NAMES}
    assert extras == {"IRzz": 0.078, "yB": 0.0, "yH": 0.0, "IFzz": 0.081}
    read = read_benchmark_file(path)
    assert sorted(read.values) == sorted(BENCHMARK_NAMES)
    assert read.uncertainties == dict.fromkeys(BENCHMARK_NAMES, 0.0)
    assert read.notes == (
        _implied("IRzz", "0.078", "the rear wheel is axisymmetric: IRzz = IRxx"),
        _implied("IFzz", "0.081", "the front wheel is axisymmetric: IFzz = IFxx"),
        _implied("yB", "0.0", SYMMETRIC), _implied("yH", "0.0", SYMMETRIC))


def test_rigids_handlebar_and_fork_are_noted_apart_with_their_mass_against_mH():
    """BicycleParameters' Rigid gives the handlebar G and fork S measured apart: each is left
    out with one note listing its keys in the file's order, and their masses are set against
    the assembly's by hand, mG + mS = 3.6 + 2.1 = 5.7 kg against mH = 5.4 kg, (5.7 - 5.4) / 5.4 =
    +5.6 %. Planted: a part's note None; the keys joined by "XX, XX"; the front-body text
    altered or lower/upper-cased; the mass note never made (``{G, S} < parts``, a name of the
    parts or masses altered) or None; ``mG - mS``; the percentage by ``*`` or ``100 /`` or
    ``101 *`` or ``total + mH``; the note's words altered or upper-cased."""
    path = shipped("Rigid")
    order = list(file_values(path))
    handlebar = [k for k in order if k in ("mG", "xG", "zG") or k.startswith("IG")]
    fork = [k for k in order if k in ("mS", "xS", "zS") or k.startswith("IS")]
    assert len(handlebar) == len(fork) == 7
    read = read_benchmark_file(path)
    assert sorted(read.values) == sorted(BENCHMARK_NAMES)
    assert read.notes == (
        f"{', '.join(handlebar)}: the handlebar (G) measured apart, not used: {FRONT_BODY}",
        f"{', '.join(fork)}: the fork (S) measured apart, not used: {FRONT_BODY}",
        "mG + mS = 5.7 kg against mH = 5.4 kg in the source (+5.6 %); mH used as given")


def test_handlebar_and_fork_without_their_masses_are_noted_without_a_mass_note():
    """Handlebar and fork inertias without mG, mS: both are noted as measured apart, and there
    is no mass comparison to make. Planted: ``{G, S} <= parts or ...`` (a KeyError on mG)."""
    read = parse_benchmark_text("IGxx = 0.05\nISxx = 0.08\nmH = 5.4\n", "b.txt")
    assert read.values == {"mH": 5.4}
    assert read.notes == (f"IGxx: the handlebar (G) measured apart, not used: {FRONT_BODY}",
                          f"ISxx: the fork (S) measured apart, not used: {FRONT_BODY}")


def test_the_mass_note_gives_the_parts_excess_over_mH_in_per_cent():
    """mG = 3 kg, mS = 1 kg against mH = 2 kg: the parts weigh 4 kg, (4 - 2) / 2 = +100.0 % of
    mH, which is used as given. Planted: the per cent as ``101 * ...`` (+101.0 %, which
    Rigid's +5.6 % does not show)."""
    read = parse_benchmark_text("mG = 3\nmS = 1\nmH = 2\n", "b.txt")
    assert read.values == {"mH": 2.0}
    assert read.notes[-1] == ("mG + mS = 4 kg against mH = 2 kg in the source (+100.0 %); "
                              "mH used as given")


def test_an_off_plane_centre_of_mass_is_refused_with_the_fix_to_make_it_zero():
    """yB = 0.01 m: Table 1 cannot hold it; the fix says to make it 0 (not "None = 0.0") or
    remove it. Planted: the source None; the target "0" only for the wheels' keys; "0" or
    "cannot hold a bicycle that differs" altered or upper-cased."""
    err = _refusal(parse_benchmark_text, "w = 1.02\nyB = 0.01\n", "b.txt")
    assert _parts(err) == (
        "b.txt", "yB", f"yB = 0.01, but {SYMMETRIC}; Table 1 cannot hold a bicycle that differs",
        "make yB equal 0 or remove it (the model implies it)")


def test_the_implied_values_must_agree_to_1e_12_relative_to_their_own_size():
    """The same number written twice passes, a real difference does not: IRzz may differ from
    IRxx by 1e-12 of IRxx (inclusive: 1e12 + 1 against 1e12 passes), not by 5e-12 of a small
    IRxx = 0.0603 (3e-13 absolute); a y of 1e-13 m is not 0 (the scale of 0 is 1e-300, not 1).
    Planted: ``<`` for ``<=`` (the bound itself refused); the scale floored at 1.0 (small
    differences of small inertias, and any y below 1e-12, accepted)."""
    read = parse_benchmark_text("IRxx = 1e12\nIRzz = 1000000000001\n", "b.txt")
    assert read.values == {"IRxx": 1e12} and read.notes[0].startswith("IRzz = 1000000000001.0: ")
    with pytest.raises(ParameterError, match=r"^b\.txt: IRzz: IRzz = 0\.06030000000030"):
        parse_benchmark_text(f"IRxx = 0.0603\nIRzz = {0.0603 * (1 + 5e-12)!r}\n", "b.txt")
    with pytest.raises(ParameterError, match=r"^b\.txt: yB: yB = 1e-13, but "):
        parse_benchmark_text("yB = 1e-13\n", "b.txt")


# -- writing ---------------------------------------------------------------------------------


def test_write_import_creates_the_missing_folders_and_leaves_only_the_file(tmp_path):
    """``write_import`` into two folders that do not exist yet: they are made (``parents``
    defaults to True), the file is there whole (it loads back: the returned parameters'
    source is it) and nothing else is. Planted: ``parents`` defaulting to False, or
    ``mkdir(parents=None/False)`` or without ``parents`` (FileNotFoundError)."""
    out = tmp_path / "a" / "b" / "bike.toml"
    params = write_import(DATA / "Table1Benchmark.txt", out)
    assert params.source == str(out)
    assert sorted(p.name for p in out.parent.iterdir()) == ["bike.toml"]
    assert tomllib.loads(out.read_text(encoding="utf-8"))["model"]["name"] == "Table1Benchmark"


def test_the_temporary_is_a_hidden_sibling_named_after_the_file(tmp_path, monkeypatch):
    """The temporary is renamed onto the file from the same folder (a rename within one file
    system is atomic), and is ``.<name>.<random>.tmp``: what a hard kill could leave behind
    says which file it was and that it is temporary. Planted: the temporary in the system's
    temporary folder (``dir=None`` or none given); no prefix, or no or another suffix."""
    renamed = []
    real = os.replace

    def spy(src, dst):
        renamed.append((Path(src), Path(dst)))
        real(src, dst)

    monkeypatch.setattr(os, "replace", spy)
    out = tmp_path / "bike.toml"
    _write_atomically(out, "w = 1.02\n")
    [(src, dst)] = renamed
    assert dst == out and src.parent == tmp_path
    assert src.name.startswith(".bike.toml.") and src.name.endswith(".tmp")
    assert len(src.name) > len(".bike.toml..tmp")
    assert out.read_text(encoding="utf-8") == "w = 1.02\n"


def test_bytes_are_written_as_they_are(tmp_path):
    """Bytes (the FMU export's archive) are written unchanged, not as text. Planted: the bytes
    written through a text handle (``isinstance(...) and False``: a TypeError); ``fdopen``'s
    descriptor or mode None, dropped, or the mode altered or upper-cased."""
    data = bytes(range(256))
    out = tmp_path / "x.fmu"
    _write_atomically(out, data, parents=False)
    assert out.read_bytes() == data
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.fmu"]


def test_text_is_utf8_whatever_the_locale(tmp_path):
    """Text is written as UTF-8 (the parameter file is TOML, which is UTF-8) even under a
    locale whose encoding is ASCII (LC_CTYPE "C"). Planted: the encoding None or not given
    (the locale's: a UnicodeEncodeError on "é", in a process not in Python's UTF-8 mode)."""
    out = tmp_path / "bike.toml"
    before = locale.setlocale(locale.LC_CTYPE)
    locale.setlocale(locale.LC_CTYPE, "C")
    try:
        _write_atomically(out, 'description = "my café bike"\n')
    finally:
        locale.setlocale(locale.LC_CTYPE, before)
    assert out.read_bytes() == 'description = "my café bike"\n'.encode("utf-8")


def test_a_failed_rename_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    """The rename fails (a full or read-only file system): the failure propagates as it was,
    the file already there is untouched and the temporary is gone. Planted: the clean-up
    given ``Path(None)`` (a TypeError in place of the failure)."""
    out = _write(tmp_path / "bike.toml", "old\n")
    failure = OSError(errno.EROFS, os.strerror(errno.EROFS))

    def fail(src, dst):
        raise failure

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError) as info:
        _write_atomically(out, "new\n")
    assert info.value is failure
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bike.toml"]
    assert out.read_text(encoding="utf-8") == "old\n"


def test_an_interrupt_just_after_the_rename_stays_an_interrupt(tmp_path, monkeypatch):
    """Ctrl-C arriving just after the rename: the new file is whole, nothing else is left, and
    the KeyboardInterrupt propagates (the clean-up of the temporary, already renamed away, must
    not turn it into a FileNotFoundError). Planted: ``unlink(missing_ok=False/None)``."""
    real = os.replace

    def rename_then_interrupt(src, dst):
        real(src, dst)
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", rename_then_interrupt)
    out = tmp_path / "bike.toml"
    with pytest.raises(KeyboardInterrupt):
        _write_atomically(out, "new\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bike.toml"]
    assert out.read_text(encoding="utf-8") == "new\n"


def test_a_generated_file_that_would_not_load_back_is_refused_and_not_written(tmp_path,
                                                                             monkeypatch):
    """``write_import`` loads the text back before writing and needs the same model, name
    included: a generator that writes another name (the Table 1 values still equal) is
    refused with an AssertionError naming the output, and nothing is written. Planted: the
    check needing the model *and* its Table 1 to differ; the message None."""
    real = benchmark_files.toml_text

    def renaming(*args, **kwargs):
        return real(*args, **kwargs).replace('name = "bike"', 'name = "other"', 1)

    monkeypatch.setattr(benchmark_files, "toml_text", renaming)
    out = tmp_path / "bike.toml"
    with pytest.raises(AssertionError) as info:
        write_import(DATA / "Table1Benchmark.txt", out, name="bike")
    assert str(info.value) == f"{out}: the generated file does not load back to the imported model"
    assert list(tmp_path.iterdir()) == []
