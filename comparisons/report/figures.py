"""The report's figures (matplotlib, Agg): one drawing function per figure kind.

Stages describe a figure as data (`comparisons.stages.results.Figure`: a kind and the arrays
it needs); `save_figure` draws it and writes the PNG atomically, quantized to a 256-colour
palette (line plots lose nothing visible and the files shrink about threefold). Conventions:
every axis carries its unit; a difference of round-off size is drawn as a difference on a log
scale, never as a signal with an offset; each engine has one fixed style in every figure,
its colour and marker (declared, or a fallback no other engine has) with a line style per run
setup (`comparisons.report.styles`), and a
drawing names runs and engines only from its data (the curves' keys are run labels; an axis
that names the engine compared takes it as ``engine_label``).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Callable

import numpy as np

from reference_model import CONSTRAINT_NAMES, TORQUE_NAMES

from .styles import mark_of, style_of

WIDTH = 10.0        # inches at DPI: the figures fill the report's content width
DPI = 80
FLOOR = 1e-17       # log-scale floor for exact zeros
#: a signal whose spread is below this fraction of its size is drawn as a deviation (log scale)
ROUND_OFF_SPREAD = 1e-9


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    # plain tick labels ("1e-14"): mathtext for every log-axis label costs about a third of the
    # drawing time and says nothing more
    matplotlib.rcParams["axes.formatter.use_mathtext"] = False
    return plt


def _plain_log_axes(fig) -> None:
    """Every log axis of ``fig`` ticked at the decades (or at 1, 2, 5 per decade where the axis
    spans under two) and labelled as plain text (1e-14, 2e-03), no minor ticks. matplotlib's
    default minor ticks and mathtext labels cost half the drawing time and say nothing more.
    Run on the finished figure, when each axis knows its range."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator
    label = FuncFormatter(lambda v, _: f"{v:.0e}".replace("e+00", ""))
    for ax in fig.axes:
        for axis, lim in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            if axis.get_scale() != "log":
                continue
            lo, hi = sorted(lim)
            narrow = lo > 0 and np.log10(hi / lo) < 2
            axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0) if narrow else (1.0,),
                                              numticks=8))
            axis.set_major_formatter(label)
            axis.set_minor_locator(NullLocator())


def _semilogy(ax, t, y, **kw):
    ax.semilogy(t, np.maximum(np.asarray(y, dtype=float), FLOOR), **kw)


# -- drawings: each returns a matplotlib figure ----------------------------------------------

def matrix_error(relative, labels, tolerance, title, colorbar):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(WIDTH * 0.6, WIDTH * 0.5))
    im = ax.imshow(np.log10(np.maximum(relative, 1e-18)), cmap="viridis", vmin=-18,
                   vmax=np.log10(tolerance))
    ax.set_xticks(range(len(labels)), labels, rotation=45)
    ax.set_yticks(range(len(labels)), labels)
    fig.colorbar(im, ax=ax, label=colorbar + " [-]")
    ax.set_title(f"{title}\n(top of the colour scale = the tolerance {tolerance:g})")
    return fig


def error_vs_time(curves, horizon, threshold, title, engine_label="engine"):
    """Each run's |error| to the reference against time (theta, and xc thinner); ``curves``:
    run label -> {"t", "theta", "xc"}; ``engine_label`` names the engine on the axis."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(WIDTH, 3.6))
    for lab, c in curves.items():
        _semilogy(ax, c["t"], c["theta"], label=f"{lab}: theta [rad]", **style_of(lab))
        _semilogy(ax, c["t"], c["xc"], label=f"{lab}: xc [m]", **mark_of(lab),
                  ls="-", lw=0.6, alpha=0.6)
    ax.axhline(threshold, color="grey", lw=0.8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"|{engine_label} - reference| [rad or m]")
    ax.set_title(title + f" (grey: {threshold:g})")
    ax.legend(fontsize=7, ncol=2)
    return fig


def _loglog_study(points, guide, xlabel, ylabel, title):
    """A study on log-log axes: each curve's points (x, y, label) as dots joined by lines, and
    a dashed guide (x, y, label): an order of convergence, a tolerance."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(WIDTH * 0.75, 4.2))
    for x, y, label in points:
        ax.loglog(x, y, "o-", label=label)
    gx, gy, glabel = guide
    ax.loglog(gx, gy, "k--", lw=0.8, label=glabel)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=7)
    return fig


def convergence(curves, horizon, title):
    h = np.array(curves[0]["steps"]) if curves else np.array([1e-3])
    return _loglog_study([(c["steps"], c["errors"], c["label"]) for c in curves],
                         (h, 120 * h**2, "slope 2 (second order)"), "step h [s]",
                         f"max error up to {horizon} s [rad or m]", title)


def lean_panels(panels, ylabel):
    plt = _plt()
    fig, axes = plt.subplots(len(panels), 1, figsize=(WIDTH, 2.3 * len(panels)), sharex=True,
                             squeeze=False)
    for ax, p in zip(axes[:, 0], panels):
        for lab, (t, y) in p["lines"].items():
            ax.plot(t, y, label=lab, **style_of(lab))
        ax.set_ylabel(ylabel)
        ax.set_title(p["title"], fontsize=9)
        ax.grid(True, lw=0.3)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("t [s]")
    return fig


def error_panels(panels, threshold, engine_label="engine"):
    """A panel per manoeuvre: each run's |error| to the reference (theta, and the max over q
    dotted); ``panels``: [{"title", "curves": run label -> {"t", "theta", "max"}}]."""
    plt = _plt()
    fig, axes = plt.subplots(len(panels), 1, figsize=(WIDTH, 2.3 * len(panels)), sharex=True,
                             squeeze=False)
    for ax, p in zip(axes[:, 0], panels):
        for lab, c in p["curves"].items():
            _semilogy(ax, c["t"], c["theta"], label=f"{lab}: theta [rad]", lw=0.9,
                      **mark_of(lab))
            _semilogy(ax, c["t"], c["max"], label=f"{lab}: max over q [rad or m]", ls=":", lw=1.1,
                      **mark_of(lab))
        ax.axhline(threshold, color="grey", lw=0.8)
        ax.set_ylim(bottom=1e-12)
        ax.set_ylabel(f"|{engine_label} - ref|\n[rad or m]")
        ax.set_title(p["title"], fontsize=9)
        ax.grid(True, lw=0.3)
    axes[0, 0].legend(fontsize=7, ncol=2)
    axes[-1, 0].set_xlabel("t [s]")
    return fig


def nonlinear_fits(curves, coefficient, floor):
    aa = np.logspace(-4.5, -0.7, 20)
    return _loglog_study([(c["a"], c["deviation"], c["label"]) for c in curves],
                         (aa, coefficient * aa**2 + floor,
                          f"tolerance {coefficient:g} a² + {floor:.0e}"),
                         "amplitude a = max |theta|, |gamma| [rad]",
                         "|fitted - linear| / |linear| [-]",
                         "eigenvalues from nonlinear runs against the linearization")


def eigenvalues(v, re, im, weave, capsize, model):
    """Real (black) and imaginary (grey) parts against speed, weave and capsize speeds marked,
    the self-stable range shaded."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(WIDTH, 4.8))
    for k in range(re.shape[1]):
        ax.plot(v, np.where(im[:, k] > 0, im[:, k], np.nan), ".", color="0.6", ms=2,
                label="imaginary part" if k == 0 else None)
        ax.plot(v, re[:, k], ".", color="k", ms=2, label="real part" if k == 0 else None)
    ax.axhline(0.0, color="0.3", lw=0.6)
    for speed, name, ls in ((weave, "weave", "--"), (capsize, "capsize", ":")):
        if speed is not None:
            ax.axvline(speed, color="tab:blue", ls=ls, lw=1.0, label=f"{name} speed {speed:.6f} m/s")
    if weave is not None and capsize is not None and capsize > weave:
        ax.axvspan(weave, capsize, color="tab:green", alpha=0.12, label="self-stable")
    if v.max() > v.min():
        ax.set_xlim(v.min(), v.max())
    ax.set_xlabel("forward speed v [m/s]")
    ax.set_ylabel("eigenvalue [1/s]")
    ax.set_title(f"{model}: roll/steer eigenvalues about upright straight running")
    ax.legend(loc="lower left", fontsize=8, markerscale=4)
    ax.grid(True, lw=0.3)
    return fig


def option_study(engine, label, quantity, unit, values, reference_value, v, re, ref_re, critical,
                 ref_critical, model):
    """An option study (`comparisons.stages.option_study`): left, the real parts of the four
    eigenvalues against speed, one curve set per option value (the engine's colour and marker,
    darker for larger values), the reference's exact ones thin black underneath; right, the
    weave and capsize speeds against the option value, the reference's marked at its value.
    ``engine``: the engine's name (its style), ``label`` how the report names it."""
    from matplotlib.colors import to_rgb
    plt = _plt()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(WIDTH, 4.6), gridspec_kw={"width_ratios": (3, 2)})
    mark = mark_of(engine)
    base = np.array(to_rgb(mark["color"]))
    vals = [float(x) for x in values]
    span = (max(vals) - min(vals)) or 1.0
    for k in range(ref_re.shape[1]):
        ax.plot(v, ref_re[:, k], "-", color="k", lw=0.8,
                label="reference (exact)" if k == 0 else None)
    for i, x in enumerate(vals):
        shade = 0.35 + 0.65 * (x - min(vals)) / span     # lighter for small values
        colour = tuple(1.0 - shade * (1.0 - base))
        for k in range(np.shape(re)[2]):
            ax.plot(v, re[i][:, k], ls="--" if x != reference_value else ":", lw=1.2,
                    color=colour, marker=mark["marker"], ms=3, markevery=(2 * i + k, 10),
                    label=f"{x:g} {unit}" if k == 0 else None)
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_ylim(max(float(np.min(ref_re)), -10.0) - 0.5, float(np.max(ref_re)) + 0.5)
    ax.set_xlabel("forward speed v [m/s]")
    ax.set_ylabel("eigenvalue real part [1/s]")
    ax.set_title(f"{model}: {label}, {quantity}")
    ax.legend(fontsize=7, loc="lower left")
    ax.grid(True, lw=0.3)
    for j, (name, ls) in enumerate((("weave", "--"), ("capsize", ":"))):
        ys = [np.nan if c[j] is None else c[j] for c in critical]
        bx.plot(vals, ys, ls=ls, color=mark["color"], marker=mark["marker"], ms=5,
                label=f"{name} speed ({label})")
        if ref_critical[j] is not None:
            bx.plot([reference_value], [ref_critical[j]], "o", mfc="none", color="k", ms=9,
                    label=f"{name} speed (reference)")
    bx.set_xlabel(f"{quantity} [{unit}]")
    bx.set_ylabel("critical speed [m/s]")
    bx.legend(fontsize=7)
    bx.grid(True, lw=0.3)
    return fig


def torque_overlay(scenario, runs):
    """Rider torques of every engine overlaid (a torque constant to round-off is drawn as its
    deviation from its mean, on a log scale), and each engine's |difference| to the reference."""
    plt = _plt()
    ref = runs["reference"]
    fig, ax = plt.subplots(4, 1, figsize=(WIDTH, 8), sharex=True)
    for i, n in enumerate(TORQUE_NAMES):
        values = np.concatenate([r.T[:, i] for r in runs.values()])
        size = float(np.abs(values).max())
        if size > 0 and np.ptp(values) <= ROUND_OFF_SPREAD * size:
            mean = float(values.mean())
            for eng, r in runs.items():
                _semilogy(ax[i], r.t, np.abs(r.T[:, i] - mean), label=eng, **style_of(eng))
            ax[i].set_ylabel(f"|{n} - {mean:.6g}|\n[N m]")
            ax[i].set_title(f"{n} is constant ({mean:.6g} N m) to round-off: its deviation",
                            fontsize=8)
            continue
        for eng, r in runs.items():
            ax[i].plot(r.t, r.T[:, i], label=eng, **style_of(eng))
        ax[i].ticklabel_format(axis="y", useOffset=False)
        ax[i].set_ylabel(f"{n} [N m]")
    ax[0].legend(fontsize=7)
    for eng, r in runs.items():
        if eng != "reference":
            _semilogy(ax[3], r.t, np.abs(r.T - ref.T).max(axis=1), label=f"{eng}: max over torques",
                      **style_of(eng))
    ax[3].set_ylabel("|T - T_ref| [N m]")
    ax[3].set_xlabel("t [s]")
    if len(runs) > 1:
        ax[3].legend(fontsize=7)
    else:
        ax[3].text(0.5, 0.5, "no second engine with inverse dynamics", ha="center",
                   transform=ax[3].transAxes)
    fig.suptitle(f"{scenario}: rider torques from inverse dynamics, every engine")
    return fig


def trajectory_overlay(scenario, runs, errors, horizon, threshold):
    """theta and gamma of every engine against time, and the error of all eight coordinates
    (max over them) against time on a log scale up to the horizon."""
    plt = _plt()
    fig, ax = plt.subplots(3, 1, figsize=(WIDTH, 7), sharex=True)
    for eng, r in runs.items():
        ax[0].plot(r.t, r.q[:, 3], label=f"{eng} ({r.status} at {r.t_end:.2f} s)", **style_of(eng))
        ax[1].plot(r.t, r.q[:, 6], **style_of(eng))
    ax[0].set_ylabel("theta (lean) [rad]")
    ax[1].set_ylabel("gamma (steer) [rad]")
    ax[0].legend(fontsize=7)
    for eng, (t, e) in errors.items():
        if len(t):
            _semilogy(ax[2], t, e, label=f"{eng}: max over the 8 coordinates", **style_of(eng))
    for a in ax:
        a.axvline(horizon, color="grey", lw=0.8)
    ax[2].axhline(threshold, color="grey", lw=0.6, ls="--")
    ax[2].set_ylabel("|q - q_ref| [rad or m]")
    ax[2].set_xlabel(f"t [s] (grey line: meaningful horizon {horizon:.2f} s)")
    if errors:
        ax[2].legend(fontsize=7)
    fig.suptitle(f"{scenario}: every engine against the reference")
    return fig


def constraint_residuals(panels, bound):
    """One row per forward scenario: the position constraint rD_z (m) on the left, the largest
    velocity constraint (m/s) on the right, one line per engine, measured by the reference."""
    plt = _plt()
    fig, axes = plt.subplots(len(panels), 2, figsize=(WIDTH, 1.9 * len(panels) + 0.8),
                             sharex=True, squeeze=False)
    for row, (name, lines) in zip(axes, panels.items()):
        for eng, (t, pos, vel) in lines.items():
            _semilogy(row[0], t, pos, label=eng, **style_of(eng))
            _semilogy(row[1], t, vel, label=eng, **style_of(eng))
        for a in row:
            a.axhline(bound, color="r", lw=0.6, ls="--")
        row[0].set_ylabel(f"{name}\n|{CONSTRAINT_NAMES[0]}| [m]", fontsize=8)
        row[1].set_ylabel(f"max |{', '.join(CONSTRAINT_NAMES[1:])}|\n[m/s]", fontsize=8)
    axes[0, 0].set_title("position constraint [m]", fontsize=9)
    axes[0, 1].set_title("velocity constraints [m/s]", fontsize=9)
    axes[0, 0].legend(fontsize=7, ncol=3)
    for a in axes[-1]:
        a.set_xlabel(f"t [s] (red: the thesis's bound {bound:g})")
    fig.suptitle("constraint residual of every run, measured by the reference model")
    return fig


def _by_psid(kv):
    """Sort key of 'stability-psidN[-on-<model>]' names: (model, N)."""
    rest = kv[0].partition("psid")[2]
    speed, _, model = rest.partition("-on-")
    try:
        return (model, float(speed))
    except ValueError:
        return (model + kv[0], 0.0)


def stability_study(runs):
    """theta against time for the stability runs (thesis Figs. 6-4 to 6-7), a panel per engine;
    ``runs``: engine -> {scenario: (t, theta, status, t_end)}."""
    plt = _plt()
    engines = list(runs)
    fig, axes = plt.subplots(1, len(engines), figsize=(WIDTH, 3.8), sharey=True, squeeze=False)
    for ax, eng in zip(axes[0], engines):
        for name, (t, theta, status, t_end) in sorted(runs[eng].items(), key=_by_psid):
            head, _, rest = name.partition("psid")
            speed, _, model = rest.partition("-on-")     # stability-psidN[-on-<model>]
            ax.plot(t, theta, label=f"psi_dot(0) = {speed} rad/s{f' on {model}' if model else ''}"
                                    f" ({status} {t_end:.2f} s)")
        ax.set_title(eng)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=6)
    axes[0, 0].set_ylabel("theta (lean) [rad]")
    fig.suptitle("stability study (thesis Figs. 6-4 to 6-7), every engine")
    return fig


def replay_vs_zigzag(zigzag, replays):
    """theta and gamma of each engine's replay against the zig-zag it should reproduce;
    ``zigzag`` and each replay: (t, theta, gamma)."""
    plt = _plt()
    fig, ax = plt.subplots(2, 1, figsize=(WIDTH, 5), sharex=True)
    for i, lab in enumerate(("theta", "gamma")):
        ax[i].plot(zigzag[0], zigzag[1 + i], color="0.6", lw=3, label="zigzag (inverse kinematics)")
        for eng, r in replays.items():
            ax[i].plot(r[0], r[1 + i], label=f"replay on {eng}", **style_of(eng))
        ax[i].set_ylabel(f"{lab} [rad]")
    ax[0].legend(fontsize=7)
    ax[-1].set_xlabel("t [s]")
    fig.suptitle("replay: forward motion under the zig-zag's torques, every engine")
    return fig


def contact_run(t, error, horizon, slip, penetration, normal, ideal_normal, title,
                engine_label="engine"):
    """A soft-contact run against ideal rolling: error, slip, penetration, normal forces;
    ``engine_label`` names the engine on the axes."""
    plt = _plt()
    fig, ax = plt.subplots(4, 1, figsize=(WIDTH, 8.4), sharex=True)
    _semilogy(ax[0], error["t"], error["max"], color="k", lw=1.0, label="max over q [rad or m]")
    _semilogy(ax[0], error["t"], error["theta"], color="tab:red", lw=0.8, label="theta [rad]")
    ax[0].set_ylabel(f"|{engine_label} - ref|\n[rad or m]")
    colours = {"rear": "tab:blue", "front": "tab:orange"}
    for w, c in colours.items():
        _semilogy(ax[1], t, slip[w], color=c, lw=0.9, label=w)
        ax[2].plot(t, 1e6 * np.asarray(penetration[w]), color=c, lw=0.9, label=w)
        if normal.get(w) is not None:
            ax[3].plot(t, normal[w], color=c, lw=0.9, label=f"{w}: {engine_label}")
        ax[3].plot(ideal_normal["t"], ideal_normal[w], color=c, ls="--", lw=0.8,
                   label=f"{w}: ideal rolling needs")
    ax[0].set_ylim(bottom=1e-12)
    ax[1].set_ylim(bottom=1e-8)
    # the penetration's scale from the loaded part: a lifted wheel's height would flatten it
    t_arr = np.asarray(t, dtype=float)
    loaded = 1e6 * np.concatenate([np.asarray(penetration[w], dtype=float)[t_arr <= horizon]
                                   for w in colours])
    if loaded.size:
        span = max(float(loaded.max() - loaded.min()), 1e-3)
        ax[2].set_ylim(float(loaded.min()) - 0.5 * span, float(loaded.max()) + 0.5 * span)
    ax[1].set_ylabel("slip speed\n[m/s]")
    ax[2].set_ylabel("penetration\n[um] (scale: loaded part)")
    ax[3].set_ylabel("normal force\n[N]")
    ax[3].axhline(0.0, color="grey", lw=0.6)
    lo = min(float(np.min(n)) for n in (ideal_normal["rear"], ideal_normal["front"]))
    ax[3].set_ylim(max(lo, -2000.0) - 50, 2500)
    for a in ax:
        a.axvline(horizon, color="grey", lw=0.8, ls=":")
        a.grid(True, lw=0.3)
        a.legend(fontsize=7, ncol=4)
    ax[-1].set_xlabel(f"t [s] (dotted: last time both wheels carry load, {horizon:.2f} s)")
    ax[0].set_title(title)
    return fig


def refinement(curves, at_time, title):
    """Errors against a refined contact parameter, log-log, with a first-order guide."""
    v = np.array(curves[0]["values"])
    e = np.array(curves[0]["errors"])
    return _loglog_study([(c["values"], c["errors"], c["label"]) for c in curves],
                         (v, e[-1] * v / v[-1], "slope 1 (first order)"),
                         "refined value (time constant or timestep) [s]",
                         f"max error at {at_time:g} s [rad or m]", title)


DRAWINGS: dict[str, Callable] = {f.__name__: f for f in (
    matrix_error, error_vs_time, convergence, lean_panels, error_panels, nonlinear_fits,
    eigenvalues, option_study, torque_overlay, trajectory_overlay, constraint_residuals, stability_study,
    replay_vs_zigzag, contact_run, refinement)}


def png_bytes(fig) -> bytes:
    """The figure as a palette PNG (deterministic: no software or date metadata)."""
    from PIL import Image
    plt = _plt()
    fig.set_dpi(DPI)
    _plain_log_axes(fig)
    fig.tight_layout()
    fig.canvas.draw()   # the pixels straight from Agg: no full-colour PNG encoded and decoded again
    rgba = np.asarray(fig.canvas.buffer_rgba())
    plt.close(fig)
    # fast octree + zlib level 6: 0.12 s for the quick report's 15 figures against 0.91 s for
    # median cut + optimize, and smaller files (246 against 302 kB): line plots have few colours
    image = Image.fromarray(rgba[..., :3]).quantize(colors=256, method=Image.Quantize.FASTOCTREE,
                                                    dither=Image.Dither.NONE)
    out = io.BytesIO()
    image.save(out, format="png", compress_level=6)
    return out.getvalue()


def draw_png(kind: str, data: dict) -> bytes:
    """Figure ``kind`` drawn from ``data`` as PNG bytes (a top-level function: workers call it)."""
    return png_bytes(DRAWINGS[kind](**data))


def save_figure(kind: str, data: dict, path: Path) -> Path:
    """Draw figure ``kind`` from ``data`` and write it to ``path`` (PNG, atomically)."""
    from ..stages.files import write_bytes
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"figure file {path} must end in .png (the figures are PNG images)")
    return write_bytes(path, png_bytes(DRAWINGS[kind](**data)))
