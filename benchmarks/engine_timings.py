"""Timings of the engines: Pinocchio's own crba and rnea on the adapter's tree (the yardstick,
checked against the reference first), the Pinocchio adapter's constrained right-hand side and
a forward run through it, Exudyn's import and system set-up, and every forward scenario on
Exudyn's two builds beside the reference."""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np

from benchmarks.common import N_SINGLE, SEED, Micro, Row, best_wall, timed_import
from benchmarks.reference_timings import rhs_args

PIN_CHECK_STATES = 8
PIN_CHECK_RTOL = 1e-12


# -- 6. Pinocchio ----------------------------------------------------------------------------

def build_pinocchio(model):
    """The Pinocchio tree of the engines' adapter (engines/pinocchio/engine.py; its joint order is
    asserted there and its terms are checked by tests/test_engine_conformance.py)."""
    from engines.pinocchio import build_pinocchio_model
    pm = build_pinocchio_model(model)
    return pm, pm.createData()


def check_pinocchio(pin, pm, pd, model, rng) -> dict:
    """Max relative errors of crba (symmetrised) and rnea against the reference model."""
    err_m = err_r = 0.0
    for _ in range(PIN_CHECK_STATES):
        q = rng.uniform(-np.pi, np.pi, 8)
        v = rng.uniform(-3, 3, 8)
        a = rng.uniform(-3, 3, 8)
        Mp = np.array(pin.crba(pm, pd, q))
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        Mr = model.mass_matrix(q)
        err_m = max(err_m, float(np.max(np.abs(Mp - Mr)) / np.max(np.abs(Mr))))
        tau_p = np.array(pin.rnea(pm, pd, q, v, a))
        tau_r = Mr @ a - model.Qv(q, v) - model.Qgrav(q)
        err_r = max(err_r, float(np.max(np.abs(tau_p - tau_r)) / np.max(np.abs(tau_r))))
    return {"states": PIN_CHECK_STATES, "rtol": PIN_CHECK_RTOL, "mass_matrix_max_rel_err": err_m,
            "rnea_max_rel_err": err_r, "ok": err_m <= PIN_CHECK_RTOL and err_r <= PIN_CHECK_RTOL}


def pinocchio_micros(pin, pm, pd, model, q, dq, T) -> list[Micro]:
    """crba and rnea (the yardstick) and the adapter's constrained right-hand side, on the
    same states as the reference's calls."""
    from engines import load_engine
    k = N_SINGLE
    acc = np.random.default_rng(SEED + 1).uniform(-1, 1, (k, 8))
    adapter = load_engine("pinocchio", model)
    return [
        Micro("pin_crba", "Pinocchio crba, 1 state", pin.crba, [(pm, pd, q[i].copy()) for i in range(k)]),
        Micro("pin_rnea", "Pinocchio rnea, 1 state", pin.rnea,
              [(pm, pd, q[i].copy(), dq[i].copy(), acc[i]) for i in range(k)]),
        Micro("pin_adapter_rhs", "Pinocchio adapter constrained RHS forward(q, dq, T, Baumgarte), 1 state",
              adapter.forward, rhs_args(q, dq, T)),
    ]



def bench_pinocchio_forward(model, repeat: int) -> list[Row]:
    """stability-psid10 through the same solver on Pinocchio's terms (the adapter) and on the
    reference's generated code: what `bicycle-xval run` pays per engine run. 'per RHS' is the
    run's wall time over its right-hand-side evaluations (the integrator's own work included)."""
    from engines import load_engine
    from reference_model.scenarios import SCENARIOS, run_forward
    sc = SCENARIOS["stability-psid10"]
    pin = load_engine("pinocchio", model)
    w_pin, t_pin = best_wall(lambda: pin.simulate(sc), repeat)
    w_ref, t_ref = best_wall(lambda: run_forward(model, sc), repeat)
    n_ref, n_pin = t_ref.timing["nfev"], t_pin.timing["nfev"]
    return [
        Row("psid10_reference", f"stability-psid10 forward run, reference ({n_ref} RHS)", w_ref,
            details={"nfev": n_ref, "wall_per_rhs_s": w_ref / n_ref}),
        Row("psid10_pinocchio", f"stability-psid10 forward run, Pinocchio adapter ({n_pin} RHS): "
            f"{w_pin / w_ref:.3g}x the reference's", w_pin,
            details={"nfev": n_pin, "wall_per_rhs_s": w_pin / n_pin, "ratio_to_reference": w_pin / w_ref}),
        Row("psid10_pinocchio_per_rhs", "  Pinocchio adapter run: wall per RHS evaluation", w_pin / n_pin),
    ]


def bench_exudyn() -> list[Row]:
    exu, t_imp, already = timed_import("exudyn")
    t0 = time.perf_counter()
    sc = exu.SystemContainer()
    sc.AddSystem()
    t_sc = time.perf_counter() - t0
    return [Row("import_exudyn", "import exudyn (in-process" + (", already loaded)" if already else ")"),
                t_imp),
            Row("exudyn_system", "exu.SystemContainer() + AddSystem()", t_sc)]


# -- 8. Exudyn forward runs against the reference ---------------------------------------------

def bench_exudyn_scenarios(quick: bool) -> list[Row]:
    """Wall time of each forward scenario on thesis-disc (the contact both Exudyn builds
    realise): the reference (`run_forward`, default settings: Baumgarte, DOP853 rtol 1e-10)
    and Exudyn's tree and redundant builds at h = 1e-3, one run each, in the same process.
    Each wall time covers the whole call (initial projection, the replay's torque spline,
    building the Exudyn system, the run). The thesis-disc library is compiled into a fresh
    temporary cache (timed as a row), so the user's cache is not touched."""
    from engines import load_engine
    from reference_model import load_model
    from reference_model.scenarios import SCENARIOS, run_forward

    step = 1e-3
    names = ("stability-psid10",) if quick else (
        "replay", "stability-psid0", "stability-psid1", "stability-psid5", "stability-psid10")
    old = os.environ.get("BICYCLE_XVAL_CACHE")
    with tempfile.TemporaryDirectory(prefix="bicycle-xval-bench-disc-") as tmp:
        os.environ["BICYCLE_XVAL_CACHE"] = tmp
        try:
            t0 = time.perf_counter()
            disc = load_model("thesis-disc")
            t_load = time.perf_counter() - t0
        finally:
            if old is None:
                os.environ.pop("BICYCLE_XVAL_CACHE", None)
            else:
                os.environ["BICYCLE_XVAL_CACHE"] = old
    rows = [Row("exudyn_disc_load", "load_model('thesis-disc'), fresh temporary cache"
                + (" (compiled)" if disc.library.built_now else ""), t_load)]
    engines = {b: load_engine("exudyn", disc, build=b, step=step)
               for b in ("tree", "redundant")}
    for eng in engines.values():   # first-call costs (imports, symbolic machinery) not timed
        eng.simulate(SCENARIOS["stability-psid0"], t_end=0.05)
    for name in names:
        sc = SCENARIOS[name]
        t0 = time.perf_counter()
        ref = run_forward(disc, sc)
        t_ref = time.perf_counter() - t0
        rows.append(Row(f"exudyn_{name}_reference",
                        f"{name}, reference thesis-disc ({ref.status} at {ref.t_end:.2f} s)", t_ref,
                        details={"status": ref.status, "t_end": ref.t_end,
                                 "wall_per_simulated_s": t_ref / ref.t_end,
                                 "settings": {k: ref.settings[k] for k in
                                              ("integrator", "rtol", "atol", "constraints")},
                                 "nfev": ref.timing["nfev"]}))
        for build, eng in engines.items():
            t0 = time.perf_counter()
            tr = eng.simulate(sc)
            wall = time.perf_counter() - t0
            ratio = wall / t_ref
            # the runs may end at different times (a fall): also per simulated second
            ratio_sim = (wall / tr.t_end) / (t_ref / ref.t_end)
            rows.append(Row(
                f"exudyn_{name}_{build}",
                f"  Exudyn {build}, h = {step:g} ({tr.status} at {tr.t_end:.2f} s): "
                f"{ratio:.3g}x ref, {ratio_sim:.3g}x per simulated s", wall,
                details={"status": tr.status, "t_end": tr.t_end, "ratio_to_reference": ratio,
                         "wall_per_simulated_s": wall / tr.t_end,
                         "ratio_to_reference_per_simulated_s": ratio_sim,
                         "steps": tr.timing["steps"],
                         "newton_iterations": tr.timing.get("newton_iterations"),
                         "solve_s": tr.timing["solve_seconds"],
                         "build_s": tr.timing["build_seconds"],
                         "solver": tr.settings["solver_type"],
                         "spectral_radius": tr.settings["spectral_radius"]}))
    return rows


