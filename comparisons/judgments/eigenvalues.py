"""Eigenvalues of the linearized roll/steer dynamics against forward speed: the table and the
critical speeds (what the report and ``bicycle-xval eigenvalues`` show).

The linearization is :mod:`reference_model.linearize` (upright straight running, exact complex-
step derivatives). Table columns: ``v`` (forward speed, m/s), then ``re_k, im_k`` (1/s) for the
four eigenvalues k = 1..4 in the order of ``linearize.sort_eigenvalues`` (complex pairs first,
+imag before -imag, then the real ones decreasing: for the benchmark above ~0.7 m/s, weave,
weave, capsize, castor, as Table 2 of Meijaard et al. 2007), and ``stable`` (all real parts < 0).
"""

from __future__ import annotations

import numpy as np

__all__ = ["critical_speeds", "eigenvalue_curves", "eigenvalue_table"]


def eigenvalue_table(model, speeds) -> "pd.DataFrame":  # noqa: F821
    """Eigenvalues at each speed: columns v, re_1, im_1, ..., re_4, im_4, stable (module doc)."""
    import pandas as pd

    from reference_model.linearize import eigenvalues

    v = np.atleast_1d(np.asarray(speeds, dtype=np.float64))
    lam = eigenvalues(model, v)
    cols: dict[str, np.ndarray] = {"v": v}
    for k in range(4):
        cols[f"re_{k + 1}"] = lam[:, k].real
        cols[f"im_{k + 1}"] = lam[:, k].imag
    cols["stable"] = np.all(lam.real < 0, axis=1)
    return pd.DataFrame(cols)



def critical_speeds(model, speeds) -> tuple[float | None, float | None]:
    """(weave speed, capsize speed) within [max(0, min speeds), max speeds]; None where none."""
    from reference_model.linearize import CriticalSpeedError, capsize_speed, weave_speed

    v = np.asarray(speeds, dtype=np.float64)
    lo, hi = max(0.0, float(v.min())), float(v.max())
    if not hi > lo:
        return None, None
    found = []
    for fn in (weave_speed, capsize_speed):
        try:
            found.append(fn(model, (lo, hi)))
        except CriticalSpeedError:
            found.append(None)
    return found[0], found[1]



def eigenvalue_curves(model, speeds) -> dict:
    """What the eigenvalues-against-speed figure draws: speeds, real and imaginary parts (4
    columns each, as in `eigenvalue_table`), the weave and capsize speeds (None where none) and
    the model's name."""
    from reference_model.linearize import eigenvalues

    v = np.atleast_1d(np.asarray(speeds, dtype=np.float64))
    lam = eigenvalues(model, v)[:, :4]
    weave, capsize = critical_speeds(model, v)
    return {"v": v, "re": np.ascontiguousarray(lam.real), "im": np.ascontiguousarray(lam.imag),
            "weave": weave, "capsize": capsize, "model": model.name}
