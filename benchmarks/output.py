"""The benchmark's output: the printed table, the JSON record, the mismatch banner."""

from __future__ import annotations

import datetime as _dt

from benchmarks.common import SEED, Row, fmt_ratio, fmt_time


def table(rows: list[Row], crba: float) -> str:
    head = ("quantity", "measured", "target", "within target", "ratio to crba")
    body = []
    for r in rows:
        if r.unit == "s":
            measured = r.measured_text or fmt_time(r.value)
            ratio = fmt_ratio(r.value / crba) if r.value is not None and r.vs_crba else "-"
        elif r.unit == "x":
            measured, ratio = fmt_ratio(r.value), "-"
        else:
            measured, ratio = f"{r.value:.0f}", "-"
        if r.target is None:
            target = "-"
        else:
            target = f"<= {r.target:g}x" if r.unit == "x" else f"<= {fmt_time(r.target)}"
        within = {None: "-", True: "yes", False: "NO"}[r.within]
        body.append((r.quantity, measured, target, within, ratio))
    widths = [max(len(x[i]) for x in [head, *body]) for i in range(len(head))]

    def line(cells):
        return "  ".join([cells[0].ljust(widths[0]), *(c.rjust(w) for c, w in zip(cells[1:], widths[1:]))])
    sep = "  ".join("-" * w for w in widths)
    return "\n".join([line(head), sep, *(line(b) for b in body)])


def to_json(rows, crba, info, check, args) -> dict:
    return {
        "schema": "bicycle-xval-benchmarks/1",
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "quick": args.quick,
        "seed": SEED,
        "machine": info,
        "pinocchio_check": check,
        "crba_seconds": crba,
        "results": [{"key": r.key, "quantity": r.quantity.strip(), "value": r.value, "unit": r.unit,
                     "target": r.target, "within_target": r.within,
                     "ratio_to_crba": (r.value / crba) if r.unit == "s" and r.value is not None else None,
                     "details": r.details} for r in rows],
    }


def mismatch_banner(check: dict) -> str:
    return ("!" * 78 + "\n!!! PINOCCHIO DOES NOT MATCH THE REFERENCE MODEL: crba max rel. error "
            f"{check['mass_matrix_max_rel_err']:.3e}, rnea {check['rnea_max_rel_err']:.3e} "
            f"(tolerance {check['rtol']:.0e}).\n!!! The crba ratios below use a suspect yardstick; "
            "report this to the lead.\n" + "!" * 78)
