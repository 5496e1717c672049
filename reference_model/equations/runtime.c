/* Hand-written runtime of the reference model: the thesis's linear systems.
 *
 * Included at the end of the generated file (bicycle_generated.c), so it can call the
 * generated kernels bx_dynamics and bx_constraints directly and the compiler can inline them.
 *
 * Layouts (row-major):
 *   bx_dynamics    out = [M (8x8) | F = Qv + Qgrav + Qaero (8) | S (8x3)]
 *   bx_constraints out = [C (5) | D (5x8) | dD dq (5)]
 * Forward dynamics (din_Bicicleta):  [M D'; D 0] [ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C],
 *   solved in range space (Cholesky of M, then of D M^-1 D').
 *   (a1 = a2 = 0: exact constrained accelerations, no Baumgarte).
 * Inverse dynamics (Dinamica_inversa): unknowns [ddq_dep (5); T (3); lambda (5)],
 *   [M_dep  -S  D'; D_dep 0 0] x = [F - M_ind ddq_ind; -dD dq - D_ind ddq_ind]
 *   with dep = (xc, yc, phi, beta, eps) and ind = (theta, psi, gamma).
 * Return status: 0 ok, 1 singular system, 2 non-finite input or result.
 */
#define NQ 8
#define NC 5
#define NK (NQ + NC)
#define DYN_SIZE (NQ * NQ + NQ + NQ * 3)
#define CON_SIZE (NC + NC * NQ + NC)

static const int DEP[NC] = {0, 1, 2, 5, 7};
static const int IND[3] = {3, 4, 6};

/* Gaussian elimination with partial pivoting, in place: A (n x n, row-major), b (n). */
static int solve_dense(int n, double *A, double *b)
{
    double scale = 0.0;
    for (int i = 0; i < n * n; ++i) {
        double a = fabs(A[i]);
        if (!isfinite(a)) return 2;
        if (a > scale) scale = a;
    }
    if (scale == 0.0) return 1;
    const double tiny = 1e-14 * scale;
    for (int k = 0; k < n; ++k) {
        int piv = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            double a = fabs(A[i * n + k]);
            if (a > best) { best = a; piv = i; }
        }
        if (best <= tiny) return 1;
        if (piv != k) {
            for (int j = 0; j < n; ++j) {
                double t = A[k * n + j]; A[k * n + j] = A[piv * n + j]; A[piv * n + j] = t;
            }
            double t = b[k]; b[k] = b[piv]; b[piv] = t;
        }
        const double inv = 1.0 / A[k * n + k];
        for (int i = k + 1; i < n; ++i) {
            const double f = A[i * n + k] * inv;
            if (f == 0.0) continue;
            for (int j = k + 1; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int j = i + 1; j < n; ++j) s -= A[i * n + j] * b[j];
        b[i] = s / A[i * n + i];
        if (!isfinite(b[i])) return 2;
    }
    return 0;
}

/* In-place Cholesky A = L L^T of an n x n SPD matrix (lower triangle), with the reciprocals
 * of L's diagonal in inv (divisions are the slow part of such small solves). Returns 1 if A is
 * not positive definite (pivot below 1e-14 of the largest diagonal entry), 2 if not finite. */
static int cholesky(int n, double *A, double *inv)
{
    double scale = 0.0;
    for (int i = 0; i < n; ++i) if (A[i * n + i] > scale) scale = A[i * n + i];
    if (!(scale > 0.0) || !isfinite(scale)) return isfinite(scale) ? 1 : 2;
    for (int j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
        if (!(d > 1e-14 * scale)) return isfinite(d) ? 1 : 2;
        d = sqrt(d);
        A[j * n + j] = d;
        inv[j] = 1.0 / d;
        for (int i = j + 1; i < n; ++i) {
            double s = A[i * n + j];
            for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s * inv[j];
        }
    }
    return 0;
}

/* Forward substitution L y = b in place for m right-hand sides stored as rows of B (m x n). */
static void lower_solve(int n, const double *L, const double *inv, int m, double *B)
{
    for (int r = 0; r < m; ++r) {
        double *x = B + r * n;
        for (int i = 0; i < n; ++i) {
            double s = x[i];
            for (int k = 0; k < i; ++k) s -= L[i * n + k] * x[k];
            x[i] = s * inv[i];
        }
    }
}

/* Back substitution L^T x = y in place. */
static void upper_solve(int n, const double *L, const double *inv, double *x)
{
    for (int i = n - 1; i >= 0; --i) {
        double s = x[i];
        for (int k = i + 1; k < n; ++k) s -= L[k * n + i] * x[k];
        x[i] = s * inv[i];
    }
}

/* Range-space solution of the KKT system (M symmetric positive definite, M = L L^T):
 *   y = L^-1 (F + S T),  Y = L^-1 D^T,  (Y^T Y) lambda = Y^T y - b,  ddq = L^-T (y - Y lambda),
 * with b = -dD dq - 2 a1 D dq - a2^2 C (Y^T Y = D M^-1 D^T, Y^T y = D M^-1 (F + S T)). Same
 * solution as [M D'; D 0] \ [F + S T; b]: six forward substitutions and one back substitution
 * instead of a 13x13 LU, and M's positive definiteness is checked on the way. */
int bx_forward(const double *q, const double *dq, const double *T, const double *p,
               double a1, double a2, double *ddq, double *lam)
{
    double dyn[DYN_SIZE], con[CON_SIZE], B[(NC + 1) * NQ], DX[NC * NC], r[NC], inv[NQ];
    bx_dynamics(q, dq, p, dyn);
    bx_constraints(q, dq, p, con);
    double *M = dyn;
    const double *F = dyn + NQ * NQ, *S = dyn + NQ * NQ + NQ;
    const double *C = con, *D = con + NC, *bias = con + NC + NC * NQ;
    for (int i = 0; i < NQ; ++i)
        B[i] = F[i] + S[i * 3] * T[0] + S[i * 3 + 1] * T[1] + S[i * 3 + 2] * T[2];
    for (int k = 0; k < NC; ++k)
        for (int i = 0; i < NQ; ++i) B[(k + 1) * NQ + i] = D[k * NQ + i];
    int status = cholesky(NQ, M, inv);
    if (status) goto fail;
    lower_solve(NQ, M, inv, NC + 1, B);            /* B = [y; Y^T] */
    double *y = B;
    const double *Yt = B + NQ;
    for (int k = 0; k < NC; ++k) {
        double Yy = 0.0, Ddq = 0.0;
        for (int i = 0; i < NQ; ++i) { Yy += Yt[k * NQ + i] * y[i]; Ddq += D[k * NQ + i] * dq[i]; }
        r[k] = Yy + bias[k] + 2.0 * a1 * Ddq + a2 * a2 * C[k];
        for (int l = 0; l <= k; ++l) {
            double s = 0.0;
            for (int i = 0; i < NQ; ++i) s += Yt[k * NQ + i] * Yt[l * NQ + i];
            DX[k * NC + l] = s;
            DX[l * NC + k] = s;
        }
    }
    double invS[NC];
    status = cholesky(NC, DX, invS);
    if (status) goto fail;
    lower_solve(NC, DX, invS, 1, r);
    upper_solve(NC, DX, invS, r);                  /* r = lambda */
    for (int i = 0; i < NQ; ++i) {
        double s = y[i];
        for (int k = 0; k < NC; ++k) s -= Yt[k * NQ + i] * r[k];
        ddq[i] = s;
    }
    upper_solve(NQ, M, inv, ddq);
    for (int i = 0; i < NQ; ++i) if (!isfinite(ddq[i])) status = 2;
    for (int k = 0; k < NC; ++k) lam[k] = r[k];
    return status;
fail:
    for (int i = 0; i < NQ; ++i) ddq[i] = 0.0;
    for (int k = 0; k < NC; ++k) lam[k] = 0.0;
    return status;
}

long bx_forward_batch(long n, const double *q, const double *dq, const double *T, const double *p,
                      double a1, double a2, double *ddq, double *lam, int *status)
{
    long failures = 0;
    for (long i = 0; i < n; ++i) {
        status[i] = bx_forward(q + NQ * i, dq + NQ * i, T + 3 * i, p, a1, a2, ddq + NQ * i, lam + NC * i);
        failures += status[i] != 0;
    }
    return failures;
}

/* out = [ddq_dep (5) | T = (Mdir, Mped, Mvue) | lambda (5)] */
int bx_inverse_dynamics(const double *q, const double *dq, const double *ddq_ind, const double *p,
                        double *out)
{
    double dyn[DYN_SIZE], con[CON_SIZE], A[NK * NK], b[NK];
    bx_dynamics(q, dq, p, dyn);
    bx_constraints(q, dq, p, con);
    const double *M = dyn, *F = dyn + NQ * NQ, *S = dyn + NQ * NQ + NQ;
    const double *D = con + NC, *bias = con + NC + NC * NQ;
    for (int i = 0; i < NK * NK; ++i) A[i] = 0.0;
    for (int r = 0; r < NQ; ++r) {
        for (int j = 0; j < NC; ++j) A[r * NK + j] = M[r * NQ + DEP[j]];
        for (int j = 0; j < 3; ++j) A[r * NK + NC + j] = -S[r * 3 + j];
        for (int k = 0; k < NC; ++k) A[r * NK + NC + 3 + k] = D[k * NQ + r];
        double s = F[r];
        for (int j = 0; j < 3; ++j) s -= M[r * NQ + IND[j]] * ddq_ind[j];
        b[r] = s;
    }
    for (int k = 0; k < NC; ++k) {
        for (int j = 0; j < NC; ++j) A[(NQ + k) * NK + j] = D[k * NQ + DEP[j]];
        double s = -bias[k];
        for (int j = 0; j < 3; ++j) s -= D[k * NQ + IND[j]] * ddq_ind[j];
        b[NQ + k] = s;
    }
    int status = solve_dense(NK, A, b);
    for (int i = 0; i < NK; ++i) out[i] = b[i];
    return status;
}

long bx_inverse_dynamics_batch(long n, const double *q, const double *dq, const double *ddq_ind,
                               const double *p, double *out, int *status)
{
    long failures = 0;
    for (long i = 0; i < n; ++i) {
        status[i] = bx_inverse_dynamics(q + NQ * i, dq + NQ * i, ddq_ind + 3 * i, p, out + NK * i);
        failures += status[i] != 0;
    }
    return failures;
}
