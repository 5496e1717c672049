"""The settings of a forward run on DART's contact: the engine's options, checked once."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

from ..base import EngineUsageError

__all__ = ["COLLISION_DETECTORS", "DEFAULTS", "RunSettings", "SOLVERS"]

#: DART's collision detectors by option value (the dartpy class names in `run`)
COLLISION_DETECTORS = ("bullet", "ode", "fcl", "dart")
#: the boxed-LCP solvers of DART's constraint solver: Dantzig's pivoting (exact, with PGS as
#: its fallback) or projected Gauss-Seidel alone (iterative)
SOLVERS = ("dantzig", "pgs")


@dataclass(frozen=True)
class RunSettings:
    """What determines a run on DART's contact (the engine's options).

    ``timestep`` (s): DART's fixed step (semi-implicit Euler; must divide the scenario's
    sampling interval); ``collision_detector``: which of DART's detectors finds the
    wheel-ground contacts; ``friction``: the Coulomb coefficient of both wheels and the ground;
    ``solver``: the boxed LCP solver; ``wheel_half_width`` (m): half the cylinder's length (the
    model's wheel is a knife edge); ``split_impulse``: DART's split-impulse position correction
    (off: the penetration is corrected by the velocity-level error reduction instead)."""

    timestep: float = 5e-4
    collision_detector: str = "ode"
    friction: float = 2.0
    solver: str = "dantzig"
    wheel_half_width: float = 1e-6
    split_impulse: bool = False

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    @classmethod
    def checked(cls, **values) -> "RunSettings":
        """The settings, or an EngineUsageError naming the option and the fix."""
        for name in ("timestep", "friction", "wheel_half_width"):
            v = values.get(name, getattr(cls, name))
            if isinstance(v, str):
                try:
                    v = float(v)
                except ValueError:
                    v = None
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) \
                    or v <= 0:
                raise EngineUsageError(f"DART option {name} = {values.get(name)!r}: must be a "
                                       f"positive number; fix: e.g. {name}={getattr(cls, name)!r}")
            values[name] = float(v)
        for name, allowed in (("collision_detector", COLLISION_DETECTORS), ("solver", SOLVERS)):
            v = values.get(name, getattr(cls, name))
            if v not in allowed:
                raise EngineUsageError(f"DART option {name} = {v!r}: unknown; fix: one of "
                                       f"{', '.join(allowed)}")
        v = values.get("split_impulse", cls.split_impulse)
        if isinstance(v, str) and v.lower() in ("true", "false", "1", "0"):
            v = v.lower() in ("true", "1")
        if not isinstance(v, bool):
            raise EngineUsageError(f"DART option split_impulse = {v!r}: must be true or false")
        values["split_impulse"] = v
        return cls(**values)

    def as_dict(self) -> dict:
        return asdict(self)


DEFAULTS = RunSettings()
