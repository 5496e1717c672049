"""The generated-code cache under damage and without a compiler (issue 14, items 1, 7, 10).

Every case that could crash the interpreter (a truncated or overwritten shared library is
mapped by dlopen: SIGBUS, SIGILL) runs in a subprocess on a copy of a pristine cache, and
must exit 0 with the numbers of the intact code. The expected numbers come from the test
process's own model (the ordinary cache, compiled with -O2), not from the damaged entry.

Speed: builds here use a compiler wrapper that appends -O0 (0.5 s instead of ~8 s per variant;
the numbers are the same: no fast-math, no FMA contraction in ISO C mode), and a damaged
library is recompiled from the entry's intact C source, without deriving again.
"""

from __future__ import annotations

import functools
import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from reference_model import codegen, linearize, load_model

ROOT = Path(__file__).resolve().parents[1]
# leaned, steered, pitched: the thesis and disc contacts give different D here
Q = np.array([0.3, -0.2, 0.1, 0.25, 1.0, 0.05, -0.4, 0.3])
DQ = np.array([0.1, 0.2, -0.3, 0.4, 5.0, -0.1, 0.6, 0.2])
T = np.array([0.5, 1.0, -0.2])

PROBE = textwrap.dedent("""
    import json, sys
    import numpy as np
    from reference_model import load_model
    q, dq, T = (np.array(json.loads(a)) for a in sys.argv[2:5])
    m = load_model(sys.argv[1])
    ddq_ind = np.array([0.3, -0.1, 0.2])
    rows = np.stack([q, q * 0.5, -q]); drows = np.stack([dq, -dq, dq * 0.3])
    ddq, torques, lam, status = m.inverse_dynamics_step(rows, drows, np.tile(ddq_ind, (3, 1)))
    print(json.dumps({
        "backend": getattr(m, "backend", "c"), "path": str(m.library.path),
        "M": m.mass_matrix(q).tolist(), "F": m.generalized_forces(q, dq, T).tolist(),
        "D": m.constraint_jacobian(q).tolist(), "bias": m.constraint_bias(q, dq).tolist(),
        "ddq": m.forward_acceleration(q, dq, T).tolist(),
        "ddq_batch": m.forward_acceleration(rows, drows, T).tolist(),
        "id_T": torques.tolist(), "id_lam": lam.tolist(), "id_ddq": ddq.tolist(),
    }))
""")


def _env(cache: Path, cc: str | None, **extra) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("CC", "BICYCLE_XVAL_BACKEND")}
    env.update(BICYCLE_XVAL_CACHE=str(cache), PYTHONPATH=str(ROOT), **extra)
    if cc is not None:
        env["CC"] = cc
    return env


def _run(script: str, args: list[str], env: dict, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", script, *args], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def _probe(cache: Path, cc: str | None, model: str = "thesis", **extra) -> tuple[dict, str]:
    res = _run(PROBE, [model, json.dumps(Q.tolist()), json.dumps(DQ.tolist()),
                       json.dumps(T.tolist())], _env(cache, cc, **extra))
    assert res.returncode == 0, (f"exit {res.returncode} (negative: killed by signal "
                                 f"{-res.returncode})\n{res.stderr[-3000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1]), res.stderr


def _expected(model) -> dict:
    rows = np.stack([Q, Q * 0.5, -Q])
    drows = np.stack([DQ, -DQ, DQ * 0.3])
    ddq, torques, lam, _ = model.inverse_dynamics_step(rows, drows, np.tile([0.3, -0.1, 0.2], (3, 1)))
    return {"M": model.mass_matrix(Q), "F": model.generalized_forces(Q, DQ, T),
            "D": model.constraint_jacobian(Q), "bias": model.constraint_bias(Q, DQ),
            "ddq": model.forward_acceleration(Q, DQ, T),
            "ddq_batch": model.forward_acceleration(rows, drows, T),
            "id_T": torques, "id_lam": lam, "id_ddq": ddq}


def _assert_same(got: dict, want: dict, rtol: float) -> None:
    for name, value in want.items():
        value = np.asarray(value)
        err = np.max(np.abs(np.asarray(got[name]) - value)) / max(np.max(np.abs(value)), 1e-300)
        assert err <= rtol, f"{name}: relative difference {err:.2e} > {rtol:.0e}"


def _no_litter(cache: Path) -> None:
    hidden = [p.name for p in cache.iterdir() if p.name.startswith(".")]
    assert not hidden, f"temporaries left in the cache: {hidden}"
    for entry in cache.iterdir():
        if entry.is_dir():
            files = {p.name for p in entry.iterdir()}
            assert "manifest.json" in files, f"{entry.name} committed without a manifest"
            if "bicycle_generated.c" in files:
                assert "libbicycle.so" in files, f"{entry.name} committed without its library"


@pytest.fixture(scope="module")
def pristine(tmp_path_factory, fast_cc) -> Path:
    """A cache with the thesis and disc C entries and both linearization evaluators, built in
    this process (so later in-process rebuilds reuse its derivations)."""
    cache = tmp_path_factory.mktemp("pristine")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BICYCLE_XVAL_CACHE", str(cache))
        mp.setenv("CC", fast_cc)
        for contact in ("thesis", "disc"):
            codegen.build(contact)
            linearize._evaluator.__wrapped__(contact)
    return cache


@pytest.fixture
def cache(pristine, tmp_path) -> Path:
    copy = tmp_path / "cache"
    shutil.copytree(pristine, copy)
    return copy


def _entry(cache: Path, variant: str) -> Path:
    (entry,) = [p for p in cache.iterdir() if p.is_dir() and p.name.split("-")[0] == variant
                and "numpy" not in p.name and "nogyro" not in p.name]
    return entry


def _linearize_file(cache: Path, contact: str) -> Path:
    (path,) = cache.glob(f"linearize-{contact}-*.py")
    return path


@pytest.fixture(scope="module")
def reference_thesis():
    return _expected(load_model("thesis"))


@pytest.fixture(scope="module")
def reference_disc():
    return _expected(load_model("thesis-disc"))


# -- damaged entries -------------------------------------------------------------------

# The damaged entry is rebuilt from the same source, so its numbers are the intact code's:
# equal to round-off (1e-13 relative; -O0 and -O2 round alike here, measured 0).
RTOL_SAME_CODE = 1e-13


@pytest.mark.slow
def test_truncated_library_is_rebuilt_not_a_crash(cache, fast_cc, reference_thesis):
    so = _entry(cache, "thesis") / "libbicycle.so"
    with open(so, "r+b") as fh:      # issue 14: SIGBUS (exit 135) on every run
        fh.truncate(50_000)
    got, _ = _probe(cache, fast_cc)
    _assert_same(got, reference_thesis, RTOL_SAME_CODE)
    assert so.stat().st_size > 50_000
    _no_litter(cache)


@pytest.mark.slow
def test_flipped_bytes_in_library_are_rebuilt_not_a_crash(cache, fast_cc, reference_thesis):
    so = _entry(cache, "thesis") / "libbicycle.so"
    data = bytearray(so.read_bytes())
    for i in range(0x1000, len(data) - 64, 997):   # code and data sections: SIGILL on main
        data[i] ^= 0xFF
    so.write_bytes(bytes(data))
    got, _ = _probe(cache, fast_cc)
    _assert_same(got, reference_thesis, RTOL_SAME_CODE)
    _no_litter(cache)


@pytest.mark.slow
def test_other_variants_library_copied_in_is_not_used(cache, fast_cc, reference_thesis, reference_disc):
    # the check can tell the variants apart: their D differ at Q by far more than round-off
    assert np.max(np.abs(reference_thesis["D"] - reference_disc["D"])) > 1e-3
    shutil.copy(_entry(cache, "disc") / "libbicycle.so", _entry(cache, "thesis") / "libbicycle.so")
    got, _ = _probe(cache, fast_cc)
    _assert_same(got, reference_thesis, RTOL_SAME_CODE)


@pytest.mark.slow
def test_other_variants_whole_entry_copied_in_is_not_used(cache, fast_cc, monkeypatch):
    """(In process: on main this gave wrong numbers, not a crash.)"""
    thesis, disc = _entry(cache, "thesis"), _entry(cache, "disc")
    for name in ("libbicycle.so", "bicycle_generated.c", "manifest.json"):
        shutil.copy(disc / name, thesis / name)
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(cache))
    monkeypatch.setenv("CC", fast_cc)
    lib = codegen.build("thesis")
    assert lib.built_now and lib.path == thesis
    assert "Contact model: thesis" in (thesis / "bicycle_generated.c").read_text()
    assert json.loads((thesis / "manifest.json").read_text())["contact"] == "thesis"


@pytest.fixture(scope="module")
def benchmark_eigenvalues():
    """Eigenvalues at 5 m/s of the benchmark geometry with each front contact (the ordinary
    cache); the two contacts differ there by O(1) (issue 11, survivor 7)."""
    return {c: np.sort_complex(load_model("benchmark", contact=c).eigenvalues(5.0))
            for c in ("thesis", "disc")}


def _eigen(cache: Path, contact: str, monkeypatch) -> np.ndarray:
    """Eigenvalues with the evaluator read from ``cache`` (in process: on main a damaged
    evaluator gave wrong numbers or a TypeError, not a crash)."""
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(cache))
    model = load_model("benchmark", contact=contact)
    ev = linearize._evaluator.__wrapped__(contact)
    monkeypatch.setattr(linearize, "_evaluator", lambda c: ev)
    # a fresh memo of the speed-independent matrices (the module's one holds the intact ones)
    monkeypatch.setattr(linearize, "_expansion", functools.lru_cache(linearize._expansion.__wrapped__))
    return np.sort_complex(linearize.eigenvalues(model, 5.0))


@pytest.mark.slow
def test_other_contacts_linearize_file_copied_in_is_not_used(cache, benchmark_eigenvalues, monkeypatch):
    want, other = benchmark_eigenvalues["thesis"], benchmark_eigenvalues["disc"]
    assert np.max(np.abs(want - other)) > 0.1
    shutil.copy(_linearize_file(cache, "disc"), _linearize_file(cache, "thesis"))
    got = _eigen(cache, "thesis", monkeypatch)
    # same generated evaluator, same complex-step arithmetic: 1e-10 relative covers the
    # eigenvalue solver's rounding
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10)


@pytest.mark.slow
def test_cut_linearize_file_is_regenerated(cache, benchmark_eigenvalues, monkeypatch):
    path = _linearize_file(cache, "thesis")
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[: len(lines) // 2]))    # issue 14: TypeError on every run
    got = _eigen(cache, "thesis", monkeypatch)
    np.testing.assert_allclose(got, benchmark_eigenvalues["thesis"], rtol=1e-10, atol=1e-10)
    assert path.read_text().count("\n") > len(lines) // 2
    _no_litter(cache)


@pytest.mark.slow
def test_killed_cold_build_leaves_no_litter(tmp_path, fast_cc, monkeypatch):
    """SIGTERM during a cold build (as soon as its temporary exists): the next build removes
    the killed build's temporary (issue 14: left in the cache for good)."""
    slow = tmp_path / "slowcc"     # compiles the probe at once, sleeps on the generated file
    slow.write_text('#!/bin/sh\ncase "$*" in *bicycle_generated.c*) sleep 60;; esac\n'
                    f'exec {fast_cc} "$@"\n')
    slow.chmod(0o755)
    cache = tmp_path / "cache"
    proc = subprocess.Popen([sys.executable, "-c", "from reference_model import codegen; "
                             "codegen.build('thesis')"], env=_env(cache, str(slow)), cwd=ROOT,
                            start_new_session=True, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not (cache.is_dir() and [p for p in cache.iterdir() if p.name.startswith(".")]):
            assert proc.poll() is None, proc.stderr.read().decode()[-2000:]
            assert time.monotonic() < deadline, "the build never reached the compiler"
            time.sleep(0.05)
        time.sleep(0.2)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)   # the compiler wrapper it left sleeping
        except ProcessLookupError:
            pass
    assert [p for p in cache.iterdir() if p.name.startswith(".")], "precondition: litter left"
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(cache))
    monkeypatch.setenv("CC", fast_cc)
    lib = codegen.build("thesis")
    assert lib.built_now and (lib.path / "libbicycle.so").exists()
    _no_litter(cache)


def test_live_builds_temporaries_are_kept(tmp_path):
    """Cleaning never removes the temporary of a build still running (here: this process)."""
    mine = tmp_path / (codegen.temporary_prefix("thesis") + "x")
    mine.mkdir()
    foreign = tmp_path / ".profile"       # not a name the cache writes: never touched
    foreign.write_text("keep")
    os.utime(foreign, (0, 0))
    assert codegen.clean_stale_temporaries(tmp_path) == []
    assert mine.exists() and foreign.exists()


# -- compilers -------------------------------------------------------------------------

@pytest.fixture(scope="module")
def no_compiler_cache(tmp_path_factory, pristine) -> Path:
    """A cache with the numpy code of both contact variants, generated in this process (it
    reuses the derivations of `pristine`); the subprocesses load it."""
    cache = tmp_path_factory.mktemp("nocc")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("BICYCLE_XVAL_CACHE", str(cache))
        for contact in ("thesis", "disc"):
            codegen.build(contact, backend="numpy")
    return cache


@pytest.mark.slow
def test_cut_numpy_code_is_regenerated(no_compiler_cache, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    shutil.copytree(no_compiler_cache, cache)
    (entry,) = cache.glob("thesis-numpy-*")
    code = entry / "bicycle_generated.py"
    text = code.read_text()
    code.write_text(text[: len(text) // 2])
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(cache))
    lib = codegen.build("thesis", backend="numpy")
    assert lib.built_now and code.read_text() == text


@pytest.mark.parametrize("cc, model", [("/nonexistent/bin/cc", "thesis"), ("/bin/false", "thesis"),
                                       ("/bin/true", "thesis"), ("/nonexistent/bin/cc", "thesis-disc")])
@pytest.mark.slow
def test_no_working_compiler_runs_on_numpy(no_compiler_cache, cc, model, reference_thesis,
                                           reference_disc):
    """No compiler, CC at nothing, a compiler that fails, one that writes no library: one
    warning line, the numpy backend, the same numbers as C (both contact variants)."""
    got, stderr = _probe(no_compiler_cache, cc, model)
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "numpy" in lines[0] and "CC" in lines[0] and "slower" in lines[0], stderr
    assert got["backend"] == "numpy"
    # The kernels are the same straight-line code (bit-identical, measured); the KKT solves
    # take other routes (LAPACK vs the C runtime's Cholesky/elimination), so they agree to
    # condition number x eps: 1e-11 relative to the largest entry is well above that (1e-13).
    want = reference_thesis if model == "thesis" else reference_disc
    _assert_same(got, want, 1e-11)
    _no_litter(no_compiler_cache)


@pytest.mark.slow
@pytest.mark.parametrize("spelling", ["sh {cc}", "gcc -O2", "  env  gcc  "])
def test_compiler_command_with_arguments_works(fast_cc, monkeypatch, spelling):
    """CC="ccache gcc" style (issue 14: a traceback): a command with arguments is split like a
    shell would, and compiles (the probe builds and loads a library through the same
    `_run_compiler` call as the real build)."""
    monkeypatch.setenv("CC", spelling.format(cc=fast_cc))
    cmd = codegen.compiler_command()
    assert cmd == tuple(spelling.format(cc=fast_cc).split())
    assert codegen.compiler_problem(cmd) is None


def test_unparsable_cc_is_one_line(monkeypatch):
    monkeypatch.setenv("CC", "gcc 'unterminated")
    with pytest.raises(codegen.CodegenError) as info:
        codegen.compiler_command()
    assert "CC=" in _one_line(info.value) and "fix:" in str(info.value)


def _one_line(exc: BaseException) -> str:
    text = str(exc)
    assert "\n" not in text, text
    return text


@pytest.mark.slow
def test_compiler_failing_midway_is_one_line_naming_cc(tmp_path, fast_cc, monkeypatch):
    broken = tmp_path / "brokencc"     # works on the probe, fails on the generated code
    broken.write_text('#!/bin/sh\ncase "$*" in *bicycle_generated.c*) '
                      'echo "internal compiler error: Segmentation fault" >&2; exit 4;; esac\n'
                      f'exec {fast_cc} "$@"\n')
    broken.chmod(0o755)
    monkeypatch.setenv("CC", str(broken))
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(tmp_path / "cache"))
    with pytest.raises(codegen.CodegenError) as info:
        codegen.build("thesis")
    text = _one_line(info.value)
    assert "(CC)" in text and "fix:" in text and "internal compiler error" in text
    assert not list((tmp_path / "cache").iterdir()), "nothing may be committed"


@pytest.mark.slow
def test_compiler_writing_no_library_commits_nothing(tmp_path, fast_cc, monkeypatch):
    """Issue 14: CC=/bin/true committed an entry without a library; here a compiler that
    passes the probe and then exits 0 without output."""
    liar = tmp_path / "liarcc"
    liar.write_text('#!/bin/sh\ncase "$*" in *bicycle_generated.c*) exit 0;; esac\n'
                    f'exec {fast_cc} "$@"\n')
    liar.chmod(0o755)
    monkeypatch.setenv("CC", str(liar))
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(tmp_path / "cache"))
    with pytest.raises(codegen.CodegenError) as info:
        codegen.build("thesis")
    assert "wrote no library" in _one_line(info.value)
    assert not list((tmp_path / "cache").iterdir())


def test_insisting_on_c_without_compiler_is_one_line(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "/nonexistent/bin/cc")
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(tmp_path))
    with pytest.raises(codegen.CodegenError) as info:
        codegen.build("thesis", backend="c")
    text = _one_line(info.value)
    assert "/nonexistent/bin/cc" in text and "CC" in text and "fix:" in text


def test_unusable_cache_path_names_the_variable(tmp_path, monkeypatch):
    not_a_folder = tmp_path / "file"
    not_a_folder.write_text("")
    monkeypatch.setenv("BICYCLE_XVAL_CACHE", str(not_a_folder / "sub"))
    with pytest.raises(codegen.CodegenError) as info:
        codegen.build("thesis")
    text = _one_line(info.value)
    assert "BICYCLE_XVAL_CACHE" in text and str(not_a_folder) in text


@pytest.mark.slow
def test_concurrent_builds_keep_the_entry_committed_first(cache):
    """Two processes building the same variant: the second to finish keeps the intact entry
    the first committed (a process may be loading it), and replaces only a damaged one."""
    target = _entry(cache, "thesis")
    info = json.loads((target / "manifest.json").read_text())
    identity = {k: info[k] for k in ("variant", "contact", "gyroscopic", "backend", "key")}
    late = cache / (codegen.temporary_prefix("thesis") + "late")
    shutil.copytree(target, late)
    inode = (target / "libbicycle.so").stat().st_ino
    codegen._commit(late, target, identity, codegen.C_FILES)
    assert not late.exists() and (target / "libbicycle.so").stat().st_ino == inode
    shutil.copytree(target, late)
    (target / "libbicycle.so").write_bytes(b"damaged")
    codegen._commit(late, target, identity, codegen.C_FILES)
    assert codegen.verify_entry(target, identity, codegen.C_FILES)[0] is not None
    _no_litter(cache)
