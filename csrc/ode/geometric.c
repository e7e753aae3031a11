/* Geometric integrators, fixed step: the velocity Verlet (kick-drift-kick)
 * method and Yoshida's symmetric compositions of it (orders 4 and 6) for
 * separable systems q'' = a(t, q), and the two-stage Gauss-Legendre method
 * (order 4, implicit, symplectic, keeps quadratic invariants). */
#include "ode/ode.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* ---- Verlet and its compositions ---------------------------------------- */

static int separable_alloc(mp_ode_ws *w)
{
    size_t nq = w->p->nq;
    return (nq > 0 && 2 * nq == w->n) ? MP_OK : MP_EDOM;
}

/* One kick-drift-kick step of size h on y = (q, v), with f = f(t, y) on
 * entry and f(t + h, y) on exit; one right-hand side evaluation. */
static int kdk(mp_ode_ws *w, double t, double h, double *y, double *f)
{
    size_t nq = w->p->nq;
    double *q = y, *v = y + nq;
    for (size_t i = 0; i < nq; i++) v[i] += 0.5 * h * f[nq + i];
    for (size_t i = 0; i < nq; i++) q[i] += h * v[i];
    int rc = mp_ode_ws_rhs(w, t + h, y, f); /* its second half is a(t + h, q) */
    if (rc != MP_OK) return rc;
    for (size_t i = 0; i < nq; i++) v[i] += 0.5 * h * f[nq + i];
    memcpy(f, v, nq * sizeof(double)); /* q' = v at the new state */
    return MP_OK;
}

static int compose(mp_ode_ws *w, double t, double h, const double *c, int ns)
{
    memcpy(w->ynew, w->y, w->n * sizeof(double));
    memcpy(w->fnew, w->f, w->n * sizeof(double));
    double tt = t;
    for (int i = 0; i < ns; i++) {
        int rc = kdk(w, tt, c[i] * h, w->ynew, w->fnew);
        if (rc != MP_OK) return rc;
        tt += c[i] * h;
    }
    return MP_OK;
}

static const double verlet_c[1] = {1.0};
/* Yoshida (1990): w1 = 1/(2 - 2^(1/3)), w0 = -2^(1/3) w1 */
#define Y4_W1 1.3512071919596576340476878089715
#define Y4_W0 (-1.7024143839193152680953756179429)
static const double yoshida4_c[3] = {Y4_W1, Y4_W0, Y4_W1};
/* Yoshida (1990), solution A of the sixth-order symmetric composition */
#define Y6_W1 (-1.17767998417887)
#define Y6_W2 0.235573213359357
#define Y6_W3 0.784513610477560
#define Y6_W0 (1.0 - 2.0 * (Y6_W1 + Y6_W2 + Y6_W3))
static const double yoshida6_c[7] = {Y6_W3, Y6_W2, Y6_W1, Y6_W0, Y6_W1, Y6_W2, Y6_W3};

static int verlet_step(mp_ode_ws *w, double t, double h, double *err)
{
    *err = 0.0;
    return compose(w, t, h, verlet_c, 1);
}

static int yoshida4_step(mp_ode_ws *w, double t, double h, double *err)
{
    *err = 0.0;
    return compose(w, t, h, yoshida4_c, 3);
}

static int yoshida6_step(mp_ode_ws *w, double t, double h, double *err)
{
    *err = 0.0;
    return compose(w, t, h, yoshida6_c, 7);
}

/* fnew = f(t + h, ynew) came out of the last kick */
static int fsal_hermite_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    (void)t;
    w->fnew_valid = 1;
    if (need_dense) mp_ode_dense_hermite(w->n, h, w->y, w->ynew, w->f, w->fnew, w->coef);
    return MP_OK;
}

#define MP_SPLIT_ROW(nm, ord)                                                                 \
    const mp_ode_method mp_ode_##nm = {                                                       \
        .name = #nm, .order = ord, .adaptive = 0, .symplectic = 1, .dense_order = 3,          \
        .ncoef = 4, .nscratch = 0, .alloc = separable_alloc, .step = nm##_step,               \
        .finish = fsal_hermite_finish,                                                       \
    }

MP_SPLIT_ROW(verlet, 2);
MP_SPLIT_ROW(yoshida4, 4);
MP_SPLIT_ROW(yoshida6, 6);

/* ---- Gauss-Legendre, two stages ------------------------------------------- */

#define SQ3_6 0.28867513459481288225457439025098 /* sqrt(3)/6 */
static const double gl_c[2] = {0.5 - SQ3_6, 0.5 + SQ3_6};
static const double gl_a[2][2] = {{0.25, 0.25 - SQ3_6}, {0.25 + SQ3_6, 0.25}};

/* f at a stage; a non-finite value means the iteration diverges (the step
 * is too large for it), not a bad right-hand side. */
static int gl_stage(mp_ode_ws *w, double t, const double *Y, double *K)
{
    int rc = w->p->rhs(t, Y, K, w->p->data);
    w->nfev++;
    if (rc != MP_OK) return rc;
    for (size_t i = 0; i < w->n; i++)
        if (!isfinite(K[i])) return MP_ENOCONV;
    return MP_OK;
}

/* Stages by fixed-point iteration, to round-off (a non-stiff, Hamiltonian
 * setting; a step too large for it to contract is MP_ENOCONV). */
static int gauss4_step(mp_ode_ws *w, double t, double h, double *err)
{
    size_t n = w->n;
    double *K1 = w->k, *K2 = K1 + n, *N1 = K2 + n, *N2 = N1 + n, *Y = N2 + n;
    double prev = INFINITY;
    *err = 0.0;
    memcpy(K1, w->f, n * sizeof(double));
    memcpy(K2, w->f, n * sizeof(double));
    for (int it = 0; it < 100; it++) {
        int rc;
        for (size_t i = 0; i < n; i++) Y[i] = w->y[i] + h * (gl_a[0][0] * K1[i] + gl_a[0][1] * K2[i]);
        if ((rc = gl_stage(w, t + gl_c[0] * h, Y, N1)) != MP_OK) return rc;
        for (size_t i = 0; i < n; i++) Y[i] = w->y[i] + h * (gl_a[1][0] * K1[i] + gl_a[1][1] * K2[i]);
        if ((rc = gl_stage(w, t + gl_c[1] * h, Y, N2)) != MP_OK) return rc;
        /* the change of the stages against the size of the state as a whole:
         * a component passing through zero must not demand relative round-off */
        double d = 0.0, ynorm = DBL_MIN;
        for (size_t i = 0; i < n; i++) {
            ynorm = fmax(ynorm, fabs(w->y[i]));
            d = fmax(d, fabs(h) * (fabs(N1[i] - K1[i]) + fabs(N2[i] - K2[i])));
        }
        d /= ynorm;
        memcpy(K1, N1, n * sizeof(double));
        memcpy(K2, N2, n * sizeof(double));
        /* converged to round-off, or stagnating at it */
        if (d <= 2.0 * DBL_EPSILON || (d >= prev && d < 1e-13)) {
            for (size_t i = 0; i < n; i++) w->ynew[i] = w->y[i] + 0.5 * h * (K1[i] + K2[i]);
            return MP_OK;
        }
        if (!isfinite(d) || (it > 3 && d > prev)) return MP_ENOCONV; /* not contracting */
        prev = d;
    }
    return MP_ENOCONV;
}

const mp_ode_method mp_ode_gauss4 = {
    .name = "gauss4", .order = 4, .adaptive = 0, .implicit = 1, .symplectic = 1,
    .dense_order = 3, .ncoef = 4, .nscratch = 5, .step = gauss4_step,
    .finish = mp_ode_finish_fnew_hermite,
};
