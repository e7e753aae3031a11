/* GSL's odeiv2 steppers as rows of the method table.  Each takes its own
 * accepted steps through gsl_odeiv2_evolve_apply with a scaled control
 * (D_i = atol_i + rtol |y_i|); the driver loop does everything else: budget,
 * interrupts, t_eval, events.
 *
 * GSL has no dense output.  The one-step rows of order >= 4 build a quintic Hermite
 * interpolant through y and f at t, t + h/2 and t + h: y(t + h/2) comes from
 * one extra step of the same stepper (a second instance, so the main one's
 * state is untouched), only on steps that need an interpolant; while the solve
 * has output between steps, steps are kept to the length at which that
 * interpolant meets the tolerance.  The low-order rows (rk2, rk1imp, rk2imp)
 * and the multistep rows (msadams, msbdf) take short steps and use the cubic
 * Hermite interpolant through y and f at both ends. */
#include "ode/ode.h"
#include "ode/control.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

typedef struct {
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *d;
    mp_ode_ws *w;
    int status;        /* the last failure of a callback in this step */
    int f_stale;       /* w->f is not f at the current point (a step without dense output) */
    gsl_odeiv2_step *half; /* one-step rows: a second stepper for the midpoint */
    double h_cap;      /* longest step whose interpolant meets the tolerance (0: none yet) */
    double *ytmp, *ftmp, *f0, *ym, *fm, *yerr;
} gsl_state;

/* Contract: a failure of the right-hand side stops GSL at once (GSL_EBADFUNC),
 * except a non-finite value, which GSL treats as a failed trial step: it
 * halves the step and tries again (st->status remembers it in case GSL gives
 * up). */
static int gsl_status(gsl_state *st, int rc)
{
    if (rc == MP_OK) return GSL_SUCCESS;
    st->status = rc;
    return rc == MP_ENONFINITE ? GSL_FAILURE : GSL_EBADFUNC;
}

/* GSL forms its stage times as t + c h with its own rounding: a time an ulp
 * past either end of the interval is taken as that end. */
static double gsl_clamp_t(const mp_ode_ws *w, double t)
{
    return t > w->t_end ? w->t_end : t < w->t_start ? w->t_start : t;
}

static int gsl_fn(double t, const double y[], double dydt[], void *params)
{
    gsl_state *st = params;
    return gsl_status(st, mp_ode_ws_rhs(st->w, gsl_clamp_t(st->w, t), y, dydt));
}

static int gsl_jacfn(double t, const double y[], double *dfdy, double dfdt[], void *params)
{
    gsl_state *st = params;
    mp_ode_ws *w = st->w;
    size_t n = w->n;
    t = gsl_clamp_t(w, t);
    int rc = mp_ode_ws_rhs(w, t, y, st->f0);
    if (rc == MP_OK) rc = mp_ode_ws_jac(w, t, y, st->f0, dfdy, st->ytmp, st->ftmp);
    if (rc == MP_OK) {
        /* df/dt by a one-sided difference that stays inside [t_start, t_end]:
         * forwards, or backwards when t + dt would pass the end */
        double dt = sqrt(2.2e-16) * fmax(fabs(t), 1.0);
        if (t + dt > w->t_end) dt = -dt;
        double t2 = t + dt;
        if (t2 < w->t_start) t2 = w->t_start;
        dt = t2 - t;
        if (dt == 0.0) {
            for (size_t i = 0; i < n; i++) dfdt[i] = 0.0; /* an interval below round-off */
        } else {
            rc = mp_ode_ws_rhs(w, t2, y, st->ftmp);
            if (rc == MP_OK)
                for (size_t i = 0; i < n; i++) dfdt[i] = (st->ftmp[i] - st->f0[i]) / dt;
        }
    }
    return gsl_status(st, rc);
}

static int gsl_alloc(mp_ode_ws *w)
{
    size_t n = w->n;
    const gsl_odeiv2_step_type *const *type = w->m->extra;
    /* GSL's control takes one rtol: a per-component one is outside its domain */
    for (size_t i = 0; i < n; i++)
        if (w->o->rtolv[i] != w->o->rtol) return MP_EDOM;
    gsl_state *st = calloc(1, sizeof *st);
    if (!st) return MP_ENOMEM;
    w->state = st;
    st->w = w;
    st->ytmp = malloc(6 * n * sizeof(double));
    if (!st->ytmp) return MP_ENOMEM;
    st->ftmp = st->ytmp + n;
    st->f0 = st->ftmp + n;
    st->ym = st->f0 + n;
    st->fm = st->ym + n;
    st->yerr = st->fm + n;
    st->sys.function = gsl_fn;
    st->sys.jacobian = gsl_jacfn;
    st->sys.dimension = n;
    st->sys.params = st;
    /* D_i = 1 * atol_i + rtol * |y_i|; h is set on every step anyway */
    st->d = gsl_odeiv2_driver_alloc_scaled_new(&st->sys, *type, 1e-6, 1.0, w->o->rtol, 1.0, 0.0,
                                               w->o->atol);
    if (!st->d) return MP_ENOMEM;
    if (w->m->ncoef == 6) {
        st->half = gsl_odeiv2_step_alloc(*type, n);
        if (!st->half) return MP_ENOMEM;
        gsl_odeiv2_step_set_driver(st->half, st->d);
    }
    return MP_OK;
}

static void gsl_free(mp_ode_ws *w)
{
    gsl_state *st = w->state;
    if (!st) return;
    if (st->d) gsl_odeiv2_driver_free(st->d);
    if (st->half) gsl_odeiv2_step_free(st->half);
    free(st->ytmp);
    free(st);
    w->state = NULL;
}

static int gsl_step(mp_ode_ws *w, double t, double h, double *err)
{
    gsl_state *st = w->state;
    /* The end of the interval, not t + h, so that GSL treats the step as an
     * ordinary one and adapts its size (it never grows a "final" step).  The
     * step tried is h, which the driver has clamped to max_step. */
    double tt = t, hh = h, t1 = w->t_end;
    size_t failed = st->d->e->failed_steps;
    memcpy(w->ynew, w->y, w->n * sizeof(double));
    st->status = MP_OK;
    int g = gsl_odeiv2_evolve_apply(st->d->e, st->d->c, st->d->s, &st->sys, &tt, t1, &hh, w->ynew);
    w->nreject_inner += (long)(st->d->e->failed_steps - failed);
    *err = 0.0;
    if (g != GSL_SUCCESS && st->status != MP_OK) return st->status;
    /* step size underflow: GSL_FAILURE from evolve, GSL_EUNDRFLW from bsimp
     * when t + h == t */
    if (g == GSL_FAILURE || g == GSL_EUNDRFLW) return MP_ESTEP;
    if (g != GSL_SUCCESS) return MP_EGSL;
    w->h_taken = tt == t1 ? h : tt - t; /* the driver sets t = t_end on a final step */
    w->h_next = hh;
    if (st->h_cap > 0 && hh > st->h_cap) w->h_next = st->h_cap;
    if (!(w->h_taken > 0)) return MP_ESTEP;
    if (st->d->s->type->gives_exact_dydt_out) { /* f at the new point, free */
        memcpy(w->fnew, st->d->e->dydt_out, w->n * sizeof(double));
        w->fnew_valid = 1;
    }
    return MP_OK;
}

/* Contract: forget every history GSL keeps between steps, as at the start of a
 * solve; the driver calls it after an action has replaced the state (ode.h's
 * restart).  Two histories would otherwise carry the state before the jump
 * into the first step after it:
 *   - gsl_odeiv2_evolve_apply takes f at a step's start from the previous
 *     step's end (dydt_out) once it has taken a step (its count > 0): the
 *     first stage of an explicit row would use f before the action;
 *   - msadams and msbdf continue from their Nordsieck history, not from the
 *     y they are given.
 * gsl_odeiv2_driver_reset resets the evolve object (count 0: f is evaluated
 * at the new state) and the stepper (msadams/msbdf start again at order 1).
 * The driver has made w->f = f(t, y) current; the interpolant's step cap is
 * measured afresh from the new state. */
static void gsl_restart(mp_ode_ws *w)
{
    gsl_state *st = w->state;
    if (!st || !st->d) return;
    gsl_odeiv2_driver_reset(st->d);
    st->f_stale = 0;
    st->h_cap = 0.0;
}

/* Contract: the quintic Hermite interpolant of [t, t + h] in the driver's
 * nested form from y, f at both ends (w) and at the midpoint (ym, fm): the
 * cubic Hermite part plus s^2 (1-s)^2 (c5 + s c6), whose value and slope at
 * s = 1/2 take up the cubic's misfit there.  Returns an estimate of the
 * quintic's error, scaled by the tolerances (RMS): successive Hermite
 * corrections shrink alike, so it is e3^2 / e1 from the misfits at s = 1/2
 * of the cubic (e3) and of the chord (e1); pessimistic by ~20 for a sine. */
static double quintic_hermite(mp_ode_ws *w, double h, const double *ym, const double *fm)
{
    size_t n = w->n;
    double *c = w->coef, est = 0.0;
    mp_ode_dense_hermite(n, h, w->y, w->ynew, w->f, w->fnew, c);
    for (size_t i = 0; i < n; i++) {
        double dy = w->ynew[i] - w->y[i], chord = 0.5 * (w->y[i] + w->ynew[i]);
        double p_m = chord + 0.125 * h * (w->f[i] - w->fnew[i]); /* the cubic at s = 1/2 */
        double e1 = fabs(ym[i] - chord), e3 = fabs(ym[i] - p_m);
        double sc = mp_ode_weight(w->o->atol[i], w->o->rtolv[i], fabs(ym[i]));
        double q = e1 > 0.0 ? fmin(e3, e3 * e3 / e1) / sc : 0.0;
        est += q * q;
        double dp_m = 1.5 * dy - 0.25 * h * (w->f[i] + w->fnew[i]); /* d/ds at s = 1/2 */
        double c6 = 16.0 * (h * fm[i] - dp_m);
        c[4 * n + i] = 16.0 * (ym[i] - p_m) - 0.5 * c6;
        c[5 * n + i] = c6;
    }
    return sqrt(est / (double)n);
}

static int gsl_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    gsl_state *st = w->state;
    const mp_ode_options *o = w->o;
    /* until the first interpolant has set h_cap, every step of a solve with
     * output between steps builds one (GSL would grow the step unchecked) */
    if (st->half && st->h_cap == 0.0 && (o->n_eval || o->dense || o->n_events)) need_dense = 1;
    if (!need_dense) { /* without GSL's f at the new point, w->f goes stale */
        if (!w->fnew_valid) st->f_stale = 1;
        return MP_OK;
    }
    int rc;
    if (st->f_stale && (rc = mp_ode_ws_rhs(w, t, w->y, w->f)) != MP_OK) return rc;
    st->f_stale = 0;
    if ((rc = mp_ode_finish_fnew_hermite(w, t, h, !st->half)) != MP_OK || !st->half) return rc;
    /* the midpoint: half a step of the same method from (t, y) */
    memcpy(st->ym, w->y, w->n * sizeof(double));
    gsl_odeiv2_step_reset(st->half);
    st->status = MP_OK;
    const double *fin = st->half->type->can_use_dydt_in ? w->f : NULL;
    int g = gsl_odeiv2_step_apply(st->half, t, 0.5 * h, st->ym, st->yerr, fin, st->fm, &st->sys);
    if (g != GSL_SUCCESS && st->status != MP_OK) return st->status;
    if (g == GSL_EUNDRFLW || g == GSL_FAILURE) {
        /* a half step too short for the stepper's own substeps (bsimp's, near
         * an accumulation of impacts): the cubic Hermite, for this step */
        mp_ode_dense_hermite(w->n, h, w->y, w->ynew, w->f, w->fnew, w->coef);
        memset(w->coef + 4 * w->n, 0, 2 * w->n * sizeof(double));
        return MP_OK;
    }
    if (g != GSL_SUCCESS) return MP_EGSL;
    if (!st->half->type->gives_exact_dydt_out &&
        (rc = mp_ode_ws_rhs(w, t + 0.5 * h, st->ym, st->fm)) != MP_OK)
        return rc;
    /* the error of the interpolant ~ h^6: steps after this one are kept to the
     * length at which it meets the tolerance */
    double est = quintic_hermite(w, h, st->ym, st->fm);
    st->h_cap = est > 0.0 ? h * fmax(0.2, 0.9 * pow(est, -1.0 / 6.0)) : 0.0;
    return MP_OK;
}

/* nc: 6 for the one-step rows of order >= 4 (quintic interpolant), 4 for the
 * low-order and multistep rows, whose short steps keep the cubic within
 * their own error (a low-order midpoint would not help a quintic) */
#define MP_GSL_ROW(nm, T, ord, impl, jac, nc)                                                  \
    const mp_ode_method mp_ode_gsl_##T = {                                                    \
        .name = nm, .order = ord, .adaptive = 1, .implicit = impl, .needs_jacobian = jac,      \
        .dense_order = nc - 1, .ncoef = nc, .nscratch = 0, .self_controlled = 1,              \
        .scalar_rtol = 1,                                                                      \
        .extra = &gsl_odeiv2_step_##T, .alloc = gsl_alloc, .free = gsl_free,                  \
        .step = gsl_step, .finish = gsl_finish, .restart = gsl_restart,                       \
    }

MP_GSL_ROW("gsl:rk2", rk2, 2, 0, 0, 4);
MP_GSL_ROW("gsl:rk4", rk4, 4, 0, 0, 6);
MP_GSL_ROW("gsl:rkf45", rkf45, 5, 0, 0, 6);
MP_GSL_ROW("gsl:rkck", rkck, 5, 0, 0, 6);
MP_GSL_ROW("gsl:rk8pd", rk8pd, 8, 0, 0, 6);
MP_GSL_ROW("gsl:msadams", msadams, 5, 0, 0, 4);
MP_GSL_ROW("gsl:rk1imp", rk1imp, 1, 1, 1, 4);
MP_GSL_ROW("gsl:rk2imp", rk2imp, 2, 1, 1, 4);
MP_GSL_ROW("gsl:rk4imp", rk4imp, 4, 1, 1, 6);
MP_GSL_ROW("gsl:bsimp", bsimp, 6, 1, 1, 6);
MP_GSL_ROW("gsl:msbdf", msbdf, 5, 1, 1, 4);
