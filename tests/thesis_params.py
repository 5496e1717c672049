"""The thesis parameters, typed in by hand from its MATLAB listing (`din_Bicicleta`).

Source: the thesis's MATLAB listing, chapter 8, `din_Bicicleta` (the values in force in the
dynamics; the one script that writes z3 = 0.55+0.39647 is not the dynamics).  Written in the
generalised names of docs/model.md:

    thesis x4, z4  -> xa, za   (steering-axis point from the rear hub, frame axes)
    thesis (none)  -> dx4 = dz4 = 0   (the fork CoM lies on that point)
    thesis R       -> R_rear = R_front

Deliberately independent of reference_model/parameters/*.toml: tests compare the two, so a
wrong number in the TOML (or in this file) shows up as a failure instead of agreeing silently.
"""

from types import SimpleNamespace

THESIS_PARAMS = {
    "R_rear": 0.32,
    "R_front": 0.32,
    "x3": 0.23 + 0.03047,
    "z3": 0.55 + 0.39687,
    "xa": 0.85 + 0.05109,
    "za": 0.55 - 0.14221,
    "dx4": 0.0,
    "dz4": 0.0,
    "x5": 0.12 - 0.05109,
    "z5": -0.55 + 0.14221,
    "m2": 2.612,
    "m3": 77.391,
    "m4": 1.725,
    "m5": 2.612,
    "I2xx": 0.108,
    "I2yy": 0.216,
    "I2zz": 0.108,
    "I3xx": 20.213,
    "I3yy": 21.769,
    "I3zz": 3.205,
    "I3xz": -1.820,
    "I4xx": 0.116,
    "I4yy": 0.103,
    "I4zz": 0.025,
    "I4xz": 0.018,
    "I5xx": 0.108,
    "I5yy": 0.216,
    "I5zz": 0.108,
    "g": 9.81,
    "cv": 0.8,
}


def thesis_params() -> SimpleNamespace:
    """The thesis parameters with attribute access (p.R_rear, ...)."""
    return SimpleNamespace(**THESIS_PARAMS)
