"""What the Exudyn adapter's edge tests share (tests/test_exudyn*.py): the rotations of
docs/engines.md written out again (a second formulation of engines/exudyn/mapping.py's),
the simulation settings of a short fixed-step run, the solve, and random states of the
general bicycle within the thesis's working ranges. Imported only by tests that have already
skipped themselves where Exudyn is not installed."""

import numpy as np

__all__ = ["H", "Rx", "Ry", "Rz", "random_states", "rotations", "settings", "solve"]

H = 1e-3                 # s, the engine's run step (engines/exudyn/engine.py RUN_STEP)


def Rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def Ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def Rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotations(q):
    """A_lean and A2..A5 as docs/engines.md writes them."""
    lean = Rz(q[2]) @ Rx(q[3])
    A3 = lean @ Ry(q[5])
    A4 = A3 @ Rz(q[6])
    return {"lean": lean, 2: lean @ Ry(q[4]), 3: A3, 4: A4, 5: A4 @ Ry(q[7])}


def settings(n_steps, newton_tolerance=1e-10, newton_iterations=None):
    """Exudyn's settings for n_steps fixed steps of H, quiet, no solution file."""
    import exudyn as exu
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.numberOfSteps, ti.startTime, ti.endTime = n_steps, 0.0, n_steps * H
    ti.verboseMode = ti.verboseModeFile = 0
    ti.automaticStepSize = ti.adaptiveStep = False
    ti.newton.relativeTolerance = ti.newton.absoluteTolerance = newton_tolerance
    if newton_iterations is not None:
        ti.newton.maxIterations = newton_iterations
    ti.generalizedAlpha.computeInitialAccelerations = True
    ss.solution.file.write = False            # the solution file is the engine's setting; the
    ss.solution.sensors.writePeriod = H       # sensors' files are the build's (add_sensors)
    ss.show.computationTime = ss.show.statistics = False
    return ss


def solve(mbs, ss, solver="GeneralizedAlpha"):
    import exudyn as exu
    exu.SolveDynamic(mbs, ss, solverType=getattr(exu.DynamicSolverType, solver),
                     showHints=False, showCausingItems=False)


def random_states(n, seed):
    """n states (q, dq) of the general bicycle, not projected onto the constraints, within
    the thesis's working ranges, and the generator for anything further drawn after them."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n, 8))
    q[:, :2] = rng.uniform(-10, 10, (n, 2))
    q[:, 3] = rng.uniform(-1.3, 1.3, n)          # roll short of the fall
    q[:, 5] = rng.uniform(-0.6, 0.6, n)          # frame pitch
    q[:, 6] = rng.uniform(-1.5, 1.5, n)          # steer
    return q, rng.uniform(-20, 20, (n, 8)), rng
