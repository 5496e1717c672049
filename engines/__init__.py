"""Engine adapters behind one small interface (`engines.base.Engine`).

    from engines import load_engine
    eng = load_engine("pinocchio", model)     # model from reference_model.load_model
    eng = load_engine("exudyn", model, build="redundant", step=1e-3)
"""

from __future__ import annotations

from .base import CAPABILITIES, CapabilityError, Engine, EngineError, EngineUsageError

ENGINES = ("reference", "pinocchio", "exudyn")


def load_engine(name: str, model, **options) -> Engine:
    """Build engine ``name`` for a `reference_model.Model`; ``options`` go to the engine
    (Exudyn: build, step, solver, ...); the reference and Pinocchio engines take none."""
    if options and name in ("reference", "pinocchio"):
        raise EngineError(f"engine {name!r} takes no options; got {', '.join(sorted(options))}")
    if name == "reference":
        from .reference import ReferenceEngine
        return ReferenceEngine(model)
    if name == "pinocchio":
        from .pinocchio import PinocchioEngine
        return PinocchioEngine(model)
    if name == "exudyn":
        from .exudyn import ExudynEngine
        return ExudynEngine(model, **options)
    raise EngineError(f"unknown engine {name!r}; available: {', '.join(ENGINES)}")


__all__ = ["CAPABILITIES", "ENGINES", "CapabilityError", "Engine", "EngineError",
           "EngineUsageError", "load_engine"]
