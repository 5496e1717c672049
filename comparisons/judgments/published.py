"""Published reference numbers the report checks the model against.

Meijaard, Papadopoulos, Ruina, Schwab (2007), "Linearized dynamics equations for the balance
and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463, Table 2: the
eigenvalues of the benchmark bicycle (weave pair re +- im i, capsize, castor; at v = 0 the
four real roots) and its weave and capsize speeds, and the numerical M, C1, K0, K2 it prints
for Table 1's bicycle (section 4; g = 9.81 m/s^2, [phi, delta], 14 decimals), typed from the
paper.
"""

from __future__ import annotations

import numpy as np

# v (m/s): (weave re, weave im, capsize, castor); v = 0: the four real roots
MEIJAARD_TABLE2 = {
    0: (5.53094371765393, 3.13164324790656, -3.13164324790656, -5.53094371765393),
    1: (3.52696170990070, 0.80774027519930, -3.13423125066578, -7.11008014637442),
    2: (2.68234517512745, 1.68066296590675, -3.07158645641514, -8.67387984831735),
    3: (1.70675605663975, 2.31582447384325, -2.63366137253667, -10.35101467245920),
    4: (0.41325331521125, 3.07910818603206, -1.42944427361326, -12.15861426576450),
    5: (-0.77534188219585, 4.46486771378823, -0.32286642900409, -14.07838969279820),
    6: (-1.52644486584142, 5.87673060598709, -0.00406690076970, -16.08537123098030),
    7: (-2.13875644258362, 7.19525913329805, 0.10268170574766, -18.15788466125262),
    8: (-2.69348683581097, 8.46037971396931, 0.14327879765713, -20.27940894394569),
    9: (-3.21675402252485, 9.69377351531791, 0.15790184030917, -22.43788559040858),
    10: (-3.72016840437287, 10.90681139476287, 0.16105338653172, -24.62459635017404),
}
MEIJAARD_WEAVE_SPEED = 4.29238253634111     # m/s
MEIJAARD_CAPSIZE_SPEED = 6.02426201538837   # m/s
# M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi, T_delta]; kg m^2, kg m^2/s per m/s, kg m, kg
MEIJAARD_MATRICES = {
    "M": ((80.81722, 2.31941332208709), (2.31941332208709, 0.29784188199686)),
    "C1": ((0.0, 33.86641391492494), (-0.85035641456978, 1.68540397397560)),
    "K0": ((-80.95, -2.59951685249872), (-2.59951685249872, -0.80329488458618)),
    "K2": ((0.0, 76.59734589573222), (0.0, 2.65431523794604)),
}


def table2_eigenvalues(v: int) -> np.ndarray:
    """The four eigenvalues at speed v as complex numbers, in `linearize`'s sort order
    (complex pair +im first, then real ones in decreasing order)."""
    a, b, c, d = MEIJAARD_TABLE2[v]
    if v == 0:
        return np.array([a, b, c, d], dtype=complex)
    return np.array([complex(a, b), complex(a, -b), c, d])
