"""Hypothesis strategies for bicycle states, shared by the physics and oracle tests.

Ranges: xc, yc +-10 m; phi, psi, eps a full turn; lean theta up to ~69 deg; pitch beta +-0.5
rad; steer gamma up to ~86 deg (near +-pi/2 included); rates up to 20 rad/s or m/s.
"""

import numpy as np
from hypothesis import strategies as st


def finite(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


coords = st.tuples(finite(-10, 10), finite(-10, 10), finite(-np.pi, np.pi), finite(-1.2, 1.2),
                   finite(-np.pi, np.pi), finite(-0.5, 0.5), finite(-1.5, 1.5), finite(-np.pi, np.pi))
rates = st.tuples(*[finite(-20, 20)] * 8)
states = st.tuples(coords, rates).map(lambda t: (np.array(t[0]), np.array(t[1])))
torques = st.tuples(finite(-50, 50), finite(-50, 50), finite(-50, 50)).map(np.array)
