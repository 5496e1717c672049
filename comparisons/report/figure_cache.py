"""Drawn figures kept by what they show: a figure whose drawing code and data are the same as
in an earlier run is not drawn again.

matplotlib is the report's slowest writer (the full report's 35 figures cost about 7.5 s of
CPU on the 2-core machine, a sixth of the whole run), and every figure is a pure function of
its kind and data (`comparisons.stages.results.Figure`), drawn deterministically
(`figures.png_bytes`: no dates, no software tags). So a PNG is stored under a key that hashes

* the drawing code: the sources of `comparisons.report.figures` and `.styles`;
* the versions of matplotlib, Pillow and numpy (a new release may draw other pixels);
* the figure's kind and a canonical encoding of its data (`data_key`): arrays by dtype, shape
  and bytes, floats by their exact ``repr``, dicts in their order (the order of the curves and
  of the legend).

A `engines.runs.Run` in the data is keyed by what a drawing reads of it, never by its
``seconds``, ``message`` or ``trajectory`` (measured timings and settings: they would make
every run a miss). Data of a type this module does not know is not cached (the figure is drawn).

The files live in ``<cache_root>/figures/`` (`reference_model.equations.codegen.cache_root`:
``$BICYCLE_XVAL_CACHE``, else ``~/.cache/bicycle-xval``), each written atomically; a file that
is not a PNG is ignored and drawn again; at most `MAX_FILES` are kept (the least recently used
go first). A cache that cannot be read or written only costs the drawing, and is said once.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FigureCache", "MAX_FILES", "NOT_DRAWN", "Uncacheable", "data_key", "drawing_key"]

#: files kept; one full report holds about 50 figures of 30 kB on average (about 1.5 MB), so
#: this is about 20 reports' worth, some 30 MB at most
MAX_FILES = 1000
#: the fields of a dataclass in a figure's data that no drawing reads: measured timings and
#: solver settings (`engines.runs.Run`)
NOT_DRAWN = frozenset({"seconds", "message", "trajectory"})
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_SOURCES = ("figures.py", "styles.py")


class Uncacheable(TypeError):
    """A figure's data holds a value `data_key` cannot encode canonically."""


def _feed(h, x: Any) -> None:
    """Feed ``x`` into the hash ``h``: a tag per type, then its content."""
    if x is None or isinstance(x, (bool, np.bool_)):
        h.update(b"B" + repr(None if x is None else bool(x)).encode())
    elif isinstance(x, (int, np.integer)):
        h.update(b"I" + str(int(x)).encode() + b";")
    elif isinstance(x, (float, np.floating)):
        h.update(b"F" + struct.pack("<d", float(x)))
    elif isinstance(x, str):
        b = x.encode()
        h.update(b"S" + str(len(b)).encode() + b":" + b)
    elif isinstance(x, np.ndarray):
        if x.dtype.hasobject:
            h.update(b"O" + repr(x.shape).encode())
            for v in x.ravel():
                _feed(h, v)
            return
        a = np.ascontiguousarray(x)
        h.update(b"A" + a.dtype.str.encode() + repr(a.shape).encode() + b":")
        h.update(a.tobytes())
    elif isinstance(x, dict):
        h.update(b"D" + str(len(x)).encode() + b":")
        for k, v in x.items():
            _feed(h, k)
            _feed(h, v)
    elif isinstance(x, (list, tuple)):
        h.update((b"L" if isinstance(x, list) else b"T") + str(len(x)).encode() + b":")
        for v in x:
            _feed(h, v)
    elif dataclasses.is_dataclass(x) and not isinstance(x, type):
        h.update(b"C" + type(x).__qualname__.encode() + b":")
        for f in dataclasses.fields(x):
            if f.name not in NOT_DRAWN:
                _feed(h, f.name)
                _feed(h, getattr(x, f.name))
    else:
        raise Uncacheable(f"a {type(x).__name__} in a figure's data has no canonical key")


def data_key(kind: str, data: dict) -> str:
    """The hash of a figure's kind and data (hex); `Uncacheable` for data it cannot encode."""
    h = hashlib.sha256()
    _feed(h, kind)
    _feed(h, data)
    return h.hexdigest()


def drawing_key(sources: Path | None = None) -> str:
    """The hash of what draws the pixels: the drawing sources (this package's, or those in
    ``sources``: tests pass an edited copy) and the versions of the libraries that render them."""
    import matplotlib
    import PIL
    h = hashlib.sha256()
    here = Path(sources) if sources is not None else Path(__file__).resolve().parent
    for name in _SOURCES:
        h.update(name.encode() + b":" + (here / name).read_bytes())
    h.update(f"matplotlib={matplotlib.__version__};pillow={PIL.__version__};"
             f"numpy={np.__version__}".encode())
    return h.hexdigest()


@dataclass(frozen=True)
class FigureCache:
    """The drawn figures under ``root`` (one PNG per key; see the module doc)."""

    root: Path
    max_files: int = MAX_FILES
    read: bool = True       # False: nothing is read back (every figure drawn), all is stored

    @classmethod
    def default(cls, read: bool = True) -> "FigureCache":
        from reference_model.equations.codegen import cache_root
        return cls(cache_root() / "figures", read=read)

    def key(self, drawing: str, kind: str, data: dict) -> str | None:
        """The file key of a figure, None if its data cannot be keyed (then it is drawn)."""
        try:
            dk = data_key(kind, data)
        except Uncacheable:
            return None
        return hashlib.sha256((drawing + dk).encode()).hexdigest()[:32]

    def _path(self, key: str) -> Path:
        return self.root / key[:2] / f"{key}.png"

    def get(self, key: str) -> bytes | None:
        """The stored PNG of ``key``, None if there is none (or it is not a PNG). Raises
        OSError only if the cache cannot be read at all."""
        if not self.read:
            return None
        path = self._path(key)
        try:
            png = path.read_bytes()
        except (FileNotFoundError, NotADirectoryError):   # no such file (or folder) yet
            return None
        if not png.startswith(PNG_SIGNATURE):
            return None
        try:
            os.utime(path)       # recently used: pruned last
        except OSError:
            pass
        return png

    def put(self, key: str, png: bytes) -> None:
        """Store ``png`` under ``key`` atomically (a reader never sees half a file)."""
        from ..stages.files import write_bytes
        write_bytes(self._path(key), png)

    def read_back(self, figs) -> tuple[dict[str, bytes], dict[str, str]]:
        """For figures (`Figure`: name, kind, data): the PNGs held, by name, and the key of every
        figure that can be keyed. Raises OSError only if the cache cannot be read at all."""
        drawing = drawing_key()
        held, keys = {}, {}
        for f in figs:
            key = self.key(drawing, f.kind, f.data)
            if key is not None:
                keys[f.name] = key
                png = self.get(key)
                if png is not None:
                    held[f.name] = png
        return held, keys

    def store(self, keys: dict[str, str], pngs: dict[str, bytes]) -> None:
        """Keep each PNG of ``pngs`` (by name) under its key in ``keys`` (the names without a
        key are not kept), then prune. Raises OSError at the first file that cannot be written."""
        for name, png in pngs.items():
            if name in keys:
                self.put(keys[name], png)
        self.prune()

    def prune(self) -> int:
        """Remove the least recently used files beyond ``max_files``; returns how many."""
        try:
            files = [(p.stat().st_mtime, p) for p in self.root.glob("*/*.png")]
        except OSError:
            return 0
        extra = len(files) - self.max_files
        if extra <= 0:
            return 0
        removed = 0
        for _, p in sorted(files)[:extra]:
            try:
                p.unlink()
                removed += 1
            except OSError:
                pass
        return removed
