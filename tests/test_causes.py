"""The candidate causes of comparisons/judgments/causes.py, each built from the model's terms
and checked against an independent fact: gravity is linear in g and in each mass (so a
change and its double move Qgrav in the ratio 1:2, and the central difference in g is Qgrav/g
exactly), the chain of rotations is the thesis's (standard rotation matrices; the angular
velocity a second way, from the rotation matrices' own time derivative), a rider torque on
the frame about its y axis is a generalized force on the pitch beta alone at upright, and the
discrete causes' effects are the changes written out (-2T, -T, columns swapped). The
localization that ranks them is tests/test_diagnose_planted.py (slow fixtures). ~0.3 s."""

import math

import numpy as np
import pytest

from comparisons.judgments.causes import (Cause, body_angular_jacobians, changed_terms,
                                          coordinate_swap_causes, parameter_evaluator,
                                          parameter_term_causes, table1_causes, table1_of,
                                          term_sign_causes, torque_causes)
from comparisons.judgments.term_checks import TERMS, model_terms
from comparisons.judgments.terms import States, random_states
from reference_model import COORDINATES, TORQUE_NAMES, load_model

STATES = random_states(3, seed=2)


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def test_an_effect_on_one_source_is_preferred_to_the_terms_own():
    a, b = np.ones(2), np.zeros(2)
    c = Cause("x", "x", None, "structural", True, {("Qv", None): a, ("Qv", "F"): b})
    assert c.effect("Qv", "F") is b and c.effect("Qv", "") is a and c.effect("M", "") is None


def test_changed_terms_is_linear_in_a_mass_and_refuses_an_invalid_one(thesis):
    m3 = thesis.params.m3
    one = changed_terms(thesis, STATES, model_terms, ["Qgrav", "M"], m3=2 * m3)
    two = changed_terms(thesis, STATES, model_terms, ["Qgrav", "M"], m3=3 * m3)
    assert set(one) == {("Qgrav", None), ("M", None)}
    # Qgrav is linear in each mass: +2 m3 moves it exactly twice as far as +m3 (round-off)
    np.testing.assert_allclose(two[("Qgrav", None)], 2 * one[("Qgrav", None)], rtol=1e-9,
                               atol=1e-9)
    assert np.abs(one[("Qgrav", None)]).max() > 1.0
    assert changed_terms(thesis, STATES, model_terms, ["Qgrav"], m3=-1.0) is None
    ev = parameter_evaluator(thesis, STATES, model_terms, ["Qgrav", "M"], "m3")
    got = ev(m3)
    for k in one:
        np.testing.assert_array_equal(got[k], one[k])
    only = parameter_evaluator(thesis, STATES, model_terms, ["Qgrav", "M"], "m3", only="M")(m3)
    assert set(only) == {("M", None)}


def test_a_parameter_reaching_several_terms_gives_one_cause_per_term(thesis):
    z = np.zeros((3, 8))
    effects = {"m3": {"Qgrav": np.ones((3, 8)), "M": np.ones((3, 8, 8)), "D": np.zeros((3, 5, 8))},
               "g": {"Qgrav": np.ones((3, 8)), "M": np.zeros((3, 8, 8))},   # one term: none
               "unknown": {"Qgrav": z, "M": z}}
    units = {"m3": "kg", "g": "m/s^2"}
    causes = parameter_term_causes(effects, thesis, units, lambda n: 3 if n == "m3" else None)
    assert [c.id for c in causes] == ["m3@Qgrav", "m3@M"]
    c = causes[1]
    assert (c.label, c.body, c.kind, c.fixed, c.unit, c.value) == (
        "m3 in M only", 3, "term-parameter", False, "kg", thesis.params.m3)
    assert list(c.effects) == [("M", None)] and c.evaluate is None
    with_eval = parameter_term_causes(effects, thesis, units, lambda n: None, STATES, model_terms)
    step = with_eval[0].evaluate(1.0)
    assert set(step) == {("Qgrav", None)}
    np.testing.assert_array_equal(step[("Qgrav", None)], changed_terms(
        thesis, STATES, model_terms, ["Qgrav"], m3=thesis.params.m3 + 1.0)[("Qgrav", None)])


def test_a_terms_sign_and_absence_in_every_copy_and_in_one():
    ref = {"Qgrav": np.full((2, 8), 3.0), "M": np.full((2, 8, 8), 5.0),
           "Qv": np.full((2, 8), 7.0)}
    causes = term_sign_causes(ref, {"Qgrav": ("", "F"), "M": ("",), "Qv": ("ID", "F")})
    got = {c.id: c for c in causes}
    assert list(got) == [
        "sign:Qgrav", "missing:Qgrav", "sign:Qgrav[own]", "missing:Qgrav[own]",
        "sign:Qgrav[F]", "missing:Qgrav[F]", "sign:M", "missing:M",
        "sign:Qv", "missing:Qv", "sign:Qv[ID]", "missing:Qv[ID]", "sign:Qv[F]", "missing:Qv[F]"]
    assert got["sign:Qgrav"].label == "sign of Qgrav flipped"
    assert got["missing:Qgrav[own]"].label == "Qgrav missing in the engine's own gravity()"
    assert got["sign:Qgrav[F]"].label == "sign of Qgrav flipped in generalized_forces"
    assert got["sign:Qv[ID]"].label == "sign of Qv flipped in inverse_dynamics"
    for c in causes:
        assert (c.kind, c.fixed, c.body) == ("structural", True, None)
    np.testing.assert_array_equal(got["sign:Qgrav[F]"].effects[("Qgrav", "F")], -6.0)
    np.testing.assert_array_equal(got["missing:M"].effects[("M", None)], -5.0)
    np.testing.assert_array_equal(got["missing:Qgrav[own]"].effects[("Qgrav", "")], -3.0)


def _Rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _Rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_the_bodies_rotations_are_the_thesis_chain_and_their_angular_velocities():
    q = STATES.q
    A, J = body_angular_jacobians(q)
    for n in range(len(q)):
        yaw, lean, psi, beta, gamma, eps = q[n, 2], q[n, 3], q[n, 4], q[n, 5], q[n, 6], q[n, 7]
        frame = _Rz(yaw) @ _Rx(lean) @ _Ry(beta)
        np.testing.assert_allclose(A[2][n], _Rz(yaw) @ _Rx(lean) @ _Ry(psi), atol=1e-14)
        np.testing.assert_allclose(A[3][n], frame, atol=1e-14)
        np.testing.assert_allclose(A[4][n], frame @ _Rz(gamma), atol=1e-14)
        np.testing.assert_allclose(A[5][n], frame @ _Rz(gamma) @ _Ry(eps), atol=1e-14)
    # omega a second way: skew(omega) = dA/dt A^T, dA/dt by central differences along dq
    dq, h = STATES.dq, 1e-6
    Ap, _ = body_angular_jacobians(q + h * dq)
    Am, _ = body_angular_jacobians(q - h * dq)
    for b in (2, 3, 4, 5):
        W = (Ap[b] - Am[b]) / (2 * h) @ np.swapaxes(A[b], 1, 2)
        omega = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], axis=1)
        # 1e-6: the h^2 truncation (rates ~20 rad/s: ~1e-9) and the 1e-10/h round-off
        np.testing.assert_allclose(np.einsum("nik,nk->ni", J[b], dq), omega, atol=1e-6)


def test_the_rider_torque_causes(thesis):
    q = STATES.q
    S = thesis.S(q)
    causes = torque_causes(S, q)
    got = {c.id: c for c in causes}
    assert len(causes) == 3 + 3 * 3 + 3
    assert [c.id for c in causes if c.id.startswith("swap")] == [
        "swap:S[Mdir,Mped]", "swap:S[Mdir,Mvue]", "swap:S[Mped,Mvue]"]
    k = TORQUE_NAMES.index
    sign = got["sign:S[Mped]"]
    assert (sign.body, sign.label) == (2, "rider torque Mped applied with the wrong sign")
    flipped = S + sign.effects[("S", None)]
    np.testing.assert_allclose(flipped[:, :, k("Mped")], -S[:, :, k("Mped")], atol=1e-12)
    np.testing.assert_array_equal(flipped[:, :, k("Mdir")], S[:, :, k("Mdir")])
    sw = S + got["swap:S[Mdir,Mvue]"].effects[("S", None)]
    np.testing.assert_allclose(sw[:, :, k("Mdir")], S[:, :, k("Mvue")], atol=1e-12)
    np.testing.assert_allclose(sw[:, :, k("Mvue")], S[:, :, k("Mdir")], atol=1e-12)
    assert "body:S[Mped]->2" not in got       # its own body is not another one
    c = got["body:S[Mped]->3"]
    assert c.body == 3 and c.label == ("rider torque Mped applied to the frame+rider instead "
                                       "of the rear wheel")
    # at upright (q = 0) the frame's y axis is the global y axis, which only the pitch beta
    # turns about: Mped on the frame is a unit generalized force on beta and nothing else
    q0 = np.zeros((1, 8))
    S0 = thesis.S(q0)
    moved = S0 + next(c for c in torque_causes(S0, q0)
                      if c.id == "body:S[Mped]->3").effects[("S", None)]
    np.testing.assert_allclose(moved[0, :, k("Mped")], np.eye(8)[COORDINATES.index("beta")],
                               atol=1e-15)


def test_coordinate_swaps_name_the_terms_that_see_them():
    """T = xc + 2 yc and U = phi (made-up terms): swapping xc and yc changes T alone; xc and
    phi both; theta and psi neither."""
    def terms(model, s):
        return {"T": s.q[:, 0] + 2 * s.q[:, 1], "U": s.q[:, 2].copy()}
    ref = terms(None, STATES)
    causes = coordinate_swap_causes(terms, None, STATES, ref, ["T", "U"])
    ids = [c.id for c in causes]
    assert "swap:T:xc,yc" in ids and "swap:U:xc,yc" not in ids and "swap:all:xc,yc" not in ids
    assert {"swap:T:xc,phi", "swap:U:xc,phi", "swap:all:xc,phi"} <= set(ids)
    assert not any("theta,psi" in i for i in ids)
    c = next(c for c in causes if c.id == "swap:T:xc,yc")
    # (yc + 2 xc) - (xc + 2 yc) = xc - yc
    np.testing.assert_allclose(c.effects[("T", None)], STATES.q[:, 0] - STATES.q[:, 1],
                               atol=1e-12)
    assert c.label == "xc and yc swapped in the arguments of T" and c.fixed
    every = next(c for c in causes if c.id == "swap:all:xc,phi")
    assert set(every.effects) == {("T", None), ("U", None)}
    assert every.label == "xc and phi swapped in the state (every term)"
    assert isinstance(STATES, States)


def test_table1_inputs_as_causes(bench, thesis):
    causes = table1_causes(bench, STATES, model_terms, TERMS)
    ids = [c.id for c in causes]
    assert len(ids) == 26 + 4 and ids[-4:] == ["table1:c-sign", "table1:lam-deg2rad",
                                               "table1:lam-head-angle", "table1:lam-sign"]
    g = next(c for c in causes if c.id == "table1:g")
    assert (g.kind, g.fixed, g.unit, g.value, g.body) == ("table1", False, "m/s^2", 9.81, None)
    assert g.label == "Table 1's g (gravity)"
    base = model_terms(bench, STATES)
    # Qgrav is linear in g: its central difference is Qgrav / g exactly (round-off), and
    # nothing else depends on g
    np.testing.assert_allclose(g.effects[("Qgrav", None)], base["Qgrav"] / 9.81,
                               rtol=1e-6, atol=1e-6)
    assert np.abs(g.effects[("M", None)]).max() == 0.0
    np.testing.assert_allclose(g.evaluate(1.0)[("Qgrav", None)], base["Qgrav"] / 9.81,
                               rtol=1e-9, atol=1e-9)
    bodies = {c.id: c.body for c in causes}
    assert (bodies["table1:mR"], bodies["table1:xB"], bodies["table1:IHxz"], bodies["table1:rF"],
            bodies["table1:rR"], bodies["table1:IFyy"], bodies["table1:w"]) == (2, 3, 4, 5, 2,
                                                                                5, None)
    mr = next(c for c in causes if c.id == "table1:mR")
    assert (mr.unit, mr.label) == ("kg", "Table 1's mR (rear wheel mass)")
    slip = next(c for c in causes if c.id == "table1:c-sign")
    assert slip.fixed and slip.kind == "structural"
    assert table1_of(bench) is bench.params.benchmark
    assert table1_of(thesis) is None and table1_causes(thesis, STATES, model_terms, TERMS) == []
