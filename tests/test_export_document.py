"""The JSON export against its documented format (docs/model.md, "The JSON export"): the
page's document is the contract a tool reading the file is written to, so every key, every
fixed text and where each parameter goes must be as the page has them, on the thesis model
(fork-axis contact, equal wheels) and on the benchmark (disc contact, unequal wheels, an
off-axis fork CoM, its provenance a Table 1)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from reference_model import load_model
from reference_model.exports.description import json_text, model_description
from reference_model.parameters.schema import PARAMETER_NAMES

DOC = Path(__file__).resolve().parents[1] / "docs" / "model.md"


def _documented():
    text = DOC.read_text("utf-8")
    section = text.split("## The JSON export", 1)[1].split("\n## ", 1)[0]
    skeleton, fronts = (json.loads(b) for b in re.findall(r"```json\n(.*?)```", section, re.S))
    return skeleton, fronts


def _match(doc, got, p, fronts, where="$"):
    """Every difference between the documented value and the export's, as 'path: why'."""
    if isinstance(doc, str) and doc.startswith("<") and doc.endswith(">"):
        kind = doc[1:-1]
        if kind == "number":
            ok = isinstance(got, (int, float)) and not isinstance(got, bool)
        elif kind == "text":
            ok = isinstance(got, str)
        elif kind == "object":
            ok = isinstance(got, dict)
        elif kind == "front contact text":
            ok = got == fronts[p.contact]
        else:
            assert kind in PARAMETER_NAMES, f"{where}: the page names no parameter {kind!r}"
            ok = not isinstance(got, bool) and got == float(getattr(p, kind))
        return [] if ok else [f"{where}: {got!r} is not {doc}"]
    if isinstance(doc, dict):
        if not isinstance(got, dict) or set(doc) != set(got):
            return [f"{where}: keys {sorted(got) if isinstance(got, dict) else got!r}, "
                    f"documented {sorted(doc)}"]
        return [e for k in doc for e in _match(doc[k], got[k], p, fronts, f"{where}.{k}")]
    if isinstance(doc, list):
        if not isinstance(got, list) or len(doc) != len(got):
            return [f"{where}: {got!r}, documented {len(doc)} entries"]
        return [e for i, (d, g) in enumerate(zip(doc, got))
                for e in _match(d, g, p, fronts, f"{where}[{i}]")]
    same = got == doc and type(got) is type(doc) or (
        isinstance(doc, float) and isinstance(got, float) and got == doc)
    return [] if same else [f"{where}: {got!r}, documented {doc!r}"]


@pytest.mark.parametrize("name", ["thesis", "benchmark"])
def test_the_export_is_the_documented_document(name):
    skeleton, fronts = _documented()
    p = load_model(name).params
    got = json.loads(json_text(p))            # as a reader of the file gets it
    problems = _match(skeleton, got, p, fronts)
    assert not problems, "\n".join(problems)


def test_the_parameters_and_the_name_are_the_models():
    p = load_model("benchmark").params
    d = model_description(p)
    assert d["parameters"] == {n: float(getattr(p, n)) for n in PARAMETER_NAMES}
    assert d["model"] == {"name": "benchmark", "contact": "disc", "source": p.source}
    assert d["provenance"]["benchmark"]["lam"] == pytest.approx(0.3141592653589793)
    assert d["provenance"]["triangle"] == "strict"


def test_the_matcher_sees_a_moved_parameter_and_a_changed_text():
    """The check itself: a fork CoM put on the frame's entry, a wheel axle renamed and a key
    dropped are each reported (so the test above can fail)."""
    skeleton, fronts = _documented()
    p = load_model("benchmark").params
    got = json.loads(json_text(p))
    got["bodies"][1]["com"][0] = p.dx4
    got["wheels"]["front"]["axle"] = "body z"
    del got["loads"]["drag"]["unit"]
    problems = _match(skeleton, got, p, fronts)
    assert len(problems) == 3, problems
    assert problems[0].startswith("$.bodies[1].com[0]")


def test_provenance_values_are_made_plain_json():
    """What a parameter file carries besides the parameters goes out as JSON's own types:
    numbers, text, booleans and null as they are, a dataclass (Table 1) and a table as objects
    with text keys, a numpy number as a float, anything else as its text."""
    import dataclasses as dc
    from pathlib import PurePosixPath

    import numpy as np

    from reference_model.exports.description import _plain

    @dc.dataclass
    class Row:
        w: float
        name: str

    for v in (None, "x", True, 3, 2.5):
        assert _plain(v) is v
    assert _plain(Row(1.02, "b")) == {"w": 1.02, "name": "b"}
    nested = _plain({1: np.float64(0.5), "t": {"row": Row(0.3, "c")}})
    assert nested == {"1": 0.5, "t": {"row": {"w": 0.3, "name": "c"}}}    # float64 is a float
    assert type(_plain(np.float32(0.25))) is float and _plain(np.float32(0.25)) == 0.25
    assert _plain(PurePosixPath("/a/b.toml")) == "/a/b.toml"
