"""SymBRiM's crown study prepares the toroidal variant (engines/symbrim/engine.py
`_prepare_torus`, the study's ``prepare``), checked without deriving it: the code loader is
replaced by a recorder. ~0.1 s (the derivation itself is the slow tests' and the report's)."""

from __future__ import annotations

from engines.symbrim import codegen
from engines.symbrim.engine import CROWN_STUDY


def test_the_crown_study_prepares_the_toroidal_code_once(monkeypatch):
    """The study's values other than 0 run the toroidal tyre, whose generated code is a second
    derivation; its prepare step (run once before workers fork) must ask the loader for that
    variant, front_crown=True, and nothing else. Planted: front_crown False or None (the
    knife-edge code prepared, the torus then derived cold in every worker)."""
    asked = []
    monkeypatch.setattr(codegen, "load", lambda **kw: asked.append(kw))
    CROWN_STUDY.prepare()
    assert asked == [{"front_crown": True}]
