"""Which files of a report folder belong to the harness, and which folders it may write into.

A report folder's manifest (`MANIFEST`) says what an earlier run wrote; it is a file in
the user's folder, so anyone can edit it, or hand the user a folder with a crafted one. An
entry is therefore trusted only when it is a name the report writer itself produces
(`is_report_name`) and, on disk, neither it nor its folder is a symbolic link and it resolves
inside ``out`` (`owned_target`). A folder is accepted as ``--out`` (`check_out_folder`) unless
it lies inside this project's installed packages or is the project's root, or it is a
non-empty folder with no manifest (someone else's files) and ``force`` was not given.
"""

from __future__ import annotations

import importlib
from pathlib import Path, PurePosixPath

__all__ = ["MANIFEST", "REPORT_FILES", "REPORT_FOLDERS", "OutFolderError", "check_out_folder",
           "is_report_name", "owned_target", "package_folders"]

#: what a report folder holds that the harness wrote; nothing else is ever moved or deleted
MANIFEST = ".bicycle-xval-files"
#: the files at the top of a report folder (`comparisons.report.writer.write_report`)
REPORT_FILES = frozenset({"report.md", "report.html", "summary.json", "timings.json"})
#: its subfolders and the one suffix each holds: figures/<name>.png, data/<scenario>_<engine>.csv
REPORT_FOLDERS = {"figures": ".png", "data": ".csv"}
#: the packages whose folders never hold a report (data flows reference_model -> engines -> comparisons)
_PACKAGES = ("reference_model", "engines", "comparisons")


class OutFolderError(ValueError):
    """``--out`` names a folder the harness must not write into; the message is one line."""


def is_report_name(rel: str) -> bool:
    """True for a plain relative name the report writer produces: one of `REPORT_FILES`, or
    ``figures/NAME.png`` / ``data/NAME.csv`` one level down. Absolute names, ``..`` (never
    one of these shapes), ``.``, empty parts, backslashes and anything else are not."""
    if not rel or "\\" in rel or "\0" in rel:
        return False
    path = PurePosixPath(rel)
    if path.is_absolute() or str(path) != rel:     # "./x", "a//b", "a/" are not the writer's
        return False
    if len(path.parts) == 1:
        return rel in REPORT_FILES
    return len(path.parts) == 2 and REPORT_FOLDERS.get(path.parts[0]) == path.suffix


def owned_target(out: Path, rel: str) -> Path | None:
    """``out / rel`` if the harness may replace or remove it: ``rel`` is a report name, no
    part of it below ``out`` is a symbolic link, and it resolves inside ``out``; else None."""
    if not is_report_name(rel):
        return None
    out = Path(out)
    target = out / rel
    if target.parent != out and target.parent.is_symlink():
        return None
    if target.is_symlink():
        return None
    root = out.resolve()
    if target.resolve().parent != root / PurePosixPath(rel).parent:
        return None
    return target


def package_folders() -> tuple[Path, ...]:
    """The folders of this project's packages as imported (from their ``__file__``: a source
    checkout, an editable install or site-packages alike)."""
    return tuple(Path(importlib.import_module(name).__file__).resolve().parent
                 for name in _PACKAGES)


def _is_project_root(folder: Path) -> bool:
    """A folder with the pyproject.toml of this project (``name = "bicycle-xval"``)."""
    pyproject = folder / "pyproject.toml"
    if not pyproject.is_file():
        return False
    try:
        import tomllib
        return tomllib.loads(pyproject.read_text(encoding="utf-8")).get(
            "project", {}).get("name") == "bicycle-xval"
    except (OSError, ValueError):
        return False


def check_out_folder(out: Path, force: bool = False) -> None:
    """Raise `OutFolderError` (one line: the folder, why, what to do) if ``out`` may not
    receive a report: a file, a folder of the installed packages, the folder holding them or
    any folder with this project's pyproject.toml, a
    report subfolder (figures/, data/) that is a symbolic link or not a folder, or a
    non-empty folder without a manifest unless ``force``."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise OutFolderError(f"--out {out} is a file; give a folder for the report")
    real = out.resolve()
    for pkg in package_folders():
        if real == pkg or real.is_relative_to(pkg):
            raise OutFolderError(f"--out {out} is inside the package folder {pkg}; write the "
                                 "report elsewhere, e.g. --out reports/latest")
    if real in {pkg.parent for pkg in package_folders()} or _is_project_root(real):
        raise OutFolderError(f"--out {out} holds the bicycle-xval sources; write the report "
                             "into a folder of its own, e.g. --out reports/latest")
    if not out.is_dir():
        return
    for sub in REPORT_FOLDERS:
        if (out / sub).is_symlink() or ((out / sub).exists() and not (out / sub).is_dir()):
            raise OutFolderError(f"--out {out}: {sub} is a symbolic link or not a folder; the "
                                 f"report writes {sub}/ inside --out only: remove it or choose "
                                 "another folder")
    manifest = out / MANIFEST
    has_manifest = manifest.is_file() and not manifest.is_symlink()
    if not has_manifest and not force and any(out.iterdir()):
        raise OutFolderError(f"--out {out} holds files and no earlier report of bicycle-xval; "
                             "choose an empty or new folder, or add --force to overwrite only "
                             "the files the report writes (report.md, summary.json, figures/, "
                             "data/ ...) and keep the rest")
