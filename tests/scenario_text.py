"""The user's forward scenario file the scenario-file tests edit, and their writer: one
leaned, pedalling start on the thesis bicycle (0.5 s at 0.01 s), every optional table left
to its default."""

from pathlib import Path

__all__ = ["FORWARD", "write"]

FORWARD = """[scenario]
name = "mine"
description = "leaned start, pedalling"
kind = "forward"

[grid]
step = 0.01
duration = 0.5

[initial]
theta = 0.1
dpsi = 5.0

[inputs]
torques = { Mped = 1.0 }
"""


def write(folder: Path, text: str, name: str = "sc.toml") -> Path:
    """``text`` written to ``folder/name`` (UTF-8); its path."""
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path
