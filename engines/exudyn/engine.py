"""The thesis bicycle rebuilt in Exudyn, in two ways (see ``tree`` and ``redundant``).

    from engines import load_engine
    eng = load_engine("exudyn", model, build="tree", step=1e-3)   # or build="redundant"
    eng.mass_matrix(q)                 # tree build only: Exudyn's M(q) in the thesis's q
    traj = eng.simulate(SCENARIOS["stability-psid10"])

Both builds start from the scenario's projected initial state (the same for every engine,
`reference_model.scenarios.initial_state`) and return a `reference_model.solvers.Trajectory`
on the scenario's grid.

What is Exudyn's and what is ours in a run:

* Exudyn: the bodies or the kinematic tree, gravity, the joints, the rolling discs, the loads
  and the implicit integrator (``GeneralizedAlpha``, index 3, or ``TrapezoidalIndex2``) at a
  fixed step ``step`` (no step-size control; a Newton failure is a failure).
* Rider torques, single-sided as in the thesis: ``LoadTorqueVector(bodyFixed=True)`` on one
  body each — steer [0, 0, Mdir] on the fork, pedal [0, Mped, 0] on the rear wheel, anti-roll
  [Mvue, 0, 0] on the frame. Constant torques are plain load vectors; a torque history (the
  replay's cubic spline) becomes an Exudyn *symbolic* user function (a balanced tree of
  ``IfThenElse`` over the spline's pieces, evaluated in C++), so there is no Python callback
  in the time loop. It is checked against the given function at the knots and mid-points;
  a torque function that is not a cubic spline on the scenario grid falls back to a Python
  user function (and ``settings['torques']`` says so).
* Drag Qaero = -cv |vG3| vG3 at the frame's CoM: a ``CartesianSpringDamper`` between the
  ground and the frame's CoM with zero stiffness and damping and a symbolic
  ``springForceUserFunction`` returning cv |v| v (the connector applies minus that force to the
  frame), again without a Python callback.
* Ours: the mapping of the redundant build's poses back to q, dq (``mapping``); the
  accelerations ``ddq``, which are **central finite differences of dq on the step grid**
  (second order; Exudyn's stored accelerations are not used — they are wrong at the start
  with rolling constraints); the constraint residuals ``C``, evaluated by the reference model
  on the mapped states; fall detection (Exudyn has no events: a pre-step user function —
  one cheap Python call per step, outside the Newton loop — ends the run one step after
  |theta| passes fall_limit; the first step beyond is found in the stored data, the event
  located by cubic Hermite interpolation between the two steps around it, the trajectory
  cut there, status 'fell'; ``stop_at_fall=False`` runs to the end and cuts afterwards); the
  thesis's fork-axis front contact as user constraints on the tree
  (``tree.ThesisFrontContact``: Python user functions, in the Newton loop — the one place
  where Exudyn offers no alternative).

Beyond runs, the tree build gives Exudyn's mass matrix M(q) (``ComputeMassMatrix``) and its
generalized forces Qv + Qgrav + Qaero + S T (the right-hand side with the run's loads,
``ComputeODE2RHS``), both in the thesis's coordinates.

Pitfalls handled: sensors store every step (write period = step), and their time stamps are
checked against the step grid before the output is taken on the scenario's grid (which must
be a multiple of the step); ``exu.SolverError`` (and Exudyn's arithmetic errors) become status
'failed' with the partial trajectory up to the last finite step; Exudyn writes nothing to the
console while it runs (``exu.config.printToConsole = False`` for the duration, restored
after; verbose modes 0; no solution or sensor files).
"""

from __future__ import annotations

import contextlib
import math
import sys
import time
import warnings
from typing import Callable

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from reference_model import Model
from reference_model.model import torque_array
from reference_model.scenarios import Scenario, initial_state, torque_input
from reference_model.solvers import THETA, Trajectory, checked_fall_limit

from ..base import Engine, EngineError, EngineUsageError
from ..facts import Costs, FixedStep, RunSetup

try:
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import LoadTorqueVector, ObjectConnectorCartesianSpringDamper
except ImportError as exc:  # pragma: no cover - exudyn is a declared dependency
    raise EngineError("the Exudyn adapter needs the package 'exudyn' (pip install exudyn)") from exc

from .redundant import RedundantBuild
from .tree import TreeBuild, TreeMassMatrix

__all__ = ["ExudynEngine", "BUILDS", "SOLVERS", "check_step", "LONG_RUN_SECONDS"]

N_Q = 8
BUILDS = {"tree": TreeBuild, "redundant": RedundantBuild}
SOLVERS = {"generalizedAlpha": "GeneralizedAlpha", "trapezoidal": "TrapezoidalIndex2"}
#: When Exudyn's (modified) Newton recomputes its Jacobian. 'when-slow', Exudyn's default,
#: keeps it across steps until the iteration stops contracting: about 7.5 linearly converging
#: iterations per step at h = 1e-3. 'per-step' recomputes it at each step's start: 2.5
#: iterations. Both stop at the same tolerance at different points: on the IFToMM manoeuvres
#: the runs differ by up to 2e-8 rad and the constraint residuals stay below 1.1e-8 (4e-9
#: with the default), far inside every tolerance that judges them. Which is faster depends
#: on what a Jacobian costs (measured, tree build, h = 1e-3): 'per-step' takes 0.59x the time
#: on the benchmark bicycle (no drag), 1.0-1.1x on thesis-disc (the drag connector's user
#: function is differentiated numerically) and 2.5x on the thesis contact (Python user
#: constraints). Hence the default stays Exudyn's, and the benchmark stages ask for 'per-step'.
JACOBIAN_UPDATES = ("when-slow", "per-step")
RUN_STEP = 1e-3   # s: the harness's runs (divides the 0.01 s output grid)
# rider torque k -> (body marker, body axis): steer z4 on the fork, pedal y2 on the rear
# wheel, anti-roll x3 on the frame
TORQUE_TARGETS = (("fork", 2), ("rear", 1), ("frame", 0))
# options of the reference's simulate that have no meaning here; accepted and recorded
_REFERENCE_ONLY = ("rtol", "atol", "constraints", "baumgarte")
#: Wall time per step used for the estimate before a run (s): measured on the development
#: machine (2 cores shared with other jobs, load ~5) at h = 1e-3 s on stability-psid10
#: (tree 1.2 ms, redundant 0.57 ms per step, ~8 Newton iterations each); smaller steps need
#: fewer Newton iterations, so this is on the long side.
STEP_SECONDS = {"tree": 1.2e-3, "redundant": 6e-4}
#: A run estimated longer than this (s) is announced (steps x cost per step) and reports its
#: progress every PROGRESS_EVERY seconds.
LONG_RUN_SECONDS = 120.0
PROGRESS_EVERY = 30.0
#: After this much wall time (s) the cost per step is measured on the run itself.
MEASURE_AFTER = 2.0


def _stderr_line(text: str) -> None:
    sys.stderr.write(f"bicycle-xval: {text}\n")
    sys.stderr.flush()


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def check_step(h: float, interval: float, span: float | None = None) -> int:
    """Steps per output interval for a fixed step ``h``; raises EngineUsageError (a usage
    error) unless h is a positive step dividing the interval (and the span, if given)."""
    if not (isinstance(h, (int, float)) and not isinstance(h, bool) and math.isfinite(h) and h > 0):
        raise EngineUsageError(f"the Exudyn step must be a positive time in s; got {h!r}")
    per = int(round(interval / h))
    if per < 1 or abs(per * h - interval) > 1e-9 * interval:
        k = max(1, int(interval / h))
        options = sorted({interval / k, interval / (k + 1)}, reverse=True)
        raise EngineUsageError(
            f"the Exudyn step h = {h:g} s must divide the output interval {interval:g} s (the "
            f"steps must land on the output samples); fix: use {interval:g}/k s, e.g. "
            + " or ".join(f"{o:.10g}" for o in options))
    if span is not None and abs(round(span / h) * h - span) > 1e-9 * max(span, 1.0):
        raise EngineUsageError(f"the Exudyn step h = {h:g} s must divide the run's duration "
                               f"{span:g} s; fix: a step dividing both {interval:g} s and {span:g} s")
    return per


class _Monitor:
    """Per-step bookkeeping for long runs: the measured cost per step, the estimate, progress."""

    def __init__(self, n_steps: int, t0: float, t1: float, what: str,
                 notify: Callable[[str], None] | None, progress: Callable[[float], None] | None,
                 announced: bool):
        self.n_steps, self.t0, self.t1, self.what = n_steps, t0, t1, what
        self.notify, self.progress = notify, progress
        self.steps = 0
        self.start = time.perf_counter()
        self.measured = False
        self.long = announced
        self.next_report = self.start + PROGRESS_EVERY

    def __call__(self, t: float) -> None:
        self.steps += 1
        if self.progress is not None:
            self.progress(float(t))
        if self.notify is None:
            return
        now = time.perf_counter()
        elapsed = now - self.start
        if not self.measured and elapsed >= MEASURE_AFTER and self.steps > 1:
            self.measured = True
            total = elapsed / self.steps * self.n_steps
            if total > LONG_RUN_SECONDS:
                self.long = True
                self.notify(f"{self.what}: measured {elapsed / self.steps * 1e3:.2f} ms per step: "
                            f"about {_duration(total)} in all, {_duration(total - elapsed)} left")
        if self.long and now >= self.next_report:
            self.next_report = now + PROGRESS_EVERY
            done = (t - self.t0) / (self.t1 - self.t0) if self.t1 > self.t0 else 1.0
            left = elapsed / max(done, 1e-9) - elapsed
            self.notify(f"{self.what}: t = {t:.4f} of {self.t1:.4f} s ({100 * done:.0f}%), "
                        f"about {_duration(left)} left")


@contextlib.contextmanager
def quiet():
    """Keep Exudyn's console output (and its Python warnings) out of ours."""
    before = exu.config.printToConsole
    exu.config.printToConsole = False
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        exu.config.printToConsole = before


# -- loads -----------------------------------------------------------------------------------

def _symbolic_spline(spline: CubicSpline, j: int):
    """Symbolic expression builder for component j of a cubic spline: a balanced binary tree of
    IfThenElse over its pieces (Horner form per piece; outside the knots the end pieces extend,
    as scipy's)."""
    esym = exu.symbolic
    x, c = spline.x, spline.c

    def piece(t, k):
        s = t - float(x[k])
        return ((float(c[0, k, j]) * s + float(c[1, k, j])) * s + float(c[2, k, j])) * s \
            + float(c[3, k, j])

    def tree(t, lo, hi):
        if hi - lo == 1:
            return piece(t, lo)
        mid = (lo + hi) // 2
        return esym.IfThenElse(t < float(x[mid]), tree(t, lo, mid), tree(t, mid, hi))

    return lambda t: tree(t, 0, len(x) - 1)


def _as_spline(torque, grid: np.ndarray):
    """The not-a-knot cubic spline through torque(grid), if it reproduces the function (to
    1e-9 relative at knots and mid-points; a spline with these knots is reproduced exactly),
    else None."""
    try:
        vals = np.array([np.asarray(torque(t), dtype=float) for t in grid]).reshape(-1, 3)
        spline = CubicSpline(grid, vals, axis=0, bc_type="not-a-knot")
        mid = 0.5 * (grid[1:] + grid[:-1])
        probe = np.concatenate([grid, mid])
        given = np.array([np.asarray(torque(t), dtype=float) for t in probe]).reshape(-1, 3)
    except (ValueError, TypeError):
        return None
    scale = max(1.0, float(np.abs(given).max()))
    if np.abs(spline(probe) - given).max() > 1e-9 * scale:
        return None
    return spline


def _spline_load(expr, axis):
    def uf(mbs, t, loadVector):      # exactly the argument list Exudyn expects
        out = [0.0, 0.0, 0.0]
        out[axis] = expr(t)
        return out
    return uf


def _python_load(torque, j, axis):
    def uf(mbs, t, loadVector):
        out = [0.0, 0.0, 0.0]
        out[axis] = float(np.asarray(torque(t), dtype=float).reshape(3)[j])
        return out
    return uf


def add_torques(mbs, markers, torque, grid) -> str:
    """Single-sided rider torques as body-fixed LoadTorqueVector on fork, rear wheel, frame.
    Returns how they were realised (for the settings)."""
    if not callable(torque):
        T = np.asarray(torque, dtype=float).reshape(3)
        for (where, axis), value in zip(TORQUE_TARGETS, T):
            if value != 0.0:
                vec = [0.0, 0.0, 0.0]
                vec[axis] = float(value)
                mbs.AddLoad(LoadTorqueVector(markerNumber=markers[where], loadVector=vec,
                                             bodyFixed=True))
        return "constant body-fixed LoadTorqueVector"
    spline = _as_spline(torque, grid)
    keep = []
    for j, (where, axis) in enumerate(TORQUE_TARGETS):
        load = mbs.AddLoad(LoadTorqueVector(markerNumber=markers[where], loadVector=[0.0] * 3,
                                            bodyFixed=True))
        if spline is not None:
            sym = CreateSymbolicUserFunction(mbs, _spline_load(_symbolic_spline(spline, j), axis),
                                             "loadVectorUserFunction", load)
            mbs.SetLoadParameter(load, "loadVectorUserFunction", sym)
            keep.append(sym)     # the expression tree must outlive the run
        else:
            mbs.SetLoadParameter(load, "loadVectorUserFunction", _python_load(torque, j, axis))
    mbs.variables["_symbolic_keepalive"] = mbs.variables.get("_symbolic_keepalive", []) + keep
    if spline is not None:
        return ("body-fixed LoadTorqueVector with symbolic user functions (the cubic spline "
                f"of the torque history, {len(spline.x) - 1} pieces, evaluated in C++)")
    return "body-fixed LoadTorqueVector with Python user functions (torque function of time)"


def add_drag(mbs, markers, cv: float) -> str:
    """Qaero = -cv |vG3| vG3 on the frame's CoM, through a zero-stiffness Cartesian spring-damper
    to the ground with a symbolic force user function."""
    if cv == 0.0:
        return "none (cv = 0)"
    esym = exu.symbolic
    csd = mbs.AddObject(ObjectConnectorCartesianSpringDamper(
        markerNumbers=[markers["ground"], markers["frame_com"]], stiffness=[0.0] * 3,
        damping=[0.0] * 3))

    def drag(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
        v = velocity
        speed = esym.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        return [cv * speed * v[0], cv * speed * v[1], cv * speed * v[2]]

    sym = CreateSymbolicUserFunction(mbs, drag, "springForceUserFunction", csd)
    mbs.SetObjectParameter(csd, "springForceUserFunction", sym)
    mbs.variables["_symbolic_keepalive"] = mbs.variables.get("_symbolic_keepalive", []) + [sym]
    return ("CartesianSpringDamper frame CoM - ground, symbolic force cv |v| v "
            "(evaluated in C++)")


class TreeForces:
    """Exudyn's generalized forces on the tree, Qv + Qgrav + Qaero + S T: the ODE2 right-hand
    side (``MainSolverStatic.ComputeODE2RHS``) of the tree with the run's loads (the three
    body-fixed rider torques and the drag connector) and the rolling discs switched off."""

    def __init__(self, params):
        self.SC = exu.SystemContainer()
        self.mbs = mbs = self.SC.AddSystem()
        build = TreeBuild(mbs, params, np.zeros(N_Q), np.zeros(N_Q), "disc")
        mbs.SetObjectParameter(build.rear_disc, "activeConnector", False)
        mbs.SetObjectParameter(build.front_disc, "activeConnector", False)
        self.loads = [mbs.AddLoad(LoadTorqueVector(markerNumber=build.markers[where],
                                                   loadVector=[0.0] * 3, bodyFixed=True))
                      for where, _ in TORQUE_TARGETS]
        add_drag(mbs, build.markers, float(params.cv))
        mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.solution.file.write = False
        settings.solution.sensors.active = False
        settings.staticSolver.verboseMode = 0
        self.solver = exu.MainSolverStatic()
        self.solver.InitializeSolver(mbs, settings)

    def __call__(self, q, dq, torques) -> np.ndarray:
        mbs, cur = self.mbs, exu.ConfigurationType.Current
        for load, (_, axis), value in zip(self.loads, TORQUE_TARGETS,
                                          np.asarray(torques, dtype=float).reshape(3)):
            vec = [0.0, 0.0, 0.0]
            vec[axis] = float(value)
            mbs.SetLoadParameter(load, "loadVector", vec)
        mbs.systemData.SetODE2Coordinates([float(v) for v in q], configuration=cur)
        mbs.systemData.SetODE2Coordinates_t([float(v) for v in dq], configuration=cur)
        self.solver.ComputeODE2RHS(mbs)
        return np.array(self.solver.GetSystemResidual(), dtype=float)[:N_Q]


# -- the engine ------------------------------------------------------------------------------

class ExudynEngine(Engine):
    """Exudyn's mass matrix and generalized forces (tree build) and forward runs (both builds).

    ``build``: 'tree' (ObjectKinematicTree in the thesis's coordinates) or 'redundant' (rigid
    bodies + joints); ``step``: the fixed time step h (s); ``solver``: 'generalizedAlpha'
    (index 3) or 'trapezoidal' (TrapezoidalIndex2); ``spectral_radius`` of generalized-alpha;
    ``newton_tolerance``: Newton's relative and absolute tolerance; ``jacobian``: when Newton
    recomputes its Jacobian, 'when-slow' (Exudyn's default) or 'per-step' (`JACOBIAN_UPDATES`)."""

    name = "exudyn"
    # with the default build='tree'; build='redundant' narrows them to {'simulate'}
    capabilities = frozenset({"mass_matrix", "generalized_forces", "simulate"})
    label = "Exudyn"
    colour = "tab:blue"
    marker = "^"
    #: a fixed-step integrator: its runs are reported against the reference, and judged by
    #: their convergence order (the fixed-step study, `fixed_step` below)
    trajectory_tolerance = None
    trajectory_judged_by = "its convergence order (the fixed-step study)"
    run_setups = (RunSetup("tree", (("build", "tree"), ("step", RUN_STEP)), kinds=("forward",),
                           settings=f"ObjectKinematicTree, generalized-alpha (spectral radius "
                                    f"0.9, index 3), h = {RUN_STEP:g} s, Newton tolerance 1e-10; "
                                    "no inverse dynamics"),)
    #: the replay on the thesis contact: ~8 Newton iterations a step through the contact's
    #: Python user functions, 5.3 simulated s before it falls; measured 6-9 s of CPU on the
    #: 2-core machine (the run's longest stage: declared so, it starts first)
    costs = Costs(run_per_second=0.6, short_run=0.8, terms=1.0, faults=3.0,
                  scenario_runs=(("replay", 8.0),))
    fixed_step = FixedStep(
        option="step", step=RUN_STEP, order=2.0,
        variants=(("tree", (("build", "tree"),)), ("redundant", (("build", "redundant"),))),
        thesis_variant="tree", quick_variants=("tree",),
        # Newton's Jacobian recomputed every step on the benchmark bicycle: 2.5 instead of 7.5
        # Newton iterations per step, 0.59x the run time (JACOBIAN_UPDATES); the runs move by
        # up to 2e-8 rad and every verdict stays
        benchmark_options=(("jacobian", "per-step"),),
        describe="generalized-alpha (spectral radius 0.9, index 3)")

    def __init__(self, model: Model, build: str = "tree", step: float = 1e-3,
                 solver: str = "generalizedAlpha", spectral_radius: float = 0.9,
                 newton_tolerance: float = 1e-10, jacobian: str = "when-slow"):
        super().__init__(model)
        if jacobian not in JACOBIAN_UPDATES:
            raise EngineUsageError(f"unknown Jacobian update {jacobian!r}; choose one of: "
                                   f"{', '.join(JACOBIAN_UPDATES)}")
        if build not in BUILDS:
            raise EngineUsageError(f"unknown Exudyn build {build!r}; choose one of: {', '.join(BUILDS)}")
        if solver not in SOLVERS:
            raise EngineUsageError(f"unknown Exudyn solver {solver!r}; choose one of: {', '.join(SOLVERS)}")
        if not (isinstance(step, (int, float)) and not isinstance(step, bool) and np.isfinite(step)
                and step > 0):
            raise EngineUsageError(f"step must be a positive time step in s; got {step!r}")
        if build == "redundant" and model.contact != "disc":
            raise EngineError(
                f"the redundant Exudyn build realises only the rolling-disc contact (true lowest "
                f"point of the disc), not the {model.contact!r} front contact of model "
                f"{model.name!r}; use build='tree' or a model with contact 'disc' (thesis-disc)")
        self.build, self.step, self.solver = build, float(step), solver
        self.spectral_radius = float(spectral_radius)
        self.newton_tolerance = float(newton_tolerance)
        self.jacobian = jacobian
        tree_only = {"mass_matrix", "generalized_forces"} if build == "tree" else set()
        self.capabilities = frozenset({"simulate"} | tree_only)
        self._mass = self._forces = None

    def __repr__(self) -> str:
        return (f"ExudynEngine(model={self.model.name!r}, contact={self.model.contact!r}, "
                f"build={self.build!r}, step={self.step!r}, solver={self.solver!r})")

    # -- mass matrix ---------------------------------------------------------------------
    def mass_matrix(self, q):
        if "mass_matrix" not in self.capabilities:
            self._missing("mass_matrix")
        if self._mass is None:
            with quiet():
                self._mass = TreeMassMatrix(self.model.params)
        q = np.asarray(q, dtype=float)
        with quiet():
            if q.ndim == 1:
                return self._mass(q)
            return np.array([self._mass(row) for row in q])

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        """Qv + Qgrav + Qaero + S T from the tree's right-hand side with the run's loads."""
        if "generalized_forces" not in self.capabilities:
            self._missing("generalized_forces")
        if self._forces is None:
            with quiet():
                self._forces = TreeForces(self.model.params)
        q, dq = np.asarray(q, dtype=float), np.asarray(dq, dtype=float)
        single = q.ndim == 1
        T = torque_array(torques, 1 if single else q.shape[0], single)
        T = T[0] if single else T
        with quiet():
            if q.ndim == 1:
                return self._forces(q, dq, T)
            return np.array([self._forces(a, b, c) for a, b, c in zip(q, dq, T)])

    # -- forward runs --------------------------------------------------------------------
    def _settings(self, n_steps: int, t0: float, t1: float):
        ss = exu.SimulationSettings()
        ti = ss.timeIntegration
        ti.numberOfSteps = n_steps
        ti.startTime = t0
        ti.endTime = t1
        ti.verboseMode = 0
        ti.verboseModeFile = 0
        ti.automaticStepSize = False
        ti.adaptiveStep = False
        ti.newton.relativeTolerance = self.newton_tolerance
        ti.newton.absoluteTolerance = self.newton_tolerance
        ti.newton.modifiedNewtonJacUpdatePerStep = self.jacobian == "per-step"
        ti.generalizedAlpha.spectralRadius = self.spectral_radius
        ti.generalizedAlpha.computeInitialAccelerations = True
        ss.solution.file.write = False
        ss.solution.sensors.writePeriod = self.step
        ss.show.computationTime = False
        ss.show.statistics = False
        return ss

    def simulate(self, scenario: Scenario, **options) -> Trajectory:
        """Forward run of ``scenario`` from its projected initial state.

        Options: ``fall_limit`` (rad, default the scenario's), ``t_end`` (stop early, s),
        ``every_step`` (return every step instead of the scenario's grid), ``stop_at_fall``
        (default True: a per-step check ends the run one step after |theta| passes the
        limit; False runs to the end and cuts afterwards), ``progress`` (called with the time
        reached after every step, as the reference's), ``notify`` (one-line messages; default:
        stderr): a run estimated longer than LONG_RUN_SECONDS (steps x cost per step) is
        announced before it starts, re-estimated from its own cost after MEASURE_AFTER s, and
        reports its progress every PROGRESS_EVERY s. The reference-only options rtol, atol,
        constraints, baumgarte are accepted and ignored (listed in
        ``settings['ignored_options']``). A step that does not divide the scenario's sampling
        interval is an `EngineUsageError`, raised before anything runs."""
        wall0 = time.perf_counter()
        fall_limit = options.pop("fall_limit", scenario.fall_limit)
        t_end = options.pop("t_end", None)
        every_step = bool(options.pop("every_step", False))
        stop_at_fall = bool(options.pop("stop_at_fall", True))
        progress = options.pop("progress", None)
        notify = options.pop("notify", _stderr_line)
        ignored = {k: options.pop(k) for k in _REFERENCE_ONLY if k in options}
        if options:
            raise TypeError(f"ExudynEngine.simulate got unknown option(s): {', '.join(options)}")
        fall_limit = checked_fall_limit(fall_limit)
        if scenario.kind != "forward":
            raise ValueError(f"scenario {scenario.name!r} is an inverse scenario; Exudyn runs only "
                             "forward scenarios")
        model, h = self.model, self.step
        grid = scenario.t
        if t_end is not None:
            grid = grid[grid <= float(t_end) + 1e-12]
            if grid.size < 2:
                raise ValueError(f"t_end = {t_end!r} leaves fewer than 2 grid samples")
        dt = float(grid[1] - grid[0])
        span = float(grid[-1] - grid[0])
        per = check_step(h, dt, span)
        n_steps = int(round(span / h))
        what = f"exudyn {self.build} on {scenario.name}"
        estimate = n_steps * STEP_SECONDS[self.build]
        if notify is not None and estimate > LONG_RUN_SECONDS:
            notify(f"{what}: {n_steps} steps of h = {h:g} s, estimated {_duration(estimate)} "
                   f"({STEP_SECONDS[self.build] * 1e3:.1f} ms per step); progress every "
                   f"{PROGRESS_EVERY:g} s")
        init = initial_state(model, scenario)
        torque = torque_input(model, scenario)

        # build
        build_t0 = time.perf_counter()
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        with quiet():
            build = BUILDS[self.build](mbs, model.params, init.q, init.dq, model.contact)
            torque_how = add_torques(mbs, build.markers, torque, scenario.t)
            drag_how = add_drag(mbs, build.markers, float(model.params.cv))
            build.add_sensors(mbs)
            monitor = _Monitor(n_steps, float(grid[0]), float(grid[-1]), what, notify, progress,
                               announced=estimate > LONG_RUN_SECONDS)

            def pre_step(mbs, t):
                # one cheap call per step (not in the Newton loop): progress and, as Exudyn has
                # no events, the fall check: stop one step after |theta| passes the limit (the
                # fall is located afterwards)
                monitor(t)
                return bool(abs(build.theta_now(mbs)) < fall_limit) if stop_at_fall else True

            mbs.SetPreStepUserFunction(pre_step)
            mbs.Assemble()
        build_seconds = time.perf_counter() - build_t0

        # run
        status, message = "completed", "reached the end of the grid"
        solve_t0 = time.perf_counter()
        solver_type = getattr(exu.DynamicSolverType, SOLVERS[self.solver])
        try:
            with quiet():
                exu.SolveDynamic(mbs, self._settings(n_steps, float(grid[0]), float(grid[-1])),
                                 solverType=solver_type, storeSolver=True, showHints=False,
                                 showCausingItems=False)
        except (exu.SolverError, exu.ExudynArithmeticError) as exc:
            status = "failed"
            message = f"Exudyn solver failed: {type(exc).__name__}: {' '.join(str(exc).split())}"
            why = _solver_error_string(mbs)
            if why:
                message += f" ({why})"
        solve_seconds = time.perf_counter() - solve_t0
        newton = _newton_count(mbs)

        # read back on the step grid
        t_raw, q, dq = build.read(mbs, init.q)
        n = t_raw.size
        steps_done = max(n - 1, 0)
        t_steps = grid[0] + h * np.arange(n)
        if n and np.abs(t_raw - t_steps).max() > 1e-6 * h:
            raise EngineError(f"Exudyn's sensor time stamps left the step grid (max offset "
                              f"{np.abs(t_raw - t_steps).max():.3e} s)")
        finite = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(dq), axis=1)
        if not np.all(finite):
            k = int(np.argmin(finite))
            t_steps, q, dq = t_steps[:k], q[:k], dq[:k]
            if status != "failed":
                last = t_steps[-1] if k else grid[0]
                status, message = "failed", f"state became non-finite after t = {last:.6f} s"
        n = t_steps.size
        if n == 0:
            q, dq = init.q[None, :], init.dq[None, :]
            t_steps = grid[:1].copy()
            n = 1
        if status == "failed":
            message += f"; last step reached t = {t_steps[-1]:.6f} s"
        ddq = np.gradient(dq, h, axis=0, edge_order=2) if n >= 3 else np.zeros_like(dq)

        # fall: first step at or beyond the limit
        over = np.flatnonzero(np.abs(q[:, THETA]) >= fall_limit)
        event = None
        if over.size:
            k = int(over[0])
            if k == 0:
                status = "fell"
                message = f"|theta| = {abs(q[0, THETA]):.3f} rad >= fall limit at the start"
                n = 1
            else:
                event = _hermite_event(t_steps[k - 1:k + 1], q[k - 1:k + 1], dq[k - 1:k + 1],
                                       ddq[k - 1:k + 1], fall_limit)
                if status == "failed":
                    message = f"; after the fall, {message}"
                else:
                    message = ""
                status = "fell"
                message = (f"|theta| reached the fall limit {fall_limit:.4f} rad at "
                           f"t = {event[0]:.6f} s" + message)
                n = k
        rows = np.arange(n) if every_step else np.arange(0, n, per)
        if status == "failed" and rows[-1] != n - 1:
            rows = np.append(rows, n - 1)     # the last step before the failure ends the run
        t_out, q_out, dq_out, ddq_out = t_steps[rows], q[rows], dq[rows], ddq[rows]
        if event is not None and event[0] > t_out[-1]:
            t_out = np.append(t_out, event[0])
            q_out, dq_out, ddq_out = (np.vstack([a, e]) for a, e in
                                      zip((q_out, dq_out, ddq_out), event[1:]))
        if callable(torque):
            T = np.array([np.asarray(torque(t), dtype=float).reshape(3) for t in t_out])
        else:
            T = np.broadcast_to(np.asarray(torque, dtype=float), (t_out.size, 3)).copy()
        C = model.constraint_residual(q_out, dq_out).reshape(-1, 5)
        uc = getattr(build, "user_contact", None)
        drift = getattr(build, "hub_height_drift", None)
        return Trajectory(
            t=t_out, q=q_out, dq=dq_out, ddq=ddq_out, C=C, T=T, status=status, message=message,
            t_end=float(t_out[-1]),
            settings={
                "engine": "exudyn", "exudyn_version": exu.__version__,
                "build": self.build, "step": h, "solver": self.solver,
                "solver_type": SOLVERS[self.solver], "spectral_radius": self.spectral_radius,
                "newton_tolerance": self.newton_tolerance, "jacobian": self.jacobian,
                "contact": model.contact,
                "front_contact": ("ObjectJointRollingDisc (true lowest point)"
                                  if model.contact == "disc" else
                                  "thesis fork-axis point, user constraints (Python) on the tree"),
                "rear_contact": "ObjectJointRollingDisc",
                "torques": torque_how, "drag": drag_how, "fall_limit": fall_limit,
                "grid": "every step" if every_step else f"scenario grid (every {per} steps)",
                "ddq": ("central finite differences of dq on the step grid (second order, "
                        "one-sided at the ends); not Exudyn's stored accelerations"),
                "dq": ("tree coordinates' velocities" if self.build == "tree" else
                       "solved from the bodies' angular velocities and the rear hub velocity "
                       "(linear map, engines.exudyn.mapping)"),
                "C": "reference model's constraint_residual on the Exudyn states",
                "initial_correction": init.describe(), "beta_correction": init.beta_correction,
                "stop_at_fall": stop_at_fall, "ignored_options": sorted(ignored),
                **({"rear_hub_height_drift": drift} if drift is not None else {}),
            },
            timing={"wall_seconds": time.perf_counter() - wall0, "build_seconds": build_seconds,
                    "solve_seconds": solve_seconds, "steps": steps_done,
                    **({"newton_iterations": newton} if newton is not None else {}),
                    **({"user_constraint_calls": uc.calls} if uc is not None else {})},
        )


def _newton_count(mbs):
    try:
        return int(mbs.sys["dynamicSolver"].it.newtonStepsCount)
    except Exception:   # noqa: BLE001 - timing information only
        return None


def _solver_error_string(mbs) -> str:
    try:
        return " ".join(str(mbs.sys["dynamicSolver"].GetErrorString()).split())
    except Exception:   # noqa: BLE001 - only for the message
        return ""


def _hermite_event(t, q, dq, ddq, limit):
    """(t_event, q, dq, ddq) where |theta| reaches ``limit`` between two steps: cubic Hermite
    interpolation of q from (q, dq) and of dq from (dq, ddq) at both ends (so the event row
    stays close to the constraints: its residual is O(h^3) instead of O(h^2)); ddq linear."""
    t0, t1 = float(t[0]), float(t[1])
    hh = t1 - t0
    sign = np.sign(q[1, THETA])

    def hermite(y, dy, s):
        u = (s - t0) / hh
        h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
        h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
        return h00 * y[0] + h10 * hh * dy[0] + h01 * y[1] + h11 * hh * dy[1]

    f = lambda s: sign * hermite(q, dq, s)[THETA] - limit
    s = brentq(f, t0, t1, xtol=1e-14) if f(t0) < 0 < f(t1) else t1
    u = (s - t0) / hh
    return s, hermite(q, dq, s), hermite(dq, ddq, s), (1 - u) * ddq[0] + u * ddq[1]
