"""The Drake engine's contact-run settings: one frozen record, validated when it is made, so a
bad value is a one-line usage error naming the option and the fix."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..base import EngineUsageError

__all__ = ["APPROXIMATIONS", "CONTACT_MODELS", "DEFAULTS", "RunSettings", "settings_from"]

#: Drake's discrete contact approximations (``DiscreteContactApproximation``), by option value
APPROXIMATIONS = ("tamsi", "sap", "lagged", "similar")
CONTACT_MODELS = ("point", "hydroelastic")


@dataclass(frozen=True)
class RunSettings:
    """What determines a contact run (all SI). ``time_step``: the discrete plant's step (s);
    ``approximation``: Drake's contact solver; ``contact_model``: point or hydroelastic;
    ``stiction_tolerance``: the regularized friction's slip speed at full friction (m/s);
    ``friction``: the Coulomb coefficient (static = dynamic); ``point_stiffness`` (N/m) and
    ``dissipation`` (Hunt-Crossley, s/m) of the point contact; ``hydroelastic_modulus`` (Pa)
    of the wheels' compliant hydroelastic cylinders; ``wheel_half_width`` (m): half the
    cylinders' length (the model's wheel is a knife edge)."""

    time_step: float = 5e-4
    approximation: str = "tamsi"
    contact_model: str = "point"
    stiction_tolerance: float = 1e-4
    friction: float = 2.0
    point_stiffness: float = 1e8
    dissipation: float = 10.0
    hydroelastic_modulus: float = 1e9
    wheel_half_width: float = 1e-6

    def __post_init__(self):
        for name in ("time_step", "stiction_tolerance", "friction", "point_stiffness",
                     "hydroelastic_modulus", "wheel_half_width"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or v <= 0:
                raise EngineUsageError(f"Drake option {name} = {v!r}: must be a positive number; "
                                       f"fix: e.g. {name}={getattr(RunSettings, name)!r}")
        d = self.dissipation
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d < 0:
            raise EngineUsageError(f"Drake option dissipation = {d!r}: must be a number >= 0 "
                                   "(s/m); fix: e.g. dissipation=10")
        for name, allowed in (("approximation", APPROXIMATIONS), ("contact_model", CONTACT_MODELS)):
            if getattr(self, name) not in allowed:
                raise EngineUsageError(f"Drake option {name} = {getattr(self, name)!r}: not one of "
                                       f"{', '.join(allowed)}; fix: {name}={allowed[0]}")

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(cls))

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    def replace(self, **changes) -> "RunSettings":
        return settings_from(**{**self.as_dict(), **changes})


def _number(name: str, value):
    """A number given as text (the CLI's ``--engine-option key=value``) as a float."""
    if isinstance(value, str) and name not in ("approximation", "contact_model"):
        try:
            return float(value)
        except ValueError:
            raise EngineUsageError(f"Drake option {name} = {value!r}: not a number; fix: e.g. "
                                   f"{name}={getattr(RunSettings, name)!r}") from None
    return value


def settings_from(**options) -> RunSettings:
    unknown = sorted(set(options) - set(RunSettings.field_names()))
    if unknown:
        raise EngineUsageError(f"Drake got unknown option(s) {', '.join(unknown)}; it takes "
                               f"{', '.join(RunSettings.field_names())}")
    return RunSettings(**{k: _number(k, v) for k, v in options.items()})


DEFAULTS = RunSettings()
