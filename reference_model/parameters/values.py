"""The reference bicycle's parameter set: :class:`Parameters`, one validated, frozen set of
the 30 values of ``reference_model.parameters.schema`` (SI, thesis notation), and its two
ways to and from the Meijaard et al. (2007) benchmark's Table 1 (:func:`parameters_from_benchmark`,
:func:`to_benchmark`, :func:`attach_benchmark`; the formulas are
``reference_model.parameters.benchmark``'s). No file is read or written here
(``reference_model.parameters.model_file`` and ``loading``).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .benchmark import Table1, benchmark_values, checked_table, consistent_table, model_values
from .schema import (BODY_NAMES, INERTIA_KEYS, MEMORY_SOURCE, PARAMETER_GROUPS, PARAMETER_NAMES,
                     ParameterError, TriangleInequalityError, as_real, check_bounds,
                     check_contact, check_inertia, check_signs, check_triangle_mode, closest,
                     qualified)

__all__ = ["Parameters", "attach_benchmark", "parameters_from_benchmark", "to_benchmark"]


@dataclass(frozen=True)
class Parameters:
    """One validated parameter set of the reference bicycle (SI units, thesis notation).

    The float fields are exactly :data:`PARAMETER_NAMES`, in that order; ``name`` is the model
    name, ``contact`` the front contact model (one of :data:`CONTACT_MODELS`) and ``source``
    the file it was read from (``"<memory>"`` if built in code). Validation runs on every
    construction, including :meth:`replace` and :meth:`with_contact`.

    ``triangle`` is the triangle-inequality check mode (:data:`TRIANGLE_MODES`): "strict"
    raises :class:`TriangleInequalityError`, "warn" keeps one line per violating body in
    ``warnings`` (a tuple of strings, empty for a clean set; not an argument). ``benchmark``
    is the :class:`~reference_model.parameters.benchmark.Table1` the values were computed
    from, if any (provenance for an exact :func:`to_benchmark`; not compared;
    :meth:`replace` drops it when a parameter value changes).
    """

    R_rear: float
    R_front: float
    x3: float
    z3: float
    xa: float
    za: float
    dx4: float
    dz4: float
    x5: float
    z5: float
    m2: float
    m3: float
    m4: float
    m5: float
    I2xx: float
    I2yy: float
    I2zz: float
    I3xx: float
    I3yy: float
    I3zz: float
    I3xz: float
    I4xx: float
    I4yy: float
    I4zz: float
    I4xz: float
    I5xx: float
    I5yy: float
    I5zz: float
    g: float
    cv: float
    name: str = "custom"
    contact: str = "thesis"
    source: str = MEMORY_SOURCE
    triangle: str = "strict"
    benchmark: Table1 | None = field(default=None, compare=False, repr=False)
    warnings: tuple[str, ...] = field(init=False, default=(), compare=False)

    def __post_init__(self) -> None:
        source = self.source
        if isinstance(source, os.PathLike):
            source = os.fspath(source)
            object.__setattr__(self, "source", source)
        if not isinstance(source, str):
            raise ParameterError(
                repr(source), "source", "source must be a string", "pass a file path or '<memory>'"
            )
        if not isinstance(self.name, str):
            raise ParameterError(
                source, "model.name", f"name {self.name!r} is not a string", "use a string name"
            )
        values = {n: as_real(source, qualified(n), getattr(self, n)) for n in PARAMETER_NAMES}
        for n, v in values.items():
            object.__setattr__(self, n, v)
        check_signs(source, values)
        check_bounds(source, values)
        check_triangle_mode(source, self.triangle)
        warned: list[str] = []
        for body in INERTIA_KEYS:
            try:
                check_inertia(source, body, values)
            except TriangleInequalityError as exc:
                if self.triangle == "strict":
                    raise TriangleInequalityError(
                        exc.file, exc.key, exc.problem,
                        f"{exc.fix}; if the values are measured and right, allow it with "
                        '[checks] triangle = "warn" (or allow_triangle_violation=True)',
                    ) from None
                warned.append(f"{exc.key}: {exc.problem} (allowed: triangle = \"warn\")")
        object.__setattr__(self, "warnings", tuple(warned))
        check_contact(source, self.contact)

    # -- conversions ---------------------------------------------------------------------

    def vector(self) -> np.ndarray:
        """The flat parameter vector ``p`` (float64, :data:`PARAMETER_NAMES` order)."""
        return np.array([getattr(self, n) for n in PARAMETER_NAMES], dtype=np.float64)

    @classmethod
    def from_vector(
        cls,
        p: Iterable[float],
        *,
        name: str = "custom",
        contact: str = "thesis",
        source: str = MEMORY_SOURCE,
        triangle: str = "strict",
    ) -> Parameters:
        """Inverse of :meth:`vector`."""
        values = [float(x) for x in np.asarray(p, dtype=np.float64).ravel()]
        if len(values) != len(PARAMETER_NAMES):
            raise ParameterError(
                source,
                "(vector)",
                f"parameter vector has {len(values)} entries, expected {len(PARAMETER_NAMES)}",
                "pass one value per name in PARAMETER_NAMES, in that order",
            )
        return cls(**dict(zip(PARAMETER_NAMES, values)), name=name, contact=contact, source=source,
                   triangle=triangle)

    @classmethod
    def from_benchmark(
        cls,
        mapping: Mapping[str, Any],
        *,
        name: str = "custom",
        source: str = MEMORY_SOURCE,
        allow_triangle_violation: bool = False,
    ) -> Parameters:
        """The model from Meijaard et al. (2007) Table 1 names (``w, c, lam, g, rR, ...``: all
        26, any real numbers, NumPy scalars included), front contact "disc" (the benchmark's
        knife-edge wheel), the formulas of :mod:`reference_model.parameters.benchmark`. Bad
        input raises one :class:`ParameterError` naming the benchmark key."""
        table = checked_table(mapping, source=source,
                              allow_triangle_violation=allow_triangle_violation)
        return cls(**model_values(table), name=name, contact="disc", source=str(source),
                   triangle="warn" if allow_triangle_violation else "strict", benchmark=table)

    def as_dict(self) -> dict[str, Any]:
        """All init fields: the parameters in :data:`PARAMETER_NAMES` order, then name, contact,
        source, triangle, benchmark. ``Parameters(**p.as_dict()) == p``."""
        out: dict[str, Any] = {n: getattr(self, n) for n in PARAMETER_NAMES}
        out.update(name=self.name, contact=self.contact, source=self.source,
                   triangle=self.triangle, benchmark=self.benchmark)
        return out

    # -- derived copies ------------------------------------------------------------------

    def replace(self, **changes: Any) -> Parameters:
        """A copy with some fields changed, validated again."""
        fields = {f.name for f in dataclasses.fields(self) if f.init}
        for key in changes:
            if key not in fields:
                hint = closest(key, fields)
                raise ParameterError(
                    self.source,
                    qualified(key) if key in PARAMETER_GROUPS else key,
                    f"{key!r} is not a field of Parameters",
                    f"use {hint!r}" if hint else "use a name from PARAMETER_NAMES, or name/contact/source",
                )
        if "benchmark" not in changes and any(n in changes for n in PARAMETER_NAMES):
            changes["benchmark"] = None      # the Table 1 provenance no longer holds
        return dataclasses.replace(self, **changes)

    def with_contact(self, contact: str) -> Parameters:
        """The same parameters with another front contact model (see :data:`CONTACT_MODELS`)."""
        return self.replace(contact=contact)

    # -- derived quantities --------------------------------------------------------------

    def inertia(self, body: int) -> np.ndarray:
        """Inertia tensor (3x3, symmetric, kg*m^2) of body 2..5 about its CoM in body axes.

        ``xz`` is the tensor entry ``[0, 2] = [2, 0]`` (thesis I3, I4); the wheels have none.
        """
        if isinstance(body, bool) or body not in INERTIA_KEYS:
            raise ValueError(
                f"body must be one of {tuple(INERTIA_KEYS)} "
                f"({', '.join(f'{b}: {n}' for b, n in BODY_NAMES.items())}), got {body!r}"
            )
        kxx, kyy, kzz, kxz = INERTIA_KEYS[body]
        xz = getattr(self, kxz) if kxz is not None else 0.0
        return np.array(
            [
                [getattr(self, kxx), 0.0, xz],
                [0.0, getattr(self, kyy), 0.0],
                [xz, 0.0, getattr(self, kzz)],
            ],
            dtype=np.float64,
        )


def parameters_from_benchmark(
    mapping: Mapping[str, Any] | Table1,
    *,
    name: str = "custom",
    source: str = MEMORY_SOURCE,
    allow_triangle_violation: bool = False,
) -> Parameters:
    """The model (contact "disc") of a bicycle given by Table 1's 26 names (any real numbers).

    The triangle inequality is an error naming Table 1's keys unless
    ``allow_triangle_violation``: then the model carries it in ``warnings``. Every problem
    raises one :class:`ParameterError` naming ``source`` and the key.
    """
    return Parameters.from_benchmark(mapping, name=name, source=source,
                                     allow_triangle_violation=allow_triangle_violation)


def attach_benchmark(params: Parameters, mapping: Mapping[str, Any], *, key: str = "benchmark") -> Parameters:
    """``params`` with the Table 1 of a parameter file's ``[benchmark]`` table attached, after
    checking that the model's values follow from it (to rounding: ``CONSISTENCY_RTOL``)."""
    table = consistent_table(_values(params), mapping, source=params.source, key=key)
    return dataclasses.replace(params, benchmark=table)


def to_benchmark(params: Parameters) -> dict[str, float]:
    """Table 1's 26 values (``BENCHMARK_NAMES`` order, SI) of a model with a benchmark
    counterpart (contact "disc", ``cv = 0``, wheels with ``Izz = Ixx``).

    A model built from Table 1 values (import, ``[benchmark]`` table) returns them exactly,
    once checked to reproduce its parameters; otherwise the reverse formulas of
    ``reference_model.parameters.benchmark`` (exact to rounding). Raises one
    :class:`ParameterError` listing every parameter without a benchmark counterpart otherwise.
    """
    return benchmark_values(_values(params), contact=params.contact, name=params.name,
                            source=params.source, table=params.benchmark)


def _values(params: Parameters) -> dict[str, float]:
    return {n: getattr(params, n) for n in PARAMETER_NAMES}
