"""The FMU export's binary cache (`reference_model.exports.fmu._compile`): a binary is compiled
once per compiler command and set of sources, kept in the code cache
(``<cache>/fmu-binaries/<binary_key>.so``) and copied from there on the next export of the same
bicycle (4.4 s -> 0.07 s for thesis-disc's FMU with directional derivatives, measured on the
2-core Intel Xeon, 2026-12-06).

The compiler here is a stand-in (``subprocess.run`` replaced): it writes a binary that names
the sources it was given and counts its calls, so the tests see exactly when the export
compiles and which binary it returns, without gcc's seconds. The one real build at the end
checks that a cached binary is the compiler's own, byte for byte, in an FMU fmpy accepts.

Each test names the planted bugs it was seen failing on."""

from __future__ import annotations

import hashlib
import stat
import subprocess
import zipfile
from pathlib import Path

import pytest

from reference_model.exports import fmu as fmu_export

CC = ("gcc",)


class FakeCompiler:
    """``subprocess.run`` for `_compile`: writes, at the ``-o`` path, a binary that is the
    hash of the wrapper it was asked to compile, and records each call's command."""

    def __init__(self, returncode: int = 0):
        self.calls: list[list[str]] = []
        self.returncode = returncode

    def __call__(self, cmd, **kwargs):
        self.calls.append(list(cmd))
        if self.returncode == 0:
            out = Path(cmd[cmd.index("-o") + 1])
            src = Path(next(c for c in cmd if c.endswith("fmu_wrapper.c")))
            out.write_bytes(b"BIN:" + hashlib.sha256(src.read_bytes()).hexdigest().encode())
        return subprocess.CompletedProcess(cmd, self.returncode, "",
                                           "" if self.returncode == 0 else "x.c:1: error: boom\n")


@pytest.fixture()
def cache(tmp_path, monkeypatch):
    root = tmp_path / "cache"
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(root))
    return root


@pytest.fixture()
def fake(monkeypatch):
    cc = FakeCompiler()
    monkeypatch.setattr(fmu_export.subprocess, "run", cc)
    return cc


def _tree(base: Path, wrapper: str = "int main;", header: str = "/* fmi2 */") -> tuple[Path, Path]:
    """A build folder (the wrapper and one generated source) and a headers folder."""
    build, headers = base / "build", base / "headers"
    build.mkdir(parents=True)
    headers.mkdir(parents=True)
    (build / "fmu_wrapper.c").write_text(wrapper)
    (build / "bicycle_generated.c").write_text("double f(double x) { return x; }")
    (headers / "fmi2Functions.h").write_text(header)
    return build, headers


def test_the_same_sources_compile_once_and_the_second_export_gets_the_same_binary(
        tmp_path, cache, fake):
    """Two builds of the same sources in different temporary folders (as two exports do):
    the compiler runs once and both binaries are its output, byte for byte, executable as the
    compiler leaves it; the cached copy is under fmu-binaries/<binary_key>.so.
    Planted: no cache lookup (the compiler runs twice); the lookup under another folder than
    the store; the key over the folders' paths (each export's temporary folder differs, so
    the cache never hits)."""
    b1, h1 = _tree(tmp_path / "one")
    b2, h2 = _tree(tmp_path / "two")
    so1 = fmu_export._compile(b1, h1, CC)
    so2 = fmu_export._compile(b2, h2, CC)
    assert len(fake.calls) == 1
    want = b"BIN:" + hashlib.sha256(b"int main;").hexdigest().encode()
    assert so1.read_bytes() == so2.read_bytes() == want
    assert so2 == b2 / f"{fmu_export.MODEL_IDENTIFIER}.so"
    assert stat.S_IMODE(so2.stat().st_mode) == 0o755
    key = fmu_export.binary_key(b1, h1, CC)
    assert key == fmu_export.binary_key(b2, h2, CC)
    assert (cache / "fmu-binaries" / f"{key}.so").read_bytes() == want
    assert [p.name for p in (cache / "fmu-binaries").iterdir()] == [f"{key}.so"]


@pytest.mark.parametrize("change", ["wrapper", "generated", "new source", "header", "compiler"])
def test_any_change_to_what_the_compiler_reads_compiles_again(tmp_path, cache, fake, change):
    """A byte changed in the wrapper (e.g. the Co-Simulation switch), in a generated source, a
    source added (the complex copy for directional derivatives), a header changed, or another
    compiler: a new key and a new compile, whose binary is the new one (never the cached
    binary of other sources). Planted: a source, the headers or the compiler left out of the
    key; the build folder's or the headers' sources globbed by the wrong pattern."""
    b1, h1 = _tree(tmp_path / "one")
    fmu_export._compile(b1, h1, CC)
    b2, h2 = _tree(tmp_path / "two", wrapper="int main; /* cs */" if change == "wrapper"
                   else "int main;", header="/* fmi2 v2 */" if change == "header" else "/* fmi2 */")
    cc = ("clang",) if change == "compiler" else CC
    if change == "generated":
        (b2 / "bicycle_generated.c").write_text("double f(double x) { return -x; }")
    if change == "new source":
        (b2 / "bicycle_complex.c").write_text("double _Complex g;")
    assert fmu_export.binary_key(b2, h2, cc) != fmu_export.binary_key(b1, h1, CC)
    so = fmu_export._compile(b2, h2, cc)
    assert len(fake.calls) == 2
    assert fake.calls[1][0] == cc[0]
    assert so.read_bytes() == b"BIN:" + hashlib.sha256(
        (b2 / "fmu_wrapper.c").read_bytes()).hexdigest().encode()


def test_a_source_renamed_is_another_key(tmp_path):
    """The key covers each source's name with its bytes, and which folder it is in: the same
    text under another name, or a header moved into the build folder, is another build.
    Planted: the names left out of the key; the folder tag dropped."""
    b1, h1 = _tree(tmp_path / "one")
    b2, h2 = _tree(tmp_path / "two")
    (b2 / "bicycle_generated.c").rename(b2 / "bicycle_other.c")
    assert fmu_export.binary_key(b1, h1, CC) != fmu_export.binary_key(b2, h2, CC)
    b3, h3 = _tree(tmp_path / "three")
    (h3 / "fmi2Functions.h").rename(b3 / "fmi2Functions.h")
    assert fmu_export.binary_key(b1, h1, CC) != fmu_export.binary_key(b3, h3, CC)


def test_the_compile_command_is_the_documented_one(tmp_path, cache, fake):
    """The command: $CC, -O2 -fPIC -shared -std=c99 -fno-fast-math -fvisibility=default, both
    include folders, the output, the wrapper, -lm (docs/engines.md: gcc or $CC; a shared
    library FMI tools load). Planted: a flag dropped or changed, an include folder lost."""
    build, headers = _tree(tmp_path)
    fmu_export._compile(build, headers, ("ccache", "gcc"))
    so = build / f"{fmu_export.MODEL_IDENTIFIER}.so"
    assert fake.calls == [["ccache", "gcc", "-O2", "-fPIC", "-shared", "-std=c99",
                           "-fno-fast-math", "-fvisibility=default", f"-I{headers}",
                           f"-I{build}", "-o", str(so), str(build / "fmu_wrapper.c"), "-lm"]]


def test_a_failed_compile_is_one_line_and_caches_nothing(tmp_path, cache, monkeypatch):
    """A compiler that fails: FmuExportError naming CC, the compiler's last line and the fix;
    nothing is cached, so the next export tries again. Planted: the binary cached before the
    return code is checked."""
    bad = FakeCompiler(returncode=1)
    monkeypatch.setattr(fmu_export.subprocess, "run", bad)
    build, headers = _tree(tmp_path)
    with pytest.raises(fmu_export.FmuExportError,
                       match=r"^C compiler 'gcc' \(CC\) failed on the FMU wrapper: x\.c:1: "
                             r"error: boom; fix: set CC to a working C99 compiler$"):
        fmu_export._compile(build, headers, CC)
    assert not (cache / "fmu-binaries").exists() or not any((cache / "fmu-binaries").iterdir())
    with pytest.raises(fmu_export.FmuExportError):
        fmu_export._compile(build, headers, CC)
    assert len(bad.calls) == 2


def test_a_read_only_cache_still_builds(tmp_path, monkeypatch, fake):
    """A cache that cannot be written (a file where its folder should be): the binary is built
    and returned, only not kept; the next build compiles again. Planted: the store's OSError
    not caught (the export fails on a read-only cache)."""
    blocker = tmp_path / "cache"
    blocker.write_text("not a folder")
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(blocker))
    build, headers = _tree(tmp_path / "b")
    so = fmu_export._compile(build, headers, CC)
    assert so.read_bytes().startswith(b"BIN:")
    fmu_export._compile(build, headers, CC)
    assert len(fake.calls) == 2


def test_a_cached_binary_is_the_compilers_own_in_a_real_export(tmp_path, monkeypatch):
    """Two real exports (gcc, the user's code cache: the first compiles only on a cold cache):
    the second does not run the compiler, and its FMU holds the same binary, byte for byte, an
    ELF shared object, in an FMU that passes fmpy's validation. Planted: the copy from the
    cache not written to the FMU's binary path; the cache stored under another key than the
    one looked up (the second export compiles)."""
    fmpy = pytest.importorskip("fmpy")
    from fmpy.validation import validate_fmu
    from reference_model import load_model
    model = load_model("thesis-disc")
    first = fmu_export.write_fmu(model, tmp_path / "a.fmu", directional_derivatives=False)
    calls = []
    real = fmu_export.subprocess.run
    monkeypatch.setattr(fmu_export.subprocess, "run",
                        lambda *a, **k: calls.append(a) or real(*a, **k))
    second = fmu_export.write_fmu(model, tmp_path / "b.fmu", directional_derivatives=False)
    assert calls == []
    binary = f"binaries/linux64/{fmu_export.MODEL_IDENTIFIER}.so"
    with zipfile.ZipFile(first) as a, zipfile.ZipFile(second) as b:
        assert a.read(binary) == b.read(binary)
        assert a.read(binary)[:4] == b"\x7fELF"
    assert validate_fmu(str(second)) == []
