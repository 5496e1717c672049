"""Eigenvalues of the linearized roll/steer dynamics against forward speed: table, CSV, figure,
and the ``bicycle-xval eigenvalues`` command.

    bicycle-xval eigenvalues --model benchmark --speeds 0:10:0.01 --out eig.csv [--figure eig.png]

The linearization is :mod:`reference_model.linearize` (upright straight running, exact complex-
step derivatives). CSV columns: ``v`` (forward speed, m/s), then ``re_k, im_k`` (1/s) for the
four eigenvalues k = 1..4 in the order of ``linearize.sort_eigenvalues`` (complex pairs first,
+imag before -imag, then the real ones decreasing: for the benchmark above ~0.7 m/s, weave,
weave, capsize, castor, as Table 2 of Meijaard et al. 2007), and ``stable`` (all real parts < 0).
Numbers are written with 17 significant digits.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = [
    "SPEEDS_HELP", "add_eigenvalues_parser", "critical_speeds", "eigenvalue_figure",
    "eigenvalue_table", "parse_speeds", "run_eigenvalues", "write_eigenvalues_csv",
]

SPEEDS_HELP = "speeds in m/s as start:stop:step (stop included when on the grid), e.g. 0:10:0.01"
MAX_SPEEDS = 1_000_000
_EXAMPLE = "e.g. --speeds 0:10:0.01"


def _usage(message: str) -> Exception:
    from .cli import UsageError  # late: cli imports this module
    return UsageError(message)


def parse_speeds(text: str, option: str = "--speeds") -> np.ndarray:
    """``start:stop:step`` -> the speeds start, start + step, ..., stop (m/s).

    stop is included when it lies on the grid (to 1e-9 of a step) and is then exactly ``stop``;
    otherwise the grid ends at the last point below stop. A single number is one speed.
    Anything else raises ``comparisons.cli.UsageError`` with one line naming ``option`` and the fix.
    """
    raw = str(text).strip()
    parts = raw.split(":")
    if len(parts) not in (1, 3) or not all(p.strip() for p in parts):
        raise _usage(f"{option} {raw!r}: expected start:stop:step or one speed; {_EXAMPLE}")
    values = []
    for name, part in zip(("start", "stop", "step") if len(parts) == 3 else ("speed",), parts):
        try:
            x = float(part)
        except ValueError:
            raise _usage(f"{option} {raw!r}: {name} {part.strip()!r} is not a number; "
                         f"{_EXAMPLE}") from None
        if not math.isfinite(x):
            raise _usage(f"{option} {raw!r}: {name} must be finite; {_EXAMPLE}")
        values.append(x)
    if len(values) == 1:
        return np.array(values)
    start, stop, step = values
    if step <= 0:
        raise _usage(f"{option} {raw!r}: step must be > 0; {_EXAMPLE}")
    if stop < start:
        raise _usage(f"{option} {raw!r}: stop {stop:g} is below start {start:g}; write "
                     f"start:stop:step with start <= stop, {_EXAMPLE}")
    span = (stop - start) / step
    n = math.floor(span + 1e-9)
    if n + 1 > MAX_SPEEDS:
        raise _usage(f"{option} {raw!r}: {n + 1} speeds is more than {MAX_SPEEDS}; use a larger "
                     "step or a shorter range")
    speeds = start + step * np.arange(n + 1)
    if abs(span - n) <= 1e-9:
        speeds[-1] = stop
    return speeds


def eigenvalue_table(model, speeds) -> "pd.DataFrame":  # noqa: F821
    """Eigenvalues at each speed: columns v, re_1, im_1, ..., re_4, im_4, stable (module doc)."""
    import pandas as pd

    from reference_model.linearize import eigenvalues

    v = np.atleast_1d(np.asarray(speeds, dtype=np.float64))
    lam = eigenvalues(model, v)
    cols: dict[str, np.ndarray] = {"v": v}
    for k in range(4):
        cols[f"re_{k + 1}"] = lam[:, k].real
        cols[f"im_{k + 1}"] = lam[:, k].imag
    cols["stable"] = np.all(lam.real < 0, axis=1)
    return pd.DataFrame(cols)


def write_eigenvalues_csv(model, speeds, out_path) -> "pd.DataFrame":  # noqa: F821
    """Write :func:`eigenvalue_table` to ``out_path`` (17 significant digits); return the table."""
    frame = eigenvalue_table(model, speeds)
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(out, index=False, float_format="%.17g")
    return frame


def critical_speeds(model, speeds) -> tuple[float | None, float | None]:
    """(weave speed, capsize speed) within [max(0, min speeds), max speeds]; None where none."""
    from reference_model.linearize import CriticalSpeedError, capsize_speed, weave_speed

    v = np.asarray(speeds, dtype=np.float64)
    lo, hi = max(0.0, float(v.min())), float(v.max())
    if not hi > lo:
        return None, None
    found = []
    for fn in (weave_speed, capsize_speed):
        try:
            found.append(fn(model, (lo, hi)))
        except CriticalSpeedError:
            found.append(None)
    return found[0], found[1]


def eigenvalue_figure(model, speeds, path) -> Path:
    """Real (black) and imaginary (grey) parts of the eigenvalues against speed, with the
    weave and capsize speeds marked and the self-stable range shaded (matplotlib Agg, PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frame = eigenvalue_table(model, speeds)
    v = frame["v"].to_numpy()
    weave, capsize = critical_speeds(model, v)
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    for k in range(1, 5):
        im = frame[f"im_{k}"].to_numpy()
        ax.plot(v, np.where(im > 0, im, np.nan), ".", color="0.6", ms=2,
                label="imaginary part" if k == 1 else None)
        ax.plot(v, frame[f"re_{k}"].to_numpy(), ".", color="k", ms=2,
                label="real part" if k == 1 else None)
    ax.axhline(0.0, color="0.3", lw=0.6)
    for speed, name, style in ((weave, "weave", "--"), (capsize, "capsize", ":")):
        if speed is not None:
            ax.axvline(speed, color="tab:blue", ls=style, lw=1.0,
                       label=f"{name} speed {speed:.6f} m/s")
    if weave is not None and capsize is not None and capsize > weave:
        ax.axvspan(weave, capsize, color="tab:green", alpha=0.12, label="self-stable")
    if v.max() > v.min():
        ax.set_xlim(v.min(), v.max())
    ax.set_xlabel("forward speed v (m/s)")
    ax.set_ylabel("eigenvalue (1/s)")
    ax.set_title(f"{model.name}: roll/steer eigenvalues about upright straight running")
    ax.legend(loc="lower left", fontsize=8, markerscale=4)
    ax.grid(True, lw=0.3)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out, dpi=90, metadata={"Software": None})
    plt.close(fig)
    return out


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
    model = load_model(args.model, contact=getattr(args, "contact", None))
    if getattr(args, "no_drag", False) and model.params.cv != 0.0:
        model = model.with_params(model.params.replace(cv=0.0))
    if model.params.cv != 0.0:
        raise _usage(f"--model {args.model}: drag cv = {model.params.cv:g} kg/m: upright straight "
                     "running at constant speed is not a steady motion with drag; fix: add "
                     "--no-drag to linearize with cv = 0")
    try:
        lin = linearize(model, float(speeds[0]))
    except LinearizationError as exc:
        raise _usage(f"--model {args.model}: {exc}") from None
    frame = write_eigenvalues_csv(model, speeds, args.out)
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
    figure = getattr(args, "figure", None)
    if figure is not None:
        print(f"  figure -> {eigenvalue_figure(model, speeds, figure)}")
    return 0
