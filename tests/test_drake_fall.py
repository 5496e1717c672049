"""Drake's forward run ends at a fall of the *lean* (engines/drake/run.py; docs/engines.md,
"### `simulate`": "fell": |theta| reached the fall limit, the final row the fall itself).

Found by the mutation tests of the run (tests/test_drake_run.py): the run read its fall test at
index 3 of the run plant's coordinates, where zc after yc puts the heading phi, not the lean:
a leaning bicycle never fell on Drake and a heading past the limit did. Expected values: the
reference engine's run of the same scenario (its fall time; Drake's compliant contact differs
from the rolling constraint by about 1 ms here, 5 ms allowed) and the contract's final row.
Cost: two Drake runs of 0.4 s and 0.05 s (about 0.5 s).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from engines.reference import ReferenceEngine
from reference_model import load_model
from reference_model.scenarios import get_scenario

pytest.importorskip("pydrake")

from engines.drake import DrakeEngine  # noqa: E402

THETA, PHI = 3, 2        # the lean's and the heading's index in the thesis's q
LIMIT = 0.3              # rad: the standing bicycle, leaned 0.196 rad, passes it at ~0.38 s


@pytest.fixture(scope="module")
def model():
    return load_model("thesis-disc")


@pytest.fixture(scope="module")
def engine(model):
    return DrakeEngine(model)


def test_a_leaning_bicycle_falls_when_its_lean_reaches_the_limit(engine, model):
    """stability-psid0 (standing still, leaned 0.196 rad) with a fall limit of 0.3 rad: status
    'fell' within 5 ms of the reference's fall, the final row at |theta| = the limit (the step
    that crossed it, interpolated: 1e-9) and every row before it below. Planted: the fall
    tested on the heading (the run never falls: 'completed')."""
    sc = dataclasses.replace(get_scenario("stability-psid0"), grid=(0.0, 0.01, 61))
    ref = ReferenceEngine(model).simulate(sc, fall_limit=LIMIT)
    run = engine.simulate(sc, fall_limit=LIMIT)
    assert ref.status == "fell"
    assert run.status == "fell", run.message
    assert abs(run.t_end - ref.t_end) < 5e-3
    assert abs(abs(run.q[-1, THETA]) - LIMIT) < 1e-9
    assert np.abs(run.q[:-1, THETA]).max() < LIMIT
    assert run.message == f"|theta| reached the fall limit {LIMIT:.4f} rad at t = {run.t_end:.6f} s"


def test_a_heading_past_the_limit_is_not_a_fall(engine):
    """The same bicycle rolling upright-ish (stability-psid10, lean 0.196 rad, well inside the
    limit) started on a heading of 0.5 rad, past the 0.3 rad limit: heading is not lean, so the
    50 ms run completes. Planted: the fall tested on the heading (it 'fell' at the first step)."""
    base = get_scenario("stability-psid10")
    q0 = list(base.q0)
    q0[PHI] = 0.5
    sc = dataclasses.replace(base, q0=tuple(q0), grid=(0.0, 0.01, 6))
    run = engine.simulate(sc, fall_limit=LIMIT)
    assert run.status == "completed", run.message
    assert np.abs(run.q[:, THETA]).max() < LIMIT
