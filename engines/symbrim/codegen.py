"""SymBRiM's equations printed to code and cached, by the Kane engine's machinery
(`engines.kane.codegen`: the same printer, the same verified cache folder in the reference
model's cache root; never committed).

The cache key hashes this folder's derivation and this file, the Kane printer that writes the
module, sympy's version and symbrim's version: a new SymBRiM release or a change to either
source derives again. One entry per variant: the knife-edge front wheel, and the toroidal one
(the crown-radius option). The first derivation costs ~40 s (SymBRiM's model ~12 s of it);
a cached load ~0.1 s; within a process the loaded module is kept.
"""

from __future__ import annotations

import functools
import hashlib
from importlib import metadata
from pathlib import Path
from types import ModuleType

from ..kane import codegen as kane_codegen

__all__ = ["cache_key", "generate_source", "load"]

HERE = Path(__file__).resolve().parent
#: Files whose content the generated module depends on (the Kane printer's among them).
KEY_SOURCES = (HERE / "derivation.py", HERE / "codegen.py",
               Path(kane_codegen.__file__).resolve(),
               HERE.parent / "kane" / "derivation.py")   # KaneDerivation's fields


def cache_key(front_crown: bool) -> str:
    h = hashlib.sha256()
    for path in KEY_SOURCES:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(f"sympy {metadata.version('sympy')} symbrim {metadata.version('symbrim')} "
             f"toroidal {front_crown}".encode())
    return h.hexdigest()[:16]


def generate_source(front_crown: bool) -> str:
    from . import derivation
    return kane_codegen.module_source(
        derivation.derive(front_crown),
        f"engines/symbrim/codegen.py from SymBRiM {metadata.version('symbrim')}'s Whipple "
        f"bicycle ({'toroidal' if front_crown else 'knife-edge'} front wheel)")


@functools.lru_cache(maxsize=None)
def load(front_crown: bool = False) -> ModuleType:
    """The generated module of one variant, from the cache or generated first."""
    variant = "symbrim-toroidal" if front_crown else "symbrim-knife-edge"
    return kane_codegen.load_cached(variant, cache_key(front_crown), variant,
                                    lambda: generate_source(front_crown))
