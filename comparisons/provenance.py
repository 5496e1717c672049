"""What produced a report: the bicycle-xval version, the git commit of the code (when it is a
checkout), the reading guide's location, and which bicycles the comparisons ran on.

The commit is that of the repository the package is imported from, and only when the package
*is* that repository's own tree (its import root is the checkout's top level): a wheel installed
in a virtualenv that happens to sit inside some other git checkout reports no commit rather
than that checkout's. ``dirty`` says whether the package's own files (the three packages and
pyproject.toml) differ from the commit; a report folder written into the tree does not count,
so regenerating a committed example report does not change what the next run records. Git
missing, slow or failing gives ``None``, never an error.

The bicycles: every model named by a comparison or an engine run, by its built-in name
(``thesis``, ``thesis-disc``, ``benchmark``; a label such as ``thesis-disc (cv = 0)`` is that
model with a setting changed), with the parameter file it comes from (as a path inside the
package, the same on every machine) and its contact model.
"""

from __future__ import annotations

import importlib.metadata as metadata
import subprocess
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Bicycle", "Provenance", "bicycles_compared", "guide_path", "package_provenance",
           "record", "version_line"]

DISTRIBUTION = "bicycle-xval"
#: the import root: the folder holding comparisons/, engines/ and reference_model/
IMPORT_ROOT = Path(__file__).resolve().parents[1]
#: what "dirty" looks at (paths relative to the checkout's top level)
SOURCE_PATHS = ("comparisons", "engines", "reference_model", "pyproject.toml")
GIT_TIMEOUT_S = 5.0   # a cold `git status` on a large tree on a loaded disk; never a hang
GUIDE = "report.md"


@dataclass(frozen=True)
class Provenance:
    """The code that ran: its version (None when not installed) and, in a git checkout, the
    commit and whether the package's files differ from it (both None outside a checkout)."""

    version: str | None
    commit: str | None
    dirty: bool | None

    def as_dict(self) -> dict:
        return {"version": self.version, "commit": self.commit, "dirty": self.dirty}


def _git(*args: str, cwd: Path) -> str | None:
    """stdout of ``git args`` in ``cwd``, or None if git is missing, fails or times out."""
    try:
        res = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True,
                             timeout=GIT_TIMEOUT_S, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return None
    return res.stdout if res.returncode == 0 else None


def _commit(root: Path) -> tuple[str | None, bool | None]:
    out = _git("rev-parse", "--show-toplevel", "HEAD", cwd=root)
    lines = (out or "").split()
    if len(lines) != 2 or Path(lines[0]).resolve() != root.resolve():
        return None, None      # not a checkout, or the package is not its tree
    status = _git("status", "--porcelain", "--untracked-files=no", "--", *SOURCE_PATHS, cwd=root)
    return lines[1], (None if status is None else bool(status.strip()))


def package_provenance(root: Path = IMPORT_ROOT) -> Provenance:
    """The version of the installed distribution and the commit of the code at ``root``."""
    try:
        version = metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        version = None
    return Provenance(version, *_commit(root))


def version_line(p: Provenance) -> str:
    """``bicycle-xval 0.1.0`` and, in a checkout, ``(commit <sha>[, uncommitted changes])``."""
    text = f"{DISTRIBUTION} {p.version or '(not installed)'}"
    if p.commit:
        text += f" (commit {p.commit}{', uncommitted changes' if p.dirty else ''})"
    return text


def guide_path(root: Path = IMPORT_ROOT) -> Path | None:
    """The reading guide docs/report.md: in an installed wheel ``comparisons/docs/``
    (pyproject.toml maps docs/ there), in a checkout the repository's ``docs/``."""
    for path in (root / "comparisons" / "docs" / GUIDE, root / "docs" / GUIDE):
        if path.is_file():
            return path
    return None


@dataclass(frozen=True)
class Bicycle:
    """A built-in bicycle the comparisons ran on, as the report's verdict block names it."""

    name: str
    source: str            # its parameter file, as a path inside the package
    contact: str
    comparisons: int       # how many of summary.json's comparisons are on it
    variants: tuple[str, ...] = ()   # settings changed in some of them, e.g. "cv = 0"

    def as_dict(self) -> dict:
        return {"name": self.name, "source": self.source, "contact": self.contact,
                "comparisons": self.comparisons, "variants": list(self.variants)}


def _split(label: str) -> tuple[str, str | None]:
    """'thesis-disc (cv = 0)' -> ('thesis-disc', 'cv = 0'); 'thesis' -> ('thesis', None)."""
    name, sep, rest = label.partition(" (")
    return name, (rest[:-1] if sep and rest.endswith(")") else None)


def _inside_package(path: Path) -> str:
    path = Path(path).resolve()
    return path.relative_to(IMPORT_ROOT).as_posix() if path.is_relative_to(IMPORT_ROOT) \
        else path.name


def bicycles_compared(comparisons, engine_runs) -> list[Bicycle]:
    """The built-in bicycles named by ``comparisons`` (summary.json's dicts, their ``model``)
    and by the ``engine_runs`` that ran (objects with ``model`` and ``status``), in order of
    first appearance. A model that is not built-in (a user's file) is not listed here:
    summary.json's ``models`` describes it."""
    from reference_model import NAMED_MODELS
    counts: dict[str, int] = {}
    variants: dict[str, list[str]] = {}
    labels = [(r.model, 0) for r in engine_runs if r.status != "not run"]
    labels += [(c["model"], 1) for c in comparisons if "model" in c]
    for label, n in labels:
        name, variant = _split(str(label))
        if name in NAMED_MODELS:
            counts[name] = counts.get(name, 0) + n
            seen = variants.setdefault(name, [])
            if variant and variant not in seen:
                seen.append(variant)
    return [Bicycle(name, _inside_package(NAMED_MODELS[name][0]), NAMED_MODELS[name][1], n,
                    tuple(variants[name])) for name, n in counts.items()]


def record(comparisons, engine_runs) -> dict:
    """summary.json's ``provenance``: the code that ran and the built-in bicycles compared."""
    return {**package_provenance().as_dict(),
            "bicycles": [b.as_dict() for b in bicycles_compared(comparisons, engine_runs)]}
