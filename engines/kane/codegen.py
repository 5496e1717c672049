"""The code generator of the Kane derivation: prints its expressions as a Python module and
caches that module on disk like the reference model's (the module is never committed).

The derivation (`engines.kane.derivation`, 7 s measured) runs once: its expressions go through
sympy's common-subexpression elimination and are printed twice, as numpy functions
vectorized over a batch of states (every symbol a (N,) array, the parameters scalars) and as
plain-float `math` functions of one state (``<name>_one``, and ``terms_one`` with everything
the forward right-hand side needs), ~20 times faster than the vectorized code on a single
state. The module is stored in the reference model's cache folder
(`reference_model.codegen.cache_root`, ``$BICYCLE_XVAL_CACHE``), in a folder named by a key
that hashes this file, the derivation's sources and sympy's version; the folder is written
under a temporary name and renamed into place, and carries a manifest with the size and
SHA-256 of the module, verified before it is imported (the reference's
`write_manifest` / `verify_entry`). Within a process the loaded module is kept
(`functools.lru_cache`), so a cold derivation happens at most once per process and once
per machine until a source or sympy changes.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import shutil
import tempfile
import time
from importlib import metadata
from pathlib import Path
from types import ModuleType

from reference_model.codegen import (cache_root, clean_stale_temporaries, temporary_prefix,
                                     verify_entry, write_manifest)

# sympy (and the derivation, which imports sympy.physics.mechanics: ~0.6 s) is imported only
# to generate: a process that loads the cached module, or builds the engine only to learn
# that it cannot use a model, never pays for it
HERE = Path(__file__).resolve().parent
#: Files whose content the generated module depends on.
KEY_SOURCES = ("names.py", "derivation.py", "codegen.py")
MODULE = "kane_generated.py"
FILES = (MODULE,)
#: The generated functions: name -> (derivation field, arguments).
FUNCTIONS = {
    "mass": ("mass", ("q", "p")),
    "forcing": ("forcing", ("q", "u", "p", "T")),
    "constraints": ("constraints", ("q", "u", "p")),
    "jacobian": ("jacobian", ("q", "p")),
    "bias": ("bias", ("q", "u", "p")),
}
#: Also generated for one state (``<name>_one``): what solving the constraints for the
#: initial state and the projection after each step evaluate.
SCALAR = ("mass", "constraints", "jacobian")
#: ``terms_one(q, u, p, T)``: the entries of these, one after the other, at one state (what
#: the forward right-hand side needs).
TERMS_ONE = ("mass", "forcing", "jacobian", "bias", "constraints")


def cache_key() -> str:
    h = hashlib.sha256()
    for name in KEY_SOURCES:
        h.update(name.encode())
        h.update((HERE / name).read_bytes())
    h.update(f"sympy {metadata.version('sympy')}".encode())
    return h.hexdigest()[:16]


def _printer(scalar: bool):
    """sympy's numpy printer (``numpy.sin``...) or its plain-Python one (``math.sin``...)."""
    from sympy.printing.numpy import NumPyPrinter
    from sympy.printing.pycode import PythonCodePrinter
    cls = PythonCodePrinter if scalar else NumPyPrinter
    return cls({"fully_qualified_modules": True, "inline": True})


def _unpack(args: tuple[str, ...], der, index) -> list[str]:
    """The lines binding each symbol to its argument entry; ``index(i)`` prints entry i."""
    lines = []
    for arg, syms in (("q", der.q), ("u", der.u), ("p", der.p), ("T", der.T)):
        if arg in args:
            lines += [f"    {s} = {arg}{index(arg, i)}" for i, s in enumerate(syms)]
    return lines


def _cse(exprs: list) -> tuple[list, list]:
    # optimizations=None: sympy's "basic" pre-optimizations (factor_terms on every expression)
    # took 16-30 s of a 30-70 s cold start and bought nothing measurable at run time
    import sympy as sp
    return sp.cse(exprs, symbols=sp.numbered_symbols("x"), optimizations=None)


def _vectorized(name: str, args: tuple[str, ...], M, der) -> str:
    """``name(*args) -> (N, rows, cols)``, vectorized over a batch (every state argument
    (N, k), the parameters (k,))."""
    subs, reduced = _cse(list(M))
    pr = _printer(scalar=False)
    lines = [f"def {name}({', '.join(args)}):", "    n = q.shape[0]"]
    lines += _unpack(args, der, lambda a, i: f"[{i}]" if a == "p" else f"[:, {i}]")
    lines += [f"    {sym} = {pr.doprint(e)}" for sym, e in subs]
    lines.append(f"    out = numpy.zeros((n, {M.rows}, {M.cols}))")
    for k, e in enumerate(reduced):
        if e != 0:
            lines.append(f"    out[:, {k // M.cols}, {k % M.cols}] = {pr.doprint(e)}")
    lines.append("    return out")
    return "\n".join(lines) + "\n"


def _scalar(name: str, args: tuple[str, ...], matrices: list, der) -> str:
    """``name(*args) -> list`` of floats, the entries of ``matrices`` row-major one after the
    other, for ONE state in plain Python floats and `math`: the integrator's right-hand side
    evaluates one state at a time, where a numpy call on a 1-element array costs ~1 us and a
    float operation ~50 ns. One common-subexpression elimination over all the matrices."""
    subs, reduced = _cse([e for M in matrices for e in M])
    pr = _printer(scalar=True)
    lines = [f"def {name}({', '.join(args)}):"]
    lines += _unpack(args, der, lambda a, i: f"[{i}]")
    lines += [f"    {sym} = {pr.doprint(e)}" for sym, e in subs]
    lines.append("    return [" + ", ".join("0.0" if e == 0 else pr.doprint(e) for e in reduced)
                 + "]")
    return "\n".join(lines) + "\n"


def module_source(der, origin: str) -> str:
    """The generated module's source for a derivation ``der`` (a `KaneDerivation`: Moore's
    coordinates, the five matrices), headed by where it came from (``origin``)."""
    import sympy as sp
    parts = [f"# Generated by {origin} (sympy {sp.__version__}), cached, never hand-edited "
             f"(as the reference model's code).\n",
             "import math\n\nimport numpy\n"]
    for name, (field, args) in FUNCTIONS.items():
        parts.append(_vectorized(name, args, getattr(der, field), der))
        if name in SCALAR:
            parts.append(_scalar(f"{name}_one", args, [getattr(der, field)], der))
    parts.append(_scalar("terms_one", ("q", "u", "p", "T"),
                         [getattr(der, f) for f in TERMS_ONE], der))
    return "\n\n".join(parts)


def generate_source() -> str:
    from . import derivation
    return module_source(derivation.derive(),
                         "engines/kane/codegen.py from engines/kane/derivation.py")


def _import(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"{path.stem}_{path.parent.name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def load_cached(prefix: str, key: str, variant: str, generate) -> ModuleType:
    """The module ``generate()`` prints, from the cache folder ``<prefix>-<key>`` (identity
    ``variant``), or generated, written and verified first. The Kane engine's loader, and any
    other engine's that prints a `KaneDerivation` (`module_source`)."""
    root = cache_root()
    target = root / f"{prefix}-{key}"
    identity = {"variant": variant, "backend": "numpy", "key": key}
    if verify_entry(target, identity, FILES)[0] is None:
        root.mkdir(parents=True, exist_ok=True)
        clean_stale_temporaries(root)
        t0 = time.perf_counter()
        source = generate()
        tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(prefix), dir=root))
        try:
            (tmp / MODULE).write_text(source, encoding="utf-8")
            write_manifest(tmp, identity, FILES,
                           {"derivation_seconds": round(time.perf_counter() - t0, 2)})
            if target.exists():            # damaged or stale: out of the way first
                shutil.rmtree(target, ignore_errors=True)
            try:
                os.replace(tmp, target)
            except OSError:                # another process won the race
                pass
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        info, why = verify_entry(target, identity, FILES)
        if info is None:
            raise RuntimeError(f"the {variant} code cache entry {target} is not intact after "
                               f"writing it ({why}); check that {root} is writable")
    return _import(target / MODULE)


@functools.lru_cache(maxsize=None)
def load(log=None) -> ModuleType:
    """The generated module, from the cache, or derived, generated and cached first."""
    return load_cached("kane", cache_key(), "kane-moore", generate_source)
