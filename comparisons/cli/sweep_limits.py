"""``bicycle-xval sweep``'s limits: the cap on the bicycles of one sweep (``--max-bicycles``)
and the time one bicycle may take (``--bicycle-timeout``); what they are:
`comparisons.stages.sweep_budget`."""

from __future__ import annotations

import math

from .errors import UsageError

__all__ = ["add_limit_arguments", "check_limits"]


def add_limit_arguments(parser) -> None:
    from ..stages.sweep_budget import DEFAULT_MAX_BICYCLES, LIMIT_FACTOR, LIMIT_FLOOR
    parser.add_argument("--max-bicycles", type=int, default=DEFAULT_MAX_BICYCLES, metavar="N",
                        help="refuse a sweep of more bicycles; raise it to run a larger one "
                             f"[{DEFAULT_MAX_BICYCLES}]")
    parser.add_argument("--bicycle-timeout", type=float, default=None, metavar="S",
                        help="seconds one bicycle may take before it is reported as timed out "
                             f"[{LIMIT_FACTOR:g} x its estimated cost, at least {LIMIT_FLOOR:g}]")


def check_limits(args) -> None:
    """A `UsageError` (one line) for a bad limit, or for more bicycles than ``--max-bicycles``,
    before anything is built or started."""
    from ..stages.sweep_budget import SweepTooLarge, count_bicycles, refuse_huge
    if args.max_bicycles < 1:
        raise UsageError(f"--max-bicycles {args.max_bicycles}: give at least 1")
    t = args.bicycle_timeout
    if t is not None and not (math.isfinite(t) and t > 0):
        raise UsageError(f"--bicycle-timeout {t}: give a positive number of seconds, e.g. 600")
    n = count_bicycles(args.vary, args.sample)
    if n is not None:
        try:
            refuse_huge(n, args.max_bicycles)
        except SweepTooLarge as exc:
            raise UsageError(str(exc)) from None
