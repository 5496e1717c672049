"""The summary table: quantity x engine pair, the worst error over scenarios, the verdict."""

from __future__ import annotations

import numpy as np


def summary_table(comparisons) -> list[dict]:
    """One row per (quantity, engines): the worst error, the tolerance(s), the verdict (pass, FAIL (k of n),
    reported) and its reason where it is not obvious ('reported' rows say who judges them; a pass that is an
    expected difference says so), and where the worst case is."""
    groups: dict[tuple[str, str], list[dict]] = {}
    for c in comparisons:
        groups.setdefault((c["quantity"], " vs ".join(c["engines"])), []).append(c)
    rows = []
    for (quantity, pair), cs in groups.items():
        judged = [c for c in cs if c.get("passed") is not None]
        errs = [c["max_error"] for c in cs if c.get("max_error") is not None]
        worst = max(cs, key=lambda c: -np.inf if c.get("max_error") is None else c["max_error"])
        tol = sorted({c["tolerance"] for c in cs if c.get("tolerance") is not None})
        if not judged:
            reasons = sorted({(c.get("why") or c.get("note") or "").removeprefix(
                "reported, not judged: ") for c in cs} - {""})
            verdict, reason = "reported", (reasons[0] if reasons else "")
        elif all(c["passed"] for c in judged):
            expected = sorted({c["expected"] for c in judged
                               if c.get("expected") not in (None, "converges")
                               and not str(c.get("expected", "")).startswith(("weave", "slow"))})
            verdict = "pass"
            reason = (f"expected '{', '.join(expected)}': a declared model difference"
                      if expected else "")
        else:
            verdict = f"FAIL ({sum(not c['passed'] for c in judged)} of {len(judged)})"
            reason = ""
        rows.append({
            "quantity": quantity, "engines": pair, "n": len(cs),
            "max_error": max(errs) if errs else None,
            "tolerance": tol[0] if len(tol) == 1 else (None if not tol else f"{tol[0]:.0e}..{tol[-1]:.0e}"),
            "verdict": verdict, "reason": reason,
            "worst": f"{worst['scenario']}: {worst.get('localized_to', '-')}",
        })
    return rows
