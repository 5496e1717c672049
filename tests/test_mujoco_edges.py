"""The MuJoCo adapter's edges (engines/mujoco/engine.py), issue 24: every option an engine
takes reaches the MJCF MuJoCo compiles (read back from MuJoCo's own compiled model, not from
our text), the run's model is built with the settings asked for, and the compiler's refusals
are told apart (a measured inertia MuJoCo cannot hold is a declared limitation, anything else
an engine error) with MuJoCo's message in one line. Each test names the planted bugs
(mutmut's survivors of its first run) it was seen failing on."""

import numpy as np
import pytest

from reference_model import load_model
from reference_model.exports.mjcf import MjcfSettings

mujoco = pytest.importorskip("mujoco")

from engines.base import EngineError, UnsupportedModel  # noqa: E402
from engines.mujoco import MujocoEngine  # noqa: E402
from engines.mujoco.engine import compile_mjcf  # noqa: E402

OPTIONS = dict(timestep=2e-4, integrator="RK4", solref=(4e-4, 0.9), solimp=(0.9, 0.95, 2e-3, 0.4, 3.0),
               friction=1.5, cone="pyramidal", condim=4, noslip_iterations=3, solver="CG",
               iterations=57, tolerance=1e-9, wheel_half_width=2e-6)


@pytest.fixture(scope="module")
def disc():
    return load_model("thesis-disc")


def test_every_option_reaches_the_compiled_model(disc):
    """Each option set away from its default: the engine's settings hold it, and MuJoCo's
    compiled run model (its `opt` and the tyre geoms) carries it. Planted: any option left out
    of the settings (its default used), the MJCF written without the settings."""
    eng = MujocoEngine(disc, **OPTIONS)
    assert eng.settings == MjcfSettings(**OPTIONS)
    _, m = eng.run_model()
    opt = m.opt
    assert opt.timestep == pytest.approx(2e-4)
    assert opt.integrator == int(mujoco.mjtIntegrator.mjINT_RK4)
    assert opt.cone == int(mujoco.mjtCone.mjCONE_PYRAMIDAL)
    assert opt.solver == int(mujoco.mjtSolver.mjSOL_CG)
    assert (opt.iterations, opt.noslip_iterations) == (57, 3)
    assert opt.tolerance == pytest.approx(1e-9)
    tyre = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "front_tyre")
    assert m.geom_condim[tyre] == 4
    np.testing.assert_allclose(m.geom_friction[tyre], [1.5, 0.0, 0.0])
    np.testing.assert_allclose(m.geom_solref[tyre], [4e-4, 0.9])
    np.testing.assert_allclose(m.geom_solimp[tyre], [0.9, 0.95, 2e-3, 0.4, 3.0])
    assert m.geom_size[tyre][1] == pytest.approx(2e-6)          # the cylinder's half-length
    # the terms' model is written from the same settings
    assert 'integrator="RK4"' in eng.mjcf and 'condim="4"' in eng.mjcf


def test_a_bad_option_is_a_usage_error_naming_it(disc):
    """Planted: solimp's name lost in the conversion of a text option."""
    from engines.base import EngineUsageError
    with pytest.raises(EngineUsageError, match=r"^MuJoCo option: MJCF setting solimp = "):
        MujocoEngine(disc, solimp=(0.9, 0.95))
    with pytest.raises(EngineUsageError, match=r"^MuJoCo option solimp = '0\.9 nope': not a list "
                       r"of numbers; fix: e\.g\. solimp="):
        MujocoEngine(disc, solimp="0.9 nope")


def test_the_run_model_is_built_for_the_settings_asked(disc):
    """run_model(settings) compiles those settings, once each; the terms' own model has no
    contact (it is switched off: the rigid-body terms only) and the run's has its zc joint.
    Planted: the argument ignored (`or True`), the zc link's placeholder mass left in
    (the massless links of the chain without zc zeroed)."""
    eng = MujocoEngine(disc)
    other = MjcfSettings(timestep=5e-4)
    text, m = eng.run_model(other)
    assert m.opt.timestep == pytest.approx(5e-4) and eng.run_model(other)[1] is m
    assert eng.run_model()[1].opt.timestep == pytest.approx(eng.settings.timestep)
    assert m.joint(2).name == "zc" and m.nq == 9
    for link in ("xc_link", "yc_link", "zc_link", "yaw", "lean"):    # placeholders zeroed
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, link)
        assert m.body_mass[b] == 0.0 and not m.body_inertia[b].any(), link
    assert eng.mj_model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def test_the_compilers_refusals_are_told_apart():
    """An inertia that breaks A + B >= C: a declared limitation (`UnsupportedModel`) quoting
    MuJoCo's message in one line; any other compile error an `EngineError` with it. Planted:
    the message's test inverted or its text lost, the flattened text lost."""
    bad_inertia = ('<mujoco><worldbody><body><joint type="hinge"/>'
                   '<inertial pos="0 0 0" mass="1" diaginertia="1 1 5"/></body></worldbody></mujoco>')
    with pytest.raises(UnsupportedModel, match=r"^MuJoCo requires every body's principal moments "
                       r"of inertia to satisfy the triangle inequality A \+ B >= C, and this "
                       r"bicycle's measured inertia breaks it \(MuJoCo's compiler: .*inertia must "
                       r"satisfy.*\)$") as err:
        compile_mjcf(bad_inertia, ())
    assert "\n" not in str(err.value)
    with pytest.raises(EngineError, match=r"^MuJoCo did not compile the bicycle's MJCF: .*nope") as err:
        compile_mjcf("<mujoco><nope/></mujoco>", ())
    assert "\n" not in str(err.value) and not isinstance(err.value, UnsupportedModel)


def test_gravity_and_integer_states(disc):
    """Q_grav against the reference's, one state given as integers and a batch. Planted: the
    gravity buffer missing, the states not converted to floats."""
    eng = MujocoEngine(disc)
    q = np.array([0, 0, 0, 1, 0, 0, 1, 0])
    np.testing.assert_allclose(eng.gravity(q), disc.Qgrav(q.astype(float)), atol=1e-9)
    qs = np.array([q, 2 * q])
    np.testing.assert_allclose(eng.gravity(qs), disc.Qgrav(qs.astype(float)), atol=1e-9)
    np.testing.assert_allclose(eng.mass_matrix(q), disc.mass_matrix(q.astype(float)), atol=1e-9)
