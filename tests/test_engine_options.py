"""The soft-contact engines' options as a user gives them (Python values, or text from the
CLI's ``--engine-option key=value``): each accepted value as given, each bad one a one-line
`EngineUsageError` that names the option and a fix (the house's rule for bad input). No engine
library runs here: the settings records are plain Python, so this is milliseconds."""

from __future__ import annotations

import dataclasses
import math

import pytest

from engines.base import EngineUsageError
from engines.dart import options as dart
from engines.drake import options as drake
from engines.mujoco.options import tuple_option

# -- Drake ---------------------------------------------------------------------------------

DRAKE_POSITIVE = ("time_step", "stiction_tolerance", "friction", "point_stiffness",
                  "hydroelastic_modulus", "wheel_half_width")


@pytest.mark.parametrize("name", DRAKE_POSITIVE)
@pytest.mark.parametrize("bad", [0, -1.0, math.inf, math.nan, True, "x", None])
def test_drake_refuses_a_non_positive_or_non_number_option(name, bad):
    with pytest.raises(EngineUsageError) as err:
        drake.settings_from(**{name: bad})
    msg = str(err.value)
    assert msg.startswith(f"Drake option {name} = ") and "\n" not in msg
    assert f"fix: e.g. {name}={getattr(drake.RunSettings, name)!r}" in msg
    assert ("not a number" if bad == "x" else "must be a positive number") in msg


@pytest.mark.parametrize("name", DRAKE_POSITIVE)
def test_drake_takes_a_positive_number_given_as_text(name):
    s = drake.settings_from(**{name: "2.5e-3"})
    assert getattr(s, name) == 2.5e-3 and isinstance(getattr(s, name), float)
    # every other field keeps its default
    for other in drake.RunSettings.field_names():
        if other != name:
            assert getattr(s, other) == getattr(drake.DEFAULTS, other)


def test_drake_dissipation_may_be_zero_but_not_negative():
    assert drake.settings_from(dissipation=0).dissipation == 0
    assert drake.settings_from(dissipation="0").dissipation == 0.0
    for bad in (-1e-9, math.nan, math.inf, True, None):
        with pytest.raises(EngineUsageError, match=r"^Drake option dissipation = .*must be a "
                                                   r"number >= 0 \(s/m\); fix: e\.g\. dissipation=10$"):
            drake.settings_from(dissipation=bad)


def test_drake_solver_and_contact_model_are_one_of_drakes():
    for a in ("tamsi", "sap", "lagged", "similar"):
        assert drake.settings_from(approximation=a).approximation == a
    for c in ("point", "hydroelastic"):
        assert drake.settings_from(contact_model=c).contact_model == c
    with pytest.raises(EngineUsageError, match=r"^Drake option approximation = 'SAP': not one of "
                                               r"tamsi, sap, lagged, similar; fix: approximation=tamsi$"):
        drake.settings_from(approximation="SAP")
    with pytest.raises(EngineUsageError, match=r"contact_model = 'soft': not one of point, "
                                               r"hydroelastic; fix: contact_model=point$"):
        drake.settings_from(contact_model="soft")


def test_drake_unknown_options_are_named_with_the_ones_it_takes():
    with pytest.raises(EngineUsageError) as err:
        drake.settings_from(timestep=1e-3, zeta=1, time_step=1e-3)
    assert str(err.value) == ("Drake got unknown option(s) timestep, zeta; it takes "
                              + ", ".join(f.name for f in dataclasses.fields(drake.RunSettings)))


def test_drake_replace_checks_the_new_values_and_keeps_the_rest():
    s = drake.DEFAULTS.replace(time_step="1e-3", approximation="sap")
    assert (s.time_step, s.approximation) == (1e-3, "sap")
    assert s.replace() == s and s.as_dict()["friction"] == drake.DEFAULTS.friction
    with pytest.raises(EngineUsageError, match="friction"):
        s.replace(friction=-2)
    assert drake.DEFAULTS == drake.RunSettings()


# -- DART ----------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ("timestep", "friction", "wheel_half_width"))
@pytest.mark.parametrize("bad", [0, -1.0, math.inf, math.nan, True, "x", None])
def test_dart_refuses_a_non_positive_or_non_number_option(name, bad):
    with pytest.raises(EngineUsageError) as err:
        dart.RunSettings.checked(**{name: bad})
    assert str(err.value) == (f"DART option {name} = {bad!r}: must be a positive number; fix: "
                              f"e.g. {name}={getattr(dart.RunSettings, name)!r}")


def test_dart_numbers_given_as_text_become_floats_and_defaults_stay():
    s = dart.RunSettings.checked(timestep="1e-3", friction="1", wheel_half_width=2e-6)
    assert (s.timestep, s.friction, s.wheel_half_width) == (1e-3, 1.0, 2e-6)
    assert isinstance(s.friction, float)
    assert dart.RunSettings.checked() == dart.DEFAULTS == dart.RunSettings()
    assert dart.RunSettings.checked(friction=3).as_dict() == {**dart.DEFAULTS.as_dict(),
                                                              "friction": 3.0}


def test_dart_detector_and_solver_are_one_of_darts():
    for d in ("bullet", "ode", "fcl", "dart"):
        assert dart.RunSettings.checked(collision_detector=d).collision_detector == d
    for s in ("dantzig", "pgs"):
        assert dart.RunSettings.checked(solver=s).solver == s
    with pytest.raises(EngineUsageError) as err:
        dart.RunSettings.checked(collision_detector="ODE")
    assert str(err.value) == ("DART option collision_detector = 'ODE': unknown; fix: one of "
                              "bullet, ode, fcl, dart")
    with pytest.raises(EngineUsageError) as err:
        dart.RunSettings.checked(solver="lemke")
    assert str(err.value) == "DART option solver = 'lemke': unknown; fix: one of dantzig, pgs"


@pytest.mark.parametrize("given, value", [(True, True), (False, False), ("true", True),
                                          ("False", False), ("1", True), ("0", False)])
def test_dart_split_impulse_from_a_bool_or_its_text(given, value):
    assert dart.RunSettings.checked(split_impulse=given).split_impulse is value


@pytest.mark.parametrize("bad", ["yes", 1, 0, None, "2"])
def test_dart_split_impulse_refuses_anything_else(bad):
    with pytest.raises(EngineUsageError) as err:
        dart.RunSettings.checked(split_impulse=bad)
    assert str(err.value) == f"DART option split_impulse = {bad!r}: must be true or false"


# -- MuJoCo --------------------------------------------------------------------------------

@pytest.mark.parametrize("text, value", [("0.02,1", (0.02, 1.0)), ("0.02 1", (0.02, 1.0)),
                                         ("0.9, 0.95, 0.001", (0.9, 0.95, 0.001))])
def test_mujoco_solref_and_solimp_from_text(text, value):
    assert tuple_option("solref", text) == value


def test_mujoco_a_sequence_is_taken_as_given_and_bad_text_names_the_option():
    seq = [0.02, 1.0]
    assert tuple_option("solref", seq) is seq
    from reference_model.export_mjcf import MjcfSettings
    with pytest.raises(EngineUsageError) as err:
        tuple_option("solimp", "0.9;0.95")
    example = ",".join(map(repr, MjcfSettings().solimp))
    assert str(err.value) == (f"MuJoCo option solimp = '0.9;0.95': not a list of numbers; "
                              f"fix: e.g. solimp={example}")
