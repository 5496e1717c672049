"""The thesis's stability claims on the soft-contact engines' runs, side by side.

A soft-contact engine cannot run the thesis's fork-axis front contact, so its stability claims
are judged on its runs of the same scenarios with the disc contact (``thesis-disc``, the
engine's defaults). The reference's runs on ``thesis-disc`` are made once (one task, not one per
engine) and shown beside every soft-contact engine's in one table: the claims as rows, the
reference and each engine as columns. The engines' verdicts replace their ``not assessed``
entries in the claims table, their evidence starting "on thesis-disc". A soft contact is a
declared model difference: a claim's verdict says what the engine's bicycle does, never a
failure of the ideal-rolling tolerances (the claims carry no pass or fail).

    ref = reference_claims_on_disc(("stability-psid0", ...))        # a stage
    disc = claims_on_disc("mujoco", ("stability-psid0", ...))       # a stage, per engine
    section = claims_section(ref, [disc])
    claims = merge_claims(claims, disc)
"""

from __future__ import annotations

from dataclasses import dataclass

from engines import load_engine
from reference_model import load_model
from reference_model.scenarios import SCENARIOS

from .results import Section

__all__ = ["DiscClaims", "claims_on_disc", "claims_section", "merge_claims", "on_disc",
           "reference_claims_on_disc"]

MODEL = "thesis-disc"


def on_disc(label: str) -> str:
    """The prefix of a claim's evidence judged on the engine's thesis-disc run."""
    return (f"on thesis-disc ({label} has no thesis fork-axis contact; the claim judged on its "
            "run of the same scenario with the disc contact): ")


@dataclass(frozen=True)
class DiscClaims:
    """The stability claims judged on one engine's thesis-disc runs: ``claims`` the
    `judge_claims` entries of ``engine`` (evidence as judged, without the prefix)."""

    engine: str
    label: str
    claims: tuple[dict, ...]


def _judged(name: str, engine, stab: tuple[str, ...]) -> tuple[dict, ...]:
    from engines.runs import run_scenario

    from ..judgments.claims import judge_claims
    model = load_model(MODEL)
    runs = {(name, n): run_scenario(name, engine, model, SCENARIOS[n], ("forward",))
            for n in stab}
    return tuple(c for c in judge_claims(runs, [name], model, stab)
                 if c["claim_id"].startswith("stability-"))


def _stability(names) -> tuple[str, ...]:
    return tuple(n for n in names if n.startswith("stability-"))


def claims_on_disc(spec: str, names: tuple[str, ...]) -> DiscClaims:
    """The stability scenarios among ``names`` on the engine ``spec`` (defaults) on
    thesis-disc, and the claims that need them judged (`judge_claims`). A stage."""
    from engines.facts import engine_facts
    facts = engine_facts(spec)
    engine = load_engine(spec, load_model(MODEL))
    return DiscClaims(facts.name, facts.label, _judged(facts.name, engine, _stability(names)))


def reference_claims_on_disc(names: tuple[str, ...]) -> DiscClaims:
    """The same on the reference (DOP853, the scenario's Baumgarte constraint handling), once
    for every soft-contact engine. A stage."""
    engine = load_engine("reference", load_model(MODEL))
    return DiscClaims("reference", "reference", _judged("reference", engine, _stability(names)))


def claims_section(reference: DiscClaims | None, engines: list[DiscClaims]) -> Section:
    """One table: each claim judged, a column for the reference (when its runs were made) and
    one per engine of ``engines``, in their order."""
    labels = [d.label for d in engines]
    who = " and ".join(x for x in (", ".join(labels[:-1]), labels[-1]) if x) if labels else "-"
    sec = Section("The thesis's stability claims on thesis-disc: the soft-contact engines")
    sec.text(f"{who} cannot run the thesis's fork-axis contact, so the stability claims are "
             "judged on each engine's runs of the same scenarios with the disc contact "
             "(`thesis-disc`, the engine's defaults), beside the reference's runs on "
             "`thesis-disc` (DOP853, the scenario's Baumgarte constraint handling). A soft "
             "contact is a declared model difference: where the steer whips a wheel off the "
             "ground the runs leave the reference (see the contact study), and the verdicts say "
             "what each engine's bicycle does, not how closely it follows the reference; none "
             "is a failure of the ideal-rolling tolerances.")
    columns = ([reference] if reference is not None else []) + list(engines)
    ids = list(dict.fromkeys(c["claim_id"] for d in columns for c in d.claims))
    text = {c["claim_id"]: c["claim"] for d in columns for c in d.claims}
    cell = {(d.engine, c["claim_id"]): f"{c['verdict']}: {c['evidence']}"
            for d in columns for c in d.claims}
    sec.table(("claim", *(f"{d.engine} thesis-disc" for d in columns)),
              [(text[i], *(cell.get((d.engine, i), "-") for d in columns)) for i in ids])
    return sec


def merge_claims(claims: list[dict], disc: DiscClaims) -> list[dict]:
    """``claims`` with ``disc.engine``'s entries replaced by their thesis-disc judgments where
    made (evidence prefixed `on_disc`); every other engine's entries untouched."""
    new = {c["claim_id"]: dict(c, evidence=on_disc(disc.label) + c["evidence"])
           for c in disc.claims}
    return [new.get(c["claim_id"], c) if c["engine"] == disc.engine else c for c in claims]
