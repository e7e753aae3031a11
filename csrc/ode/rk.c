/* Explicit Runge-Kutta methods: classical rk4 (fixed step), Dormand-Prince
 * 5(4) with Shampine's 4th-order dense output, and Hairer's DOP853 8(5,3)
 * with 7th-order dense output.  Step-size control lives in driver.c. */
#include "ode/ode.h"
#include "ode/control.h"
#include "ode/fixed.h"

#include <math.h>
#include <string.h>

#include "ode/dop853_tableau.h"

/* out = y + h sum_j a[j] K[j] over the non-zero a[j] (Hairer's order of
 * operations: the sum starts at its first term, not at 0.0 + it).  Always
 * inlined: called with a constant tableau row and stage count, the zero tests
 * fold away and the stage loop unrolls into the explicit formulas of Hairer's
 * codes.  out is none of y and the K[j] (the workspace's own vectors), so the
 * components run in SIMD lanes, each with the same operations as alone. */
MP_ODE_INLINE void
stage_point(size_t n, const double *y, double h, const double *a, double *const *K, size_t ns,
            double *out)
{
#pragma omp simd
    for (size_t i = 0; i < n; i++) {
        double sum = 0.0;
        int first = 1;
#pragma GCC unroll 16
        for (size_t j = 0; j < ns; j++)
            if (a[j] != 0.0) {
                sum = first ? a[j] * K[j][i] : sum + a[j] * K[j][i];
                first = 0;
            }
        out[i] = y[i] + h * sum;
    }
}

/* Hairer's stiffness estimate h |lambda| ~ h |f(a) - f(b)| / |a - b| from two
 * stages evaluated at the same time. */
static double stiffness_ratio(size_t n, double h, const double *fa, const double *fb,
                              const double *a, const double *b)
{
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < n; i++) {
        num += (fa[i] - fb[i]) * (fa[i] - fb[i]);
        den += (a[i] - b[i]) * (a[i] - b[i]);
    }
    return den > 0.0 ? fabs(h) * sqrt(num / den) : 0.0;
}

/* ---- classical RK4 ------------------------------------------------------- */

static int rk4_step(mp_ode_ws *w, double t, double h, double *err)
{
    *err = 0.0;
    return mp_ode_rk4_stages(mp_ode_ws_eval, w, w->n, t, h, w->y, w->f, w->ynew, w->k);
}

/* Contract: the block of ode.h's method row: k steps in place, each one's
 * four evaluations as rk4_step and the finish make them; the problem's own
 * blocks when it has them. */
static int rk4_block(mp_ode_ws *w, double t0, long i0, double h, long k, double *ts,
                     double *ys)
{
    const mp_ode_problem *p = w->p;
    w->nfev += 4 * k;
    if (p->blocks && p->blocks->rhs == p->rhs)
        return p->blocks->rk4(p->data, t0, i0, h, k, w->y, w->f, ts, ys);
    return mp_ode_rk4_steps(p->rhs, p->data, w->n, t0, i0, h, k, w->y, w->f, w->k, ts, ys);
}

const mp_ode_method mp_ode_rk4 = {
    .name = "rk4", .order = 4, .adaptive = 0, .dense_order = 3, .lanes = MP_LANE_RK4, .ncoef = 4, .nscratch = 4,
    .step = rk4_step, .finish = mp_ode_finish_fnew_hermite, .block = rk4_block,
};

/* ---- Dormand-Prince 5(4) ------------------------------------------------- */

/* dp_c, dp_a, dp_e (error weights), dp_d (dense output) */
#include "ode/dopri5_tableau.h"

static void dp_stages(mp_ode_ws *w, double **K)
{
    size_t n = w->n;
    K[0] = w->f;
    for (int s = 1; s < 6; s++) K[s] = w->k + (size_t)(s - 1) * n;
    K[6] = w->fnew;
}

static int dopri5_step(mp_ode_ws *w, double t, double h, double *err)
{
    size_t n = w->n;
    double *K[7];
    double *yt = w->k + 5 * n;
    int rc;
    dp_stages(w, K);
#define DP_STAGE(s)                                                                 \
    do {                                                                            \
        stage_point(n, w->y, h, dp_a[s], K, (s), yt);                               \
        if ((rc = mp_ode_ws_rhs(w, t + dp_c[s] * h, yt, K[s])) != MP_OK) return rc; \
    } while (0)
    DP_STAGE(1); DP_STAGE(2); DP_STAGE(3); DP_STAGE(4); DP_STAGE(5);
#undef DP_STAGE
    stage_point(n, w->y, h, dp_a[6], K, 6, w->ynew);
    if ((rc = mp_ode_ws_rhs(w, t + h, w->ynew, K[6])) != MP_OK) return rc; /* FSAL */
    w->rho = stiffness_ratio(n, h, K[6], K[5], w->ynew, yt); /* stages 6, 7 both at t + h */
    uint64_t bad = 0; /* the new state's check (driver.c's check_state), in this loop */
    for (size_t i = 0; i < n; i++) {
        double e = 0.0;
        for (int s = 0; s < 7; s++) e += dp_e[s] * K[s][i];
        yt[i] = h * e;
        bad |= mp_ode_nonfinite_bit(w->ynew[i]);
    }
    if (bad >> 63) return mp_ode_ws_bad_state(w);
    *err = mp_ode_err_norm(w, yt, w->y, w->ynew);
    return MP_OK;
}

static int dopri5_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    (void)t;
    size_t n = w->n;
    w->fnew_valid = 1; /* stage 7 */
    if (!need_dense) return MP_OK;
    double *K[7];
    dp_stages(w, K);
    double *c = w->coef;
    for (size_t i = 0; i < n; i++) {
        double dy = w->ynew[i] - w->y[i];
        double c3 = h * K[0][i] - dy;
        double d = 0.0;
        for (int s = 0; s < 7; s++) d += dp_d[s] * K[s][i];
        c[i] = w->y[i];
        c[n + i] = dy;
        c[2 * n + i] = c3;
        c[3 * n + i] = dy - h * K[6][i] - c3;
        c[4 * n + i] = h * d;
    }
    return MP_OK;
}

const mp_ode_method mp_ode_dopri5 = {
    .name = "dopri5", .order = 5, .adaptive = 1, .dense_order = 4, .lanes = MP_LANE_DOPRI5, .ncoef = 5, .nscratch = 6,
    .expo = 0.2, .beta = 0.04, .fac_min = 0.2, .fac_max = 10.0, .safety = 0.9,
    .stiff_rho = 3.25, .step = dopri5_step, .finish = dopri5_finish,
};

/* ---- Dormand-Prince 8(5,3) ----------------------------------------------- */

/* K[0] = f, K[1..11] scratch, K[12] = fnew, K[13..15] scratch (dense only),
 * then one scratch vector for stage points. */
static inline void d8_stages(mp_ode_ws *w, double **K, double **yt)
{
    size_t n = w->n;
    K[0] = w->f;
    for (int s = 1; s < 12; s++) K[s] = w->k + (size_t)(s - 1) * n;
    K[12] = w->fnew;
    for (int s = 13; s < 16; s++) K[s] = w->k + (size_t)(s - 2) * n;
    *yt = w->k + 14 * n;
}

static int dop853_step(mp_ode_ws *w, double t, double h, double *err)
{
    size_t n = w->n;
    double *K[16], *yt;
    int rc;
    d8_stages(w, K, &yt);
    /* the stages written out, so that each stage_point sees its constant row */
#define D8_STAGE(s)                                                                     \
    do {                                                                                \
        stage_point(n, w->y, h, mp_dop853_a[s], K, (s), yt);                            \
        if ((rc = mp_ode_ws_rhs(w, t + mp_dop853_c[s] * h, yt, K[s])) != MP_OK) return rc; \
    } while (0)
    D8_STAGE(1); D8_STAGE(2); D8_STAGE(3); D8_STAGE(4); D8_STAGE(5); D8_STAGE(6);
    D8_STAGE(7); D8_STAGE(8); D8_STAGE(9); D8_STAGE(10); D8_STAGE(11);
#undef D8_STAGE
    stage_point(n, w->y, h, mp_dop853_b, K, 12, w->ynew);
    double e5s = 0.0, e3s = 0.0;
    uint64_t bad = 0; /* the new state's check (driver.c's check_state), in this loop */
    for (size_t i = 0; i < n; i++) {
        double e5 = 0.0, e3 = 0.0;
        bad |= mp_ode_nonfinite_bit(w->ynew[i]);
#pragma GCC unroll 12
        for (int s = 0; s < 12; s++) { /* constant weights: the zero terms fold away */
            if (mp_dop853_e5[s] != 0.0) e5 += mp_dop853_e5[s] * K[s][i];
            if (mp_dop853_e3[s] != 0.0) e3 += mp_dop853_e3[s] * K[s][i];
        }
        double sk = mp_ode_weight(w->o->atol[i], w->o->rtolv[i],
                                  mp_ode_absmax(w->y[i], w->ynew[i]));
        e5s += (e5 / sk) * (e5 / sk);
        e3s += (e3 / sk) * (e3 / sk);
    }
    if (bad >> 63) return mp_ode_ws_bad_state(w);
    double deno = e5s + 0.01 * e3s;
    if (deno <= 0.0) deno = 1.0;
    *err = fabs(h) * e5s / sqrt(deno * (double)n);
    return MP_OK;
}

static int dop853_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    size_t n = w->n;
    double *K[16], *yt;
    int rc;
    d8_stages(w, K, &yt);
    if ((rc = mp_ode_ws_rhs(w, t + h, w->ynew, K[12])) != MP_OK) return rc;
    w->fnew_valid = 1;
    w->rho = stiffness_ratio(n, h, K[12], K[11], w->ynew, yt); /* yt: stage 12's point */
    if (!need_dense) return MP_OK;
    for (int s = 13; s < 16; s++) {
        stage_point(n, w->y, h, mp_dop853_a[s], K, (size_t)s, yt);
        if ((rc = mp_ode_ws_rhs(w, t + mp_dop853_c[s] * h, yt, K[s])) != MP_OK) return rc;
    }
    double *c = w->coef;
    for (size_t i = 0; i < n; i++) {
        double dy = w->ynew[i] - w->y[i];
        c[i] = w->y[i];
        c[n + i] = dy;
        c[2 * n + i] = h * K[0][i] - dy;
        c[3 * n + i] = 2.0 * dy - h * (K[12][i] + K[0][i]);
        for (int r = 0; r < 4; r++) {
            double d = 0.0;
            for (int s = 0; s < 16; s++) d += mp_dop853_d[r][s] * K[s][i];
            c[(size_t)(4 + r) * n + i] = h * d;
        }
    }
    return MP_OK;
}

const mp_ode_method mp_ode_dop853 = {
    .name = "dop853", .order = 8, .adaptive = 1, .dense_order = 7, .lanes = MP_LANE_DOP853, .ncoef = 8, .nscratch = 15,
    .expo = 1.0 / 8.0, .beta = 0.0, .fac_min = 0.333, .fac_max = 6.0, .safety = 0.9,
    .stiff_rho = 6.1, .step = dop853_step, .finish = dop853_finish,
};
