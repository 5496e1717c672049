"""``bicycle-xval eigenvalues``: the linearized roll/steer eigenvalues against speed, to CSV and
optionally a figure.

    bicycle-xval eigenvalues --model benchmark --speeds 0:10:0.01 --out eig.csv [--figure eig.png]

CSV columns as `comparisons.judgments.eigenvalues.eigenvalue_table`, each value its shortest exact decimal.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..judgments.eigenvalues import critical_speeds, eigenvalue_curves, eigenvalue_table
from .errors import UsageError


SPEEDS_HELP = "speeds in m/s as start:stop:step (stop included when on the grid), e.g. 0:10:0.01"
MAX_SPEEDS = 1_000_000
_EXAMPLE = "e.g. --speeds 0:10:0.01"


def parse_speeds(text: str, option: str = "--speeds") -> np.ndarray:
    """``start:stop:step`` -> the speeds start, start + step, ..., stop (m/s).

    stop is included when it lies on the grid (to 1e-9 of a step) and is then exactly ``stop``;
    otherwise the grid ends at the last point below stop. A single number is one speed.
    Anything else raises `UsageError` with one line naming ``option`` and the fix.
    """
    raw = str(text).strip()
    parts = raw.split(":")
    if len(parts) not in (1, 3) or not all(p.strip() for p in parts):
        raise UsageError(f"{option} {raw!r}: expected start:stop:step or one speed; {_EXAMPLE}")
    values = []
    for name, part in zip(("start", "stop", "step") if len(parts) == 3 else ("speed",), parts):
        try:
            x = float(part)
        except ValueError:
            raise UsageError(f"{option} {raw!r}: {name} {part.strip()!r} is not a number; "
                         f"{_EXAMPLE}") from None
        if not math.isfinite(x):
            raise UsageError(f"{option} {raw!r}: {name} must be finite; {_EXAMPLE}")
        values.append(x)
    if len(values) == 1:
        return np.array(values)
    start, stop, step = values
    if step <= 0:
        raise UsageError(f"{option} {raw!r}: step must be > 0; {_EXAMPLE}")
    if stop < start:
        raise UsageError(f"{option} {raw!r}: stop {stop:g} is below start {start:g}; write "
                     f"start:stop:step with start <= stop, {_EXAMPLE}")
    span = (stop - start) / step
    if stop > start and span < 1 - 1e-9:   # one speed of a range asked for: not what was meant
        raise UsageError(f"{option} {raw!r}: step {step:g} is larger than the range {start:g} to "
                         f"{stop:g} m/s, which would give the one speed {start:g}; the third "
                         f"number is the step in m/s, not a count, {_EXAMPLE}")
    n = math.floor(span + 1e-9)
    if n + 1 > MAX_SPEEDS:
        raise UsageError(f"{option} {raw!r}: {n + 1} speeds is more than {MAX_SPEEDS}; use a larger "
                     "step or a shorter range")
    speeds = start + step * np.arange(n + 1)
    if abs(span - n) <= 1e-9:
        speeds[-1] = stop
    return speeds



def add_eigenvalues_parser(subparsers) -> None:
    """Register ``eigenvalues`` on the CLI's subparsers (sets ``func=run_eigenvalues``)."""
    s = subparsers.add_parser(
        "eigenvalues", help="eigenvalues of the linearized roll/steer dynamics against speed")
    s.add_argument("--model", default="benchmark",
                   help="named model (benchmark, thesis, thesis-disc) or a parameter .toml file "
                        "[benchmark]")
    s.add_argument("--contact", choices=("thesis", "disc"), default=None,
                   help="override the model's front-contact model")
    s.add_argument("--speeds", default="0:10:0.01", help=SPEEDS_HELP + " [0:10:0.01]")
    s.add_argument("--out", required=True, type=Path, help="CSV file to write")
    s.add_argument("--figure", type=Path, default=None, help="also draw the eigenvalues to this PNG")
    s.add_argument("--no-drag", action="store_true",
                   help="linearize with cv = 0 (a model with drag has no steady upright motion)")
    s.set_defaults(func=run_eigenvalues)


def run_eigenvalues(args) -> int:
    """The ``eigenvalues`` command: CSV (and figure) of the eigenvalues; exit status 0."""
    from reference_model import load_model
    from reference_model.linearize import LinearizationError, linearize

    speeds = parse_speeds(getattr(args, "speeds", "0:10:0.01"))
    figure = getattr(args, "figure", None)
    if figure is not None and Path(figure).suffix.lower() != ".png":
        raise UsageError(f"--figure {figure}: the figure is a PNG image; give a file name ending "
                         "in .png, e.g. eigenvalues.png")
    model = load_model(args.model, contact=getattr(args, "contact", None))
    if getattr(args, "no_drag", False) and model.params.cv != 0.0:
        model = model.with_params(model.params.replace(cv=0.0))
    if model.params.cv != 0.0:
        raise UsageError(f"--model {args.model}: drag cv = {model.params.cv:g} kg/m: upright straight "
                     "running at constant speed is not a steady motion with drag; fix: add "
                     "--no-drag to linearize with cv = 0")
    try:
        lin = linearize(model, float(speeds[0]))
    except LinearizationError as exc:
        raise UsageError(f"--model {args.model}: {exc}") from None
    from ..stages.files import write_csv
    frame = eigenvalue_table(model, speeds)
    write_csv(frame, args.out)
    print(f"eigenvalues of {model.name} ({model.contact} contact, frame pitch at upright "
          f"{lin.beta0:+.6f} rad) at {len(frame)} speed(s) from {speeds[0]:g} to {speeds[-1]:g} "
          f"m/s -> {args.out}")
    weave, capsize = critical_speeds(model, speeds)
    text = [f"weave speed {weave:.14g} m/s" if weave is not None else "no weave speed",
            f"capsize speed {capsize:.14g} m/s" if capsize is not None else "no capsize speed"]
    if len(speeds) > 1:
        print(f"  in [{max(0.0, speeds.min()):g}, {speeds.max():g}] m/s: " + ", ".join(text)
              + (f"; self-stable for {weave:.4f} < v < {capsize:.4f} m/s"
                 if weave is not None and capsize is not None and capsize > weave else ""))
    if figure is not None:
        from ..report.figures import save_figure
        print(f"  figure -> {save_figure('eigenvalues', eigenvalue_curves(model, speeds), figure)}")
    return 0
