"""A third party's distribution as `importlib.metadata` reads an installed one, without
installing anything: ``<dist>-<version>.dist-info/`` with METADATA and entry_points.txt in a
folder that a test puts on sys.path. Shared by the registry, error and loading tests."""

from pathlib import Path

from engines.registry import GROUP

__all__ = ["dist_info"]


def dist_info(root: Path, dist: str, version: str, entries: dict[str, str]) -> Path:
    """Write the dist-info of ``dist`` ``version`` registering ``entries`` (name -> target)
    in the engines' group under ``root``; its folder."""
    info = root / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    lines = "".join(f"{k} = {v}\n" for k, v in entries.items())
    (info / "entry_points.txt").write_text(f"[{GROUP}]\n{lines}")
    return info
