"""A sweep's chunk files: each one says which spec and which bicycles it holds, and is read
back only when it says so.

    write_chunk(frame, path, stamp, writer="parquet")     # or "csv" (no pyarrow)
    frame = read_chunk(path, stamp, columns)               # or raises ChunkMismatch(reason)

A chunk file carries a `ChunkStamp`: the spec hash it was computed under, its bicycle indices
(``start:stop``, the chunks are consecutive) and its row count. A rerun believes a file only when
it reads completely and its stamp, its ``bicycle`` column and its columns are those the plan
expects; anything else (a truncated or garbled file, a chunk copied over another, a file of
another spec or of older code with other columns) is `ChunkMismatch`, and the sweep computes
the chunk again (`stages.sweep`).

Two writers, the same stamp:

* **parquet** (pyarrow): the stamp is a key of the file's schema metadata (``bicycle-xval``);
  a cut file fails to read (its footer is at the end).
* **csv** (`files.csv_bytes`: pyarrow's CSV writer, or its plain fallback without pyarrow):
  the first line is ``# bicycle-xval sweep chunk {stamp}``, the stamp with the SHA-256 of the
  rest of the file, so a file cut anywhere (even at a row boundary) or edited is refused; the
  numbers are shortest round-trip decimals, read back exactly (`_round_trip`).
"""

from __future__ import annotations

import hashlib
import io
import json
import re
from dataclasses import dataclass
from pathlib import Path

from .files import atomic_path, csv_bytes, write_bytes

__all__ = ["CSV_LINE", "ChunkMismatch", "ChunkStamp", "METADATA_KEY", "WRITERS", "default_writer",
           "read_chunk", "read_table", "write_chunk", "write_table"]

METADATA_KEY = b"bicycle-xval"
CSV_LINE = b"# bicycle-xval sweep chunk "
#: writer -> file suffix
WRITERS = {"parquet": ".parquet", "csv": ".csv"}


class ChunkMismatch(ValueError):
    """A chunk file that cannot be believed: the reason, in a few words."""


@dataclass(frozen=True)
class ChunkStamp:
    """What a chunk file holds: the spec hash and the bicycles ``start <= k < stop``."""

    hash: str
    start: int
    stop: int

    @property
    def bicycles(self) -> range:
        return range(self.start, self.stop)

    def as_json(self) -> dict:
        return {"hash": self.hash, "bicycles": [self.start, self.stop],
                "rows": self.stop - self.start}

    def problem(self, found: dict) -> str | None:
        """Why ``found`` (a file's stamp) is not this one, or None."""
        if not isinstance(found, dict):
            return "it carries no chunk stamp"
        if found.get("hash") != self.hash:
            return f"it belongs to spec {found.get('hash')!r}, not {self.hash}"
        if found.get("bicycles") != [self.start, self.stop]:
            b = found.get("bicycles")
            held = f"{b[0]}-{b[1] - 1}" if isinstance(b, list) and len(b) == 2 else repr(b)
            return f"it holds bicycles {held}, not {self.start}-{self.stop - 1}"
        if found.get("rows") != len(self.bicycles):
            return (f"it says {found.get('rows')!r} rows for bicycles {self.start}-"
                    f"{self.stop - 1}, not {len(self.bicycles)}")
        return None


def default_writer() -> str:
    """"parquet" where pyarrow is installed, else "csv"."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return "csv"
    return "parquet"


def write_chunk(frame, path: Path, stamp: ChunkStamp, writer: str) -> Path:
    """``frame`` (the chunk's rows, `sweep.rows_frame`) written atomically with its stamp."""
    return write_table(frame, path, writer, stamp.as_json())


def write_table(frame, path: Path, writer: str, stamp: dict | None = None) -> Path:
    """A frame as Parquet or CSV, with ``stamp`` (module docstring) when given, written
    atomically."""
    if writer == "parquet":
        meta = json.dumps(stamp or {}, sort_keys=True, separators=(",", ":")).encode()
        import pyarrow as pa
        import pyarrow.parquet as pq
        table = pa.Table.from_pandas(frame, preserve_index=False)
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), METADATA_KEY: meta})
        with atomic_path(path, suffix=".parquet") as tmp:
            pq.write_table(table, tmp, compression="zstd")
        return Path(path)
    if writer != "csv":
        raise ValueError(f"chunk writer {writer!r}: one of {', '.join(WRITERS)}")
    body = csv_bytes(frame)
    if stamp is None:                 # a plain table (the merged results)
        return write_bytes(Path(path), body)
    digest = hashlib.sha256(body).hexdigest()
    head = json.dumps({**stamp, "sha256": digest}, sort_keys=True,
                      separators=(",", ":")).encode()
    return write_bytes(Path(path), CSV_LINE + head + b"\n" + body)


def read_table(path: Path):
    """(frame, stamp) of a file `write_table` wrote; `ChunkMismatch` when it does not read."""
    path = Path(path)
    try:
        if path.suffix == ".parquet":
            import pyarrow.parquet as pq
            table = pq.read_table(path)
            raw = (table.schema.metadata or {}).get(METADATA_KEY)
            return table.to_pandas(), (json.loads(raw) if raw else None)
        return _read_csv(path.read_bytes())
    except ChunkMismatch:
        raise
    except Exception as exc:      # noqa: BLE001 -- whatever a damaged file raises, it is damaged
        text = " ".join(str(exc).split())[:200]
        raise ChunkMismatch(f"it does not read ({type(exc).__name__}: {text})") from None


def _read_csv(data: bytes):
    import pandas as pd
    stamp = None
    if data.startswith(CSV_LINE):
        head, _, data = data.partition(b"\n")
        stamp = json.loads(head[len(CSV_LINE):])
        if hashlib.sha256(data).hexdigest() != stamp.pop("sha256", None):
            raise ChunkMismatch("its content does not match its SHA-256 (cut or edited)")
    frame = pd.read_csv(io.BytesIO(data), keep_default_na=False, na_values=[""],
                        **_round_trip(pd.__version__))
    return frame, stamp


def _round_trip(version: str) -> dict:
    """read_csv's option for exact floats: pandas before 3.1 needs ``float_precision=
    "round_trip"`` (its default parser can be 1 ulp off); 3.1 deprecates the option, its
    default being exact (checked: 20 000 shortest decimals over 1e-300..1e300 read back)."""
    major, minor = (int(x) for x in re.findall(r"\d+", version)[:2])
    return {} if (major, minor) >= (3, 1) else {"float_precision": "round_trip"}


def read_chunk(path: Path, stamp: ChunkStamp, columns: list[str]):
    """The chunk's frame, when the file reads and is the chunk ``stamp`` describes, with
    ``columns`` (else `ChunkMismatch` saying why)."""
    frame, found = read_table(path)
    problem = stamp.problem(found)
    if problem:
        raise ChunkMismatch(problem)
    if list(frame.columns) != list(columns):
        raise ChunkMismatch("its columns are not this sweep's (written by other code)")
    if [int(k) for k in frame["bicycle"]] != list(stamp.bicycles):
        raise ChunkMismatch(f"its rows are not bicycles {stamp.start}-{stamp.stop - 1}")
    return frame
