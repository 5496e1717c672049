/* Template of the FMI 2.0 Model-Exchange wrapper around the reference's generated C.
 * reference_model/exports/fmu.py fills in the @NAME@ fields and compiles the result with the
 * generated bicycle_generated.c (which #includes runtime.c) and the FMI headers; the filled-in
 * file ships in the FMU's sources/ and is never committed.
 *
 * Value references (@LAYOUT@):
 *   q (8) | dq (8) | der(q) (8) | der(dq) (8) | T (3) | C (5) | lambda (5) | p (30) | a1, a2
 *   | the terms: M (64) | F = Qv + Qgrav + Qaero (8) | S (24) | Qgrav (8) | D (40) | dD dq (5)
 * der(dq) and lambda are bx_forward's (runtime.c): [M D'; D 0][ddq; lambda] =
 * [F + S T; -dD dq - 2 a1 D dq - a2^2 C], Baumgarte with the a1, a2 parameters.
 *
 * Directional derivatives (when DIRECTIONAL): bicycle_complex.c is the generated C with every
 * double a double _Complex (bx_ renamed bxc_, fmu.py writes it), the elementary functions
 * below carry the imaginary part at first order (sin(x + i y) = sin x + i y cos x, ...), so a
 * seed x + i h dx through the same expressions and the KKT solve gives Im f / h = J dx
 * exactly to rounding: complex-step differentiation, h = DD_STEP / max|dx| (no subtraction,
 * no truncation error: the neglected terms are h^2 relative, 1e-40). */
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include "fmi2Functions.h"
#include "bicycle_generated.c"
#define DIRECTIONAL @DIRECTIONAL@   /* 1: fmi2GetDirectionalDerivative by complex steps */
#if DIRECTIONAL
#include <complex.h>
typedef double _Complex cplx;
#define MK(re, im) ((re) + (im) * I)
static cplx c_sin(cplx a) { return MK(sin(creal(a)), cos(creal(a)) * cimag(a)); }
static cplx c_cos(cplx a) { return MK(cos(creal(a)), -sin(creal(a)) * cimag(a)); }
/* sqrt at a zero argument has no derivative; the generated code takes it of two things: the
 * norms of the disc contact's in-plane directions (never zero on a bicycle that stands) and the
 * drag's speed |v_G3|, which is zero at rest and always multiplies v_G3 itself: the drag
 * cv |v| v is quadratic there, its derivative 0, and a zero imaginary part gives exactly that.
 * At rest the seeded square v.v is -h^2 |dv|^2 + 2 i h v.dv (the complex step's second-order
 * real part, ~1e-40): taken as 0, not as a negative number, whose sqrt would be NaN, as 1/s
 * would be infinite (both seen at v = 0, the standstill the eigenvalues start from). */
static cplx c_sqrt(cplx a)
{
    double x = creal(a), s = x > 0.0 ? sqrt(x) : 0.0;
    return MK(s, s > 0.0 ? 0.5 * cimag(a) / s : 0.0);
}
static cplx c_pow(cplx a, cplx b)
{
    double x = creal(a), e = creal(b), r = pow(x, e);
    double im = e * pow(x, e - 1.0) * cimag(a);
    if (cimag(b) != 0.0) im += r * log(x) * cimag(b);
    return MK(r, im);
}
/* The complex copy is called a few times per linearization, not per integrator step: gcc
 * compiles it unoptimized (-O2 on it added ~23 s of compile here and saved ~1 ms a speed). */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC push_options
#pragma GCC optimize ("O0")
#endif
#include "bicycle_complex.c"
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC pop_options
#endif
#endif

#define GUID "@GUID@"
#define COSIMULATION @COSIMULATION@   /* 1: also Co-Simulation, fixed-step RK4 (fmi2DoStep) */
#define CS_STEP @CS_STEP@
#define VR_Q 0
#define VR_DQ 8
#define VR_DERQ 16
#define VR_DERDQ 24
#define VR_T 32
#define VR_C 35
#define VR_LAM 40
#define VR_P 45
#define N_P @N_P@
#define VR_A1 (VR_P + N_P)
#define VR_A2 (VR_A1 + 1)
#define VR_TERMS (VR_A2 + 1)
#define N_TERMS (NQ * NQ + NQ + NQ * 3 + NQ + NC * NQ + NC)
#define N_VR (VR_TERMS + N_TERMS)
#define DD_STEP 1e-20   /* the complex step, relative to the largest seed entry */

static const double P_START[N_P] = {@P_START@};
static const double X_START[2 * NQ] = {@X_START@};

typedef struct {
    double q[NQ], dq[NQ], T[3], p[N_P], a1, a2, time;
    double ddq[NQ], lam[NC], C[NC], terms[N_TERMS];
    int dirty, status;
    fmi2CallbackFunctions cb;
    fmi2String name;
} Bicycle;

static void logf_(Bicycle *b, fmi2Status s, const char *msg)
{
    if (b->cb.logger) b->cb.logger(b->cb.componentEnvironment, b->name, s, "logError", msg);
}

static void reset(Bicycle *b)
{
    memcpy(b->q, X_START, sizeof b->q);
    memcpy(b->dq, X_START + NQ, sizeof b->dq);
    memset(b->T, 0, sizeof b->T);
    memcpy(b->p, P_START, sizeof b->p);
    b->a1 = @A1@;
    b->a2 = @A2@;
    b->time = 0.0;
    b->dirty = 1;
}

/* Everything the outputs and derivatives read, once per change of inputs or states. */
static void evaluate(Bicycle *b)
{
    if (!b->dirty) return;
    double dyn[DYN_SIZE], con[CON_SIZE], grav[NQ];
    b->status = bx_forward(b->q, b->dq, b->T, b->p, b->a1, b->a2, b->ddq, b->lam);
    bx_dynamics(b->q, b->dq, b->p, dyn);
    bx_constraints(b->q, b->dq, b->p, con);
    bx_qgrav_batch(1, b->q, b->dq, b->p, grav);
    memcpy(b->C, con, sizeof b->C);
    double *t = b->terms;
    memcpy(t, dyn, sizeof(double) * (NQ * NQ + NQ + NQ * 3)); t += NQ * NQ + NQ + NQ * 3;
    memcpy(t, grav, sizeof grav); t += NQ;
    memcpy(t, con + NC, sizeof(double) * (NC * NQ + NC));
    b->dirty = 0;
}

static double *slot(Bicycle *b, fmi2ValueReference vr)
{
    if (vr < VR_DQ) return b->q + vr;
    if (vr < VR_DERQ) return b->dq + (vr - VR_DQ);
    if (vr < VR_T) return NULL;          /* der(q), der(dq): computed */
    if (vr < VR_C) return b->T + (vr - VR_T);
    if (vr < VR_P) return NULL;
    if (vr < VR_A1) return b->p + (vr - VR_P);
    if (vr == VR_A1) return &b->a1;
    if (vr == VR_A2) return &b->a2;
    return NULL;
}

static int value(Bicycle *b, fmi2ValueReference vr, double *out)
{
    if (vr >= N_VR) return 0;
    if (vr >= VR_DERQ && vr < VR_DERDQ) { *out = b->dq[vr - VR_DERQ]; return 1; }
    if ((vr >= VR_DERDQ && vr < VR_T) || (vr >= VR_C && vr < VR_P) || vr >= VR_TERMS) {
        evaluate(b);
        if (vr >= VR_TERMS) *out = b->terms[vr - VR_TERMS];
        else if (vr >= VR_LAM) *out = b->lam[vr - VR_LAM];
        else if (vr >= VR_C) *out = b->C[vr - VR_C];
        else *out = b->ddq[vr - VR_DERDQ];
        return 1;
    }
    double *s = slot(b, vr);
    if (!s) return 0;
    *out = *s;
    return 1;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[])
{
    (void)c; (void)on; (void)n; (void)cat;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging)
{
    (void)location; (void)visible; (void)logging;
    int kind_ok = type == fmi2ModelExchange || (COSIMULATION && type == fmi2CoSimulation);
    if (!kind_ok || !guid || strcmp(guid, GUID) != 0) {
        if (cb && cb->logger)
            cb->logger(cb->componentEnvironment, name, fmi2Error, "logError",
                       !kind_ok ? "this FMU does not provide that interface"
                                : "GUID does not match the modelDescription");
        return NULL;
    }
    Bicycle *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    if (cb) b->cb = *cb;
    b->name = name;
    reset(b);
    return b;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDef, fmi2Real stop)
{
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    ((Bicycle *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { reset((Bicycle *)c); return fmi2OK; }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[])
{
    Bicycle *b = c;
    for (size_t i = 0; i < n; ++i)
        if (!value(b, vr[i], &v[i])) { logf_(b, fmi2Error, "fmi2GetReal: unknown value reference"); return fmi2Error; }
    return b->status ? fmi2Error : fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[])
{
    Bicycle *b = c;
    for (size_t i = 0; i < n; ++i) {
        double *s = slot(b, vr[i]);
        if (!s) { logf_(b, fmi2Error, "fmi2SetReal: not a state, input or parameter"); return fmi2Error; }
        *s = v[i];
    }
    b->dirty = 1;
    return fmi2OK;
}

static fmi2Status none_(fmi2Component c, size_t n)
{
    if (n == 0) return fmi2OK;
    logf_(c, fmi2Error, "this FMU has only Real variables");
    return fmi2Error;
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) { (void)vr; (void)v; return none_(c, n); }
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) { (void)vr; (void)v; return none_(c, n); }
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) { (void)vr; (void)v; return none_(c, n); }
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) { (void)vr; (void)v; return none_(c, n); }
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) { (void)vr; (void)v; return none_(c, n); }
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) { (void)vr; (void)v; return none_(c, n); }

/* canGetAndSetFMUstate, canSerializeFMUstate: false */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; (void)s; return fmi2Error; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) { (void)c; (void)s; (void)n; return fmi2Error; }
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) { (void)c; (void)s; (void)b; (void)n; return fmi2Error; }
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) { (void)c; (void)b; (void)n; (void)s; return fmi2Error; }

#if DIRECTIONAL
/* The complex twin of Bicycle's values: states, inputs, parameters and everything evaluated. */
typedef struct {
    cplx q[NQ], dq[NQ], T[3], p[N_P], a1, a2;
    cplx ddq[NQ], lam[NC], C[NC], terms[N_TERMS];
} Twin;

static cplx *twin_slot(Twin *w, fmi2ValueReference vr)
{
    if (vr < VR_DQ) return w->q + vr;
    if (vr < VR_DERQ) return w->dq + (vr - VR_DQ);
    if (vr < VR_T) return NULL;
    if (vr < VR_C) return w->T + (vr - VR_T);
    if (vr < VR_P) return NULL;
    if (vr < VR_A1) return w->p + (vr - VR_P);
    if (vr == VR_A1) return &w->a1;
    if (vr == VR_A2) return &w->a2;
    return NULL;
}

/* [M D'; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C] in complex arithmetic:
 * Gaussian elimination, pivots chosen on the real parts (the same solution as bx_forward's
 * range-space solve; only the imaginary parts, the derivative, are read). 0 ok, 1 singular. */
static int twin_evaluate(Twin *w)
{
    enum { N = NQ + NC };
    cplx dyn[DYN_SIZE], con[CON_SIZE], A[N * N], x[N];
    bxc_dynamics(w->q, w->dq, w->p, dyn);
    bxc_constraints(w->q, w->dq, w->p, con);
    const cplx *M = dyn, *F = dyn + NQ * NQ, *S = dyn + NQ * NQ + NQ;
    const cplx *C = con, *D = con + NC, *bias = con + NC + NC * NQ;
    for (int i = 0; i < N * N; ++i) A[i] = 0.0;
    for (int i = 0; i < NQ; ++i) {
        for (int j = 0; j < NQ; ++j) A[i * N + j] = M[i * NQ + j];
        for (int k = 0; k < NC; ++k) A[i * N + NQ + k] = D[k * NQ + i];
        x[i] = F[i] + S[i * 3] * w->T[0] + S[i * 3 + 1] * w->T[1] + S[i * 3 + 2] * w->T[2];
    }
    for (int k = 0; k < NC; ++k) {
        cplx Ddq = 0.0;
        for (int j = 0; j < NQ; ++j) { A[(NQ + k) * N + j] = D[k * NQ + j]; Ddq += D[k * NQ + j] * w->dq[j]; }
        x[NQ + k] = -bias[k] - 2.0 * w->a1 * Ddq - w->a2 * w->a2 * C[k];
    }
    double scale = 0.0;
    for (int i = 0; i < N * N; ++i) if (fabs(creal(A[i])) > scale) scale = fabs(creal(A[i]));
    if (!(scale > 0.0) || !isfinite(scale)) return 1;
    for (int k = 0; k < N; ++k) {
        int piv = k;
        for (int i = k + 1; i < N; ++i) if (fabs(creal(A[i * N + k])) > fabs(creal(A[piv * N + k]))) piv = i;
        if (!(fabs(creal(A[piv * N + k])) > 1e-14 * scale)) return 1;
        if (piv != k) {
            for (int j = 0; j < N; ++j) { cplx t = A[k * N + j]; A[k * N + j] = A[piv * N + j]; A[piv * N + j] = t; }
            cplx t = x[k]; x[k] = x[piv]; x[piv] = t;
        }
        for (int i = k + 1; i < N; ++i) {
            cplx f = A[i * N + k] / A[k * N + k];
            for (int j = k + 1; j < N; ++j) A[i * N + j] -= f * A[k * N + j];
            x[i] -= f * x[k];
        }
    }
    for (int i = N - 1; i >= 0; --i) {
        cplx s = x[i];
        for (int j = i + 1; j < N; ++j) s -= A[i * N + j] * x[j];
        x[i] = s / A[i * N + i];
    }
    memcpy(w->ddq, x, sizeof w->ddq);
    memcpy(w->lam, x + NQ, sizeof w->lam);
    memcpy(w->C, C, sizeof w->C);
    cplx grav[NQ], *t = w->terms;
    bxc_qgrav(w->q, w->dq, w->p, grav);
    memcpy(t, dyn, sizeof(cplx) * (NQ * NQ + NQ + NQ * 3)); t += NQ * NQ + NQ + NQ * 3;
    memcpy(t, grav, sizeof grav); t += NQ;
    memcpy(t, con + NC, sizeof(cplx) * (NC * NQ + NC));
    return 0;
}

static int twin_value(Twin *w, fmi2ValueReference vr, cplx *out)
{
    if (vr >= N_VR) return 0;
    if (vr >= VR_DERQ && vr < VR_DERDQ) { *out = w->dq[vr - VR_DERQ]; return 1; }
    if (vr >= VR_DERDQ && vr < VR_T) { *out = w->ddq[vr - VR_DERDQ]; return 1; }
    if (vr >= VR_TERMS) { *out = w->terms[vr - VR_TERMS]; return 1; }
    if (vr >= VR_LAM && vr < VR_P) { *out = w->lam[vr - VR_LAM]; return 1; }
    if (vr >= VR_C && vr < VR_P) { *out = w->C[vr - VR_C]; return 1; }
    cplx *s = twin_slot(w, vr);
    if (!s) return 0;
    *out = *s;
    return 1;
}
#endif

/* dz = d(unknowns z)/d(knowns u) . du: the knowns are states, inputs or parameters, the
 * unknowns any Real (derivatives, outputs); one complex evaluation per call. */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference z[], size_t nz,
                                        const fmi2ValueReference u[], size_t nu,
                                        const fmi2Real du[], fmi2Real dz[])
{
    Bicycle *b = c;
#if DIRECTIONAL
    Twin w;
    double scale = 0.0;
    for (size_t k = 0; k < nu; ++k) {
        if (!isfinite(du[k])) { logf_(b, fmi2Error, "fmi2GetDirectionalDerivative: non-finite seed"); return fmi2Error; }
        if (fabs(du[k]) > scale) scale = fabs(du[k]);
    }
    for (int i = 0; i < NQ; ++i) { w.q[i] = b->q[i]; w.dq[i] = b->dq[i]; }
    for (int i = 0; i < 3; ++i) w.T[i] = b->T[i];
    for (int i = 0; i < N_P; ++i) w.p[i] = b->p[i];
    w.a1 = b->a1;
    w.a2 = b->a2;
    const double h = scale > 0.0 ? DD_STEP / scale : 0.0;
    for (size_t k = 0; k < nu; ++k) {
        cplx *s = twin_slot(&w, u[k]);
        if (!s) { logf_(b, fmi2Error, "fmi2GetDirectionalDerivative: a known is not a state, input or parameter"); return fmi2Error; }
        *s += MK(0.0, h * du[k]);
    }
    if (twin_evaluate(&w)) { logf_(b, fmi2Error, "fmi2GetDirectionalDerivative: singular mass or constraint system"); return fmi2Error; }
    for (size_t j = 0; j < nz; ++j) {
        cplx v;
        if (!twin_value(&w, z[j], &v)) { logf_(b, fmi2Error, "fmi2GetDirectionalDerivative: unknown value reference"); return fmi2Error; }
        dz[j] = h > 0.0 ? cimag(v) / h : 0.0;
        if (!isfinite(dz[j])) { logf_(b, fmi2Error, "fmi2GetDirectionalDerivative: non-finite derivative"); return fmi2Error; }
    }
    return fmi2OK;
#else
    (void)z; (void)nz; (void)u; (void)nu; (void)du; (void)dz;
    logf_(b, fmi2Error, "this FMU was exported without directional derivatives");
    return fmi2Error;
#endif
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e)
{
    (void)c;
    e->newDiscreteStatesNeeded = fmi2False;
    e->terminateSimulation = fmi2False;
    e->nominalsOfContinuousStatesChanged = fmi2False;
    e->valuesOfContinuousStatesChanged = fmi2False;
    e->nextEventTimeDefined = fmi2False;
    e->nextEventTime = 0.0;
    return fmi2OK;
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSet, fmi2Boolean *enter, fmi2Boolean *term)
{
    (void)c; (void)noSet;
    *enter = fmi2False;
    *term = fmi2False;
    return fmi2OK;
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) { ((Bicycle *)c)->time = t; return fmi2OK; }

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n)
{
    Bicycle *b = c;
    if (n != 2 * NQ) return fmi2Error;
    memcpy(b->q, x, sizeof b->q);
    memcpy(b->dq, x + NQ, sizeof b->dq);
    b->dirty = 1;
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n)
{
    Bicycle *b = c;
    if (n != 2 * NQ) return fmi2Error;
    memcpy(x, b->q, sizeof b->q);
    memcpy(x + NQ, b->dq, sizeof b->dq);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n)
{
    Bicycle *b = c;
    if (n != 2 * NQ) return fmi2Error;
    evaluate(b);
    memcpy(dx, b->dq, sizeof b->dq);
    memcpy(dx + NQ, b->ddq, sizeof b->ddq);
    if (b->status) {
        logf_(b, fmi2Error, b->status == 1 ? "singular mass or constraint system" : "non-finite state");
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) { (void)c; (void)z; return n ? fmi2Error : fmi2OK; }

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n)
{
    (void)c;
    for (size_t i = 0; i < n; ++i) x[i] = 1.0;
    return fmi2OK;
}

/* -- Co-Simulation (when COSIMULATION): classical RK4 at steps of at most CS_STEP seconds, the
 * inputs held over a communication step. */
static int rk4(Bicycle *b, double h)
{
    double y[2 * NQ], k[4][2 * NQ];
    memcpy(y, b->q, sizeof b->q);
    memcpy(y + NQ, b->dq, sizeof b->dq);
    static const double c[4] = {0.0, 0.5, 0.5, 1.0};
    for (int s = 0; s < 4; ++s) {
        for (int i = 0; i < 2 * NQ; ++i) {
            double yi = y[i] + (s ? c[s] * h * k[s - 1][i] : 0.0);
            if (i < NQ) b->q[i] = yi; else b->dq[i - NQ] = yi;
        }
        b->dirty = 1;
        evaluate(b);
        if (b->status) return b->status;
        memcpy(k[s], b->dq, sizeof b->dq);
        memcpy(k[s] + NQ, b->ddq, sizeof b->ddq);
    }
    for (int i = 0; i < 2 * NQ; ++i) {
        double yi = y[i] + h / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
        if (i < NQ) b->q[i] = yi; else b->dq[i - NQ] = yi;
    }
    b->dirty = 1;
    return 0;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real dt, fmi2Boolean noSetPrior)
{
    Bicycle *b = c;
    (void)noSetPrior;
    int n = (int)ceil(dt / CS_STEP - 1e-9);
    if (n < 1) n = 1;
    for (int i = 0; i < n; ++i)
        if (rk4(b, dt / n)) { logf_(b, fmi2Error, "fmi2DoStep: singular system or non-finite state"); return fmi2Error; }
    b->time = t + dt;
    return fmi2OK;
}
fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer o[], const fmi2Real v[])
{ (void)vr; (void)o; (void)v; return none_(c, n); }
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer o[], fmi2Real v[])
{ (void)vr; (void)o; (void)v; return none_(c, n); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v)
{
    if (k != fmi2LastSuccessfulTime) return fmi2Discard;
    *v = ((Bicycle *)c)->time;
    return fmi2OK;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) { (void)c; (void)k; (void)v; return fmi2Discard; }
