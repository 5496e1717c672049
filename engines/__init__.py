"""Engine adapters behind one small interface (`engines.base.Engine`).

    from engines import load_engine
    eng = load_engine("pinocchio", model)     # model from reference_model.load_model
"""

from __future__ import annotations

from .base import CAPABILITIES, CapabilityError, Engine, EngineError

ENGINES = ("reference", "pinocchio")


def load_engine(name: str, model) -> Engine:
    """Build engine ``name`` for a `reference_model.Model`."""
    if name == "reference":
        from .reference import ReferenceEngine
        return ReferenceEngine(model)
    if name == "pinocchio":
        from .pinocchio import PinocchioEngine
        return PinocchioEngine(model)
    raise EngineError(f"unknown engine {name!r}; available: {', '.join(ENGINES)}")


__all__ = ["CAPABILITIES", "ENGINES", "CapabilityError", "Engine", "EngineError", "load_engine"]
