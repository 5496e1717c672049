"""`FmuEngine`: a Model-Exchange FMU's derivatives as the bicycle's forward accelerations.

Each Baumgarte setting is its own FMU instance, its a1, a2 set before initialization (they may
be fixed parameters): (0, 0) for the exact accelerations, a scenario's for its runs. An FMU
without mapped Baumgarte parameters is used with its own constraint handling. Runs are the
reference's `run_forward` (its initial state, its DOP853 loop) with the right-hand side from
the FMU; a run's C is the FMU's residual outputs when mapped, else the thesis's constraints at
the FMU's states.

``eigenvalues(speeds)``: the roll/steer eigenvalues about upright straight running (linear.py's
reduction) from Jacobian-vector products of the FMU's derivatives: its own
``fmi2GetDirectionalDerivative`` when it declares ``providesDirectionalDerivative``, central
differences of ``fmi2GetDerivatives`` (step `FD_STEP`) otherwise; only for an FMU whose
continuous states are exactly the mapped q and dq."""

from __future__ import annotations

import ctypes
import shutil
import zipfile
from pathlib import Path

import numpy as np

from reference_model import Model
from reference_model.model import ForwardResult
from reference_model.parameters.schema import PARAMETER_NAMES
from reference_model.scenarios import Scenario, run_forward

from ..base import Engine, EngineSpecError, UnsupportedModel
from ..facts import Costs, RunSetup
from .cosimulation import co_simulate
from .linear import roll_steer_eigenvalues
from .mapping import MappingError, parse_mapping

__all__ = ["FD_STEP", "FmuEngine", "MAPPING_IN_FMU"]

#: where an FMU exported by bicycle-xval carries its own mapping
MAPPING_IN_FMU = "resources/bicycle-xval-mapping.toml"
#: the central-difference step (SI, along a direction of largest entry 1) of the linearization
#: of an FMU without directional derivatives: truncation ~h^2 |f'''| and round-off
#: ~1e-16 |f| / h balance near 1e-6 (measured: 2.7e-13 of the largest benchmark eigenvalue,
#: tests/test_fmu_linear.py)
FD_STEP = 1e-6
_TERM_CAPABILITY = {"M": "mass_matrix", "Qgrav": "gravity", "D": "constraint_jacobian",
                    "dDdq": "constraint_bias"}


def _read(fmu: str | None, mapping: str | None):
    if not fmu:
        raise EngineSpecError("engine fmu needs its FMU; fix: --engine-option fmu=PATH.fmu")
    path = Path(fmu)
    if not path.is_file():
        raise EngineSpecError(f"engine option fmu={fmu}: no such file; fix: give the path of a "
                              ".fmu file")
    try:
        with zipfile.ZipFile(path) as z:
            inner = z.read(MAPPING_IN_FMU).decode("utf-8") if MAPPING_IN_FMU in z.namelist() else None
            z.getinfo("modelDescription.xml")
    except (zipfile.BadZipFile, KeyError):
        raise EngineSpecError(f"engine option fmu={fmu}: not an FMU (a zip file with a "
                              "modelDescription.xml); fix: give a .fmu file") from None
    if mapping is not None:
        try:
            return path, Path(mapping).read_text(encoding="utf-8"), f"mapping={mapping}"
        except OSError as exc:
            raise EngineSpecError(f"engine option mapping={mapping}: {exc.strerror or exc}; fix: "
                                  "give a readable mapping .toml file") from None
    if inner is None:
        raise EngineSpecError(f"engine option fmu={fmu}: the FMU carries no {MAPPING_IN_FMU}; "
                              "fix: --engine-option mapping=PATH.toml (bicycle-xval export "
                              "--format fmu-mapping writes the template)")
    return path, inner, f"{fmu}:{MAPPING_IN_FMU}"


class _Instance:
    """One initialized Model-Exchange instance in continuous-time mode."""

    def __init__(self, description, unzipped: str, parameters: dict[int, float]):
        from fmpy.fmi2 import FMU2Model
        self.fmu = FMU2Model(guid=description.guid, unzipDirectory=unzipped,
                             modelIdentifier=description.modelExchange.modelIdentifier,
                             instanceName="bicycle-xval")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        if parameters:
            self.fmu.setReal(list(parameters), list(parameters.values()))
        self.fmu.exitInitializationMode()
        while self.fmu.newDiscreteStates()[0]:      # newDiscreteStatesNeeded
            pass
        self.fmu.enterContinuousTimeMode()
        self.n = len(description.derivatives)
        self.x = (ctypes.c_double * self.n)()
        self.dx = (ctypes.c_double * self.n)()


class FmuEngine(Engine):
    """Any Model-Exchange FMU mapped onto the thesis's coordinates (mapping.py)."""

    name = "fmu"
    capabilities = frozenset({"forward_acceleration", "simulate"})
    label = "FMU"
    required_options = ("fmu",)     # no default engine list includes it
    colour = "tab:olive"
    marker = "P"
    run_setups = (RunSetup(settings="the FMU's derivatives integrated by the reference's "
                                    "DOP853 loop (rtol 1e-10), the scenario's Baumgarte a1, a2 "
                                    "when the mapping names them"),)
    costs = Costs(run_per_second=0.5, short_run=0.5, terms=0.5, faults=0.5)

    def __init__(self, model: Model, fmu: str | None = None, mapping: str | None = None,
                 parameters: str = "model", interface: str = "auto"):
        super().__init__(model)
        if interface not in ("auto", "me", "cs"):
            raise EngineSpecError(f"engine option interface={interface}: fix: auto (Model "
                                  "Exchange when the FMU has it), me or cs (Co-Simulation)")
        if parameters not in ("model", "fmu"):
            raise EngineSpecError(f"engine option parameters={parameters}: fix: model (set the "
                                  "FMU's mapped parameters from the model) or fmu (its own values)")
        from fmpy import extract, read_model_description
        path, text, where = _read(fmu, mapping)
        try:
            self._description = read_model_description(str(path))
        except Exception as exc:     # fmpy raises its own and lxml's errors for a bad XML
            raise EngineSpecError(f"engine option fmu={fmu}: its modelDescription.xml does not "
                                  f"read ({str(exc).splitlines()[0][:160]}); fix: give a valid "
                                  "FMI 2.0 FMU") from None
        has = {"me": self._description.modelExchange is not None,
               "cs": self._description.coSimulation is not None}
        self.interface = ("me" if has["me"] else "cs") if interface == "auto" else interface
        if not has[self.interface]:
            raise EngineSpecError(f"engine option interface={interface}: the FMU {fmu} has no "
                                  f"{'Model-Exchange' if self.interface == 'me' else 'Co-Simulation'}"
                                  " interface; fix: interface=auto")
        self._path = path
        variables = {v.name: v for v in self._description.modelVariables}
        try:
            self.mapping = parse_mapping(text, frozenset(variables), where)
        except MappingError as exc:
            raise EngineSpecError(str(exc)) from None
        if self.mapping.contact != model.contact:
            raise UnsupportedModel(f"the FMU models the {self.mapping.contact} front contact, "
                                   f"the model {model.name!r} the {model.contact} one")
        states = [d.variable.derivative.name for d in self._description.derivatives]
        mapped = [r.name for r in self.mapping.coordinates + self.mapping.rates]
        lost = [n for n in mapped if n not in states] if self.interface == "me" else []
        if lost:
            raise EngineSpecError(f"{where}: {', '.join(lost)} are not continuous states of the FMU; "
                                  "fix: map [coordinates] and [rates] to its states")
        self._index = np.array([states.index(n) for n in mapped]) if self.interface == "me" else None
        self._scale = np.array([r.scale for r in self.mapping.coordinates + self.mapping.rates])
        self._vr = {n: v.valueReference for n, v in variables.items()}
        self._torque_vr = [self._vr[r.name] for r in self.mapping.torques]
        self._torque_scale = np.array([r.scale for r in self.mapping.torques])
        values = dict(zip(PARAMETER_NAMES, model.params.vector()))
        self._parameters = {} if parameters == "fmu" else {
            self._vr[r.name]: float(values[k]) / r.scale for k, r in self.mapping.parameters.items()}
        self._unzipped = extract(str(path))
        self._instances: dict[tuple[float, float], _Instance] = {}
        caps = {"forward_acceleration", "simulate"}
        caps |= {c for t, c in _TERM_CAPABILITY.items() if t in self.mapping.terms}
        if {"F", "S"} <= set(self.mapping.terms):
            caps.add("generalized_forces")
        # the linearization needs the whole state: the FMU's continuous states exactly q, dq
        self._linear = self.interface == "me" and len(self._description.derivatives) == 16
        me = self._description.modelExchange
        self.directional = bool(self._linear and me.providesDirectionalDerivative)
        if self._linear:
            caps.add("eigenvalues")
        # a Co-Simulation FMU only steps: runs, nothing at a single state
        self.capabilities = frozenset(caps) if self.interface == "me" else frozenset({"simulate"})

    def __del__(self):
        for inst in getattr(self, "_instances", {}).values():
            try:
                inst.fmu.terminate()
                inst.fmu.freeInstance()
            except Exception:
                pass
        if getattr(self, "_unzipped", None):
            shutil.rmtree(self._unzipped, ignore_errors=True)

    def _instance(self, baumgarte: tuple[float, float] | None) -> _Instance:
        key = (0.0, 0.0) if baumgarte is None or self.mapping.baumgarte is None else \
            tuple(float(a) for a in baumgarte)
        if key not in self._instances:
            params = dict(self._parameters)
            if self.mapping.baumgarte is not None:
                params.update({self._vr[n]: a for n, a in zip(self.mapping.baumgarte, key)})
            self._instances[key] = _Instance(self._description, self._unzipped, params)
        return self._instances[key]

    def _set(self, inst: _Instance, q, dq, torques=None) -> None:
        y = np.concatenate([q, dq]) / self._scale
        x = np.frombuffer(inst.x, dtype=np.float64)
        x[self._index] = y
        inst.fmu.setContinuousStates(inst.x, inst.n)
        if torques is not None:
            inst.fmu.setReal(self._torque_vr, list(np.asarray(torques, float) / self._torque_scale))

    def _one(self, q, dq, T, baumgarte) -> tuple[np.ndarray, int]:
        inst = self._instance(baumgarte)
        try:
            self._set(inst, q, dq, T)
            inst.fmu.getDerivatives(inst.dx, inst.n)
        except Exception:            # fmpy raises on an fmi2Error/fmi2Discard status
            return np.zeros(8), 1
        dx = np.frombuffer(inst.dx, dtype=np.float64)[self._index[8:]] * self._scale[8:]
        return dx.copy(), 0 if np.all(np.isfinite(dx)) else 2

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """The reference's `Model.forward` contract (ddq, status; lambda not read: zeros)."""
        q2, dq2 = np.atleast_2d(q), np.atleast_2d(dq)
        T = np.broadcast_to(np.asarray(torques, float), (q2.shape[0], 3))
        rows = [self._one(a, b, t, baumgarte) for a, b, t in zip(q2, dq2, T)]
        ddq = np.array([r[0] for r in rows])
        status = np.array([r[1] for r in rows], dtype=np.intc)
        single = np.ndim(q) == 1
        return ForwardResult(ddq[0] if single else ddq, np.zeros((len(rows), 5))[0 if single else slice(None)],
                             status)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        if self.interface != "me":
            self._missing("forward_acceleration")
        res = self.forward(q, dq, torques, None)
        if np.any(res.status):
            raise ArithmeticError("the FMU's derivatives failed (fmi2GetDerivatives) at "
                                  f"{int(np.count_nonzero(res.status))} state(s)")
        return res.ddq

    def _outputs(self, names, q, dq, torques=(0.0, 0.0, 0.0)):
        q2, dq2 = np.atleast_2d(q), np.atleast_2d(dq)
        inst = self._instance(None)
        flat = [n for row in names for n in row]
        vrs = [self._vr[n] for n in flat]
        out = []
        for a, b in zip(q2, dq2):
            self._set(inst, a, b, torques)
            out.append(np.array(inst.fmu.getReal(vrs)).reshape(len(names), -1))
        out = np.array(out)
        if out.shape[-1] == 1:
            out = out[..., 0]
        return out[0] if np.ndim(q) == 1 else out

    def mass_matrix(self, q):
        if "mass_matrix" not in self.capabilities:   # (checked: they are instance capabilities)
            self._missing("mass_matrix")
        return self._outputs(self.mapping.terms["M"], q, np.zeros_like(np.asarray(q, float)))

    def gravity(self, q):
        if "gravity" not in self.capabilities:
            self._missing("gravity")
        return self._outputs(self.mapping.terms["Qgrav"], q, np.zeros_like(np.asarray(q, float)))

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        if "generalized_forces" not in self.capabilities:
            self._missing("generalized_forces")
        F = self._outputs(self.mapping.terms["F"], q, dq)
        S = self._outputs(self.mapping.terms["S"], q, dq)
        T = np.asarray(torques, float)
        return F + (S @ T if T.ndim == 1 else np.einsum("nij,nj->ni", S, T))

    def constraint_jacobian(self, q):
        if "constraint_jacobian" not in self.capabilities:
            self._missing("constraint_jacobian")
        return self._outputs(self.mapping.terms["D"], q, np.zeros_like(np.asarray(q, float)))

    def constraint_bias(self, q, dq):
        if "constraint_bias" not in self.capabilities:
            self._missing("constraint_bias")
        return self._outputs(self.mapping.terms["dDdq"], q, dq)

    def constraint_residual(self, q, dq):
        if self.mapping.residual is None:
            return self.model.constraint_residual(q, dq)
        return self._outputs(tuple((n,) for n in self.mapping.residual), q, dq)

    # -- the linearization (linear.py) ------------------------------------------------------

    def _state_refs(self) -> tuple[list[int], list[int]]:
        """Value references of the mapped states and of their derivatives, thesis order."""
        ders = [self._description.derivatives[i] for i in self._index]
        return ([d.variable.derivative.valueReference for d in ders],
                [d.variable.valueReference for d in ders])

    def _jvp(self, q, dq, ds) -> np.ndarray:
        """J_f ds (thesis units) at (q, dq), f = (dq, ddq) at a1 = a2 = 0 (exact accelerations)."""
        inst = self._instance(None)
        if self.directional:
            states, ders = self._state_refs()
            self._set(inst, q, dq, np.zeros(3))
            return self._directional(inst, ders, states, ds / self._scale) * self._scale
        step = FD_STEP / max(float(np.max(np.abs(ds))), 1e-300)
        up, down = np.concatenate([q, dq]) + step * ds, np.concatenate([q, dq]) - step * ds
        return (self._rates(up) - self._rates(down)) / (2 * step)

    @staticmethod
    def _directional(inst: _Instance, unknowns, knowns, seed) -> np.ndarray:
        try:
            return np.array(inst.fmu.getDirectionalDerivative(unknowns, knowns, list(seed)))
        except Exception as exc:     # fmpy raises on an fmi2Error/fmi2Discard status
            raise ArithmeticError("the FMU's fmi2GetDirectionalDerivative failed near upright "
                                  f"({str(exc).splitlines()[0][:120]}), though it declares "
                                  "providesDirectionalDerivative") from None

    def _rates(self, s) -> np.ndarray:
        ddq, status = self._one(s[:8], s[8:], np.zeros(3), None)
        if status:
            raise ArithmeticError("the FMU's derivatives failed (fmi2GetDerivatives) near upright")
        return np.concatenate([s[8:], ddq])

    def _jacobian(self, q) -> np.ndarray:
        """D (5x8): the FMU's output when mapped, else the thesis's constraints at its states."""
        if "D" in self.mapping.terms:
            return self._outputs(self.mapping.terms["D"], q, np.zeros(8))
        return self.model.constraint_jacobian(q)

    def _along(self, q, dq_dir) -> np.ndarray:
        """dD . dq_dir (5x8): directional derivatives of the FMU's D outputs when it has both,
        else central differences of D (step FD_STEP)."""
        if self.directional and "D" in self.mapping.terms:
            inst = self._instance(None)
            self._set(inst, q, np.zeros(8), np.zeros(3))
            states, _ = self._state_refs()
            names = [n for row in self.mapping.terms["D"] for n in row]
            return self._directional(inst, [self._vr[n] for n in names], states[:8],
                                     dq_dir / self._scale[:8]).reshape(5, 8)
        h = FD_STEP / max(float(np.max(np.abs(dq_dir))), 1e-300)
        return (self._jacobian(q + h * dq_dir) - self._jacobian(q - h * dq_dir)) / (2 * h)

    def eigenvalues(self, speeds) -> np.ndarray:
        """(n, 4) complex: the roll/steer eigenvalues (1/s) about upright straight running at
        each forward speed (m/s), sorted as `reference_model.linearize.sort_eigenvalues`;
        by the FMU's directional derivatives, or central differences (`directional`)."""
        if not self._linear:
            self._missing("eigenvalues")
        return roll_steer_eigenvalues(
            self._jvp, lambda q, dq: self._rates(np.concatenate([q, dq]))[8:],
            lambda q, dq: np.asarray(self.constraint_residual(q, dq)), self._jacobian, self._along,
            speeds, self.model.params.R_rear, self.model.params.g)

    def simulate(self, scenario: Scenario, **options):
        if self.interface == "cs":
            return co_simulate(self, scenario, **options)
        return run_forward(_FmuDynamics(self), scenario, torques_from=self.model, **options)


class _FmuDynamics:
    """The reference model with its forward solve (and residual) taken from the FMU: what
    `run_forward` integrates. Everything else (the initial state's projection, the torque
    histories) is the reference's, as for every engine."""

    def __init__(self, engine: FmuEngine):
        self._engine = engine

    def __getattr__(self, name):
        return getattr(self._engine.model, name)

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)):
        return self._engine.forward(q, dq, torques, baumgarte)

    def constraint_residual(self, q, dq):
        return self._engine.constraint_residual(q, dq)
