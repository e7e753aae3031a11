/* A one-dimensional chain of N masses joined by springs, optionally with the
 * Fermi-Pasta-Ulam-Tsingou nonlinearity on each spring.
 *
 * Parameter vector (doubles):
 *   [N, ends, alpha, beta, masses[N], springs[ns]]
 * with ends 0 = fixed (walls at both ends, ns = N + 1: spring 0 joins the left
 * wall to mass 0, spring N joins mass N-1 to the right wall), 1 = free
 * (ns = N - 1: spring j joins masses j and j+1), 2 = periodic (ns = N: spring
 * j joins masses j and (j+1) mod N), the conventions of mp.modes.chain.
 *
 * Spring j of constant k_j stretched by r_j = x_right - x_left stores
 *   V_j(r) = k_j (r^2/2 + alpha r^3/3 + beta r^4/4)
 * and pulls with the tension T_j = V_j'(r) = k_j (r + alpha r^2 + beta r^3):
 *   m_i x_i'' = T_right(i) - T_left(i).
 * With alpha = beta = 0 the equations are M x'' = -K x with K, M of
 * mp.modes.chain.  State (x[N], v[N]): separable, so the symplectic methods
 * apply (nq = N).  The linear right-hand side is a separate function: the
 * FPUT terms cost nothing when they are off. */
#include "models/models.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

enum { CN, CENDS, CALPHA, CBETA, CHEAD };
enum { ENDS_FIXED = 0, ENDS_FREE = 1, ENDS_PERIODIC = 2 };

/* The head; the masses (N) and springs (ns) follow it. */
static const mp_model_param chain_params[] = {
    MP_PARAM_RANGE("N", MP_REQUIRED, 1.0, INFINITY), MP_PARAM_RANGE("ends", 0.0, 0.0, 2.0),
    MP_PARAM("alpha", 0.0), MP_PARAM("beta", 0.0),
};

static size_t chain_nsprings(size_t n, int ends)
{
    return ends == ENDS_FIXED ? n + 1 : ends == ENDS_FREE ? n - 1 : n;
}

/* The state dimension 2N, or 0 when np values do not describe a chain. */
static size_t chain_dim_of(const double *p, size_t np)
{
    if (np < CHEAD + 1) return 0;
    double nd = p[CN], ed = p[CENDS];
    if (!(nd >= 1.0 && nd <= (double)np && nd == floor(nd))) return 0;
    if (!(ed == ENDS_FIXED || ed == ENDS_FREE || ed == ENDS_PERIODIC)) return 0;
    size_t n = (size_t)nd;
    if (np != CHEAD + n + chain_nsprings(n, (int)ed)) return 0;
    return 2 * n;
}

/* The masses positive, the springs non-negative (called after the bounds
 * and chain_dim_of accepted the head and the layout). */
static int chain_check(const double *p, char *why, size_t len)
{
    size_t n = (size_t)p[CN], ns = chain_nsprings(n, (int)p[CENDS]);
    const double *m = p + CHEAD, *k = m + n;
    for (size_t i = 0; i < n; i++)
        if (!(isfinite(m[i]) && m[i] > 0)) {
            if (why) snprintf(why, len, "masses must be positive and finite, got masses[%zu] = %g",
                              i, m[i]);
            return MP_EDOM;
        }
    for (size_t j = 0; j < ns; j++)
        if (!(isfinite(k[j]) && k[j] >= 0)) {
            if (why) snprintf(why, len, "springs must be non-negative and finite, got "
                              "springs[%zu] = %g", j, k[j]);
            return MP_EDOM;
        }
    return MP_OK;
}

/* Spring tension k (r + alpha r^2 + beta r^3); `nonlinear` is a constant in
 * each caller, so the linear chain compiles to k r alone. */
static inline double chain_tension(double k, double r, double a, double b, int nonlinear)
{
    return nonlinear ? k * (r + r * r * (a + b * r)) : k * r;
}

/* d tension / d r */
static inline double chain_stiffness(double k, double r, double a, double b)
{
    return k * (1.0 + r * (2.0 * a + 3.0 * b * r));
}

static inline void chain_accel(const double *p, const double *x, double *acc, int nonlinear)
{
    const size_t n = (size_t)p[CN];
    const int ends = (int)p[CENDS];
    const double a = p[CALPHA], b = p[CBETA];
    const double *m = p + CHEAD, *k = m + n;
    double tl; /* tension of the spring on the left of mass i */
    if (ends == ENDS_FIXED) {
        tl = chain_tension(k[0], x[0], a, b, nonlinear);
        for (size_t i = 0; i < n; i++) {
            double r = i + 1 < n ? x[i + 1] - x[i] : -x[i];
            double tr = chain_tension(k[i + 1], r, a, b, nonlinear);
            acc[i] = (tr - tl) / m[i];
            tl = tr;
        }
    } else if (ends == ENDS_FREE) {
        tl = 0.0;
        for (size_t i = 0; i < n; i++) {
            double tr = i + 1 < n ? chain_tension(k[i], x[i + 1] - x[i], a, b, nonlinear) : 0.0;
            acc[i] = (tr - tl) / m[i];
            tl = tr;
        }
    } else {
        /* spring n-1 joins mass n-1 to mass 0: it is mass 0's left spring */
        tl = chain_tension(k[n - 1], x[0] - x[n - 1], a, b, nonlinear);
        for (size_t i = 0; i < n; i++) {
            double r = (i + 1 < n ? x[i + 1] : x[0]) - x[i];
            double tr = chain_tension(k[i], r, a, b, nonlinear);
            acc[i] = (tr - tl) / m[i];
            tl = tr;
        }
    }
}

/* (x, v)' = (v, a(x)); `nonlinear` is a constant in each bound rhs below */
static inline void chain_rhs(const double *y, double *f, const double *p, int nonlinear)
{
    const size_t n = (size_t)p[CN];
    memcpy(f, y + n, n * sizeof(double));
    chain_accel(p, y, f + n, nonlinear);
}

static int chain_rhs_linear(double t, const double *y, double *f, void *d)
{
    (void)t;
    chain_rhs(y, f, d, 0);
    return MP_OK;
}

static int chain_rhs_fput(double t, const double *y, double *f, void *d)
{
    (void)t;
    chain_rhs(y, f, d, 1);
    return MP_OK;
}

/* Add spring (i, j) of stiffness s to the lower-left block -M^{-1} K(x) of
 * the dense Jacobian (row-major, 2n columns); j < 0 is a wall. */
static void chain_jac_spring(double *J, size_t n, const double *m, long i, long j, double s)
{
    size_t w = 2 * n;
    if (i >= 0) J[(n + (size_t)i) * w + (size_t)i] -= s / m[i];
    if (j >= 0) J[(n + (size_t)j) * w + (size_t)j] -= s / m[j];
    if (i >= 0 && j >= 0) {
        J[(n + (size_t)i) * w + (size_t)j] += s / m[i];
        J[(n + (size_t)j) * w + (size_t)i] += s / m[j];
    }
}

static int chain_jac(double t, const double *y, double *J, void *d)
{
    const double *p = d;
    const size_t n = (size_t)p[CN], w = 2 * n;
    const int ends = (int)p[CENDS];
    const double a = p[CALPHA], b = p[CBETA];
    const double *m = p + CHEAD, *k = m + n, *x = y;
    (void)t;
    memset(J, 0, w * w * sizeof(double));
    for (size_t i = 0; i < n; i++) J[i * w + n + i] = 1.0;
    long ln = (long)n;
    if (ends == ENDS_FIXED) {
        for (long j = 0; j <= ln; j++) {
            long lo = j - 1, hi = j < ln ? j : -1;
            double r = (hi >= 0 ? x[hi] : 0.0) - (lo >= 0 ? x[lo] : 0.0);
            chain_jac_spring(J, n, m, lo, hi, chain_stiffness(k[j], r, a, b));
        }
    } else if (ends == ENDS_FREE) {
        for (long j = 0; j + 1 < ln; j++)
            chain_jac_spring(J, n, m, j, j + 1, chain_stiffness(k[j], x[j + 1] - x[j], a, b));
    } else if (n > 1) { /* a one-mass ring's spring joins the mass to itself: no force */
        for (long j = 0; j < ln; j++) {
            long hi = (j + 1) % ln;
            chain_jac_spring(J, n, m, j, hi, chain_stiffness(k[j], x[hi] - x[j], a, b));
        }
    }
    return MP_OK;
}

static void chain_bind(const double *p, mp_ode_problem *prob)
{
    size_t n = (size_t)p[CN];
    mp_model_set(prob, 2 * n,
                 (p[CALPHA] != 0.0 || p[CBETA] != 0.0) ? chain_rhs_fput : chain_rhs_linear,
                 chain_jac, p, n); /* q' = v, v' = a(q): always separable */
}

static inline double chain_potential(double k, double r, double a, double b)
{
    double r2 = r * r;
    return k * r2 * (0.5 + r * (a / 3.0 + 0.25 * b * r));
}

/* sum m v^2/2 + sum k (r^2/2 + alpha r^3/3 + beta r^4/4)  [J] */
static double chain_energy(const double *p, const double *y)
{
    const size_t n = (size_t)p[CN];
    const int ends = (int)p[CENDS];
    const double a = p[CALPHA], b = p[CBETA];
    const double *m = p + CHEAD, *k = m + n, *x = y, *v = y + n;
    double t = 0.0, u = 0.0;
    for (size_t i = 0; i < n; i++) t += m[i] * v[i] * v[i];
    if (ends == ENDS_FIXED) {
        u = chain_potential(k[0], x[0], a, b) + chain_potential(k[n], -x[n - 1], a, b);
        for (size_t j = 1; j < n; j++) u += chain_potential(k[j], x[j] - x[j - 1], a, b);
    } else if (ends == ENDS_FREE) {
        for (size_t j = 0; j + 1 < n; j++) u += chain_potential(k[j], x[j + 1] - x[j], a, b);
    } else {
        for (size_t j = 0; j < n; j++)
            u += chain_potential(k[j], (j + 1 < n ? x[j + 1] : x[0]) - x[j], a, b);
    }
    return 0.5 * t + u;
}

const mp_model mp_model_chain = {
    .name = "SpringChain", .dim = 0, .nparams = CHEAD, .params = chain_params,
    .separable = MP_SEPARABLE_ALWAYS, .check = chain_check, .bind = chain_bind,
    .energy = chain_energy, .dim_of = chain_dim_of,
    .states = MP_NAMES("x#", "v#"), .coordinates = MP_NAMES("x#"), .speeds = MP_NAMES("v#"),
    .drawing = "chain",
};
