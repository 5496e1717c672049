"""Energy drift of a torque-free, drag-free run, reported the IFToMM way.

With no rider torques and no drag, the rolling constraints do no work (ideal, non-slipping
contacts), so the total mechanical energy E = T + V is conserved by the exact motion. The
IFToMM multibody benchmarks report its drift as

    drift = 100 (Emax - Emin) / |E0|   %

over the samples of a run. The normalisation by E0 makes the zero level of the potential
energy matter; here it is the model's: V = sum m_i g z_Gi with z = 0 at the ground, so E0 is
the total mechanical energy with the ground as the zero level (for the free-roll run below,
E0 = 1472 J of which T0 = 501 J). The drift relative to the initial kinetic energy,
100 (Emax - Emin) / T0, does not depend on that choice and is reported beside it.

Energies are the reference model's (`kinetic_energy`, `potential_energy`) evaluated on the
trajectory's q, dq, so every engine is measured with the same yardstick.

    model = free_roll_model(load_model("thesis-disc"))          # cv = 0
    for row in energy_drifts(model, [("my engine", engine)]): print(describe_drift(row))
"""

from __future__ import annotations

import numpy as np

from reference_model import Model
from reference_model.scenarios import Scenario, TorqueSamples, run_forward
from reference_model.solvers import Trajectory

__all__ = ["applies_torques", "energy_drift", "free_roll_model", "free_roll_scenario", "energy_drifts", "describe_run_settings",
           "describe_drift", "FREE_ROLL_DURATION"]

# 1 s: the free roll (like stability-psid10 without the pedal torque) falls at 2.04 s, and from
# ~0.6 s the steer runs away; 1 s keeps the run well before the fall while covering that part
FREE_ROLL_DURATION = 1.0
FREE_ROLL_SAMPLE = 1e-3     # s: every step of an Exudyn run at h = 1e-3 (the IFToMM drift is
                            # a max - min over the output, so the output must not skip steps)


def energy_drift(model: Model, traj: Trajectory) -> dict:
    """IFToMM energy drift of ``traj`` (all its rows), with energies from ``model``.

    Returns E0, Emax, Emin (J), drift_J = Emax - Emin, drift_percent = 100 drift_J / |E0|
    (total mechanical energy, ground as zero level of potential energy), T0 (initial kinetic
    energy) and drift_percent_of_T0 = 100 drift_J / T0, E_end_minus_E0 (J, the signed change
    over the run: negative for a dissipative scheme), t_Emax, t_Emin, samples, t_end."""
    q, dq = np.asarray(traj.q, dtype=float), np.asarray(traj.dq, dtype=float)
    if q.ndim != 2 or q.shape[0] < 1:
        raise ValueError("the trajectory has no samples")
    T = np.atleast_1d(model.kinetic_energy(q, dq))
    V = np.atleast_1d(model.potential_energy(q))
    E = T + V
    E0, T0 = float(E[0]), float(T[0])
    if E0 == 0.0:
        raise ValueError("E0 = 0: the IFToMM drift (normalised by E0) is undefined")
    i_max, i_min = int(np.argmax(E)), int(np.argmin(E))
    drift = float(E[i_max] - E[i_min])
    return {
        "E0": E0, "Emax": float(E[i_max]), "Emin": float(E[i_min]), "drift_J": drift,
        "drift_percent": 100.0 * drift / abs(E0),
        "T0": T0, "drift_percent_of_T0": 100.0 * drift / T0 if T0 > 0 else float("nan"),
        "E_end_minus_E0": float(E[-1] - E0),
        "t_Emax": float(traj.t[i_max]), "t_Emin": float(traj.t[i_min]),
        "samples": int(E.size), "t_end": float(traj.t[-1]),
        "zero_level": "potential energy sum m_i g z_Gi, z = 0 at the ground",
    }


def free_roll_model(model: Model) -> Model:
    """The same model without drag (cv = 0)."""
    return Model(model.params.replace(cv=0.0))


def free_roll_scenario(psi_dot: float = 10.0, duration: float = FREE_ROLL_DURATION,
                       sample: float = FREE_ROLL_SAMPLE, model: str = "thesis-disc",
                       lean: float = np.pi / 16) -> Scenario:
    """Torque-free run from the stability study's start (theta = gamma = ``lean``, pi/16) at
    psi_dot(0) = ``psi_dot``; use with `free_roll_model` (no drag) so energy is conserved."""
    n = int(round(duration / sample)) + 1
    return Scenario(
        name=f"free-roll-psid{psi_dot:g}",
        description=(f"torque-free, drag-free roll: leaned and steered by {lean:.4g} rad, "
                     f"psi_dot(0) = {psi_dot:g} rad/s, {duration:g} s (energy conservation)"),
        kind="forward", model=model, grid=(0.0, float(sample), n),
        q0=(0, 0, 0, float(lean), 0, 0, float(lean), 0), dq_ind0=(0.0, float(psi_dot), 0.0),
        torques=(0.0, 0.0, 0.0), constraints="projection", tags=("energy",))


def applies_torques(scenario: Scenario) -> bool:
    """Whether the scenario's rider torques can do work: constant torques not all zero, samples
    not all zero, or a named torque function (the inverse-dynamics torques of a built-in
    scenario: non-zero by construction, they balance drag or drive a motion)."""
    T = scenario.torques
    if isinstance(T, str):
        return True
    if isinstance(T, TorqueSamples):
        return bool(np.any(np.asarray(T.T, dtype=float) != 0.0))
    return bool(np.any(np.asarray(T, dtype=float) != 0.0))


def describe_run_settings(settings: dict) -> str:
    """An engine run's integrator in a phrase, from the keys a Trajectory's ``settings`` may
    carry (step, solver_type, spectral_radius, integrator, rtol)."""
    parts = []
    if "step" in settings:
        parts.append(f"h = {settings['step']:g}")
    if "solver_type" in settings:
        parts.append(str(settings["solver_type"])
                     + (f" spectral radius {settings['spectral_radius']:g}"
                        if "spectral_radius" in settings else ""))
    elif "integrator" in settings:
        parts.append(str(settings["integrator"])
                     + (f" rtol {settings['rtol']:.0e}" if "rtol" in settings else ""))
    return ", ".join(parts) or "its defaults"


def energy_drifts(model: Model, scenario: Scenario | None = None, engines=(),
                  reference_rtol: float = 1e-10) -> list[dict]:
    """Drift of the reference (DOP853 at ``reference_rtol``, projection) and of each engine of
    ``engines`` ((label, built engine) pairs) on ``scenario`` (default the free roll);
    ``model`` must have cv = 0. Each row: energy_drift's numbers plus 'engine', 'status',
    'settings'."""
    if model.params.cv != 0.0:
        raise ValueError(f"the energy check needs a drag-free model (cv = 0); got cv = "
                         f"{model.params.cv}: use free_roll_model(model)")
    sc = scenario or free_roll_scenario(model=model.name)
    if applies_torques(sc):
        raise ValueError(f"scenario {sc.name!r} applies rider torques: energy is not conserved")
    ref = run_forward(model, sc, constraints="projection", rtol=reference_rtol)
    rows = [{"engine": f"reference {model.name}", "status": ref.status,
             "settings": f"DOP853 rtol {reference_rtol:.0e}, projection",
             **energy_drift(model, ref)}]
    for label, eng in engines:
        tr = eng.simulate(sc)
        rows.append({"engine": label, "status": tr.status,
                     "settings": describe_run_settings(tr.settings), **energy_drift(model, tr)})
    return rows


def describe_drift(row: dict) -> str:
    return (f"{row['engine']} ({row['settings']}; {row['status']} at {row['t_end']:.2f} s): "
            f"E0 = {row['E0']:.4f} J, Emax - Emin = {row['drift_J']:.3e} J, drift "
            f"{row['drift_percent']:.2e} % of E0 ({row['drift_percent_of_T0']:.2e} % of T0)")
