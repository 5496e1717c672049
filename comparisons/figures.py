"""The report's figures of the scenario runs (matplotlib, Agg, 90 dpi PNG).

Each function draws one figure into ``out/figures`` and returns its file name. Line styles
per engine are fixed so the same engine looks the same in every figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from reference_model import CONSTRAINT_NAMES, TORQUE_NAMES

STYLE = {"reference": dict(color="k", ls="-", lw=1.6), "pinocchio": dict(color="tab:orange", ls="--", lw=1.2),
         "exudyn-tree": dict(color="tab:blue", ls=":", lw=1.4)}


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _save(fig, out: Path, name: str) -> str:
    plt = _plt()
    fig.tight_layout()
    fig.savefig(out / "figures" / name, dpi=90, metadata={"Software": None})
    plt.close(fig)
    return name


def _style(engine: str) -> dict:
    return STYLE.get(engine, dict(lw=1.0))


def torque_overlay(out: Path, scenario: str, runs: dict) -> str:
    """Rider torques of every engine overlaid, and each engine's |difference| on a log scale."""
    plt = _plt()
    ref = runs["reference"]
    fig, ax = plt.subplots(4, 1, figsize=(7.5, 7.5), sharex=True)
    for i, n in enumerate(TORQUE_NAMES):
        for eng, r in runs.items():
            ax[i].plot(r.t, r.T[:, i], label=eng, **_style(eng))
        ax[i].set_ylabel(f"{n} [N m]")
    ax[0].legend(fontsize=7)
    for eng, r in runs.items():
        if eng == "reference":
            continue
        diff = np.abs(r.T - ref.T).max(axis=1)
        ax[3].semilogy(r.t, np.maximum(diff, 1e-17), label=f"{eng}: max over torques", **_style(eng))
    ax[3].set_ylabel("|T - T_ref| [N m]")
    ax[3].set_xlabel("t [s]")
    if len(runs) > 1:
        ax[3].legend(fontsize=7)
    else:
        ax[3].text(0.5, 0.5, "no second engine with inverse dynamics", ha="center",
                   transform=ax[3].transAxes)
    fig.suptitle(f"{scenario}: rider torques from inverse dynamics, every engine")
    return _save(fig, out, f"{scenario}_torques.png")


def trajectory_overlay(out: Path, scenario: str, runs: dict, errors: dict, horizon: float) -> str:
    """theta and gamma of every engine against time, and the error of all eight coordinates
    (max over them) against time on a log scale up to the horizon."""
    plt = _plt()
    fig, ax = plt.subplots(3, 1, figsize=(7.5, 7), sharex=True)
    for eng, r in runs.items():
        ax[0].plot(r.t, r.q[:, 3], label=f"{eng} ({r.status} at {r.t_end:.2f} s)", **_style(eng))
        ax[1].plot(r.t, r.q[:, 6], **_style(eng))
    ax[0].set_ylabel("theta (lean) [rad]")
    ax[1].set_ylabel("gamma (steer) [rad]")
    ax[0].legend(fontsize=7)
    for eng, te in errors.items():
        if te.t.size:
            ax[2].semilogy(te.t, np.maximum(te.errors.max(axis=1), 1e-17),
                           label=f"{eng}: max over the 8 coordinates", **_style(eng))
    for a in ax:
        a.axvline(horizon, color="grey", lw=0.8)
    ax[2].axhline(1e-6, color="grey", lw=0.6, ls="--")
    ax[2].set_ylabel("|q - q_ref| [rad, m]")
    ax[2].set_xlabel(f"t [s] (grey line: meaningful horizon {horizon:.2f} s)")
    if errors:
        ax[2].legend(fontsize=7)
    fig.suptitle(f"{scenario}: every engine against the reference")
    return _save(fig, out, f"{scenario}_trajectories.png")


def constraint_residuals(out: Path, models: dict, forward: dict[str, dict]) -> str:
    """max |C| against time, one panel per forward scenario (its model in ``models``), one line
    per engine."""
    plt = _plt()
    names = list(forward)
    fig, axes = plt.subplots(len(names), 1, figsize=(7.5, 1.9 * len(names) + 0.6), sharex=True,
                             squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        model = models[name]
        for eng, r in forward[name].items():
            if r.t.size:
                C = np.abs(model.constraint_residual(r.q, r.dq)).max(axis=1)
                ax.semilogy(r.t, np.maximum(C, 1e-17), label=eng, **_style(eng))
        ax.axhline(2e-3, color="r", lw=0.6, ls="--")
        ax.set_ylabel(f"{name}\nmax |C|", fontsize=8)
    axes[0, 0].legend(fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel("t [s] (red: the thesis's bound 2e-3)")
    fig.suptitle(f"constraint residual ({', '.join(CONSTRAINT_NAMES)}), measured by the reference model")
    return _save(fig, out, "constraint_residuals.png")


def stability_study(out: Path, runs: dict[str, dict]) -> str:
    """theta against time for the four speeds (thesis Figs. 6-4 to 6-7), one panel per engine."""
    plt = _plt()
    engines = list(runs)
    fig, axes = plt.subplots(1, len(engines), figsize=(4.2 * len(engines), 3.8), sharey=True,
                             squeeze=False)
    for ax, eng in zip(axes[0], engines):
        for name, r in sorted(runs[eng].items(), key=lambda kv: float(kv[0].split("psid")[1])):
            ax.plot(r.t, r.q[:, 3], label=f"psi_dot(0) = {name.split('psid')[1]} ({r.status} "
                                          f"{r.t_end:.2f} s)")
        ax.set_title(eng)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=7)
    axes[0, 0].set_ylabel("theta (lean) [rad]")
    fig.suptitle("stability study (thesis Figs. 6-4 to 6-7), every engine")
    return _save(fig, out, "stability_theta.png")


def replay_vs_zigzag(out: Path, zigzag, replays: dict) -> str:
    """theta and gamma of each engine's replay against the zig-zag it should reproduce."""
    plt = _plt()
    fig, ax = plt.subplots(2, 1, figsize=(7.5, 5), sharex=True)
    for i, (j, lab) in enumerate(((3, "theta"), (6, "gamma"))):
        ax[i].plot(zigzag.t, zigzag.q[:, j], color="0.6", lw=3, label="zigzag (inverse kinematics)")
        for eng, r in replays.items():
            ax[i].plot(r.t, r.q[:, j], label=f"replay on {eng}", **_style(eng))
        ax[i].set_ylabel(f"{lab} [rad]")
    ax[0].legend(fontsize=7)
    ax[-1].set_xlabel("t [s]")
    fig.suptitle("replay: forward motion under the zig-zag's torques, every engine")
    return _save(fig, out, "replay_vs_zigzag.png")
