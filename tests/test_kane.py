"""The Kane engine (Moore's Whipple bicycle by sympy's KanesMethod) against the reference.

Two independent formulations: the thesis's Newton-Euler projection in its own coordinates
(generated C, KKT solve) and Moore's Kane equations in Moore's coordinates (z down, relative
wheel angles, dependent-speed elimination), joined only by the constant linear map of
`reference_model.moore` and the parameter map `engines.kane.moore_parameters`. Agreement to
round-off at arbitrary states is evidence for both and for the maps.

Tolerances: every term is a straight-line evaluation of ~10^3..10^4 flops on both sides, so
they agree to a few hundred ulps: 1e-12 relative to the largest entry (measured worst 8e-16
on 1000 random states). The constrained accelerations go through two different linear solves
(5x5 elimination plus 3x3 reduced system versus the 13x13 KKT), each losing
cond ~ 1e2..1e4 ulps: 1e-10 relative to the largest acceleration (measured worst 1.6e-11 per
state, steer up to +-1.55 rad).

The cold derivation (tens of seconds) happens at most once per machine and sympy version
(the disk cache) and once per process (`engines.kane.codegen.load` is cached).
"""

import numpy as np
import pytest
from hypothesis import given

from engines import CapabilityError, load_engine
from engines.kane import KaneEngine, moore_parameters
from engines.kane.derivation import MOORE_PARAMETERS
from reference_model import load_model

from strategies import states, torques

MODELS = ("thesis-disc", "benchmark")
TERM_TOL = 1e-12      # straight-line code on both sides: round-off (see the module docstring)
ACCEL_TOL = 1e-10     # two different linear solves (see the module docstring)


@pytest.fixture(scope="module")
def pairs():
    out = {}
    for name in MODELS:
        model = load_model(name)
        out[name] = (load_engine("reference", model), KaneEngine(model))
    return out


def _rel(a, b):
    """Error relative to the largest reference entry, floored at 1 (SI unit: kg m^2, N m,
    m/s^2...): at a state where a term vanishes (upright, at rest) both sides are round-off
    of size 1e-16 and relative to 0 would be meaningless."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1.0))


@pytest.mark.parametrize("name", MODELS)
@given(state=states, T=torques)
def test_every_term_matches_the_reference(pairs, name, state, T):
    ref, kane = pairs[name]
    q, dq = state
    for term, args in (("mass_matrix", (q,)), ("generalized_forces", (q, dq, T)),
                       ("constraint_jacobian", (q,)), ("constraint_bias", (q, dq))):
        assert _rel(getattr(kane, term)(*args), getattr(ref, term)(*args)) < TERM_TOL, term


@pytest.mark.parametrize("name", MODELS)
@given(state=states, T=torques)
def test_constrained_accelerations_match_the_reference(pairs, name, state, T):
    ref, kane = pairs[name]
    q, dq = state
    assert _rel(kane.forward_acceleration(q, dq, T), ref.forward_acceleration(q, dq, T)) < ACCEL_TOL


@pytest.mark.parametrize("name", MODELS)
def test_batches_equal_single_states_and_satisfy_the_constraints(pairs, name):
    """A batch gives each state's own answer; the accelerations satisfy D ddq + dD dq = 0."""
    _, kane = pairs[name]
    rng = np.random.default_rng(7)
    q = rng.uniform(-1, 1, (6, 8))
    dq = rng.uniform(-5, 5, (6, 8))
    T = rng.uniform(-5, 5, (6, 3))
    ddq = kane.forward_acceleration(q, dq, T)
    assert ddq.shape == (6, 8) and kane.mass_matrix(q).shape == (6, 8, 8)
    assert np.allclose(ddq[3], kane.forward_acceleration(q[3], dq[3], T[3]), rtol=0, atol=1e-12)
    D, b = kane.constraint_jacobian(q), kane.constraint_bias(q, dq)
    residual = np.einsum("nij,nj->ni", D, ddq) + b
    assert np.max(np.abs(residual)) < 1e-10 * np.max(np.abs(ddq))


def test_a_wrong_inertia_product_sign_is_caught(pairs, monkeypatch):
    """The planted bug of the parameter map (the frame's xz product without its sign flip)
    moves M far beyond the tolerance: the comparison above can fail."""
    ref, kane = pairs["benchmark"]
    bad = KaneEngine(kane.model)
    bad.p = bad.p.copy()
    bad.p[MOORE_PARAMETERS.index("ICxz")] *= -1
    q = np.array([0.3, -0.2, 0.4, 0.5, 1.0, -0.3, 0.7, 0.2])
    assert _rel(bad.mass_matrix(q), ref.mass_matrix(q)) > 1e-4
    assert _rel(kane.mass_matrix(q), ref.mass_matrix(q)) < TERM_TOL


def test_thesis_contact_is_refused_with_the_reason(thesis):
    with pytest.raises(CapabilityError, match="disc's lowest point"):
        KaneEngine(thesis)


def test_parameter_map_is_moore_geometry(disc):
    """d1..l4 from the thesis's geometry as written in reference_model.moore's docstring."""
    p = disc.params
    m = dict(zip(MOORE_PARAMETERS, moore_parameters(p)))
    assert m["d2"] == -(p.za + p.z5) and m["l4"] == p.z5 - p.dz4 and m["ICxz"] == -p.I3xz
