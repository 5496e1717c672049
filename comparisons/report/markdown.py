"""report.md from a `ComparisonResult`: the verdict first, then failures (if any) and the
thesis's claims, then the summary table, then every section's details.

How to read each section and verdict: docs/report.md.
"""

from __future__ import annotations

from ..stages.results import Figure, Heading, Section, Table, Text, num


def cell(text) -> str:
    """Text safe inside a markdown table cell (pipes escaped, one line)."""
    return " ".join(str(text).split()).replace("|", "\\|")


def table(header, rows, note: str = "") -> list[str]:
    out = ["| " + " | ".join(cell(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    out += ["| " + " | ".join(cell(c) for c in r) + " |" for r in rows]
    if note:
        out += ["", note]
    return out + [""]


def _blocks(section: Section, level: int) -> list[str]:
    out = [f"{'#' * level} {section.title}", ""]
    for b in section.blocks:
        if isinstance(b, Text):
            out += [b.text, ""]
        elif isinstance(b, Heading):
            out += [f"{'#' * (level + 1)} {b.text}", ""]
        elif isinstance(b, Table):
            out += table(b.header, b.rows, b.note)
        elif isinstance(b, Figure):
            out += [f"![{b.caption or b.name[:-4]}](figures/{b.name})", ""]
    return out


_FIGURES_SAID = {
    "failing": "drawn only for the sections where a comparison failed (`--figures failing`, "
               "the default of `--quick`); `--figures all` draws every one.",
    "none": "none drawn (`--figures none`)."}


def _verdict(summary: dict) -> list[str]:
    comps = summary["comparisons"]
    n_fail = sum(c["passed"] is False for c in comps)
    n_judged = sum(c["passed"] is not None for c in comps)
    faults = summary["faults"]
    verdicts: dict[str, int] = {}
    for c in summary["claims"]:
        verdicts[c["verdict"]] = verdicts.get(c["verdict"], 0) + 1
    dropped = summary.get("dropped_engines", [])
    if summary["passed"]:
        head = "All judged comparisons are within tolerance."
    elif n_fail:
        head = f"Something is out of tolerance: {n_fail} comparison(s) failed."
    elif dropped:
        head = f"{len(dropped)} engine(s) could not be run (below); the rest agree."
    else:
        head = "Something failed (below)."
    unobservable = sum(f["verdict"] == "not observable" for f in faults)
    not_run = sum(f['verdict'] == 'not run' for f in faults)
    return [
        f"**{head}**", "",
        *[f"- **Dropped**: engine `{d['engine']}`: {d['reason']}" for d in dropped],
        f"- Engines: {', '.join(summary['engines'])}"
        f"{' (quick subset of scenarios and states)' if summary.get('quick') else ''}.",
        *([f"- Figures: {_FIGURES_SAID[summary['figures']]}"]
          if summary.get("figures", "all") != "all" else []),
        f"- {len(comps)} comparisons, {n_judged} judged against a tolerance, {n_fail} failed; "
        f"the rest are reported (the row says who judges them).",
        (f"- Fault injection: {len(faults)} fault-engine pairs, "
         f"{sum(f['verdict'] == 'localized' for f in faults)} detected and localized"
         + (f", {unobservable} not observable by the engine" if unobservable else "")
         + (f", {not_run} not run (the engine cannot represent that bicycle: a declared "
            "limitation)" if not_run else "") + "."
         if "engine_sections" not in summary else
         f"- Fault injection and the engine sections: {summary['engine_sections']}."),
        "- The thesis's claims: " + (", ".join(f"{v} {k}" for k, v in sorted(verdicts.items()))
                                     or "none judged") + ".",
        *_models(summary),
        "", "How to read this report: `docs/report.md` in the repository. Tolerances and their "
        "reasons: `comparisons/judgments/tolerances.toml`. Machine-readable: `summary.json`.", ""]


def _models(summary: dict) -> list[str]:
    """The verdict block's lines on the models of a --model / --scenario-file run (none for the
    thesis's own run): name, source, contact, and every model's warnings, said here."""
    out = []
    for m in summary.get("models", []):
        out.append(f"- Model {m['name']}: {m['source']}, contact {m['contact']}"
                   + (", **with warnings** (below)." if m["warnings"] else "."))
        out += [f"  - **Warning** ({m['name']}): {w}" for w in m["warnings"]]
    if summary.get("not_run"):
        out.append(f"- Not run: {len(summary['not_run'])} scenario-model pair(s), each with its "
                   "reason in 'Models of this run'.")
    return out


def _failures(summary: dict, localization) -> list[str]:
    bad = [c for c in summary["comparisons"] if c["passed"] is False]
    bad_checks = [c for c in summary["checks"] if not c["passed"]]
    bad_faults = [f for f in summary["faults"]
                  if f["verdict"] not in ("localized", "not observable", "not run")]
    if not (bad or bad_checks or bad_faults or localization):
        return []
    out = ["## Failures", ""]
    if bad:
        out += table(("quantity", "scenario", "engines", "error", "tolerance", "where"),
                     [(c["quantity"], c["scenario"], " vs ".join(c["engines"]),
                       num(c["max_error"]), num(c["tolerance"]), c.get("localized_to", "-"))
                      for c in bad])
    out += [f"- analytic check failed: {c['check']} ({c['evidence']})" for c in bad_checks]
    out += [f"- fault {f['fault']} on {f['engine']}: {f['verdict']} ({f['evidence']})"
            for f in bad_faults]
    for title, text in localization:
        out += [f"### Where the engines disagree: {title}", ""]
        out += [f"- {line.strip()}" for line in text.splitlines() if line.strip()] + [""]
    return out


def _claims(summary: dict) -> list[str]:
    if not summary["claims"]:
        return []
    return ["## The thesis's claims, engine by engine", "",
            "Each claim is the thesis's sentence; the evidence gives the numbers and the "
            "threshold that turned them into the verdict.", ""] + table(
        ("claim", "engine", "verdict", "evidence"),
        [(c["claim"], c["engine"], c["verdict"], c["evidence"]) for c in summary["claims"]])


def _summary_table(summary: dict) -> list[str]:
    rows = []
    for r in summary["summary_table"]:
        tol = r["tolerance"] if isinstance(r["tolerance"], str) else num(r["tolerance"])
        verdict = r["verdict"] + (f": {r['reason']}" if r.get("reason") else "")
        rows.append((r["quantity"], r["engines"], r["n"], num(r["max_error"]), tol, verdict,
                     r["worst"]))
    return ["## Summary: quantity x engine pair", ""] + table(
        ("quantity", "engines", "comparisons", "max error", "tolerance", "verdict", "worst at"),
        rows, note="Errors are relative to the scale each tolerance names (absolute for "
                   "trajectories, in rad or m, and for constraint residuals, in m or m/s).")


def _reference(summary: dict) -> list[str]:
    out = ["## Scenarios on the reference model", ""]
    out += table(("scenario", "kind", "status", "t_end [s]", "max abs C [m, m/s]"),
                 [(r["scenario"], r["kind"], r["status"], r["t_end"], r["max_abs_C"])
                  for r in summary["scenarios"]])
    out += ["Engine runs:", ""] + table(
        ("scenario", "engine", "status", "end [s]", "message"),
        [(r["scenario"], r["engine"], r["status"], f"{r['t_end']:.3f}", r["message"])
         for r in summary["engine_runs"]])
    if summary["initial_corrections"]:
        out += ["Initial states: every engine starts from the same projected state (beta from "
                "[rD]_z = 0, dependent rates from D dq = 0). Corrections applied:", ""]
        out += [f"- {name}: {text}" for name, text in summary["initial_corrections"].items()] + [""]
    for c in summary["checks"]:
        out += [f"Analytic check: {c['check']}: {'holds' if c['passed'] else 'FAILS'} "
                f"({c['evidence']}).", ""]
    return out


def _tail(summary: dict) -> list[str]:
    out = []
    if summary["expected_differences"]:
        out += ["## Expected differences (declared in the scenario registry)", ""]
        out += [f"- {e['scenario']}, {e['quantity']}, {e['engines']}: expected '{e['expected']}' "
                f"because {e['reason']}" for e in summary["expected_differences"]] + [""]
    env = summary["environment"]
    out += ["## Environment", "",
            f"Machine: {env['machine']['cpu']}, {env['machine']['cores']} cores, "
            f"{env['machine']['platform']}.", "",
            "Packages: " + ", ".join(f"{k} {v}" for k, v in env["packages"].items()) + ".", "",
            "Solver settings:", ""]
    out += [f"- {k}: {v}" for k, v in env["solvers"].items()]
    out += ["", "Steps: " + ", ".join(f"{k} = {v}" for k, v in env["steps"].items()) + ".", "",
            "Run times are in `timings.json` (kept apart so the report is identical run to run)."]
    return out


def render(result) -> str:
    """The whole report.md of a `comparisons.stages.pipeline.ComparisonResult`."""
    s = result.summary
    lines = ["# bicycle-xval report", ""]
    lines += _verdict(s) + _failures(s, result.localization) + _claims(s) + _summary_table(s)
    lines += _reference(s)
    for sec in result.sections:
        lines += _blocks(sec, 2)
    lines += _tail(s)
    return "\n".join(lines).rstrip("\n") + "\n"
