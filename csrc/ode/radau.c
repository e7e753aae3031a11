/* Radau IIA of order 5 in the manner of Hairer & Wanner's RADAU5: the
 * collocation system is solved by simplified Newton iterations, transformed
 * so that one real and one complex n x n system are factorised (LAPACK);
 * Gustafsson's predictive step-size control; the collocation polynomial
 * serves as dense output.  A self-controlled row: the step function repeats
 * its own attempts until one is accepted.
 *
 * RADAU5's economy (Hairer & Wanner, Solving ODEs II, IV.8, and radau5.f):
 * - its Newton loop: the contraction theta from the third pass, an iteration
 *   that stops after one pass when the previous step's contraction (FACCON)
 *   says it has converged, and gives up early when theta predicts that NIT
 *   passes will not do (h shrunk as theta says);
 * - its Jacobian rule: J is kept across accepted steps while theta <= THET.
 *   RADAU5's THET is 0.001 for small systems and 0.1 "when Jacobian
 *   evaluations are costly"; here 0.1 (0.01 took 2.8-7.2x CVODE's Jacobians on
 *   the stiff set; SciPy's Radau, whose rule radau followed before, refreshes
 *   J after every Newton iteration of more than two passes at a rate above
 *   1e-3: 931 Jacobians on ROBER at rtol 1e-10 against 24 now).  A stale J is
 *   refreshed when Newton fails with it.  Unlike RADAU5, a J made at the
 *   step's own start is kept one more step even when theta exceeded THET
 *   with it: a slow contraction with a fresh J comes from the step's size,
 *   not from J's age, and a new J does not speed it (HIRES at rtol 1e-6
 *   took a new J on each of 25 consecutive steps, theta 0.10-0.18 with
 *   every one: 38 Jacobians, 35 with the rule; over the stiff set at rtol
 *   1e-4..1e-10 the errors stay below rtol, at most 3.4x larger than with
 *   RADAU5's rule (VDPOL at 1e-4) and up to 7x smaller (HIRES at 1e-4), and
 *   nfev grows by at most 16%, VDPOL at 1e-4);
 * - its LU rule: h and the LU pair are kept while the controller's new step
 *   is within QUOT1..QUOT2 of the old and J is kept.  QUOT2 is RADAU5's 1.2;
 *   QUOT1 is SciPy's 0 rather than RADAU5's 1 (keeping h also where the
 *   controller would shrink it a little: VDPOL at rtol 1e-10 took 3,138 LU
 *   pairs with 1, 252 with 0, the errors alike);
 * - its tolerance transformation rtol' = 0.1 rtol^(2/3), atol' = atol rtol' /
 *   rtol (the order-3 error estimate held to it makes the global error about
 *   rtol), capped at TOL_CAP rtol: RADAU5's own factor (10 at rtol 1e-6, 215
 *   at 1e-10) ended HIRES at 2.2e-6 for rtol 1e-6, the stiff Van der Pol
 *   above the suite's bounds at 1e-8, and SciPy's test_args (dense output at
 *   rtol 1e-10) at 1.3e-9.  The Newton tolerance FNEWT is RADAU5's, from rtol'
 *   (from RADAU5's own, uncapped rtol' it took 12-20% fewer passes on the
 *   stiff set at rtol 1e-10 but ended the stiff Van der Pol at rtol 1e-8
 *   30x further from its reference, 5.4e-10).
 *
 * A banded problem (mp_ode_problem.banded, SciPy's jac_sparsity) whose band
 * is narrow (lu.h's mp_ode_band_pays) is factorised in LAPACK's band form: the pair
 * then costs O(n (ml + mu) ml) instead of O(n^3) (the 200-state Brusselator,
 * band 2 + 2: a dense pair took about 1.5 ms).
 */
#include "ode/ode.h"
#include "ode/control.h"
#include "ode/lu.h"

#include <complex.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define S6 2.449489742783178098197284
#define NEWTON_MAXITER 7 /* RADAU5's NIT */
#define MIN_FACTOR 0.2
#define MAX_FACTOR 8.0
#define THET 0.1         /* keep the Jacobian while the Newton contraction is below */
#define QUOT1 0.0        /* keep h and the LU pair when the new step is within */
#define QUOT2 1.2        /* QUOT1 ... QUOT2 times the old */
#define TOL_CAP 2.0      /* rtol' = 0.1 rtol^(2/3), at most TOL_CAP rtol */

static const double rc_c[3] = {(4.0 - S6) / 10.0, (4.0 + S6) / 10.0, 1.0};
static const double rc_e[3] = {(-13.0 - 7.0 * S6) / 3.0, (-13.0 + 7.0 * S6) / 3.0, -1.0 / 3.0};
/* eigen-decomposition of the inverse Radau IIA matrix: T, T^-1, eigenvalues */
static const double rc_T[3][3] = {
    {0.09443876248897524, -0.14125529502095421, 0.03002919410514742},
    {0.25021312296533332, 0.20412935229379994, -0.38294211275726192},
    {1.0, 1.0, 0.0}};
static const double rc_TI[3][3] = {
    {4.17871859155190428, 0.32768282076106237, 0.52337644549944951},
    {-4.17871859155190428, -0.32768282076106237, 0.47662355450055044},
    {0.50287263494578682, -2.57192694985560522, 0.59603920482822492}};
/* collocation polynomial: Q = Z^T P gives y(t0 + x h) = y0 + Q (x, x^2, x^3) */
static const double rc_P[3][3] = {
    {13.0 / 3.0 + 7.0 * S6 / 3.0, -23.0 / 3.0 - 22.0 * S6 / 3.0, 10.0 / 3.0 + 5.0 * S6},
    {13.0 / 3.0 - 7.0 * S6 / 3.0, -23.0 / 3.0 + 22.0 * S6 / 3.0, 10.0 / 3.0 - 5.0 * S6},
    {1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0}};

typedef struct {
    int n;
    double *J;              /* n x n row-major */
    int band, kl, ku, ldab; /* band form: LUr, LUc hold n columns of ldab */
    const size_t *perm;     /* band form: the band's order of the states, or NULL */
    double *pb;             /* ... a right-hand side in that order (n) */
    double complex *pbc;
    double *dinv_r;         /* band form: 1 / U_ii of each factorisation */
    double complex *dinv_c;
    double *LUr;            /* column-major */
    double complex *LUc;
    int *piv_r, *piv_c;
    int have_J, current_J, have_LU;
    double lu_h;            /* step the LU factors were made for */
    double *Z, *W, *F, *dW; /* 3 x n each */
    double *Q;              /* 3 x n: last accepted step's polynomial */
    double q_h;             /* its step; 0 when there is none */
    double *tmp, *tmp2, *scale, *err;
    double complex *ctmp;
    double h_old, err_old;  /* Gustafsson's controller memory; <= 0 none */
    double *rtol_t, *atol_t; /* the transformed tolerances (n each) */
    double fnewt;           /* Newton's stopping tolerance (from the least rtol') */
    double faccon;          /* theta / (1 - theta) of the last Newton iteration */
} radau_state;

static void radau_free(mp_ode_ws *w)
{
    radau_state *st = w->state;
    if (!st) return;
    free(st->J);
    free(st->LUr);
    free(st->LUc);
    free(st->piv_r);
    free(st->piv_c);
    free(st->Z);
    free(st->ctmp);
    free(st->rtol_t);
    free(st->dinv_r);
    free(st->dinv_c);
    free(st->pb);
    free(st->pbc);
    free(st);
    w->state = NULL;
}

static void radau_restart(mp_ode_ws *w)
{
    radau_state *st = w->state;
    st->have_J = st->current_J = st->have_LU = 0;
    st->q_h = 0.0;
    st->h_old = st->err_old = -1.0;
    st->faccon = 1.0;
}

static int radau_alloc(mp_ode_ws *w)
{
    size_t n = w->n;
    if (n > 46340) return MP_EDOM; /* n*n must fit LAPACK's int */
    radau_state *st = calloc(1, sizeof *st);
    if (!st) return MP_ENOMEM;
    w->state = st;
    st->n = (int)n;
    const mp_ode_problem *p = w->p;
    size_t nlu = n * n;
    if (p->banded && mp_ode_band_pays(n, p->ml, p->mu)) {
        st->band = 1;
        st->kl = (int)p->ml;
        st->ku = (int)p->mu;
        st->ldab = 2 * st->kl + st->ku + 1;
        nlu = (size_t)st->ldab * n;
        st->dinv_r = malloc(n * sizeof(double));
        st->dinv_c = malloc(n * sizeof(double complex));
        if (!st->dinv_r || !st->dinv_c) return MP_ENOMEM;
        if ((st->perm = p->perm)) {
            st->pb = malloc(n * sizeof(double));
            st->pbc = malloc(n * sizeof(double complex));
            if (!st->pb || !st->pbc) return MP_ENOMEM;
        }
    }
    st->J = malloc(n * n * sizeof(double));
    st->LUr = malloc(nlu * sizeof(double));
    st->LUc = malloc(nlu * sizeof(double complex));
    st->piv_r = malloc(n * sizeof(int));
    st->piv_c = malloc(n * sizeof(int));
    st->Z = malloc(20 * n * sizeof(double));
    st->ctmp = malloc(n * sizeof(double complex));
    st->rtol_t = malloc(2 * n * sizeof(double));
    if (!st->J || !st->LUr || !st->LUc || !st->piv_r || !st->piv_c || !st->Z || !st->ctmp ||
        !st->rtol_t)
        return MP_ENOMEM;
    /* RADAU5's tolerance transformation, per component */
    const mp_ode_options *o = w->o;
    st->atol_t = st->rtol_t + n;
    double rmin = INFINITY;
    for (size_t i = 0; i < n; i++) {
        double r = o->rtolv[i], rt = fmin(0.1 * pow(r, 2.0 / 3.0), TOL_CAP * r);
        st->rtol_t[i] = rt;
        st->atol_t[i] = o->atol[i] * (rt / r);
        rmin = fmin(rmin, rt);
    }
    st->fnewt = fmax(10.0 * DBL_EPSILON / rmin, fmin(0.03, sqrt(rmin)));
    st->W = st->Z + 3 * n;
    st->F = st->W + 3 * n;
    st->dW = st->F + 3 * n;
    st->Q = st->dW + 3 * n;
    st->tmp = st->Q + 3 * n;
    st->tmp2 = st->tmp + n;
    st->scale = st->tmp2 + n;
    st->err = st->scale + n;
    radau_restart(w);
    return MP_OK;
}

/* Contract: the error estimate's RMS norm, v scaled by scale; one that
 * overflowed from finite v is recorded (mp_ode_ws_bad_norm) for the message
 * should the step size then fail. */
static double err_rms(mp_ode_ws *w, const double *v, const double *scale)
{
    size_t n = w->n;
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += (v[i] / scale[i]) * (v[i] / scale[i]);
    double r = sqrt(s / (double)n);
    if (!isfinite(r)) mp_ode_ws_bad_norm(w);
    return r;
}

static int radau_jac(mp_ode_ws *w, double t)
{
    radau_state *st = w->state;
    int rc = mp_ode_ws_jac(w, t, w->y, w->f, st->J, st->tmp, st->tmp2);
    if (rc != MP_OK) return rc;
    double jn = 0.0;
    for (int i = 0; i < st->n; i++) {
        double row = 0.0;
        for (int j = 0; j < st->n; j++) row += fabs(st->J[(size_t)i * st->n + j]);
        jn = fmax(jn, row);
    }
    w->jnorm = jn;
    st->have_J = st->current_J = 1;
    st->have_LU = 0;
    return MP_OK;
}

/* Contract: the real and complex eigenvalues of Radau IIA's inverse
 * coefficient matrix over h (the shifts of its two linear systems). */
static void radau_eig(double h, double *mr, double complex *mc)
{
    *mr = (3.0 + cbrt(9.0) - cbrt(3.0)) / h;
    *mc = (3.0 + 0.5 * (cbrt(3.0) - cbrt(9.0)) -
           0.5 * I * (pow(3.0, 5.0 / 6.0) + pow(3.0, 7.0 / 6.0))) / h;
}

static int radau_lu(mp_ode_ws *w, double h)
{
    radau_state *st = w->state;
    int n = st->n, info = 0;
    double mr;
    double complex mc;
    radau_eig(h, &mr, &mc);
    int info2 = 0;
    if (st->band) {
        int kl = st->kl, ku = st->ku, ld = st->ldab;
        /* rows 0..kl-1 of each column receive the fill-in */
        memset(st->LUr, 0, (size_t)ld * n * sizeof(double));
        memset(st->LUc, 0, (size_t)ld * n * sizeof(double complex));
        const size_t *pm = st->perm;
        for (int j = 0; j < n; j++) {
            int i0 = j > ku ? j - ku : 0, i1 = j + kl < n ? j + kl + 1 : n;
            size_t pj = pm ? pm[j] : (size_t)j;
            for (int i = i0; i < i1; i++) {
                double a = -st->J[(pm ? pm[i] : (size_t)i) * (size_t)n + pj];
                size_t at = (size_t)j * ld + (size_t)(kl + ku + i - j);
                st->LUr[at] = a + (i == j ? mr : 0.0);
                st->LUc[at] = a + (i == j ? mc : 0.0);
            }
        }
        dgbtrf_(&n, &n, &kl, &ku, st->LUr, &ld, st->piv_r, &info);
        if (info < 0) return MP_EDOM;
        zgbtrf_(&n, &n, &kl, &ku, st->LUc, &ld, st->piv_c, &info2);
        if (info2 < 0) return MP_EDOM;
        if (info == 0 && info2 == 0) {
            mp_ode_gbdinv(n, kl + ku, st->LUr, ld, st->dinv_r);
            mp_ode_zgbdinv(n, kl + ku, st->LUc, ld, st->dinv_c);
        }
    } else {
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double a = -st->J[(size_t)i * n + j];
                st->LUr[(size_t)j * n + i] = a + (i == j ? mr : 0.0);
                st->LUc[(size_t)j * n + i] = a + (i == j ? mc : 0.0);
            }
        dgetrf_(&n, &n, st->LUr, &n, st->piv_r, &info);
        if (info < 0) return MP_EDOM;
        zgetrf_(&n, &n, st->LUc, &n, st->piv_c, &info2);
        if (info2 < 0) return MP_EDOM;
    }
    w->nlu++;
    st->have_LU = (info == 0 && info2 == 0); /* singular: the caller shrinks h */
    st->lu_h = h;
    return st->have_LU ? MP_OK : MP_ESINGULAR;
}

static void solve_real(radau_state *st, double *b)
{
    if (!st->band) {
        mp_ode_getrs(st->n, st->LUr, st->piv_r, b);
        return;
    }
    /* P A P^T factorised: solve for P x from P b */
    const size_t *pm = st->perm;
    double *x = pm ? st->pb : b;
    for (int i = 0; pm && i < st->n; i++) x[i] = b[pm[i]];
    mp_ode_gbtrs(st->n, st->kl, st->ku, st->LUr, st->ldab, st->piv_r, st->dinv_r, x);
    for (int i = 0; pm && i < st->n; i++) b[pm[i]] = x[i];
}

static void solve_complex(radau_state *st, double complex *b)
{
    if (!st->band) {
        mp_ode_zgetrs(st->n, st->LUc, st->piv_c, b);
        return;
    }
    const size_t *pm = st->perm;
    double complex *x = pm ? st->pbc : b;
    for (int i = 0; pm && i < st->n; i++) x[i] = b[pm[i]];
    mp_ode_zgbtrs(st->n, st->kl, st->ku, st->LUc, st->ldab, st->piv_c, st->dinv_c, x);
    for (int i = 0; pm && i < st->n; i++) b[pm[i]] = x[i];
}

/* Newton iterations on the collocation system (RADAU5's loop); returns 1 when
 * converged, 0 when not, with *hfac the factor to shrink h by (theta's
 * prediction of a slow iteration, else 0.5; 0.1 with *nonfinite = 1 when a
 * stage value was NaN or inf: too large a step); *rc is a fatal status from
 * the right-hand side.  *iters and *theta: the passes made and the last
 * contraction (THET when one pass sufficed). */
static int radau_newton(mp_ode_ws *w, double t, double h, int *iters, double *theta,
                        double *hfac, int *rc, int *nonfinite)
{
    radau_state *st = w->state;
    size_t n = (size_t)st->n;
    double mr;
    double complex mc;
    radau_eig(h, &mr, &mc);
    double *Z = st->Z, *W = st->W, *F = st->F, *dW = st->dW;
    double dynold = 1.0, thqold = 1.0, fnewt = st->fnewt;
    double faccon = pow(fmax(st->faccon, DBL_EPSILON), 0.8);
    *theta = THET;
    *hfac = 0.5;
    *rc = MP_OK;
    /* The loops over the components below are marked `omp simd`: Z, W, F,
     * dW and tmp are disjoint parts of one allocation, which the compiler
     * cannot see (each element's arithmetic is unchanged: the same values,
     * two at a time). */
    double mcr = creal(mc), mci = cimag(mc);
    /* W = TI Z */
    for (int a = 0; a < 3; a++) {
#pragma omp simd
        for (size_t i = 0; i < n; i++)
            W[a * n + i] = rc_TI[a][0] * Z[i] + rc_TI[a][1] * Z[n + i] + rc_TI[a][2] * Z[2 * n + i];
    }
    for (int newt = 1; newt <= NEWTON_MAXITER; newt++) {
        *iters = newt;
        for (int a = 0; a < 3; a++) {
#pragma omp simd
            for (size_t i = 0; i < n; i++) st->tmp[i] = w->y[i] + Z[a * n + i];
            int r = mp_ode_ws_rhs(w, t + rc_c[a] * h, st->tmp, F + a * n);
            if (r == MP_ENONFINITE) { *nonfinite = 1; *hfac = 0.1; return 0; }
            if (r != MP_OK) { *rc = r; return 0; }
        }
        double *ct = (double *)st->ctmp; /* C11: a complex is its (re, im) pair */
#pragma omp simd
        for (size_t i = 0; i < n; i++) {
            double fr = rc_TI[0][0] * F[i] + rc_TI[0][1] * F[n + i] + rc_TI[0][2] * F[2 * n + i];
            double fc_re = rc_TI[1][0] * F[i] + rc_TI[1][1] * F[n + i] + rc_TI[1][2] * F[2 * n + i];
            double fc_im = rc_TI[2][0] * F[i] + rc_TI[2][1] * F[n + i] + rc_TI[2][2] * F[2 * n + i];
            double wr = W[n + i], wi = W[2 * n + i];
            dW[i] = fr - mr * W[i];
            ct[2 * i] = fc_re - (mcr * wr - mci * wi);  /* (fc_re + i fc_im) - mc (wr + i wi) */
            ct[2 * i + 1] = fc_im - (mcr * wi + mci * wr);
        }
        solve_real(st, dW);
        solve_complex(st, st->ctmp);
#pragma omp simd
        for (size_t i = 0; i < n; i++) {
            dW[n + i] = ct[2 * i];
            dW[2 * n + i] = ct[2 * i + 1];
        }
        double s = 0.0;
        for (int a = 0; a < 3; a++)
            for (size_t i = 0; i < n; i++) {
                double q = dW[a * n + i] / st->scale[i];
                s += q * q;
            }
        double dyno = sqrt(s / (3.0 * (double)n));
        if (!isfinite(dyno)) { /* f was finite (mp_ode_ws_rhs checked it): dW overflowed */
            mp_ode_ws_bad_norm(w);
            *nonfinite = 1;
            *hfac = 0.1;
            return 0;
        }
        if (newt > 1 && newt < NEWTON_MAXITER) {
            double thq = dyno / dynold;
            *theta = newt == 2 ? thq : sqrt(thq * thqold);
            thqold = thq;
            if (!(*theta < 0.99)) return 0; /* diverging: halve h */
            faccon = *theta / (1.0 - *theta);
            double dyth = faccon * dyno * pow(*theta, NEWTON_MAXITER - 1 - newt) / fnewt;
            if (dyth >= 1.0) { /* NIT passes will not do: shrink h as theta predicts */
                double qnewt = fmax(1e-4, fmin(20.0, dyth));
                *hfac = 0.8 * pow(qnewt, -1.0 / (4.0 + NEWTON_MAXITER - 1 - newt));
                return 0;
            }
        }
        dynold = fmax(dyno, DBL_EPSILON);
#pragma omp simd
        for (size_t i = 0; i < 3 * n; i++) W[i] += dW[i];
        for (int a = 0; a < 3; a++) {
#pragma omp simd
            for (size_t i = 0; i < n; i++)
                Z[a * n + i] = rc_T[a][0] * W[i] + rc_T[a][1] * W[n + i] + rc_T[a][2] * W[2 * n + i];
        }
        if (faccon * dyno <= fnewt) {
            st->faccon = faccon;
            return 1;
        }
    }
    return 0;
}

static double predict_factor(radau_state *st, double h, double err)
{
    double mult = 1.0;
    if (st->h_old > 0 && st->err_old > 0 && err > 0)
        mult = h / st->h_old * pow(st->err_old / err, 0.25);
    return err > 0 ? fmin(1.0, mult) * pow(err, -0.25) : MAX_FACTOR;
}

static int radau_step(mp_ode_ws *w, double t, double h_req, double *err_out)
{
    radau_state *st = w->state;
    size_t n = (size_t)st->n;
    const double *rtol = st->rtol_t, *atol = st->atol_t;
    double t_end = t + h_req; /* never step past what the driver asked for */
    double h = h_req;
    int rejected = 0, rc, iters = 0, nonfinite = 0;
    double theta = THET, hfac = 0.5, err = 0.0;
    *err_out = 0.0;
    if (!st->have_J && (rc = radau_jac(w, t)) != MP_OK) return rc;
    for (int attempt = 0;; attempt++) {
        double hmin = 10.0 * fabs(nextafter(t, INFINITY) - t);
        /* SciPy's Radau: a step asked below hmin is raised to it (and cut at t_end
         * below), so that the rest of a span a few ulps long is taken; only a
         * step shrunk there by rejections fails */
        if (attempt == 0 && h < hmin && t_end > t) h = hmin;
        if (h < hmin || attempt > 1000) return nonfinite ? MP_ENONFINITE : MP_ESTEP;
        double tn = (t + h > t_end) ? t_end : t + h;
        h = tn - t;
        /* starting guess: the previous collocation polynomial extrapolated,
         * Z_a = y(t + c_a h) - y(t) with y(t_prev + x h_prev) = y_prev + Q p(x) */
        if (st->q_h > 0) {
            for (int a = 0; a < 3; a++) {
                double x = 1.0 + rc_c[a] * h / st->q_h;
                for (size_t i = 0; i < n; i++) {
                    double at = x * (st->Q[i] + x * (st->Q[n + i] + x * st->Q[2 * n + i]));
                    double at1 = st->Q[i] + st->Q[n + i] + st->Q[2 * n + i];
                    st->Z[a * n + i] = at - at1;
                }
            }
        } else {
            memset(st->Z, 0, 3 * n * sizeof(double));
        }
        for (size_t i = 0; i < n; i++)
            st->scale[i] = mp_ode_weight(atol[i], rtol[i], fabs(w->y[i]));
        int converged = 0;
        for (;;) {
            if (!st->have_LU || st->lu_h != h) {
                rc = radau_lu(w, h);
                if (rc == MP_ESINGULAR) { hfac = 0.5; break; }
                if (rc != MP_OK) return rc;
            }
            nonfinite = 0;
            converged = radau_newton(w, t, h, &iters, &theta, &hfac, &rc, &nonfinite);
            if (nonfinite) break; /* a non-finite stage: shrink, do not refresh J */
            if (rc != MP_OK) return rc;
            if (converged || st->current_J) break;
            /* a stale Jacobian: refresh it and try the same h again */
            if ((rc = radau_jac(w, t)) != MP_OK) return rc;
            st->faccon = 1.0;
        }
        if (!converged) {
            h *= hfac;
            st->faccon = 1.0;
            w->nreject_inner++;
            continue;
        }
        /* error estimate: (M_real I - J)^-1 (f + Z^T E / h) */
        double *ynew = w->ynew, *e = st->err, *ZE = st->tmp2;
        for (size_t i = 0; i < n; i++) {
            ynew[i] = w->y[i] + st->Z[2 * n + i];
            ZE[i] = (rc_e[0] * st->Z[i] + rc_e[1] * st->Z[n + i] + rc_e[2] * st->Z[2 * n + i]) / h;
            e[i] = w->f[i] + ZE[i];
        }
        solve_real(st, e);
        for (size_t i = 0; i < n; i++)
            st->scale[i] = mp_ode_weight(atol[i], rtol[i], mp_ode_absmax(w->y[i], ynew[i]));
        err = err_rms(w, e, st->scale);
        double safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + iters);
        if ((rejected || st->q_h == 0) && err > 1.0) {
            /* Hairer's improved estimate on a first step or after a rejection */
            for (size_t i = 0; i < n; i++) st->tmp[i] = w->y[i] + e[i];
            rc = mp_ode_ws_rhs(w, t, st->tmp, e);
            if (rc == MP_OK) {
                for (size_t i = 0; i < n; i++) e[i] += ZE[i];
                solve_real(st, e);
                err = err_rms(w, e, st->scale);
            } else if (rc == MP_ENONFINITE) {
                err = NAN; /* a trial value: reject */
            } else {
                return rc;
            }
        }
        if (!(err <= 1.0)) {
            nonfinite = !isfinite(err);
            double fac = isfinite(err) ? predict_factor(st, h, err) : MIN_FACTOR;
            h *= fmax(MIN_FACTOR, safety * fac);
            rejected = 1;
            w->nreject_inner++;
            continue;
        }
        /* accepted: RADAU5's rules for the next step's Jacobian and LU pair, a
         * J made at this step's start kept (see the head of the file) */
        int recompute_jac = theta > THET && !st->current_J;
        double factor = fmin(MAX_FACTOR, safety * predict_factor(st, h, err));
        if (rejected) factor = fmin(factor, 1.0);
        if (!recompute_jac && factor >= QUOT1 && factor <= QUOT2) factor = 1.0;
        if ((rc = mp_ode_ws_rhs(w, t + h, ynew, w->fnew)) != MP_OK) return rc;
        w->fnew_valid = 1;
        /* dense output polynomial Q = Z^T P */
        for (int a = 0; a < 3; a++)
            for (size_t i = 0; i < n; i++)
                st->Q[a * n + i] = st->Z[i] * rc_P[0][a] + st->Z[n + i] * rc_P[1][a] +
                                   st->Z[2 * n + i] * rc_P[2][a];
        st->q_h = h;
        st->h_old = h;
        st->err_old = err;
        w->h_taken = h;
        w->h_next = h * factor;
        if (recompute_jac) {
            /* at the new point, once the driver has moved there: mark stale */
            st->have_J = 0;
        } else {
            st->current_J = 0;
        }
        return MP_OK;
    }
}

/* Dense output: y0 + Q1 x + Q2 x^2 + Q3 x^3 in the driver's nested form
 * c1 + s (c2 + (1-s)(c3 + s c4)). */
static int radau_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    (void)t;
    (void)h;
    radau_state *st = w->state;
    size_t n = w->n;
    if (!need_dense) return MP_OK;
    double *c = w->coef;
    for (size_t i = 0; i < n; i++) {
        double q1 = st->Q[i], q2 = st->Q[n + i], q3 = st->Q[2 * n + i];
        c[i] = w->y[i];
        c[n + i] = q1 + q2 + q3;
        c[2 * n + i] = -q3 - q2;
        c[3 * n + i] = -q3;
    }
    return MP_OK;
}

const mp_ode_method mp_ode_radau = {
    .name = "radau", .order = 5, .adaptive = 1, .implicit = 1, .needs_jacobian = 1,
    .dense_order = 3, .ncoef = 4, .nscratch = 0, .self_controlled = 1,
    .alloc = radau_alloc, .free = radau_free, .restart = radau_restart,
    .step = radau_step, .finish = radau_finish,
};
