"""Generated C for the derived bicycle: CSE, straight-line code, compilation, on-disk cache.

Why generated C (and not numba or lambdify): the equations are ~10^4 floating-point
operations of straight-line code after common-subexpression elimination. Interpreted
Python needs hundreds of microseconds for that; C compiled with the system's ``gcc`` needs
a few, a C loop over a batch needs no Python per state, and the KKT solve runs in the same
call. gcc is on every machine this project targets (the Python image ships it for packages
that compile); numba would add a large dependency and a JIT warm-up on every cold start.

The cache lives in ``$BICYCLE_XVAL_CACHE`` (default ``$XDG_CACHE_HOME/bicycle-xval`` or
``~/.cache/bicycle-xval``), one folder per key. The key hashes the sources that determine
the code (this file, ``derivation.py``, ``params.py``, ``runtime.c``), the sympy version,
the variant (contact model; the gyroscopic-terms-dropped fault variant, if asked for) and the
compiler command, so any change to them regenerates. Each
folder is written under a temporary name and renamed into place, so concurrent runs never
read a half-written library. Generated files say in their header that they are generated; they are never
committed.
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.precedence import PRECEDENCE

from . import derivation as dv
from .params import PARAMETER_NAMES

PACKAGE_DIR = Path(__file__).resolve().parent
RUNTIME_C = PACKAGE_DIR / "runtime.c"
_KEY_SOURCES = (
    PACKAGE_DIR / "derivation.py",
    PACKAGE_DIR / "codegen.py",
    PACKAGE_DIR / "params.py",
    RUNTIME_C,
)
CC = os.environ.get("CC", "gcc")
CFLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fno-fast-math", "-Wno-unused-variable")
N_Q = len(dv.COORDINATES)


class CodegenError(RuntimeError):
    """Code generation or compilation failed (message says what to fix)."""


@dataclass(frozen=True)
class GeneratedFunction:
    """One generated C function ``void bx_<name>(q, dq, p, out)`` and its output layout."""

    name: str
    size: int                       # number of doubles written to out
    symmetric: int = 0              # if > 0, out is a symmetric (n, n) matrix filled from its upper part


def cache_root() -> Path:
    env = os.environ.get("BICYCLE_XVAL_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "bicycle-xval"


def variant_name(contact: str, gyroscopic: bool = True) -> str:
    """The cache folder's prefix of a variant: the contact model, '-nogyro' for the fault
    variant without gyroscopic terms."""
    return contact if gyroscopic else f"{contact}-nogyro"


def cache_key(contact: str, gyroscopic: bool = True) -> str:
    h = hashlib.sha256()
    for path in _KEY_SOURCES:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    variant = "" if gyroscopic else ";gyroscopic=0"
    h.update(f"sympy={sp.__version__};contact={contact}{variant};cc={CC};flags={' '.join(CFLAGS)};"
             f"machine={platform.machine()}".encode())
    return h.hexdigest()[:20]


# -- C emission ------------------------------------------------------------------------

class _Printer(C99CodePrinter):
    """C99 printer: integer powers as products (exact, and cheaper than pow)."""

    def _print_Pow(self, expr):
        b, e = expr.as_base_exp()
        if e.is_Integer and 1 < abs(int(e)) <= 4:
            base = self.parenthesize(b, PRECEDENCE["Mul"] + 1)
            prod = "*".join([base] * abs(int(e)))
            return f"({prod})" if e > 0 else f"(1.0/({prod}))"
        if e == sp.Rational(1, 2):
            return f"sqrt({self._print(b)})"
        if e == -sp.Rational(1, 2):
            return f"(1.0/sqrt({self._print(b)}))"
        return super()._print_Pow(expr)


_PRINTER = _Printer()


def _c(expr: sp.Expr) -> str:
    return _PRINTER.doprint(sp.sympify(expr))


def _header_lines(sy: dv.Symbols) -> list[str]:
    lines = [f"    const double {s} = q[{i}];" for i, s in enumerate(sy.q)]
    lines += [f"    const double {s} = dq[{i}];" for i, s in enumerate(sy.dq)]
    lines += [f"    const double {s} = p[{i}];" for i, s in enumerate(sy.p)]
    return lines


def _emit_function(der: dv.Derivation, name: str, outputs: list[sp.Expr],
                   symmetric: int = 0) -> tuple[str, GeneratedFunction]:
    """Straight-line C for outputs (placeholders resolved in a first CSE stage)."""
    exprs = [sp.sympify(e) for e in outputs]
    if symmetric:
        n = symmetric
        idx = [(r, c) for r in range(n) for c in range(r, n)]
        flat = [exprs[r * n + c] for r, c in idx]
    else:
        flat = exprs
    used = set()
    for e in flat:
        used |= {s for s in e.free_symbols if s in der.placeholders}
    ph = sorted(used, key=lambda s: s.name)
    body = _header_lines(der.symbols)
    # stage 1: kinematic placeholders in terms of q, dq, p
    if ph:
        reps, red = sp.cse([der.placeholders[s] for s in ph],
                           symbols=sp.numbered_symbols("k"), order="none")
        body += [f"    const double {s} = {_c(e)};" for s, e in reps]
        body += [f"    const double {s} = {_c(e)};" for s, e in zip(ph, red)]
    # stage 2: outputs in terms of placeholders
    reps, red = sp.cse(flat, symbols=sp.numbered_symbols("t"), order="none")
    body += [f"    const double {s} = {_c(e)};" for s, e in reps]
    if symmetric:
        n = symmetric
        for (r, c), e in zip(idx, red):
            body.append(f"    out[{r * n + c}] = {_c(e)};")
            if r != c:
                body.append(f"    out[{c * n + r}] = out[{r * n + c}];")
    else:
        body += [f"    out[{k}] = {_c(e)};" for k, e in enumerate(red)]
    size = len(exprs)
    src = (f"static void bx_{name}(const double *q, const double *dq, const double *p, double *out)\n"
           "{\n" + "\n".join(body) + "\n}\n\n"
           f"void bx_{name}_batch(long n, const double *q, const double *dq, const double *p,"
           f" double *out)\n{{\n    for (long i = 0; i < n; ++i)\n"
           f"        bx_{name}(q + {N_Q} * i, dq + {N_Q} * i, p, out + {size} * i);\n}}\n\n")
    return src, GeneratedFunction(name, size, symmetric)


def _flat(M: sp.Matrix) -> list[sp.Expr]:
    return list(M)  # row-major


def generate_source(der: dv.Derivation) -> tuple[str, dict[str, GeneratedFunction]]:
    """All generated C functions of one variant, plus the runtime (KKT solves)."""
    pts = der.points
    specs: list[tuple[str, list[sp.Expr], int]] = [
        ("mass_matrix", _flat(der.M), N_Q),
        ("qv", _flat(der.Qv), 0),
        ("qgrav", _flat(der.Qgrav), 0),
        ("qaero", _flat(der.Qaero), 0),
        ("smat", _flat(der.S), 0),
        ("constraint_residual", _flat(der.C), 0),
        ("constraint_jacobian", _flat(der.D), 0),
        ("constraint_bias", _flat(der.bias), 0),
        ("energy", [der.kinetic, der.potential], 0),
        ("points", sum((_flat(pts[k]) for k in POINT_NAMES), []), 0),
        # combined kernels used by the runtime: one pass shares all subexpressions
        ("dynamics", _flat(der.M) + _flat(der.Qv + der.Qgrav + der.Qaero) + _flat(der.S), 0),
        ("constraints", _flat(der.C) + _flat(der.D) + _flat(der.bias), 0),
        ("mass_bias", _flat(der.M) + _flat(der.Qv + der.Qgrav), 0),   # unconstrained inverse dynamics
    ]
    parts = [
        "/* Generated by reference_model/codegen.py from reference_model/derivation.py.\n"
        f" * Contact model: {der.contact}"
        f"{'' if der.gyroscopic else '; gyroscopic terms dropped (fault variant)'}. Never hand-edited: rewritten whenever its sources change. */\n"
        "#include <math.h>\n\n"
    ]
    funcs = {}
    for name, exprs, sym in specs:
        src, fn = _emit_function(der, name, exprs, symmetric=sym)
        parts.append(src)
        funcs[name] = fn
    parts.append('#include "runtime.c"\n')
    return "".join(parts), funcs


POINT_NAMES = ("rC", "rA", "rG2", "rG3", "rG4", "rG5", "rD")


# -- build and cache -------------------------------------------------------------------

@dataclass(frozen=True)
class Library:
    """A loaded compiled variant: the ctypes handle and its function table."""

    contact: str
    path: Path
    lib: ctypes.CDLL
    functions: dict[str, GeneratedFunction]
    key: str
    built_now: bool
    build_seconds: float
    gyroscopic: bool = True


def _compile(c_file: Path, so_file: Path) -> None:
    if shutil.which(CC) is None:
        raise CodegenError(f"C compiler {CC!r} not found: install gcc (Debian: apt-get install gcc) "
                           "or set CC to a C99 compiler")
    cmd = [CC, *CFLAGS, f"-I{PACKAGE_DIR}", "-o", str(so_file), str(c_file), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise CodegenError(f"compiling {c_file} failed:\n{res.stderr[-2000:]}")


def build(contact: str, *, gyroscopic: bool = True, force: bool = False, log=None) -> Library:
    """Load the compiled library of a variant, generating and compiling it if needed.

    ``gyroscopic=False`` is the fault variant without gyroscopic terms in Qv (see
    `derivation.derive`)."""
    key = cache_key(contact, gyroscopic)
    root = cache_root()
    variant = variant_name(contact, gyroscopic)
    target = root / f"{variant}-{key}"
    manifest = target / "manifest.json"
    t0 = time.perf_counter()
    built = False
    if force or not manifest.exists():
        if log:
            log(f"generating code for variant {variant!r} (once per machine, a few seconds)...")
        root.mkdir(parents=True, exist_ok=True)
        der = dv.derive(contact, gyroscopic=gyroscopic)
        src, funcs = generate_source(der)
        tmp = Path(tempfile.mkdtemp(prefix=f".{variant}-", dir=root))
        try:
            c_file = tmp / "bicycle_generated.c"
            c_file.write_text(src)
            _compile(c_file, tmp / "libbicycle.so")
            (tmp / "manifest.json").write_text(json.dumps({
                "contact": contact, "gyroscopic": bool(gyroscopic), "key": key, "sympy": sp.__version__,
                "python": sys.version.split()[0], "cc": CC, "cflags": list(CFLAGS),
                "parameters": list(PARAMETER_NAMES),
                "functions": {k: [v.size, v.symmetric] for k, v in funcs.items()},
            }, indent=1))
            if target.exists():
                shutil.rmtree(target, ignore_errors=True)
            try:
                os.replace(tmp, target)
            except OSError:  # another process won the race: use its copy
                shutil.rmtree(tmp, ignore_errors=True)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)
        built = True
    try:
        info = json.loads(manifest.read_text())
        funcs = {k: GeneratedFunction(k, v[0], v[1]) for k, v in info["functions"].items()}
        lib = ctypes.CDLL(str(target / "libbicycle.so"))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        if built:
            raise CodegenError(f"the freshly built library in {target} does not load: {exc}") from exc
        if log:
            log(f"cached code in {target} is damaged ({exc}); regenerating")
        shutil.rmtree(target, ignore_errors=True)
        return build(contact, gyroscopic=gyroscopic, force=True, log=log)
    return Library(contact, target, lib, funcs, key, built, time.perf_counter() - t0,
                   bool(gyroscopic))
