/* Geometric integrators, fixed step: the velocity Verlet (kick-drift-kick)
 * method and Yoshida's symmetric compositions of it (orders 4 and 6) for
 * separable systems q'' = a(t, q), and the two-stage Gauss-Legendre method
 * (order 4, implicit, symplectic, keeps quadratic invariants). */
#include "ode/ode.h"
#include "ode/lu.h"
#include "ode/fixed.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- Verlet and its compositions ---------------------------------------- */

static int separable_alloc(mp_ode_ws *w)
{
    size_t nq = w->p->nq;
    return (nq > 0 && 2 * nq == w->n) ? MP_OK : MP_EDOM;
}

/* The composition c[0..ns) over one step h from (t, y, f) into (ynew, fnew),
 * checked; compensated (ode/fixed.h's mp_ode_sum_add: lo into lonew) when the
 * row says so. */
static int compose(mp_ode_ws *w, double t, double h, const double *c, int ns)
{
    double *lo = w->m->compensated ? w->lonew : NULL;
    memcpy(w->ynew, w->y, w->n * sizeof(double));
    if (lo) memcpy(lo, w->lo, w->n * sizeof(double));
    memcpy(w->fnew, w->f, w->n * sizeof(double));
    return mp_ode_compose(mp_ode_ws_eval, w, w->p->nq, t, h, c, ns, w->ynew, lo, w->fnew, NULL);
}

/* Contract: the block of ode.h's method row for the composition c[0..ns):
 * k steps in place, each as compose makes it; the problem's own blocks when
 * it has them. */
static int compose_block(mp_ode_ws *w, double t0, long i0, double h, long k, double *ts,
                         double *ys, const double *c, int ns)
{
    const mp_ode_problem *p = w->p;
    int comp = w->m->compensated;
    w->nfev += ns * k;
    if (p->blocks && p->blocks->rhs == p->rhs && p->blocks->compose)
        return p->blocks->compose(p->data, t0, i0, h, c, ns, k, w->y, comp ? w->lo : NULL, w->f,
                                  ts, ys, &w->discarded);
    if (comp) /* two instances: the constant NULL folds the plain one's tests away */
        return mp_ode_compose_steps(p->rhs, p->data, p->nq, t0, i0, h, c, ns, k, w->y, w->lo,
                                    w->f, ts, ys, &w->discarded);
    return mp_ode_compose_steps(p->rhs, p->data, p->nq, t0, i0, h, c, ns, k, w->y, NULL, w->f,
                                ts, ys, &w->discarded);
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

static int verlet_block(mp_ode_ws *w, double t0, long i0, double h, long k, double *ts,
                        double *ys)
{
    return compose_block(w, t0, i0, h, k, ts, ys, verlet_c, 1);
}

static int yoshida4_step(mp_ode_ws *w, double t, double h, double *err)
{
    *err = 0.0;
    return compose(w, t, h, yoshida4_c, 3);
}

static int yoshida4_block(mp_ode_ws *w, double t0, long i0, double h, long k, double *ts,
                        double *ys)
{
    return compose_block(w, t0, i0, h, k, ts, ys, yoshida4_c, 3);
}

static int yoshida6_step(mp_ode_ws *w, double t, double h, double *err)
{
    *err = 0.0;
    return compose(w, t, h, yoshida6_c, 7);
}

static int yoshida6_block(mp_ode_ws *w, double t0, long i0, double h, long k, double *ts,
                        double *ys)
{
    return compose_block(w, t0, i0, h, k, ts, ys, yoshida6_c, 7);
}

/* fnew = f(t + h, ynew) came out of the last kick */
static int fsal_hermite_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    w->fnew_valid = 1;
    return mp_ode_finish_fnew_hermite(w, t, h, need_dense);
}

/* Compensated summation (ode/fixed.h's mp_ode_sum_add) where it pays: in
 * yoshida4 and yoshida6, whose truncation error falls below the round-off of
 * the plain updates at steps a long run affords (Kepler e = 0.6, 1000 orbits,
 * energy at the orbits' ends: yoshida6 h = T/400 2.6e-13 plain, 9.8e-15
 * compensated; yoshida4 h = T/2000 3.9e-13, 4.0e-15), for +32% instructions
 * a step there (callgrind; +21% on the pendulum).  Not in verlet: its h^2
 * error stays far above round-off at any step a run can take (h = T/20000:
 * 2.8e-10; compensating changes nothing measurable there). */
#define MP_SPLIT_ROW(nm, ord, comp)                                                           \
    const mp_ode_method mp_ode_##nm = {                                                       \
        .name = #nm, .order = ord, .adaptive = 0, .symplectic = 1, .dense_order = 3,          \
        .compensated = comp,                                                                  \
        .ncoef = 4, .nscratch = 0, .alloc = separable_alloc, .step = nm##_step,               \
        .finish = fsal_hermite_finish, .block = nm##_block,                                   \
    }

MP_SPLIT_ROW(verlet, 2, 0);
MP_SPLIT_ROW(yoshida4, 4, 1);
MP_SPLIT_ROW(yoshida6, 6, 1);

/* ---- Gauss-Legendre, two stages ------------------------------------------- */

#define SQ3_6 0.28867513459481288225457439025098 /* sqrt(3)/6 */
static const double gl_c[2] = {0.5 - SQ3_6, 0.5 + SQ3_6};
static const double gl_a[2][2] = {{0.25, 0.25 - SQ3_6}, {0.25 + SQ3_6, 0.25}};

/* f at a stage; a non-finite value means the iteration diverges (the step
 * is too large for it), not a bad right-hand side. */
static int gl_stage(mp_ode_ws *w, double t, const double *Y, double *K)
{
    int rc = mp_ode_ws_rhs(w, t, Y, K);
    return rc == MP_ENONFINITE ? MP_ENOCONV : rc;
}

typedef struct {
    int n2;            /* 2n: the size of the Newton system */
    double *J;         /* n x n, row-major: df/dy at the start of a step */
    double *M;         /* 2n x 2n, column-major: LU factors of I - h (A kron J) */
    int *piv;
    double *Z, *dZ, *F; /* 2n each: stage increments Y_i - y, their update, f at the stages */
    double *Y, *tmp, *tmp2; /* n each */
    int have_J, have_LU;
    double lu_h;
} gl_state;

/* Contract: the Newton workspace of a solve; MP_ENOMEM, or MP_EDOM when 2n
 * does not fit LAPACK's int. */
static int gauss4_alloc(mp_ode_ws *w)
{
    size_t n = w->n;
    if (n > 20000) return MP_EDOM; /* (2n)^2 must fit an int index */
    gl_state *st = calloc(1, sizeof *st);
    if (!st) return MP_ENOMEM;
    w->state = st;
    st->n2 = (int)(2 * n);
    st->J = malloc((n * n + 4 * n * n + 9 * n) * sizeof(double));
    st->piv = malloc(2 * n * sizeof(int));
    if (!st->J || !st->piv) return MP_ENOMEM;
    st->M = st->J + n * n;
    st->Z = st->M + 4 * n * n;
    st->dZ = st->Z + 2 * n;
    st->F = st->dZ + 2 * n;
    st->Y = st->F + 2 * n;
    st->tmp = st->Y + n;
    st->tmp2 = st->tmp + n;
    return MP_OK;
}

static void gauss4_free(mp_ode_ws *w)
{
    gl_state *st = w->state;
    if (!st) return;
    free(st->J);
    free(st->piv);
    free(st);
    w->state = NULL;
}

/* Contract: factorise I - h (A kron J) into st->M; MP_ENOCONV when singular. */
static int gauss4_lu(mp_ode_ws *w, double h)
{
    gl_state *st = w->state;
    size_t n = w->n, n2 = (size_t)st->n2;
    for (size_t bi = 0; bi < 2; bi++)
        for (size_t bj = 0; bj < 2; bj++)
            for (size_t k = 0; k < n; k++)
                for (size_t l = 0; l < n; l++) {
                    size_t row = bi * n + k, col = bj * n + l;
                    st->M[col * n2 + row] = (row == col ? 1.0 : 0.0) -
                                            h * gl_a[bi][bj] * st->J[k * n + l];
                }
    int info = 0;
    dgetrf_(&st->n2, &st->n2, st->M, &st->n2, st->piv, &info);
    w->nlu++;
    st->have_LU = info == 0;
    st->lu_h = h;
    if (info < 0) return MP_EDOM;
    return info == 0 ? MP_OK : MP_ENOCONV;
}

/* Contract: solve the stage equations Z_i = h sum_j a_ij f(t + c_j h, y + Z_j)
 * by simplified Newton iterations with the factors in st->M, to round-off;
 * ynew = y + h (F_1 + F_2) / 2.  MP_ENOCONV when the iteration does not
 * contract (the step is too large, or the Jacobian is stale). */
static int gauss4_newton(mp_ode_ws *w, double t, double h)
{
    gl_state *st = w->state;
    size_t n = w->n;
    double prev = INFINITY, ynorm = DBL_MIN;
    for (size_t i = 0; i < n; i++) {
        ynorm = fmax(ynorm, fabs(w->y[i]));
        st->Z[i] = h * gl_c[0] * w->f[i]; /* sum_j a_ij = c_i */
        st->Z[n + i] = h * gl_c[1] * w->f[i];
    }
    for (int it = 0; it < 50; it++) {
        int rc;
        for (size_t s = 0; s < 2; s++) {
            for (size_t i = 0; i < n; i++) st->Y[i] = w->y[i] + st->Z[s * n + i];
            if ((rc = gl_stage(w, t + gl_c[s] * h, st->Y, st->F + s * n)) != MP_OK) return rc;
        }
        for (size_t s = 0; s < 2; s++)
            for (size_t i = 0; i < n; i++)
                st->dZ[s * n + i] = h * (gl_a[s][0] * st->F[i] + gl_a[s][1] * st->F[n + i]) -
                                    st->Z[s * n + i];
        mp_ode_getrs(st->n2, st->M, st->piv, st->dZ);
        /* the change of the stages against the size of the state as a whole:
         * a component passing through zero must not demand relative round-off */
        double d = 0.0;
        for (size_t i = 0; i < 2 * n; i++) {
            st->Z[i] += st->dZ[i];
            d = fmax(d, fabs(st->dZ[i]));
        }
        d /= ynorm;
        /* converged to round-off, or stagnating at it: F was taken at Z before
         * this last update, which moves ynew by h |J| d, below round-off */
        if (d <= 2.0 * DBL_EPSILON || (d >= prev && d < 1e-13)) {
            for (size_t i = 0; i < n; i++)
                w->ynew[i] = w->y[i] + 0.5 * h * (st->F[i] + st->F[n + i]);
            return MP_OK;
        }
        if (!isfinite(d) || (it > 3 && d > prev)) return MP_ENOCONV; /* not contracting */
        prev = d;
    }
    return MP_ENOCONV;
}

/* Stages by simplified Newton iterations with the Jacobian df/dy (analytic or
 * finite differences), as radau solves its own: the Jacobian and factors of
 * the last step are kept while the iteration contracts with them, and taken
 * afresh at (t, y) once when it does not.  A step too large for a fresh
 * Jacobian to converge is MP_ENOCONV. */
static int gauss4_step(mp_ode_ws *w, double t, double h, double *err)
{
    gl_state *st = w->state;
    *err = 0.0;
    for (int attempt = 0; attempt < 2; attempt++) {
        int rc;
        if (!st->have_J || attempt == 1) {
            if ((rc = mp_ode_ws_jac(w, t, w->y, w->f, st->J, st->tmp, st->tmp2)) != MP_OK)
                return rc;
            st->have_J = 1;
            st->have_LU = 0;
        }
        if (!st->have_LU || st->lu_h != h) {
            rc = gauss4_lu(w, h);
            if (rc == MP_ENOCONV && attempt == 0) continue;
            if (rc != MP_OK) return rc;
        }
        rc = gauss4_newton(w, t, h);
        if (rc != MP_ENOCONV) return rc;
    }
    return MP_ENOCONV;
}

const mp_ode_method mp_ode_gauss4 = {
    .name = "gauss4", .order = 4, .adaptive = 0, .implicit = 1, .symplectic = 1,
    .needs_jacobian = 1, .dense_order = 3, .ncoef = 4, .nscratch = 0,
    .alloc = gauss4_alloc, .free = gauss4_free, .step = gauss4_step,
    .finish = mp_ode_finish_fnew_hermite,
};
