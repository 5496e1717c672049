"""Files the harness writes, written so that none is ever left half-written (used by the
stages that keep checkpoints, the sweep, and by the report writer).

Every file goes to a temporary name in its own folder and is renamed over the target only when
complete (``os.replace`` is atomic on one file system); text is always UTF-8, whatever the
locale. A report folder is assembled beside its destination and swapped in whole
(`ReportFolder`), so an interrupted run leaves either the old complete report or nothing new,
and files in the destination that the harness did not write are never touched: the manifest
is believed only for names the report writer produces, inside the destination, never through
a symbolic link (`ownership`).
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .ownership import MANIFEST, check_out_folder, owned_target


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: Path, suffix: str = ""):
    """A temporary path beside ``path``; renamed onto ``path`` when the block ends without an
    exception, removed otherwise."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix or path.suffix,
                               dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())     # mkstemp's 0600 is for the temporary only
        os.replace(tmp, path)
    except OSError as exc:                   # e.g. a full disk: name the file being written
        Path(tmp).unlink(missing_ok=True)
        raise OSError(exc.errno, f"{exc.strerror or exc} while writing", str(path)) from exc
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` as UTF-8 to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_bytes(path: Path, data: bytes) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def csv_bytes(frame) -> bytes:
    """A table (a pandas DataFrame, or a mapping of column name to 1-D array) as CSV text
    (UTF-8): a header of the column names, then every number as its shortest exact decimal (it
    reads back to the same double), NaN as an empty field, booleans as true/false, text quoted.
    Written by pyarrow's CSV writer: 9x faster than pandas' ``to_csv`` with
    ``float_format="%.17g"`` on the report's runs (0.08 s against 0.71 s for ten), and exact
    where ``%.17g`` only rounds to the nearest 17-digit decimal. Without pyarrow (it is not in
    the core install, README "Dependencies") `plain_csv_rows` writes the same bytes."""
    import io

    import numpy as np
    columns = [str(c) for c in (frame.columns if hasattr(frame, "columns") else frame)]
    bad = [c for c in columns if any(ch in c for ch in ',"\n')]
    if bad:
        raise ValueError(f"CSV column name {bad[0]!r} needs quoting; the harness writes plain names")
    header = (",".join(columns) + "\n").encode("utf-8")
    try:
        import pyarrow as pa
        import pyarrow.csv as pa_csv
    except ImportError:
        arrays = [np.asarray(frame[c]) for c in (frame.columns if hasattr(frame, "columns") else frame)]
        return header + plain_csv_rows(arrays).encode("utf-8")
    if hasattr(frame, "columns"):
        table = pa.Table.from_pandas(frame, preserve_index=False)   # NaN -> null -> empty field
    else:
        table = pa.Table.from_arrays([_arrow_column(np.asarray(v)) for v in frame.values()],
                                     names=columns)
    buf = io.BytesIO()
    buf.write(header)
    pa_csv.write_csv(table, buf, pa_csv.WriteOptions(include_header=False, quoting_style="needed"))
    return buf.getvalue()


def plain_csv_rows(arrays) -> str:
    """The rows of `csv_bytes` without pyarrow, byte for byte what Arrow's writer gives (with
    quoting "needed"): floats as `arrow_float`, booleans true/false, integers as they are, NaN
    and None empty, anything else quoted with its quotes doubled. About 0.5 us a number."""
    import numpy as np
    cols = []
    for a in arrays:
        if a.dtype.kind == "f":
            cols.append([arrow_float(x) for x in a.astype(np.float64).tolist()])
        elif a.dtype.kind == "b":
            cols.append(["true" if x else "false" for x in a.tolist()])
        elif a.dtype.kind in "iu":
            cols.append([str(x) for x in a.tolist()])
        else:
            cols.append(["" if x is None or (isinstance(x, float) and x != x)
                         else '"' + str(x).replace('"', '""') + '"' for x in a.tolist()])
    return "".join(",".join(row) + "\n" for row in zip(*cols))


def arrow_float(v: float) -> str:
    """A double as Arrow's CSV writer prints it: the shortest digits that read back to it
    (Python's repr finds the same ones), in plain decimals for 1e-6 <= |v| < 1e10 (no trailing
    ".0"), else as d.ddde+X / d.ddde-X; NaN empty (null), inf and -inf as such."""
    if v != v:
        return ""
    if v in (float("inf"), float("-inf")):
        return "inf" if v > 0 else "-inf"
    text = repr(float(v))        # numpy's float64 reprs as np.float64(...) under numpy 2
    if 1e-4 <= abs(v) < 1e10:     # where repr is plain decimals already
        return text[:-2] if text.endswith(".0") else text
    sign, text = ("-", text[1:]) if text[0] == "-" else ("", text)
    mantissa, _, exp = text.partition("e")
    whole, _, frac = mantissa.partition(".")
    digits = (whole + frac).lstrip("0")
    point = len(whole) + int(exp or 0) - (len(whole + frac) - len(digits))   # of the first digit
    digits = digits.rstrip("0")
    if not digits:
        return sign + "0"
    if -6 <= point - 1 < 10:      # 1e-6 <= |v| < 1e-4 (the plain decimals above 1e-4 are repr's)
        return f"{sign}0.{'0' * -point}{digits}"
    rest = f".{digits[1:]}" if len(digits) > 1 else ""
    return f"{sign}{digits[0]}{rest}e{'+' if point >= 1 else '-'}{abs(point - 1)}"


def _arrow_column(a):
    """A 1-D array as an Arrow array, NaN -> null (an empty CSV field) as pandas' frames give.
    Floats are wrapped from their buffers: ``pyarrow.array`` on a numpy array imports pandas
    (0.7 s) to check the input's type, which the report's path never needs."""
    import numpy as np
    import pyarrow as pa
    if a.dtype != np.float64:
        return pa.array(a)
    a = np.ascontiguousarray(a)
    valid = ~np.isnan(a)
    return pa.Array.from_buffers(pa.float64(), len(a),
                                 [pa.py_buffer(np.packbits(valid, bitorder="little")),
                                  pa.py_buffer(a)], null_count=int(a.size - valid.sum()))


def write_csv(frame, path: Path) -> Path:
    """A table (`csv_bytes`) as CSV, written atomically."""
    return write_bytes(Path(path), csv_bytes(frame))


class ReportFolder:
    """A report assembled in a fresh folder beside ``out`` and swapped in when complete.

    ``with ReportFolder(out) as folder: ... folder.path / "report.md" ...``: on success the
    files the previous run wrote (listed in its manifest, each a report name inside ``out``,
    `ownership.owned_target`) are removed from ``out``, the new ones moved in, and the manifest
    rewritten; files the harness did not write stay as they were. A non-empty ``out`` without a
    manifest is refused unless ``force`` (then only the files the report writes are replaced),
    as is a folder of the packages (`ownership.check_out_folder`, `OutFolderError`).
    On an exception (Ctrl-C, SIGTERM, a failure) the staging folder is removed and ``out`` is
    untouched."""

    def __init__(self, out: Path, force: bool = False):
        self.out = Path(out)
        self.force = force
        check_out_folder(self.out, force)
        self.out.parent.mkdir(parents=True, exist_ok=True)
        self.path: Path | None = None

    def __enter__(self) -> "ReportFolder":
        self.path = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.partial-", dir=self.out.parent))
        os.chmod(self.path, 0o777 & ~_umask())
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        staged = self.path
        if exc_type is not None:
            shutil.rmtree(staged, ignore_errors=True)
            return False
        blocked = {signal.SIGINT, signal.SIGTERM}
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, blocked)   # the swap is not cut
        try:
            self._swap(staged)
        finally:
            shutil.rmtree(staged, ignore_errors=True)
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)
        return False

    def _swap(self, staged: Path) -> None:
        new = sorted(str(p.relative_to(staged)) for p in staged.rglob("*") if p.is_file())
        if not self.out.exists():
            os.replace(staged, self.out)            # the common case: one atomic rename
            write_text(self.out / MANIFEST, "\n".join(new) + "\n")
            return
        check_out_folder(self.out, self.force)      # again: the folder may have changed meanwhile
        manifest = self.out / MANIFEST
        listed = (manifest.read_text(encoding="utf-8").splitlines()
                  if manifest.is_file() and not manifest.is_symlink() else [])
        targets = {rel: owned_target(self.out, rel) for rel in new}
        stray = [rel for rel, t in targets.items() if t is None]
        if stray:                                   # the writer's own names always pass
            raise OSError(f"{self.out / stray[0]}: not a file a report may write")
        old = [t for t in (owned_target(self.out, rel) for rel in listed if rel not in new) if t]
        for target in old:                          # only what an earlier run wrote, inside out
            if target.is_file():
                target.unlink()
        for rel, target in targets.items():
            target.parent.mkdir(exist_ok=True)
            os.replace(staged / rel, target)
        write_text(manifest, "\n".join(new) + "\n")
        for folder in sorted({t.parent for t in old}, reverse=True):
            if folder != self.out and folder.is_dir() and not any(folder.iterdir()):
                folder.rmdir()
