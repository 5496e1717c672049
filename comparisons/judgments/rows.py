"""One comparison row: what summary.json's ``comparisons`` lists, as a typed, frozen value.

Every judged or reported comparison of a run is a `Comparison`: the common fields every row
has (quantity, scenario, model, engines, max_error, tolerance, passed, localized_to, note) and
an ``extra`` mapping for what one kind of row adds (a horizon, an order, slip statistics...).
It reads like the mapping it becomes (``row["passed"]``, ``row.get("why")``, ``set(row)``), so
a judgment, a stage or the report reads any field by its key, but it cannot be changed after it
is made; the writer turns it into a dict (`as_dict`) for summary.json.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any, Iterator

__all__ = ["COMMON", "Comparison", "FrozenMapping", "comparison_rows"]

#: the fields every row has, in summary.json's order
COMMON = ("quantity", "scenario", "model", "engines", "max_error", "tolerance", "passed",
          "localized_to", "note")


class FrozenMapping(dict):
    """A dict that refuses changes (and pickles: rows travel from worker processes)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("a comparison row cannot be changed; make a new one with .replace()")

    __setitem__ = __delitem__ = update = pop = popitem = clear = setdefault = _refuse

    def __reduce__(self):
        return (FrozenMapping, (dict(self),))

    def __hash__(self):
        return hash(tuple(sorted(self)))


@dataclass(frozen=True, eq=False)
class Comparison(Mapping):
    """A comparison row (module docstring). ``passed``: True/False when judged against
    ``tolerance``, None when reported; ``engines``: the two compared (or the one measured)."""

    quantity: str
    scenario: str
    model: str
    engines: tuple[str, ...]
    max_error: float | None
    tolerance: float | None
    passed: bool | None
    localized_to: str = "-"
    note: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "engines", tuple(str(e) for e in self.engines))
        if not isinstance(self.quantity, str) or not self.quantity:
            raise ValueError(f"a comparison needs a quantity; got {self.quantity!r}")
        if self.passed is not None and not isinstance(self.passed, bool):
            object.__setattr__(self, "passed", bool(self.passed))
        clash = set(self.extra) & set(COMMON)
        if clash:
            raise ValueError(f"extra fields {sorted(clash)} repeat common ones")
        object.__setattr__(self, "extra", FrozenMapping(self.extra))

    @classmethod
    def of(cls, row: Mapping[str, Any]) -> "Comparison":
        """A row from a mapping: the common fields by name (scenario and model '-' when
        absent), everything else into ``extra``."""
        if isinstance(row, Comparison):
            return row
        d = dict(row)
        common = {k: d.pop(k) for k in COMMON if k in d}
        common.setdefault("scenario", "-")
        common.setdefault("model", "-")
        common.setdefault("engines", ())
        for k in ("max_error", "tolerance", "passed"):
            common.setdefault(k, None)
        if common.get("localized_to") is None:
            common["localized_to"] = "-"
        if common.get("note") is None:
            common["note"] = ""
        return cls(**common, extra=d)

    def replace(self, **changes) -> "Comparison":
        """A copy with ``changes`` (common fields by name, others into ``extra``)."""
        names = {f.name for f in fields(self)}
        extra = dict(self.extra)
        extra.update({k: v for k, v in changes.items() if k not in names})
        return replace(self, **{k: v for k, v in changes.items() if k in names}, extra=extra)

    # -- read like a mapping -----------------------------------------------------------------
    def as_dict(self) -> dict[str, Any]:
        """The row as summary.json writes it: common fields first, ``engines`` a list."""
        out = {k: getattr(self, k) for k in COMMON}
        out["engines"] = list(self.engines)
        out.update(self.extra)
        return out

    def __getitem__(self, key: str) -> Any:
        if key == "engines":
            return list(self.engines)
        if key in COMMON:
            return getattr(self, key)
        return self.extra[key]

    def __iter__(self) -> Iterator[str]:
        yield from COMMON
        yield from self.extra

    def __len__(self) -> int:
        return len(COMMON) + len(self.extra)

    def __hash__(self) -> int:
        return hash((self.quantity, self.scenario, self.model, self.engines))

    def __eq__(self, other) -> bool:
        if isinstance(other, Mapping):
            return self.as_dict() == dict(other.items()) if not isinstance(other, Comparison) \
                else self.as_dict() == other.as_dict()
        return NotImplemented


def comparison_rows(rows) -> list[Comparison]:
    """Rows (mappings or `Comparison`s) as `Comparison`s."""
    return [Comparison.of(r) for r in rows]
