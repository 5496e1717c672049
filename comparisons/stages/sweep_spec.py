"""What a design-space sweep computes (`bicycle-xval sweep`): the spec, its bicycles, its hash.

    spec = make_spec(base, varies=["trail=0:0.2:41"], ...)     # or sample=N, spread=P, seed=S
    values = bicycle_values(spec, k)        # the k-th bicycle's 30 model parameters (a dict)

Two ways to choose bicycles around a base model (a `reference_model.Parameters`):

* **Grids** (``--vary NAME=LOW:HIGH:N``: N points from LOW to HIGH inclusive, SI units; several
  ``--vary`` make the cartesian product, the first one varying slowest). NAME is one of the
  model's own parameters (`reference_model.params.PARAMETER_NAMES`) or a derived benchmark
  quantity (`DERIVED`: ``trail`` c [m], ``head_angle`` pi/2 - lambda [rad], ``wheelbase`` w
  [m]), set through Meijaard et al.'s Table 1 mapping (`reference_model.benchmark`: the base is
  taken to Table 1, the quantity set, and the model rebuilt from Table 1; the other Table 1
  values stay, e.g. the front assembly's CoM stays put in global axes). Derived quantities are
  applied first, then the model's own names. Every grid point is validated when the spec is
  made: a point whose parameters are not a bicycle (e.g. an inertia that is not positive
  definite) is a `SpecError` naming the ``--vary`` and the point.
* **Samples** (``--sample N --spread P --seed S``): every positive geometric length, mass and
  wheel radius multiplied by an independent factor uniform in [1 - P/100, 1 + P/100]; zeros
  stay zero and ``g``, ``cv`` stay the base's (the environment, not the design). Inertias are
  kept physical *by construction*: a body's inertia tensor I and its second-moment matrix
  S = tr(I)/2 1 - I (S = integral of r r^T dm) determine each other, S >= 0 is exactly positive
  semi-definiteness plus the triangle inequality of I, and S' = D S D with D a positive
  diagonal keeps S' >= 0. Each diagonal factor d_i^2 is uniform in [1 - P/100, 1 + P/100], so
  every second moment moves by at most P %; the wheels get d_x = d_z (they stay axisymmetric).
  Bicycle k's factors come from ``numpy.random.SeedSequence([S, k])``: independent of the
  order, the chunking or the process that computes it.

The spec hash (`spec_hash`) is the SHA-256 of the canonical JSON of everything the results
depend on (base parameter values and contact, grids or sample, seed, engines, checks, states,
and every tolerance the checks are judged by: ``--tolerances``' values, not its file name);
the chunk files live under it, so a rerun of the same command finds its finished chunks, and a
rerun with other tolerances starts afresh instead of mixing verdicts. The tolerances travel in
the spec, so every Dask task (`sweep_task.chunk_rows(spec, ...)`) judges by them, whatever the
environment its worker was started in.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass, field

import numpy as np

from reference_model import ParameterError, Parameters
from reference_model.params import PARAMETER_NAMES, _closest

from ..judgments.tolerances import Tolerances, load_tolerances

#: derived benchmark quantities a grid may vary -> (Table 1 name, from Table 1, to Table 1)
DERIVED = {
    "trail": ("c", lambda v: v, lambda x: x),                              # m
    "head_angle": ("lam", lambda v: math.pi / 2 - v, lambda x: math.pi / 2 - x),   # rad
    "wheelbase": ("w", lambda v: v, lambda x: x),                          # m
}
CHECKS = ("terms", "eigen", "runs")
ENVIRONMENT = ("g", "cv")            # not varied by --sample
#: body -> (xx, yy, zz, xz or None) of the model's inertia names
TENSORS = {2: ("I2xx", "I2yy", "I2zz", None), 3: ("I3xx", "I3yy", "I3zz", "I3xz"),
           4: ("I4xx", "I4yy", "I4zz", "I4xz"), 5: ("I5xx", "I5yy", "I5zz", None)}
INERTIAS = tuple(n for names in TENSORS.values() for n in names if n)
MAX_BICYCLES = 10_000_000


class SpecError(ValueError):
    """A sweep spec that cannot run: one line naming the option and the fix."""


@dataclass(frozen=True)
class Grid:
    """One ``--vary NAME=LOW:HIGH:N``."""

    name: str
    low: float
    high: float
    n: int

    def points(self) -> np.ndarray:
        return np.linspace(self.low, self.high, self.n) if self.n > 1 else np.array([self.low])

    def text(self) -> str:
        return f"{self.name}={self.low!r}:{self.high!r}:{self.n}"


@dataclass(frozen=True)
class SweepSpec:
    """Everything the results of a sweep depend on (module docstring)."""

    base: tuple[tuple[str, float], ...]      # the base model's 30 parameters, in order
    base_name: str
    contact: str
    triangle: str
    grids: tuple[Grid, ...] = ()
    sample: int = 0
    spread: float = 0.0                       # per cent
    seed: int = 0
    engines: tuple[str, ...] = ()           # make_spec's default: `engines.term_engines`
    checks: tuple[str, ...] = ("terms", "eigen")
    n_states: int = 8
    #: what the terms are judged by (the CLI's --tolerances; default the packaged file)
    tolerances: Tolerances = field(default_factory=load_tolerances)

    @property
    def n_bicycles(self) -> int:
        return self.sample if not self.grids else math.prod(g.n for g in self.grids)

    @property
    def varied(self) -> tuple[str, ...]:
        """The names varied (grid names; every non-environment parameter for a sample)."""
        if self.grids:
            return tuple(g.name for g in self.grids)
        return tuple(n for n, v in self.base if n not in ENVIRONMENT and v != 0.0)

    def base_parameters(self) -> Parameters:
        return Parameters(**dict(self.base), name=self.base_name, contact=self.contact,
                          triangle=self.triangle)

    def as_json(self) -> dict:
        d = dataclasses.asdict(self)
        d["base"] = [[n, v] for n, v in self.base]
        d["grids"] = [g.text() for g in self.grids]
        d["tolerances"] = self.tolerances.as_json()    # the values, not where they were read
        return d


def spec_hash(spec: SweepSpec) -> str:
    """16 hex digits of the SHA-256 of the spec's canonical JSON (module docstring)."""
    text = json.dumps(spec.as_json(), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


# -- parsing -----------------------------------------------------------------------------------

def parse_vary(text: str) -> Grid:
    """``NAME=LOW:HIGH:N`` -> Grid; a `SpecError` naming what is wrong otherwise."""
    allowed = PARAMETER_NAMES + tuple(DERIVED)
    name, eq, rng = text.partition("=")
    name = name.strip()
    if not eq or not name:
        raise SpecError(f"--vary {text!r}: write NAME=LOW:HIGH:N, e.g. trail=0:0.2:41")
    if name not in allowed:
        hint = _closest(name, allowed)
        raise SpecError(f"--vary {text!r}: unknown parameter {name!r}; "
                        + (f"did you mean {hint!r}? " if hint else "")
                        + "use a model parameter (bicycle-xval export --format json lists them) "
                        "or trail, head_angle, wheelbase")
    parts = rng.split(":")
    if len(parts) != 3:
        raise SpecError(f"--vary {text!r}: the range must be LOW:HIGH:N (three fields), e.g. "
                        f"{name}=0.05:0.1:11")
    try:
        low, high = float(parts[0]), float(parts[1])
    except ValueError:
        raise SpecError(f"--vary {text!r}: LOW and HIGH must be numbers (SI units)") from None
    try:
        n = int(parts[2])
    except ValueError:
        raise SpecError(f"--vary {text!r}: N must be a whole number of points, e.g. 11") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise SpecError(f"--vary {text!r}: LOW and HIGH must be finite numbers")
    if n < 1 or high < low or (n > 1 and high == low):
        raise SpecError(f"--vary {text!r}: empty range; give LOW < HIGH and N >= 2 points "
                        f"(or LOW:LOW:1 for one value)")
    return Grid(name, low, high, n)


def make_spec(base: Parameters, *, varies=(), sample: int | None = None,
              spread: float | None = None, seed: int = 0,
              engines=None, checks=("terms", "eigen"),
              n_states: int = 8, tolerances: Tolerances | None = None) -> SweepSpec:
    """Validate the options into a `SweepSpec` (every grid point is built once here);
    ``engines``: names or specs (None: every installed engine with terms that models the base's
    front contact, `engines.term_engines`; the names are in the spec and its hash);
    ``tolerances``: what the checks are judged by (None: the packaged file; either way the
    values are in the spec and its hash)."""
    grids = tuple(parse_vary(v) if isinstance(v, str) else v for v in varies)
    if grids and sample is not None:
        raise SpecError("--vary and --sample: give one of them (a grid or a random sample)")
    if not grids and sample is None:
        raise SpecError("nothing to sweep: give --vary NAME=LOW:HIGH:N or --sample N --spread P")
    names = [g.name for g in grids]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup:
        raise SpecError(f"--vary {dup}: given twice; give each parameter one range")
    if sample is not None:
        if sample < 1:
            raise SpecError(f"--sample {sample}: give at least 1 bicycle")
        if spread is None:
            raise SpecError("--sample needs --spread P (per cent around the base, e.g. 20)")
        if not (math.isfinite(spread) and spread >= 0):
            raise SpecError(f"--spread {spread}: must be a non-negative per cent, e.g. 20")
        if spread >= 100:
            raise SpecError(f"--spread {spread}: must be below 100 per cent (a factor 1 - P/100 "
                            "must stay positive)")
    elif spread is not None:
        raise SpecError("--spread applies to --sample only; a grid's range is its own")
    if not 0 <= seed < 2**63:
        raise SpecError(f"--seed {seed}: must be a non-negative integer below 2**63")
    if engines is None:
        from engines import term_engines
        engines = term_engines(base.contact)
    if not engines:
        raise SpecError("--engines: give at least one engine (see 'bicycle-xval engines'; none "
                        f"installed computes terms on the {base.contact!r} front contact)")
    if not 1 <= n_states <= 10_000:
        raise SpecError(f"--states {n_states}: must be between 1 and 10000")
    unknown = [c for c in checks if c not in CHECKS]
    if unknown or not checks:
        raise SpecError(f"--checks {','.join(checks)}: choose from {','.join(CHECKS)}")
    if ("eigen" in checks or "runs" in checks) and base.contact != "disc":
        raise SpecError(f"--checks eigen/runs: model {base.name!r} has the thesis front contact; "
                        "the linearization is defined for the disc contact (use --model "
                        "thesis-disc or benchmark, or --checks terms)")
    if "runs" in checks and "eigen" not in checks:
        checks = tuple(c for c in CHECKS if c in (*checks, "eigen"))   # runs need the speeds
    if any(g.name in DERIVED for g in grids):
        from reference_model.benchmark import to_benchmark
        try:
            to_benchmark(base)
        except ParameterError as exc:
            derived = next(g.name for g in grids if g.name in DERIVED)
            raise SpecError(f"--vary {derived}: the base model has no benchmark counterpart "
                            f"({exc.problem}); vary the model's own parameters instead") from None
    if base.cv != 0.0 and ("eigen" in checks):
        base = base.replace(cv=0.0)     # linearized and run without drag (stages.stability)
    spec = SweepSpec(tuple((n, float(getattr(base, n))) for n in PARAMETER_NAMES), base.name,
                     base.contact, base.triangle, grids, sample or 0,
                     float(spread or 0.0), int(seed), tuple(engines),
                     tuple(c for c in CHECKS if c in checks), int(n_states),
                     tolerances if tolerances is not None else load_tolerances())
    if spec.n_bicycles > MAX_BICYCLES:
        raise SpecError(f"--vary: {spec.n_bicycles} bicycles; at most {MAX_BICYCLES} per sweep "
                        "(use fewer points)")
    if grids:
        _check_grid(spec)
    return spec


def _check_grid(spec: SweepSpec) -> None:
    """Every grid point is a valid bicycle (else one line naming the --vary and the point)."""
    base = spec.base_parameters()
    for k in range(spec.n_bicycles):
        try:
            grid_parameters(spec, k, base)
        except ParameterError as exc:
            point = dict(grid_point(spec, k))
            bad = next((g for g in spec.grids if g.name == exc.key.split(".")[-1]),
                       spec.grids[-1])
            raise SpecError(
                f"--vary {bad.text()}: at {', '.join(f'{n} = {v:.6g}' for n, v in point.items())} "
                f"the bicycle is not physical ({exc.key}: {exc.problem}); narrow the range") from None


# -- the bicycles ------------------------------------------------------------------------------

def grid_point(spec: SweepSpec, k: int) -> tuple[tuple[str, float], ...]:
    """The k-th grid point (first grid slowest) as (name, value) pairs."""
    sizes = [g.n for g in spec.grids]
    idx = np.unravel_index(k, sizes)
    return tuple((g.name, float(g.points()[i])) for g, i in zip(spec.grids, idx))


def grid_parameters(spec: SweepSpec, k: int, base: Parameters | None = None) -> Parameters:
    """The k-th grid bicycle (derived quantities through Table 1 first, then model names)."""
    base = base or spec.base_parameters()
    point = dict(grid_point(spec, k))
    derived = {n: v for n, v in point.items() if n in DERIVED}
    params = base
    if derived:
        from reference_model.benchmark import parameters_from_benchmark, to_benchmark
        table = to_benchmark(base)
        for n, v in derived.items():
            key, to_table, _ = DERIVED[n]
            table[key] = to_table(v)
        params = parameters_from_benchmark(table, name=base.name,
                                           allow_triangle_violation=base.triangle == "warn")
        params = params.replace(contact=base.contact, benchmark=None)
    own = {n: v for n, v in point.items() if n not in DERIVED}
    return params.replace(**own) if own else params


def sample_parameters(spec: SweepSpec, k: int) -> Parameters:
    """The k-th sampled bicycle (module docstring: lengths and masses scaled, second moments
    congruence-scaled)."""
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, k]))
    f = spec.spread / 100.0
    base = dict(spec.base)
    out = dict(base)
    for n in PARAMETER_NAMES:          # fixed order: every bicycle draws the same sequence
        if n in INERTIAS or n in ENVIRONMENT:
            continue
        factor = rng.uniform(1 - f, 1 + f)
        out[n] = base[n] * factor
    for body, (kxx, kyy, kzz, kxz) in TENSORS.items():
        I = np.array([[base[kxx], 0, base[kxz] if kxz else 0.0], [0, base[kyy], 0],
                      [base[kxz] if kxz else 0.0, 0, base[kzz]]])
        S = np.trace(I) / 2 * np.eye(3) - I
        d2 = rng.uniform(1 - f, 1 + f, 3)
        if kxz is None:
            d2[2] = d2[0]             # a wheel stays axisymmetric about its spin axis y
        d = np.sqrt(d2)
        S2 = d[:, None] * S * d[None, :]
        I2 = np.trace(S2) * np.eye(3) - S2
        out[kxx], out[kyy], out[kzz] = I2[0, 0], I2[1, 1], I2[2, 2]
        if kxz:
            out[kxz] = I2[0, 2]
    return Parameters(**out, name=spec.base_name, contact=spec.contact, triangle=spec.triangle)


def bicycle_parameters(spec: SweepSpec, k: int) -> Parameters:
    """The k-th bicycle of the sweep (raises `ParameterError` for an invalid sampled one)."""
    return grid_parameters(spec, k) if spec.grids else sample_parameters(spec, k)


def derived_values(params: Parameters) -> dict[str, float]:
    """trail, head_angle, wheelbase of a model with a benchmark counterpart (else NaN)."""
    try:
        from reference_model.benchmark import to_benchmark
        table = to_benchmark(params)
    except (ParameterError, ValueError, ZeroDivisionError):
        return {n: float("nan") for n in DERIVED}
    return {n: float(DERIVED[n][2](table[DERIVED[n][0]])) for n in DERIVED}


__all__ = ["CHECKS", "DERIVED", "Grid", "SpecError", "SweepSpec", "bicycle_parameters",
           "derived_values", "grid_parameters", "grid_point", "make_spec", "parse_vary",
           "sample_parameters", "spec_hash"]
