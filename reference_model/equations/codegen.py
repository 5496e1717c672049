"""Generated code for the derived bicycle: CSE, straight-line code, compilation, on-disk cache.

Why generated C (and not numba or lambdify): the equations are ~10^4 floating-point
operations of straight-line code after common-subexpression elimination. Interpreted
Python needs hundreds of microseconds for that; C compiled with the system's ``gcc`` needs
a few, a C loop over a batch needs no Python per state, and the KKT solve runs in the same
call. numba would add a large dependency and a JIT warm-up on every cold start.

**Backends.** The same common-subexpression code is printed twice: as C (the fast backend,
compiled with ``$CC``, default ``gcc``; ``CC`` may carry arguments, ``CC="ccache gcc"``) and
as numpy vectorized over the batch (``numpy_runtime`` holds its KKT solves). When no working C
compiler is found (none installed, ``CC`` pointing at nothing, a command that produces no
library), the numpy code is generated and used instead, with one warning line on stderr.
``BICYCLE_XVAL_BACKEND=c`` insists on C (an error if there is no compiler),
``BICYCLE_XVAL_BACKEND=numpy`` asks for numpy. A compiler that works on a test file but fails
on the generated one is an error naming ``CC``.

**Cache.** ``$BICYCLE_XVAL_CACHE`` (default ``$XDG_CACHE_HOME/bicycle-xval`` or
``~/.cache/bicycle-xval``), one folder per key. The key hashes the sources the generated code
depends on (:data:`KEY_SOURCES`: the derivation and its names, the parameter layout,
``runtime.c``, this file and ``emit``, the printing), the coordinate and parameter layouts, the sympy version, the variant (contact model;
the gyroscopic-terms-dropped fault variant), the backend and, for C, the compiler command
and flags. Each folder is written under a temporary name (``.tmp-<variant>-<host>-<pid>-*``)
and renamed into place, so concurrent runs never read a half-written library; temporaries
left by a killed process are removed by the next build.

**Integrity.** Every entry carries ``manifest.json``: its variant, backend and key, and the
size and SHA-256 of each of its files. An entry is verified before anything in it is loaded
(once per variant per process: `model.Model` keeps the loaded library); an entry whose
manifest, variant, sizes or hashes differ is removed and rebuilt, so a truncated or
overwritten library is never mapped (which would end the process with SIGBUS or SIGILL) and
another variant's library is never used. Generated files say in their header that they are
generated; they are never committed.

**sympy only when generating.** The printers and the CSE live in ``emit``, imported
(with sympy and the derivation) only when an entry is generated: a process that loads cached
code never imports sympy (0.3-0.5 s saved in every CLI command, test worker and subprocess).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import json
import os
import platform
import re
import shlex
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from ..names import COORDINATES
from ..parameters.schema import PARAMETER_NAMES

if TYPE_CHECKING:   # sympy is imported only when code is generated (module doc)
    from . import derivation as dv

__all__ = [
    "BACKENDS", "BACKEND_ENV", "CACHE_ENV", "CFLAGS", "C_FILES", "CodegenError", "DEFAULT_CC",
    "GeneratedFunction", "KEY_SOURCES", "Library", "MANIFEST", "MANIFEST_FORMAT", "NUMPY_FILES",
    "NUMPY_SLOWDOWN", "N_Q", "PACKAGE_DIR", "RUNTIME_C", "RUNTIME_DIR", "STALE_SECONDS",
    "TEMP_PREFIX", "build", "cache_key", "cache_root", "clean_stale_temporaries",
    "compiler_command", "compiler_problem", "derivation", "requested_backend", "sympy_version",
    "temporary_prefix", "variant_name", "verify_entry", "write_manifest",
]

#: The package folder (``reference_model/``), which :data:`KEY_SOURCES` are relative to.
PACKAGE_DIR = Path(__file__).resolve().parents[1]
#: This folder: ``runtime.c`` is here, and the generated C #includes it from here.
RUNTIME_DIR = Path(__file__).resolve().parent
RUNTIME_C = RUNTIME_DIR / "runtime.c"
#: Files of the package the generated code depends on (relative to the package folder):
#: the derivation (the equations) and names.py (its coordinate and point names),
#: parameters/schema.py (the parameter layout p[i], the contact models), runtime.c (the KKT
#: solves, #included), codegen.py and emit.py (how code is printed), numpy_runtime.py (the
#: numpy backend's solves). Editing any of them changes the cache key.
KEY_SOURCES = ("equations/derivation.py", "names.py", "parameters/schema.py",
               "equations/runtime.c", "equations/codegen.py", "equations/emit.py",
               "equations/numpy_runtime.py")
CACHE_ENV = "BICYCLE_XVAL_CACHE"
BACKEND_ENV = "BICYCLE_XVAL_BACKEND"
BACKENDS = ("c", "numpy")
DEFAULT_CC = "gcc"
CFLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fno-fast-math", "-Wno-unused-variable")
N_Q = len(COORDINATES)
MANIFEST = "manifest.json"
MANIFEST_FORMAT = 2
C_FILES = ("bicycle_generated.c", "libbicycle.so")
NUMPY_FILES = ("bicycle_generated.py",)
TEMP_PREFIX = ".tmp-"
#: A temporary whose owner cannot be identified (another host, an older naming) is removed
#: once it is this old (s): no build takes an hour.
STALE_SECONDS = 3600.0
# temporaries of the naming used before the owner's pid was part of the name
_LEGACY_TEMP = re.compile(r"^\.((thesis|disc)(-nogyro)?-[a-z0-9_]{8}|linearize-.*\.py)$")
#: Measured on the development machine (x86-64, 2 shared cores, gcc -O2 vs numpy): one state
#: through forward_acceleration 10 us (C) vs 3.6 ms (numpy); 1000 mass matrices 0.40 ms vs
#: 2.4 ms; 1000 forward accelerations 3.2 ms vs 18 ms; 0.5 s of stability-psid5 0.12 s vs 9.0 s.
NUMPY_SLOWDOWN = "forward runs about 75x slower than C, batched evaluations about 6x"


@functools.lru_cache(maxsize=None)
def sympy_version() -> str:
    """sympy's version, from its installed metadata (importing sympy costs 0.3-0.5 s, which
    every process that only loads cached code would pay)."""
    from importlib.metadata import version
    return version("sympy")


class CodegenError(RuntimeError):
    """Code generation, compilation or the code cache failed (one-line message with the fix)."""


@dataclass(frozen=True)
class GeneratedFunction:
    """One generated function ``bx_<name>(q, dq, p, out)`` and its output layout."""

    name: str
    size: int                       # number of doubles written to out
    symmetric: int = 0              # if > 0, out is a symmetric (n, n) matrix filled from its upper part


def cache_root() -> Path:
    """The cache folder: ``$BICYCLE_XVAL_CACHE``, else ``$XDG_CACHE_HOME/bicycle-xval``, else
    ``~/.cache/bicycle-xval``."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "bicycle-xval"


def _cache_problem(root: Path, exc: OSError) -> CodegenError:
    return CodegenError(
        f"the code cache {root} cannot be used ({exc.strerror or exc}); fix: set {CACHE_ENV} to "
        "a writable folder (it holds the generated code, a few MB)")


def variant_name(contact: str, gyroscopic: bool = True) -> str:
    """The cache folder's prefix of a variant: the contact model, '-nogyro' for the fault
    variant without gyroscopic terms."""
    return contact if gyroscopic else f"{contact}-nogyro"


def compiler_command() -> tuple[str, ...]:
    """``$CC`` split like a shell would (``CC="ccache gcc"``), default ``gcc``."""
    text = os.environ.get("CC", "").strip() or DEFAULT_CC
    try:
        cmd = tuple(shlex.split(text))
    except ValueError as exc:
        raise CodegenError(f"CC={text!r} is not a valid command line ({exc}); fix: set CC to a C "
                           "compiler command, e.g. CC=gcc or CC='ccache gcc'") from None
    return cmd or (DEFAULT_CC,)


def requested_backend(backend: str | None = None) -> str:
    """'c', 'numpy' or 'auto' (C if a compiler works, else numpy): the argument, else
    ``$BICYCLE_XVAL_BACKEND``, else 'auto'."""
    value = backend if backend is not None else os.environ.get(BACKEND_ENV, "").strip().lower()
    value = value or "auto"
    if value not in (*BACKENDS, "auto"):
        raise CodegenError(f"{BACKEND_ENV}={value!r} is not a backend; fix: use one of c, numpy, "
                           "auto (or leave it unset)")
    return value


def cache_key(contact: str, gyroscopic: bool = True, *, backend: str = "c",
              cc: tuple[str, ...] | None = None, package_dir: Path = PACKAGE_DIR) -> str:
    """Hash of everything the generated code of a variant depends on (see the module doc).

    ``package_dir`` is where the :data:`KEY_SOURCES` are read (tests pass an edited copy)."""
    h = hashlib.sha256()
    for name in KEY_SOURCES:
        h.update(name.encode())
        h.update((Path(package_dir) / name).read_bytes())
    variant = "" if gyroscopic else ";gyroscopic=0"
    h.update(f"sympy={sympy_version()};contact={contact}{variant};backend={backend};"
             f"coordinates={','.join(COORDINATES)};parameters={','.join(PARAMETER_NAMES)};"
             f"machine={platform.machine()}".encode())
    if backend == "c":
        cc = compiler_command() if cc is None else cc
        h.update(f";cc={shlex.join(cc)};flags={' '.join(CFLAGS)}".encode())
    return h.hexdigest()[:20]


# -- compiler --------------------------------------------------------------------------

_FIX_CC = ("fix: install gcc (Debian: apt-get install gcc), set CC to a working C99 compiler "
           f"(CC may carry arguments: CC='ccache gcc'), or set {BACKEND_ENV}=numpy")


def _last_line(text: str) -> str:
    lines = [line.strip() for line in (text or "").splitlines() if line.strip()]
    return lines[-1][:200] if lines else "no message"


def _run_compiler(cc: tuple[str, ...], c_file: Path, so_file: Path) -> str | None:
    """Compile c_file into so_file; None on success, else what went wrong (one line)."""
    cmd = [*cc, *CFLAGS, f"-I{RUNTIME_DIR}", "-o", str(so_file), str(c_file), "-lm"]
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
    except FileNotFoundError:
        return f"{cc[0]!r} not found"
    except OSError as exc:
        return f"{cc[0]!r} cannot be run ({exc.strerror or exc})"
    if res.returncode != 0:
        return f"exit status {res.returncode}: {_last_line(res.stderr)}"
    try:
        if so_file.stat().st_size == 0:
            return "it exited 0 but wrote an empty library"
    except FileNotFoundError:
        return "it exited 0 but wrote no library"
    return None


@functools.lru_cache(maxsize=None)
def compiler_problem(cc: tuple[str, ...]) -> str | None:
    """None if ``cc`` compiles and links a small shared library that loads, else why not
    (checked once per process per command)."""
    if shutil.which(cc[0]) is None:
        return f"C compiler {shlex.join(cc)!r} (CC) not found"
    with tempfile.TemporaryDirectory(prefix="bicycle-xval-cc-") as tmp:
        c_file, so_file = Path(tmp) / "probe.c", Path(tmp) / "probe.so"
        c_file.write_text("#include <math.h>\ndouble bx_probe(double x) { return sqrt(x); }\n")
        problem = _run_compiler(cc, c_file, so_file)
        if problem is None:
            try:
                lib = ctypes.CDLL(str(so_file))
                lib.bx_probe.restype = ctypes.c_double
                lib.bx_probe.argtypes = [ctypes.c_double]
                if lib.bx_probe(4.0) != 2.0:
                    problem = "its test library computes sqrt(4) != 2"
            except (OSError, AttributeError) as exc:
                problem = f"its test library does not load ({exc})"
    return None if problem is None else f"C compiler {shlex.join(cc)!r} (CC) does not work: {problem}"


@functools.lru_cache(maxsize=None)
def _warn_once(message: str) -> None:
    sys.stderr.write(f"bicycle-xval: warning: {message}\n")
    sys.stderr.flush()


# -- cache entries: manifest, verification, temporaries --------------------------------

def _file_record(path: Path) -> dict[str, Any]:
    data = path.read_bytes()
    return {"size": len(data), "sha256": hashlib.sha256(data).hexdigest()}


def write_manifest(folder: Path, identity: dict[str, Any], files: tuple[str, ...],
                   extra: dict[str, Any] | None = None) -> None:
    """``manifest.json`` of an entry: its identity (variant, backend, key...) and the size and
    SHA-256 of each file."""
    info = {"format": MANIFEST_FORMAT, **identity, **(extra or {}),
            "files": {name: _file_record(folder / name) for name in files}}
    (folder / MANIFEST).write_text(json.dumps(info, indent=1), encoding="utf-8")


def verify_entry(folder: Path, identity: dict[str, Any], files: tuple[str, ...]) -> tuple[dict | None, str]:
    """(manifest, "") if the entry is complete and intact, else (None, what differs)."""
    try:
        info = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None, "no manifest"
    except (OSError, ValueError) as exc:
        return None, f"unreadable manifest ({exc})"
    if not isinstance(info, dict) or info.get("format") != MANIFEST_FORMAT:
        return None, "manifest of another format"
    for k, v in identity.items():
        if info.get(k) != v:
            return None, f"manifest says {k} = {info.get(k)!r}, expected {v!r}"
    records = info.get("files")
    if not isinstance(records, dict) or set(records) != set(files):
        return None, "manifest lists other files"
    for name in files:
        rec = records[name]
        try:
            if not isinstance(rec, dict) or (folder / name).stat().st_size != rec.get("size"):
                return None, f"{name}: size differs from the manifest"
            if _file_record(folder / name)["sha256"] != rec.get("sha256"):
                return None, f"{name}: content differs from the manifest (SHA-256)"
        except OSError as exc:
            return None, f"{name}: {exc.strerror or exc}"
    return info, ""


def temporary_prefix(stem: str) -> str:
    """Prefix of a temporary in the cache: names its host and process, so a later build can
    tell a temporary of a live build from one left by a killed process."""
    host = re.sub(r"[^A-Za-z0-9_.]", "_", socket.gethostname())[:40] or "host"
    return f"{TEMP_PREFIX}{stem}-{host}-{os.getpid()}-"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:          # exists, owned by someone else
        return True
    return True


def _is_stale(path: Path, now: float) -> bool:
    name = path.name
    try:
        age = now - path.lstat().st_mtime
    except OSError:
        return False
    if name.startswith(TEMP_PREFIX):
        host = re.sub(r"[^A-Za-z0-9_.]", "_", socket.gethostname())[:40] or "host"
        m = re.match(rf"^{re.escape(TEMP_PREFIX)}.*-{re.escape(host)}-(\d+)-", name)
        if m and int(m.group(1)) != os.getpid():
            # gone, or so old that the pid must have been reused
            return not _pid_alive(int(m.group(1))) or age > 24 * STALE_SECONDS
        return age > STALE_SECONDS and not m
    return bool(_LEGACY_TEMP.match(name)) and age > STALE_SECONDS


def clean_stale_temporaries(root: Path) -> list[Path]:
    """Remove temporaries in the cache left by killed builds (their process is gone, or they
    are older than an hour and of unknown owner). Only names this module creates are
    touched. Returns what was removed."""
    removed = []
    now = time.time()
    try:
        entries = list(root.iterdir())
    except OSError:
        return removed
    for path in entries:
        if _is_stale(path, now):
            try:
                _remove(path)
            except OSError:      # a read-only cache: leave it
                continue
            removed.append(path)
    return removed


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    elif path.exists() or path.is_symlink():
        path.unlink(missing_ok=True)


def _commit(tmp: Path, target: Path, identity: dict[str, Any], files: tuple[str, ...]) -> None:
    """Rename a complete temporary entry into place. An intact entry already there (another
    process built it meanwhile) is kept; a damaged one is first renamed out of the way (an
    atomic step: no process ever sees it half deleted), then removed."""
    if target.exists() or target.is_symlink():
        if verify_entry(target, identity, files)[0] is not None:
            shutil.rmtree(tmp, ignore_errors=True)
            return
        trash = Path(tempfile.mkdtemp(prefix=temporary_prefix("trash"), dir=target.parent))
        try:
            os.replace(target, trash / "entry")
        except OSError:
            pass
        _remove(trash)
    try:
        os.replace(tmp, target)
    except OSError:  # another process won the race: its copy is verified when loaded
        shutil.rmtree(tmp, ignore_errors=True)


# -- build and load --------------------------------------------------------------------

@dataclass(frozen=True)
class Library:
    """A loaded variant: the ctypes handle (C) or the namespace of numpy functions."""

    contact: str
    path: Path
    lib: Any                        # ctypes.CDLL (backend 'c') or None
    functions: dict[str, GeneratedFunction]
    key: str
    built_now: bool
    build_seconds: float
    gyroscopic: bool = True
    backend: str = "c"
    kernels: dict[str, Callable] = field(default_factory=dict)   # numpy backend: name -> function


def _identity(contact: str, gyroscopic: bool, backend: str, key: str) -> dict[str, Any]:
    return {"variant": variant_name(contact, gyroscopic), "contact": contact,
            "gyroscopic": bool(gyroscopic), "backend": backend, "key": key}


def _functions(info: dict) -> dict[str, GeneratedFunction]:
    return {k: GeneratedFunction(k, int(v[0]), int(v[1])) for k, v in info["functions"].items()}


def _load_c(target: Path, info: dict) -> tuple[Any, dict[str, GeneratedFunction]]:
    funcs = _functions(info)
    lib = ctypes.CDLL(str(target / "libbicycle.so"))
    for name in [f"bx_{k}_batch" for k in funcs] + ["bx_forward_batch", "bx_inverse_dynamics_batch"]:
        getattr(lib, name)      # AttributeError if the library lacks it
    return lib, funcs


def _load_numpy(target: Path, info: dict) -> tuple[dict[str, Callable], dict[str, GeneratedFunction]]:
    from . import numpy_runtime

    funcs = _functions(info)
    path = target / NUMPY_FILES[0]
    namespace: dict[str, Any] = {}
    exec(compile(path.read_text(encoding="utf-8"), str(path), "exec"), namespace)
    kernels = {k: namespace[k] for k in funcs}
    kernels.update(numpy_runtime.solvers(kernels))
    return kernels, funcs


@functools.lru_cache(maxsize=None)
def derivation(contact: str, gyroscopic: bool = True) -> dv.Derivation:
    """The symbolic derivation of a variant, once per process (a few seconds)."""
    from . import derivation as dv
    return dv.derive(contact, gyroscopic=gyroscopic)


@functools.lru_cache(maxsize=None)
def _source(contact: str, gyroscopic: bool, language: str) -> tuple[str, dict[str, GeneratedFunction]]:
    """The generated source of a variant, once per process (CSE and printing: ~2 s)."""
    from .emit import generate_source
    source, layout = generate_source(derivation(contact, gyroscopic), language)
    return source, {name: GeneratedFunction(name, size, symmetric)
                    for name, (size, symmetric) in layout.items()}


def _intact_source(target: Path, identity: dict[str, Any]) -> tuple[str, dict] | None:
    """The generated C of a damaged C entry, if the manifest is this variant's and the source
    still matches its hash (then only the library has to be compiled again)."""
    try:
        info = json.loads((target / MANIFEST).read_text(encoding="utf-8"))
        if not isinstance(info, dict) or info.get("format") != MANIFEST_FORMAT or \
                any(info.get(k) != v for k, v in identity.items()):
            return None
        data = (target / C_FILES[0]).read_bytes()
        rec = info["files"][C_FILES[0]]
        if len(data) != rec["size"] or hashlib.sha256(data).hexdigest() != rec["sha256"]:
            return None
        funcs = {k: GeneratedFunction(k, int(v[0]), int(v[1])) for k, v in info["functions"].items()}
        return data.decode("utf-8"), funcs
    except (OSError, ValueError, KeyError, TypeError, IndexError, UnicodeDecodeError):
        return None


def _generate_entry(root: Path, contact: str, gyroscopic: bool, backend: str, key: str,
                    cc: tuple[str, ...] | None, log, source: tuple[str, dict] | None = None) -> None:
    """Generate (and compile) a variant into a temporary folder, then rename it into place.
    Nothing is committed unless every file is there. ``source``: an intact generated C source
    and its function table (from a damaged entry), compiled without deriving again."""
    variant = variant_name(contact, gyroscopic)
    if log:
        log(f"generating {backend} code for variant {variant!r} (once per machine, seconds)...")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(variant), dir=root))
    except OSError as exc:
        raise _cache_problem(root, exc) from None
    try:
        if source is not None and backend == "c":
            src, funcs = source
        else:
            src, funcs = _source(contact, bool(gyroscopic), backend)
        if backend == "c":
            c_file = tmp / C_FILES[0]
            c_file.write_text(src, encoding="utf-8")
            problem = _run_compiler(cc, c_file, tmp / C_FILES[1])
            if problem:
                raise CodegenError(
                    f"C compiler {shlex.join(cc)!r} (CC) failed on the generated code {c_file.name}: "
                    f"{problem}; {_FIX_CC}")
            files = C_FILES
        else:
            (tmp / NUMPY_FILES[0]).write_text(src, encoding="utf-8")
            files = NUMPY_FILES
        extra = {"sympy": sympy_version(), "python": sys.version.split()[0],
                 "parameters": list(PARAMETER_NAMES),
                 "functions": {k: [v.size, v.symmetric] for k, v in funcs.items()}}
        if backend == "c":
            extra.update(cc=list(cc), cflags=list(CFLAGS))
        identity = _identity(contact, gyroscopic, backend, key)
        write_manifest(tmp, identity, files, extra)
        _commit(tmp, root / f"{variant}-{'' if backend == 'c' else 'numpy-'}{key}", identity, files)
    except OSError as exc:
        raise _cache_problem(root, exc) from None
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _entry(root: Path, contact: str, gyroscopic: bool, backend: str, key: str,
           cc: tuple[str, ...] | None, force: bool, log, t0: float) -> Library:
    """Verify (or build) and load one entry; a damaged entry is rebuilt once."""
    variant = variant_name(contact, gyroscopic)
    target = root / f"{variant}-{'' if backend == 'c' else 'numpy-'}{key}"
    identity = _identity(contact, gyroscopic, backend, key)
    files = C_FILES if backend == "c" else NUMPY_FILES
    built = False
    for _attempt in range(3):   # load; or build and load; or (damaged) rebuild and load
        info, problem = (None, "rebuild asked for") if force and not built else \
            verify_entry(target, identity, files)
        if info is None:
            if built:
                raise CodegenError(f"the freshly built code in {target} does not verify ({problem}); "
                                   f"fix: check the disk, or set {CACHE_ENV} to another folder")
            if log and problem != "no manifest" and target.exists():
                log(f"cached code in {target} is damaged ({problem}); regenerating")
            source = _intact_source(target, identity) if backend == "c" and not force else None
            _generate_entry(root, contact, gyroscopic, backend, key, cc, log, source)
            built = True
            continue
        try:
            if backend == "c":
                lib, funcs = _load_c(target, info)
                kernels = {}
            else:
                lib = None
                kernels, funcs = _load_numpy(target, info)
        except (OSError, ValueError, KeyError, TypeError, AttributeError, SyntaxError,
                NameError) as exc:
            if built:
                raise CodegenError(f"the freshly built code in {target} does not load "
                                   f"({_last_line(str(exc))}); fix: set {CACHE_ENV} to another "
                                   "folder (not on a filesystem mounted noexec)") from None
            try:
                _remove(target)
            except OSError:
                pass
            force = True
            continue
        return Library(contact, target, lib, funcs, key, built, time.perf_counter() - t0,
                       bool(gyroscopic), backend, kernels)
    raise CodegenError(f"cached code in {target} could not be rebuilt; fix: remove it, or set "
                       f"{CACHE_ENV} to another folder")


def build(contact: str, *, gyroscopic: bool = True, force: bool = False, log=None,
          backend: str | None = None) -> Library:
    """Load the generated code of a variant, generating (and compiling) it if needed.

    ``gyroscopic=False`` is the fault variant without gyroscopic terms in Qv (see
    `derivation.derive`). ``backend``: 'c', 'numpy' or 'auto' (default: ``$BICYCLE_XVAL_BACKEND``,
    else auto: C when a C compiler works, numpy with one warning line otherwise)."""
    t0 = time.perf_counter()
    choice = requested_backend(backend)
    root = cache_root()
    try:      # (a read-only cache is fine as long as nothing has to be written to it)
        root.mkdir(parents=True, exist_ok=True)
        if not root.is_dir():
            raise NotADirectoryError(20, "not a folder")
    except OSError as exc:
        raise _cache_problem(root, exc) from None
    clean_stale_temporaries(root)
    if choice in ("c", "auto"):
        cc = compiler_command()
        key = cache_key(contact, gyroscopic, backend="c", cc=cc)
        target = root / f"{variant_name(contact, gyroscopic)}-{key}"
        if force or verify_entry(target, _identity(contact, gyroscopic, "c", key), C_FILES)[0] is None:
            problem = compiler_problem(cc)
            if problem is not None:
                if choice == "c":
                    raise CodegenError(f"{problem}; {_FIX_CC}")
                _warn_once(f"{problem}; using the numpy backend instead ({NUMPY_SLOWDOWN}); "
                           "install gcc or set CC for the fast C backend")
                choice = "numpy"
        if choice != "numpy":
            return _entry(root, contact, gyroscopic, "c", key, cc, force, log, t0)
    key = cache_key(contact, gyroscopic, backend="numpy")
    return _entry(root, contact, gyroscopic, "numpy", key, None, force, log, t0)
