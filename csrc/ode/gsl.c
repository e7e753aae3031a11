/* GSL's odeiv2 steppers as rows of the method table.  Each takes its own
 * accepted steps through gsl_odeiv2_evolve_apply with a scaled control
 * (D_i = atol_i + rtol |y_i|); the driver loop does everything else: budget,
 * interrupts, t_eval from a cubic Hermite interpolant, events. */
#include "ode/ode.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

typedef struct {
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *d;
    mp_ode_ws *w;
    int status;        /* the first failure of a callback */
    double *ytmp, *ftmp, *f0;
} gsl_state;

static int gsl_fn(double t, const double y[], double dydt[], void *params)
{
    gsl_state *st = params;
    int rc = mp_ode_ws_rhs(st->w, t, y, dydt);
    if (rc != MP_OK) {
        st->status = rc;
        return GSL_EBADFUNC;
    }
    return GSL_SUCCESS;
}

static int gsl_jacfn(double t, const double y[], double *dfdy, double dfdt[], void *params)
{
    gsl_state *st = params;
    mp_ode_ws *w = st->w;
    size_t n = w->n;
    int rc = mp_ode_ws_rhs(w, t, y, st->f0);
    if (rc == MP_OK) rc = mp_ode_ws_jac(w, t, y, st->f0, dfdy, st->ytmp, st->ftmp);
    if (rc == MP_OK) { /* df/dt by a forward difference */
        double dt = sqrt(2.2e-16) * fmax(fabs(t), 1.0);
        rc = mp_ode_ws_rhs(w, t + dt, y, st->ftmp);
        if (rc == MP_OK)
            for (size_t i = 0; i < n; i++) dfdt[i] = (st->ftmp[i] - st->f0[i]) / dt;
    }
    if (rc != MP_OK) {
        st->status = rc;
        return GSL_EBADFUNC;
    }
    return GSL_SUCCESS;
}

static int gsl_alloc(mp_ode_ws *w)
{
    size_t n = w->n;
    const gsl_odeiv2_step_type *const *type = w->m->extra;
    gsl_state *st = calloc(1, sizeof *st);
    if (!st) return MP_ENOMEM;
    w->state = st;
    st->w = w;
    st->ytmp = malloc(3 * n * sizeof(double));
    if (!st->ytmp) return MP_ENOMEM;
    st->ftmp = st->ytmp + n;
    st->f0 = st->ftmp + n;
    st->sys.function = gsl_fn;
    st->sys.jacobian = gsl_jacfn;
    st->sys.dimension = n;
    st->sys.params = st;
    /* D_i = 1 * atol_i + rtol * |y_i|; h is set on every step anyway */
    st->d = gsl_odeiv2_driver_alloc_scaled_new(&st->sys, *type, 1e-6, 1.0, w->o->rtol, 1.0, 0.0,
                                               w->o->atol);
    if (!st->d) return MP_ENOMEM;
    return MP_OK;
}

static void gsl_free(mp_ode_ws *w)
{
    gsl_state *st = w->state;
    if (!st) return;
    if (st->d) gsl_odeiv2_driver_free(st->d);
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
    if (g == GSL_EBADFUNC && st->status != MP_OK) return st->status;
    if (g == GSL_FAILURE) return MP_ESTEP; /* step size underflow */
    if (g != GSL_SUCCESS) return MP_EGSL;
    w->h_taken = tt == t1 ? h : tt - t; /* the driver sets t = t_end on a final step */
    w->h_next = hh;
    if (!(w->h_taken > 0)) return MP_ESTEP;
    return MP_OK;
}

static int gsl_finish(mp_ode_ws *w, double t, double h, int need_dense)
{
    if (!need_dense) return MP_OK; /* GSL keeps its own derivatives */
    int rc = mp_ode_ws_rhs(w, t + h, w->ynew, w->fnew);
    if (rc != MP_OK) return rc;
    w->fnew_valid = 1;
    mp_ode_dense_hermite(w->n, h, w->y, w->ynew, w->f, w->fnew, w->coef);
    return MP_OK;
}

#define MP_GSL_ROW(nm, T, ord, impl, jac)                                                      \
    const mp_ode_method mp_ode_gsl_##T = {                                                    \
        .name = nm, .order = ord, .adaptive = 1, .implicit = impl, .needs_jacobian = jac,      \
        .dense_order = 3, .ncoef = 4, .nscratch = 0, .self_controlled = 1,                    \
        .extra = &gsl_odeiv2_step_##T, .alloc = gsl_alloc, .free = gsl_free,                  \
        .step = gsl_step, .finish = gsl_finish,                                               \
    }

MP_GSL_ROW("gsl:rk2", rk2, 2, 0, 0);
MP_GSL_ROW("gsl:rk4", rk4, 4, 0, 0);
MP_GSL_ROW("gsl:rkf45", rkf45, 5, 0, 0);
MP_GSL_ROW("gsl:rkck", rkck, 5, 0, 0);
MP_GSL_ROW("gsl:rk8pd", rk8pd, 8, 0, 0);
MP_GSL_ROW("gsl:msadams", msadams, 5, 0, 0);
MP_GSL_ROW("gsl:rk1imp", rk1imp, 1, 1, 1);
MP_GSL_ROW("gsl:rk2imp", rk2imp, 2, 1, 1);
MP_GSL_ROW("gsl:rk4imp", rk4imp, 4, 1, 1);
MP_GSL_ROW("gsl:bsimp", bsimp, 6, 1, 1);
MP_GSL_ROW("gsl:msbdf", msbdf, 5, 1, 1);
