"""The numpy backend's linear systems: the same KKT solves as ``runtime.c``, batched.

Used when no C compiler works (see `codegen`). Inputs and outputs have the layouts of the C
runtime's batch functions::

    forward_batch(q, dq, T, p, a1, a2) -> (ddq (n, 8), lam (n, 5), status (n,))
    inverse_dynamics_batch(q, dq, ddq_ind, p) -> (out (n, 13), status (n,))

with out = [ddq_dep (5) | T = (Mdir, Mped, Mvue) | lambda (5)] and status 0 ok, 1 singular,
2 non-finite, as in C. Forward dynamics is solved in range space like the C runtime
(M^-1 by Cholesky, then the 5x5 D M^-1 D'), inverse dynamics as the 13x13 system.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

__all__ = [
    "DEP", "IND", "NC", "NK", "NQ", "solvers",
]

NQ, NC = 8, 5
NK = NQ + NC
DEP = (0, 1, 2, 5, 7)
IND = (3, 4, 6)
#: A pivot below this fraction of the matrix's largest entry counts as singular (the C
#: runtime's threshold for its Cholesky and Gaussian-elimination pivots).
_SINGULAR_RTOL = 1e-14


def _spd_ok(A: np.ndarray) -> np.ndarray:
    """Per matrix of a batch (n, k, k): True where A is symmetric positive definite with every
    Cholesky pivot above 1e-14 of the largest diagonal entry (the C runtime's test)."""
    n = A.shape[0]
    if n == 0:
        return np.zeros(0, dtype=bool)
    scale = np.max(np.diagonal(A, axis1=1, axis2=2), axis=1)
    try:
        L = np.linalg.cholesky(A)
    except np.linalg.LinAlgError:     # some matrix of the batch is not positive definite
        if n == 1:
            return np.zeros(1, dtype=bool)
        return np.concatenate([_spd_ok(A[i:i + 1]) for i in range(n)])
    pivots = np.diagonal(L, axis1=1, axis2=2) ** 2
    return (scale > 0.0) & np.all(pivots > _SINGULAR_RTOL * scale[:, None], axis=1)


def _finite_rows(*arrays: np.ndarray) -> np.ndarray:
    n = arrays[0].shape[0]
    return np.all(np.concatenate([np.isfinite(a).reshape(n, -1) for a in arrays], axis=1), axis=1)


def solvers(kernels: dict[str, Callable]) -> dict[str, Callable]:
    """The batch solvers over a variant's generated numpy kernels ('dynamics', 'constraints')."""

    def forward_batch(q, dq, T, p, a1, a2):
        n = q.shape[0]
        dyn, con = kernels["dynamics"](q, dq, p), kernels["constraints"](q, dq, p)
        M = dyn[:, :NQ * NQ].reshape(n, NQ, NQ)
        F = dyn[:, NQ * NQ:NQ * NQ + NQ]
        S = dyn[:, NQ * NQ + NQ:].reshape(n, NQ, 3)
        C, D = con[:, :NC], con[:, NC:NC + NC * NQ].reshape(n, NC, NQ)
        bias = con[:, NC + NC * NQ:]
        f = F + np.einsum("nij,nj->ni", S, T)
        b = -bias - 2.0 * a1 * np.einsum("nkj,nj->nk", D, dq) - a2 * a2 * C
        ddq, lam = np.zeros((n, NQ)), np.zeros((n, NC))
        status = np.where(_finite_rows(M, f, D, b), 0, 2).astype(np.intc)
        good = status == 0
        spd = np.zeros(n, dtype=bool)
        spd[good] = _spd_ok(M[good])
        status[good & ~spd] = 1
        if spd.any():
            Mi, Di = M[spd], D[spd]
            X = np.linalg.solve(Mi, np.concatenate([f[spd, :, None], np.swapaxes(Di, 1, 2)], axis=2))
            y, Y = X[:, :, 0], X[:, :, 1:]                          # M^-1 f, M^-1 D'
            A = Di @ Y                                             # D M^-1 D'
            schur = _spd_ok(A)
            rows = np.flatnonzero(spd)
            status[rows[~schur]] = 1
            if schur.any():
                r = np.einsum("nkj,nj->nk", Di[schur], y[schur]) - b[spd][schur]
                lk = np.linalg.solve(A[schur], r[..., None])[..., 0]
                ok_rows = rows[schur]
                lam[ok_rows] = lk
                ddq[ok_rows] = y[schur] - np.einsum("nik,nk->ni", Y[schur], lk)
        bad = ~_finite_rows(ddq, lam)
        status[bad] = 2
        ddq[status != 0] = 0.0
        lam[status != 0] = 0.0
        return ddq, lam, status

    def inverse_dynamics_batch(q, dq, ddq_ind, p):
        n = q.shape[0]
        dyn, con = kernels["dynamics"](q, dq, p), kernels["constraints"](q, dq, p)
        M = dyn[:, :NQ * NQ].reshape(n, NQ, NQ)
        F = dyn[:, NQ * NQ:NQ * NQ + NQ]
        S = dyn[:, NQ * NQ + NQ:].reshape(n, NQ, 3)
        D = con[:, NC:NC + NC * NQ].reshape(n, NC, NQ)
        bias = con[:, NC + NC * NQ:]
        A = np.zeros((n, NK, NK))
        A[:, :NQ, :NC] = M[:, :, DEP]
        A[:, :NQ, NC:NC + 3] = -S
        A[:, :NQ, NC + 3:] = np.swapaxes(D, 1, 2)
        A[:, NQ:, :NC] = D[:, :, DEP]
        rhs = np.concatenate([F - np.einsum("nij,nj->ni", M[:, :, IND], ddq_ind),
                              -bias - np.einsum("nkj,nj->nk", D[:, :, IND], ddq_ind)], axis=1)
        out = np.zeros((n, NK))
        status = np.where(_finite_rows(A, rhs), 0, 2).astype(np.intc)
        rows = np.flatnonzero(status == 0)
        if rows.size:
            # singular as in C's partial-pivoting elimination: smallest singular value at or
            # below 1e-14 of the largest entry
            scale = np.max(np.abs(A[rows]), axis=(1, 2))
            smallest = np.linalg.svd(A[rows], compute_uv=False)[:, -1]
            regular = (scale > 0.0) & (smallest > _SINGULAR_RTOL * scale)
            status[rows[~regular]] = 1
            ok = rows[regular]
            if ok.size:
                out[ok] = np.linalg.solve(A[ok], rhs[ok][..., None])[..., 0]
        status[(status == 0) & ~_finite_rows(out)] = 2
        return out, status

    return {"forward_batch": forward_batch, "inverse_dynamics_batch": inverse_dynamics_batch}
