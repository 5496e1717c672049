"""Every scenario on every engine that can run it, the thesis's way.

An *engine setup* is an engine with its options, labelled as the report names it:

| label        | engine     | runs                                                                |
|--------------|------------|---------------------------------------------------------------------|
| reference    | reference  | inverse (13x13 inverse dynamics) and forward (DOP853, the scenario's |
|              |            | constraint handling: Baumgarte a1 = a2 = 10 as the thesis)          |
| pinocchio    | pinocchio  | the same solvers on Pinocchio's M, RNEA and contact kinematics       |
| exudyn-tree  | exudyn     | forward only: kinematic tree, generalized-alpha, h = 1e-3 s, the     |
|              |            | model's own front contact (user constraints for the thesis contact) |
| mujoco       | mujoco     | forward only, disc-contact models: MuJoCo's soft contact, h = 1e-4 s;  |
|              |            | 'not run' on the thesis contact (a declared model difference)        |
| kane         | kane       | forward only: Kane's equations of Moore's Whipple bicycle in the     |
|              |            | reference's solvers; disc contact only (else 'not run', with why)   |

`run_one` is a top-level function of (label, scenario, model spec), so the pipeline farms runs out to
worker processes: the report's numbers do not depend on the order or the process they ran in.
"""

from __future__ import annotations

from dataclasses import dataclass

from engines.runs import Run, run_scenario
from reference_model.export_mjcf import MjcfSettings

EXUDYN_STEP = 1e-3


@dataclass(frozen=True)
class EngineSetup:
    """An engine and its options under the label the report uses."""

    label: str
    engine: str
    options: tuple[tuple[str, object], ...] = ()
    kinds: tuple[str, ...] = ("inverse", "forward")
    settings: str = ""

    def build(self, model):
        from engines import load_engine
        return load_engine(self.engine, model, **dict(self.options))


SETUPS: dict[str, EngineSetup] = {s.label: s for s in (
    EngineSetup("reference", "reference",
                settings="inverse: inverse kinematics DOP853 rtol 1e-12 + 13x13 LU; forward: "
                         "DOP853 rtol 1e-10, atol 1e-12, the scenario's constraint handling "
                         "(Baumgarte a1 = a2 = 10)"),
    EngineSetup("pinocchio", "pinocchio",
                settings="the reference's solvers on Pinocchio's crba, rnea and frame kinematics "
                         "(same integrator and tolerances)"),
    EngineSetup("exudyn-tree", "exudyn", (("build", "tree"), ("step", EXUDYN_STEP)),
                kinds=("forward",),
                settings=f"ObjectKinematicTree, generalized-alpha (spectral radius 0.9, index 3), "
                         f"h = {EXUDYN_STEP:g} s, Newton tolerance 1e-10; no inverse dynamics"),
    EngineSetup("kane", "kane", kinds=("forward",),
                settings="Moore's Whipple bicycle by Kane's method (sympy KanesMethod, generated "
                         "code, dependent speeds eliminated per state) in the reference's solvers "
                         "(same integrator and tolerances); disc front contact only; no inverse "
                         "dynamics"),
)}
_MJ = MjcfSettings()
SETUPS["mujoco"] = EngineSetup(
    "mujoco", "mujoco", kinds=("forward",),
    settings=f"MuJoCo's own soft wheel-ground contact (disc-contact models only): cylinders on "
             f"a plane, {_MJ.cone} cone, condim {_MJ.condim}, solref "
             f"({_MJ.solref[0]:g} s, {_MJ.solref[1]:g}), timestep {_MJ.timestep:g} s, "
             f"{_MJ.integrator}: the contact study's closest to ideal rolling; no inverse dynamics")
ENGINE_SETUPS = {"reference": ("reference",), "pinocchio": ("pinocchio",),
                 "exudyn": ("exudyn-tree",), "mujoco": ("mujoco",), "kane": ("kane",)}


def label_of(spec: str) -> str:
    """The report's label of an engine spec: its name, or the class name of a
    ``module:Class`` / ``file.py:Class`` spec."""
    return spec.rsplit(":", 1)[-1] if ":" in spec else spec


def plugin_setup(spec: str, options: dict | None = None) -> EngineSetup:
    """The setup of an engine that is not a built-in: its declared capabilities say which
    scenarios it runs (inverse through a ``run_inverse(scenario)`` method, forward through
    ``simulate``)."""
    from engines.registry import resolve
    cls = resolve(spec)[0]
    kinds = tuple(k for k, ok in (("inverse", callable(getattr(cls, "run_inverse", None))),
                                  ("forward", "simulate" in getattr(cls, "capabilities", ())))
                  if ok)
    opts = tuple(sorted((options or {}).items()))
    return EngineSetup(label_of(spec), spec, opts, kinds,
                       settings=f"{spec} with its own defaults"
                                + (f" and {', '.join(f'{k} = {v}' for k, v in opts)}" if opts else ""))


def setups_for(engines, options: dict | None = None) -> list[EngineSetup]:
    """The setups of the selected engines (names or specs), reference first; ``options``:
    spec -> keyword options for engines that are not built-ins."""
    out = []
    for e in engines:
        if e in ENGINE_SETUPS and not (options or {}).get(e):
            out += [SETUPS[lab] for lab in ENGINE_SETUPS[e]]
        else:
            out.append(plugin_setup(e, (options or {}).get(e)))
    return out


def run_one(setup: EngineSetup, scenario, model: str | None = None) -> Run:
    """Run ``scenario`` (a built-in's name, or a `Scenario`) on ``setup`` and on ``model`` (a
    named model or a parameter-file path; default the scenario's own). A top-level function of
    picklable arguments: worker processes call it."""
    import dataclasses

    from engines import UnsupportedModel
    from engines.registry import resolve
    from reference_model import load_model
    from reference_model.scenarios import get_scenario

    sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
    if model is not None and model != sc.model:
        sc = dataclasses.replace(sc, model=model)
    label = setup.label
    model = load_model(sc.model)
    if sc.kind not in setup.kinds:
        return run_scenario(label, None, model, sc, setup.kinds)
    try:
        engine = None if (label == "reference" and sc.kind == "inverse") else setup.build(model)
    except UnsupportedModel as exc:   # a declared limitation: not run, and why
        cls = resolve(setup.engine)[0]
        why = (_contact_reason(cls, setup, model) if model.contact not in
               getattr(cls, "contacts", ()) else f"not run on this model: {exc}")
        return Run(label, sc.name, model.name, sc.kind, "not run", why, 0.0)
    return run_scenario(label, engine, model, sc, setup.kinds)


def _contact_reason(cls, setup: EngineSetup, model) -> str:
    """Why an engine cannot run on ``model``'s front contact: the `CapabilityError` its
    constructor raises (the loader refuses the contact before asking it), or a plain
    statement."""
    from engines import CapabilityError
    try:
        cls(model, **dict(setup.options))
    except CapabilityError as exc:
        return f"CapabilityError: {' '.join(str(exc).split())}"
    except Exception:   # noqa: BLE001 - any other failure: the plain statement below
        pass
    return (f"{setup.label} models the front contact(s) {', '.join(cls.contacts)}, not "
            f"{model.contact!r} of model {model.name!r}")


def cost(label: str, scenario: str) -> float:
    """A rough run time for scheduling (s), measured on the 2-core machine."""
    scenario = scenario.split("-on-")[0]
    if scenario in ("check", "zigzag"):
        return 0.1 if label == "reference" else 0.8
    per_second = {"reference": 0.05, "pinocchio": 0.6, "exudyn-tree": 0.6, "mujoco": 0.35,
                  "kane": 0.3}.get(label, 1.0)
    length = 6.3 if scenario in ("replay", "check-forward") else 1.2
    return per_second * length
