"""Runs as tables with the documented CSV columns: plain ordered mappings of column name to
array, which `comparisons.stages.files.csv_bytes` writes (pandas, 0.7 s to import, stays off
the report's path; ``pandas.DataFrame(table)`` gives a frame where one is wanted).

Columns: ``t``, the eight coordinates, ``d_<name>``, ``dd_<name>``, then ``Mdir, Mped, Mvue``
and ``lambda_1..lambda_5`` (inverse dynamics) or ``C_1..C_5`` (simulations).
"""

from __future__ import annotations

import numpy as np

from reference_model import COORDINATES, TORQUE_NAMES


def frame(t, q, dq, ddq, extra: dict) -> dict[str, np.ndarray]:
    cols = {"t": t}
    cols.update({n: q[:, i] for i, n in enumerate(COORDINATES)})
    cols.update({f"d_{n}": dq[:, i] for i, n in enumerate(COORDINATES)})
    cols.update({f"dd_{n}": ddq[:, i] for i, n in enumerate(COORDINATES)})
    cols.update(extra)
    return cols


def inverse_frame(res):
    """An inverse-dynamics result (`reference_model.scenarios.run_inverse`) as a table."""
    m = res.motion
    extra = {n: res.T[:, i] for i, n in enumerate(TORQUE_NAMES)}
    extra.update({f"lambda_{k + 1}": res.lam[:, k] for k in range(5)})
    return frame(m.t, m.q, m.dq, res.ddq, extra)


def simulation_frame(traj):
    """A forward run (`reference_model.solvers.Trajectory`) as a table."""
    extra = {f"C_{k + 1}": traj.C[:, k] for k in range(5)}
    return frame(traj.t, traj.q, traj.dq, traj.ddq, extra)


def run_frame(r):
    """A `engines.runs.Run` as a table (accelerations NaN where the run kept none)."""
    if r.trajectory is not None:
        return simulation_frame(r.trajectory)
    extra = {}
    if r.T is not None:
        extra = {n: r.T[:, i] for i, n in enumerate(TORQUE_NAMES)}
        extra.update({f"lambda_{k + 1}": r.lam[:, k] for k in range(5)})
    ddq = r.ddq if r.ddq is not None else np.full_like(r.q, np.nan)
    return frame(r.t, r.q, r.dq, ddq, extra)
