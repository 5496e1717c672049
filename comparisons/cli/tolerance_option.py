"""``--tolerances FILE`` of ``run``, ``sweep``, ``diagnose`` and ``compare-trajectory``: the
tolerance file read once, here, into the value every judgment is given.

    add_tolerances_argument(parser)
    tols = tolerances_from(args)       # a `judgments.tolerances.Tolerances`, or a UsageError

A given file must be well formed and have every table of the packaged
`comparisons/judgments/tolerances.toml` (`judgments.tolerances.load_complete`); a problem is
one line naming the file, the table and the fix, before anything runs.
"""

from __future__ import annotations

from pathlib import Path

from .errors import UsageError

__all__ = ["add_tolerances_argument", "tolerances_from"]


def add_tolerances_argument(parser) -> None:
    from ..judgments.tolerances import PACKAGED
    parser.add_argument("--tolerances", type=Path, default=None, metavar="FILE",
                        help=f"a tolerance file replacing {PACKAGED} (same tables) [{PACKAGED}]")


def tolerances_from(args):
    """The tolerances ``--tolerances`` names (the packaged file without it), validated."""
    from ..judgments.tolerances import ToleranceError, load_complete, load_tolerances
    if getattr(args, "tolerances", None) is None:
        return load_tolerances()
    try:
        return load_complete(args.tolerances)
    except ToleranceError as exc:
        raise UsageError(f"--tolerances: {exc}") from None
