"""The report of `bicycle-xval run`: its machine-readable summary, the engine sections, the
convergence verdicts, and determinism."""

import json

import pytest

from comparisons.cli import main


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    assert main(["run", "--quick", "--out", str(out)]) == 0
    return out, json.loads((out / "summary.json").read_text())


def test_summary_comparisons_carry_the_contract_keys(quick_report):
    _, summary = quick_report
    assert summary["engines"] == ["reference", "pinocchio", "exudyn"]
    assert summary["comparisons"], "no engine comparison in the summary"
    for c in summary["comparisons"]:
        assert {"quantity", "scenario", "engines", "max_error", "tolerance", "passed"} <= set(c)


def test_pinocchio_terms_all_pass_and_name_their_worst_entry(quick_report):
    _, summary = quick_report
    terms = [c for c in summary["comparisons"] if c["engines"] == ["reference", "pinocchio"]]
    assert len(terms) == 14  # 7 quantities x 2 contact models
    assert all(c["passed"] and c["max_error"] <= c["tolerance"] for c in terms)
    assert all(c["localized_to"] for c in terms)


def test_convergence_verdicts_separate_integrator_from_model(quick_report):
    """Matched models converge at order ~2; disc contact against the thesis contact is the
    declared model difference (expected, so it passes)."""
    _, summary = quick_report
    conv = {tuple(c["engines"]) + (c["model"],): c for c in summary["comparisons"]
            if c["quantity"] == "convergence order"}
    tree = conv[("reference", "exudyn-tree-disc", "thesis-disc")]
    assert tree["verdict"] == "converges" and 1.5 <= tree["order"] <= 2.5
    diff = conv[("reference", "exudyn-tree-disc", "thesis")]
    assert diff["verdict"] == "model difference" and diff["expected"] == "model difference"
    assert diff["passed"] is True


def test_report_links_every_figure_it_wrote(quick_report):
    out, _ = quick_report
    text = (out / "report.md").read_text()
    for png in (out / "figures").glob("*.png"):
        assert f"figures/{png.name}" in text
    assert "Initial state" in text and "beta corrected by" in text


def test_same_inputs_give_the_same_numbers(quick_report, tmp_path):
    """Determinism: a second run of the reference and Pinocchio stages gives identical numbers."""
    _, first = quick_report
    assert main(["run", "--quick", "--engines", "reference,pinocchio", "--out", str(tmp_path)]) == 0
    second = json.loads((tmp_path / "summary.json").read_text())
    pick = lambda s: [c for c in s["comparisons"] if "pinocchio" in c["engines"]]  # noqa: E731
    assert pick(first) == pick(second)
    assert first["checks"] == second["checks"] and first["scenarios"] == second["scenarios"]


def test_unknown_engine_is_a_usage_error(tmp_path, capsys):
    assert main(["run", "--engines", "reference,bullet", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown engine 'bullet'" in err[0]
