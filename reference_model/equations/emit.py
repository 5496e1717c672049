"""Printing the derivation as code: the C and numpy printers, the two-stage common
subexpression elimination and the straight-line functions of every variant.

Only `codegen` imports this module, and only when it generates code: it is the part of code
generation that needs sympy, so a process that loads cached code never imports sympy.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import PRECEDENCE

from . import derivation as dv
from ..names import COORDINATES, POINT_NAMES

__all__ = [
    "LANGUAGES", "N_Q", "generate_source",
]

N_Q = len(COORDINATES)
LANGUAGES = ("c", "numpy")

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


class _NumpyPrinter(NumPyPrinter):
    """numpy printer with the C printer's products for small integer powers (the same
    operations, so both backends round alike)."""

    def _print_Pow(self, expr, rational=False):
        b, e = expr.as_base_exp()
        if e.is_Integer and 1 < abs(int(e)) <= 4:
            base = self.parenthesize(b, PRECEDENCE["Mul"] + 1)
            prod = "*".join([base] * abs(int(e)))
            return f"({prod})" if e > 0 else f"(1.0/({prod}))"
        return super()._print_Pow(expr, rational=rational)


_C_PRINTER = _Printer()
_NP_PRINTER = _NumpyPrinter({"fully_qualified_modules": True})


def _c(expr: sp.Expr) -> str:
    return _C_PRINTER.doprint(sp.sympify(expr))


def _np(expr: sp.Expr) -> str:
    return _NP_PRINTER.doprint(sp.sympify(expr))


@dataclass(frozen=True)
class _Straight:
    """One function as straight-line code: assignments (symbol, expression) then outputs
    (index, expression or the index whose value it copies)."""

    name: str
    size: int
    symmetric: int
    assignments: list = field(default_factory=list)
    outputs: list = field(default_factory=list)      # (k, expr) or (k, int: copy of out[int])


def _straight_line(der: dv.Derivation, name: str, outputs: list[sp.Expr],
                   symmetric: int = 0) -> _Straight:
    """CSE of outputs (placeholders resolved in a first CSE stage), shared by both printers."""
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
    assignments: list = []
    if ph:   # stage 1: kinematic placeholders in terms of q, dq, p
        reps, red = sp.cse([der.placeholders[s] for s in ph],
                           symbols=sp.numbered_symbols("k"), order="none")
        assignments += list(reps) + list(zip(ph, red))
    reps, red = sp.cse(flat, symbols=sp.numbered_symbols("t"), order="none")   # stage 2
    assignments += list(reps)
    outs: list = []
    if symmetric:
        n = symmetric
        for (r, c), e in zip(idx, red):
            outs.append((r * n + c, e))
            if r != c:
                outs.append((c * n + r, r * n + c))
    else:
        outs = list(enumerate(red))
    return _Straight(name, len(exprs), symmetric, assignments, outs)


def _c_function(der: dv.Derivation, fn: _Straight) -> str:
    sy = der.symbols
    body = [f"    const double {s} = q[{i}];" for i, s in enumerate(sy.q)]
    body += [f"    const double {s} = dq[{i}];" for i, s in enumerate(sy.dq)]
    body += [f"    const double {s} = p[{i}];" for i, s in enumerate(sy.p)]
    body += [f"    const double {s} = {_c(e)};" for s, e in fn.assignments]
    for k, e in fn.outputs:
        body.append(f"    out[{k}] = out[{e}];" if isinstance(e, int) else f"    out[{k}] = {_c(e)};")
    return (f"static void bx_{fn.name}(const double *q, const double *dq, const double *p, double *out)\n"
            "{\n" + "\n".join(body) + "\n}\n\n"
            f"void bx_{fn.name}_batch(long n, const double *q, const double *dq, const double *p,"
            f" double *out)\n{{\n    for (long i = 0; i < n; ++i)\n"
            f"        bx_{fn.name}(q + {N_Q} * i, dq + {N_Q} * i, p, out + {fn.size} * i);\n}}\n\n")


def _numpy_function(der: dv.Derivation, fn: _Straight) -> str:
    """``def <name>(q, dq, p)``: q, dq (n, 8), p (30,) -> out (n, size), vectorized over n."""
    sy = der.symbols
    body = [f"    {s} = q[:, {i}]" for i, s in enumerate(sy.q)]
    body += [f"    {s} = dq[:, {i}]" for i, s in enumerate(sy.dq)]
    body += [f"    {s} = p[{i}]" for i, s in enumerate(sy.p)]
    body += [f"    {s} = {_np(e)}" for s, e in fn.assignments]
    body.append(f"    out = numpy.empty((q.shape[0], {fn.size}))")
    for k, e in fn.outputs:
        body.append(f"    out[:, {k}] = out[:, {e}]" if isinstance(e, int) else f"    out[:, {k}] = {_np(e)}")
    body.append("    return out")
    return f"def {fn.name}(q, dq, p):\n" + "\n".join(body) + "\n\n\n"


def _flat(M: sp.Matrix) -> list[sp.Expr]:
    return list(M)  # row-major


def _specs(der: dv.Derivation) -> list[tuple[str, list[sp.Expr], int]]:
    pts = der.points
    return [
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


def _variant_note(der: dv.Derivation) -> str:
    return (f"Contact model: {der.contact}"
            f"{'' if der.gyroscopic else '; gyroscopic terms dropped (fault variant)'}")


def generate_source(der: dv.Derivation, language: str = "c") -> tuple[str, dict[str, tuple[int, int]]]:
    """All generated functions of one variant: C (plus the runtime, #included) or numpy (the
    runtime is `numpy_runtime`), and each function's output layout, ``{name: (size,
    symmetric)}`` (`codegen.GeneratedFunction`'s fields; this module does not import codegen)."""
    if language not in LANGUAGES:
        raise ValueError(f"language must be one of {LANGUAGES}; got {language!r}")
    if language == "c":
        parts = ["/* Generated by reference_model/equations/codegen.py from "
                 "reference_model/equations/derivation.py.\n"
                 f" * {_variant_note(der)}. Never hand-edited: rewritten whenever its sources "
                 "change. */\n#include <math.h>\n\n"]
    else:
        parts = ["# Generated by reference_model/equations/codegen.py from "
                 "reference_model/equations/derivation.py.\n"
                 f"# {_variant_note(der)}. numpy backend, vectorized over the batch. Never "
                 "hand-edited.\nimport numpy\n\n\n"]
    funcs = {}
    for name, exprs, sym in _specs(der):
        fn = _straight_line(der, name, exprs, symmetric=sym)
        parts.append(_c_function(der, fn) if language == "c" else _numpy_function(der, fn))
        funcs[name] = (fn.size, fn.symmetric)
    if language == "c":
        parts.append('#include "runtime.c"\n')
    return "".join(parts), funcs
