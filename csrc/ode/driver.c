/* The one driver loop of every integration method: step-size control,
 * budget, interrupts, output at t_eval from dense output, events, storage. */
#include "ode/ode.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MP_ODE_INTERRUPT_EVERY 256   /* steps between interrupt checks */
#define MP_ODE_EVENT_SUBDIV 4        /* sub-intervals searched for crossings per step */

/* ---- small helpers ------------------------------------------------------ */

/* Contract: dydt = f(t, y), counted in nfev; MP_ENONFINITE (with the first
 * offending component in w->bad_index) when a value is NaN or inf.  The one
 * pass over dydt is the only check of a stage: the driver decides whether a
 * non-finite value rejects a trial step or ends the solve. */
int mp_ode_ws_rhs(mp_ode_ws *w, double t, const double *y, double *dydt)
{
    int rc = w->p->rhs(t, y, dydt, w->p->data);
    w->nfev++;
    if (rc != MP_OK) return rc;
    for (size_t i = 0; i < w->n; i++)
        if (!isfinite(dydt[i])) {
            w->bad_what = MP_ODE_BAD_RHS;
            w->bad_index = i;
            return MP_ENONFINITE;
        }
    return MP_OK;
}

int mp_ode_ws_jac(mp_ode_ws *w, double t, const double *y, const double *f0, double *jac,
                  double *scratch_y, double *scratch_f)
{
    size_t n = w->n;
    if (!w->p->jac_const) w->njev++;
    if (w->p->jac) {
        int rc = w->p->jac(t, y, jac, w->p->data);
        if (rc != MP_OK) return rc;
        for (size_t i = 0; i < n * n; i++)
            if (!isfinite(jac[i])) {
                w->bad_what = MP_ODE_BAD_JAC;
                w->bad_index = i;
                return MP_ENONFINITE;
            }
        return MP_OK;
    }
    memcpy(scratch_y, y, n * sizeof(double));
    for (size_t j = 0; j < n; j++) {
        double scale = fmax(fabs(y[j]), w->o->atol[j] / w->o->rtol);
        if (!(scale > 0)) scale = 1.0;
        double yj = y[j], d = sqrt(DBL_EPSILON) * scale;
        scratch_y[j] = yj + d;
        d = scratch_y[j] - yj; /* the increment actually representable */
        int rc = mp_ode_ws_rhs(w, t, scratch_y, scratch_f);
        if (rc != MP_OK) return rc;
        for (size_t i = 0; i < n; i++) jac[i * n + j] = (scratch_f[i] - f0[i]) / d;
        scratch_y[j] = yj;
    }
    return MP_OK;
}

double mp_ode_err_norm(const mp_ode_ws *w, const double *e, const double *y0, const double *y1)
{
    double s = 0.0;
    for (size_t i = 0; i < w->n; i++) {
        double sc = w->o->atol[i] + w->o->rtol * fmax(fabs(y0[i]), fabs(y1[i]));
        double q = e[i] / sc;
        s += q * q;
    }
    return sqrt(s / (double)w->n);
}

void mp_ode_dense_eval(const double *coef, size_t ncoef, size_t n, double s, double *out)
{
    double s1 = 1.0 - s;
    for (size_t i = 0; i < n; i++) {
        double acc = coef[(ncoef - 1) * n + i];
        for (size_t j = ncoef - 1; j-- > 0;) /* j = ncoef-2 .. 0; factor after c_{j+1} */
            acc = coef[j * n + i] + ((j % 2 == 0) ? s : s1) * acc;
        out[i] = acc;
    }
}

void mp_ode_dense_hermite(size_t n, double h, const double *y0, const double *y1,
                          const double *f0, const double *f1, double *coef)
{
    for (size_t i = 0; i < n; i++) {
        double dy = y1[i] - y0[i];
        double c3 = h * f0[i] - dy;
        coef[i] = y0[i];
        coef[n + i] = dy;
        coef[2 * n + i] = c3;
        coef[3 * n + i] = dy - h * f1[i] - c3;
    }
}

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return MP_OK;
    size_t nc = *cap ? *cap : 16;
    while (nc < need) nc *= 2;
    void *q = realloc(*p, nc * elem);
    if (!q) return MP_ENOMEM;
    *p = q;
    *cap = nc;
    return MP_OK;
}

static int push_sample(mp_ode_result *r, double t, const double *y)
{
    size_t cap_t = r->mcap, cap_y = r->mcap;
    if (grow((void **)&r->t, &cap_t, r->m + 1, sizeof(double)) != MP_OK) return MP_ENOMEM;
    if (grow((void **)&r->y, &cap_y, r->m + 1, r->n * sizeof(double)) != MP_OK) return MP_ENOMEM;
    r->mcap = cap_t < cap_y ? cap_t : cap_y;
    r->t[r->m] = t;
    memcpy(r->y + r->m * r->n, y, r->n * sizeof(double));
    r->m++;
    return MP_OK;
}

static int push_segment(mp_ode_result *r, double t, double h, const double *coef)
{
    size_t c1 = r->segcap, c2 = r->segcap, c3 = r->segcap, blk = r->ncoef * r->n;
    if (grow((void **)&r->seg_t, &c1, r->nseg + 1, sizeof(double)) != MP_OK ||
        grow((void **)&r->seg_h, &c2, r->nseg + 1, sizeof(double)) != MP_OK ||
        grow((void **)&r->seg_c, &c3, r->nseg + 1, blk * sizeof(double)) != MP_OK)
        return MP_ENOMEM;
    r->segcap = c1 < c2 ? (c1 < c3 ? c1 : c3) : (c2 < c3 ? c2 : c3);
    r->seg_t[r->nseg] = t;
    r->seg_h[r->nseg] = h;
    memcpy(r->seg_c + r->nseg * blk, coef, blk * sizeof(double));
    r->nseg++;
    return MP_OK;
}

static int push_event(mp_ode_result *r, size_t k, double t, const double *y)
{
    size_t c1 = r->ev_cap[k], c2 = r->ev_cap[k];
    if (grow((void **)&r->ev_t[k], &c1, r->ev_count[k] + 1, sizeof(double)) != MP_OK ||
        grow((void **)&r->ev_y[k], &c2, r->ev_count[k] + 1, r->n * sizeof(double)) != MP_OK)
        return MP_ENOMEM;
    r->ev_cap[k] = c1 < c2 ? c1 : c2;
    r->ev_t[k][r->ev_count[k]] = t;
    memcpy(r->ev_y[k] + r->ev_count[k] * r->n, y, r->n * sizeof(double));
    r->ev_count[k]++;
    return MP_OK;
}

void mp_ode_result_free(mp_ode_result *r)
{
    free(r->t);
    free(r->y);
    free(r->seg_t);
    free(r->seg_h);
    free(r->seg_c);
    if (r->ev_t)
        for (size_t k = 0; k < r->n_events; k++) free(r->ev_t[k]);
    if (r->ev_y)
        for (size_t k = 0; k < r->n_events; k++) free(r->ev_y[k]);
    free(r->ev_t);
    free(r->ev_y);
    free(r->ev_count);
    free(r->ev_cap);
    memset(r, 0, sizeof *r);
}

int mp_ode_result_dense_eval(size_t n, size_t ncoef, size_t nseg, const double *seg_t,
                             const double *seg_h, const double *seg_c, const double *tq,
                             size_t nq, double *out)
{
    if (nseg == 0) return MP_EDOM;
    for (size_t q = 0; q < nq; q++) {
        double t = tq[q];
        if (!isfinite(t)) return MP_EDOM;
        /* binary search for the last segment starting at or before t */
        size_t lo = 0, hi = nseg;
        while (hi - lo > 1) {
            size_t mid = (lo + hi) / 2;
            if (seg_t[mid] <= t) lo = mid; else hi = mid;
        }
        double s = (t - seg_t[lo]) / seg_h[lo];
        mp_ode_dense_eval(seg_c + lo * ncoef * n, ncoef, n, s, out + q * n);
    }
    return MP_OK;
}

/* ---- event location ----------------------------------------------------- */

typedef struct {
    mp_ode_ws *w;
    const mp_ode_options *o;
    double t, h;
    double *ytmp, *gtmp;
} ev_ctx;

static int ev_at(ev_ctx *c, double s, size_t k, double *gk)
{
    mp_ode_dense_eval(c->w->coef, c->w->ncoef, c->w->n, s, c->ytmp);
    int rc = c->o->events(c->t + s * c->h, c->ytmp, c->gtmp, c->o->events_data);
    if (rc != MP_OK) return rc;
    *gk = c->gtmp[k];
    if (isfinite(*gk)) return MP_OK;
    c->w->bad_what = MP_ODE_BAD_EVENT;
    c->w->bad_index = k;
    return MP_ENONFINITE;
}

/* Root of g_k on [a, b] in step-fraction s, g(a) and g(b) of opposite signs
 * (or g(b) == 0): the Illinois variant of regula falsi, to round-off in t. */
static int ev_root(ev_ctx *c, size_t k, double a, double ga, double b, double gb, double *root)
{
    double tol = 4.0 * DBL_EPSILON * (fabs(c->t) + fabs(c->h)) / fabs(c->h);
    int side = 0;
    if (gb == 0.0) { *root = b; return MP_OK; }
    for (int it = 0; it < 200 && (b - a) > tol; it++) {
        double s = (a * gb - b * ga) / (gb - ga);
        if (!(s > a && s < b)) s = 0.5 * (a + b);
        double gs;
        int rc = ev_at(c, s, k, &gs);
        if (rc != MP_OK) return rc;
        if (gs == 0.0) { a = b = s; break; }
        if ((gs > 0) == (gb > 0)) {
            b = s; gb = gs;
            if (side == -1) ga *= 0.5;
            side = -1;
        } else {
            a = s; ga = gs;
            if (side == 1) gb *= 0.5;
            side = 1;
        }
    }
    *root = b;  /* the side past the crossing: sign(g) has changed there */
    return MP_OK;
}

static int crosses(double g0, double g1, int dir)
{
    int up = g0 < 0 && g1 >= 0, down = g0 > 0 && g1 <= 0;
    return dir > 0 ? up : dir < 0 ? down : (up || down);
}

typedef struct { double s; size_t k; } ev_hit;

static int ev_cmp(const void *a, const void *b)
{
    double x = ((const ev_hit *)a)->s, y = ((const ev_hit *)b)->s;
    return x < y ? -1 : x > y;
}

/* Find every crossing in the accepted step [t, t + h]; g_old holds g at t and
 * is updated to g at the step end.  Sets *s_stop < 1 when a terminal event
 * fires (the step is truncated there). */
static int ev_step(mp_ode_ws *w, mp_ode_result *r, const mp_ode_options *o, double t, double h,
                   double *g_old, double *g_sub, double *ytmp, double *gtmp, ev_hit *hits,
                   double *s_stop)
{
    size_t ne = o->n_events, nh = 0;
    ev_ctx c = {w, o, t, h, ytmp, gtmp};
    *s_stop = 2.0;
    for (int j = 1; j <= MP_ODE_EVENT_SUBDIV; j++) {
        double s0 = (double)(j - 1) / MP_ODE_EVENT_SUBDIV, s1 = (double)j / MP_ODE_EVENT_SUBDIV;
        int rc;
        if (j == MP_ODE_EVENT_SUBDIV) rc = o->events(t + h, w->ynew, g_sub, o->events_data);
        else {
            mp_ode_dense_eval(w->coef, w->ncoef, w->n, s1, ytmp);
            rc = o->events(t + s1 * h, ytmp, g_sub, o->events_data);
        }
        if (rc != MP_OK) return rc;
        for (size_t k = 0; k < ne; k++) {
            if (!isfinite(g_sub[k])) {
                w->bad_what = MP_ODE_BAD_EVENT;
                w->bad_index = k;
                return MP_ENONFINITE;
            }
            if (crosses(g_old[k], g_sub[k], o->direction[k])) {
                double root;
                rc = ev_root(&c, k, s0, g_old[k], s1, g_sub[k], &root);
                if (rc != MP_OK) return rc;
                hits[nh].s = root;
                hits[nh].k = k;
                nh++;
            }
            g_old[k] = g_sub[k];
        }
    }
    qsort(hits, nh, sizeof *hits, ev_cmp);
    for (size_t i = 0; i < nh; i++) {
        size_t k = hits[i].k;
        double s = hits[i].s;
        mp_ode_dense_eval(w->coef, w->ncoef, w->n, s, ytmp);
        int rc = push_event(r, k, t + s * h, ytmp);
        if (rc != MP_OK) return rc;
        if (o->terminal[k] > 0 && r->ev_count[k] >= (size_t)o->terminal[k]) {
            *s_stop = s;
            break;
        }
    }
    return MP_OK;
}

/* ---- the first step: Hairer's hinit ------------------------------------- */

static int first_step(mp_ode_ws *w, double t0, double tf, double hmax, double *h_out)
{
    size_t n = w->n;
    const mp_ode_options *o = w->o;
    double dnf = 0, dny = 0;
    for (size_t i = 0; i < n; i++) {
        double sk = o->atol[i] + o->rtol * fabs(w->y[i]);
        dnf += (w->f[i] / sk) * (w->f[i] / sk);
        dny += (w->y[i] / sk) * (w->y[i] / sk);
    }
    dnf /= (double)n;
    dny /= (double)n;
    double h = (dnf <= 1e-10 || dny <= 1e-10) ? 1e-6 : sqrt(dny / dnf) * 0.01;
    h = fmin(h, fmin(hmax, tf - t0));
    double *y1 = w->ynew, *f1 = w->fnew;
    int rc;
    for (int tries = 0;; tries++) { /* an explicit Euler trial that overflows: shorter */
        while (t0 + h > tf) h = nextafter(h, 0.0);
        for (size_t i = 0; i < n; i++) y1[i] = w->y[i] + h * w->f[i];
        rc = mp_ode_ws_rhs(w, t0 + h, y1, f1);
        if (rc != MP_ENONFINITE || tries == 20) break;
        h *= 0.1;
    }
    if (rc != MP_OK) return rc;
    double der2 = 0;
    for (size_t i = 0; i < n; i++) {
        double sk = o->atol[i] + o->rtol * fabs(w->y[i]);
        double d = (f1[i] - w->f[i]) / sk;
        der2 += d * d;
    }
    der2 = sqrt(der2 / (double)n) / h;
    double der12 = fmax(fabs(der2), sqrt(dnf));
    double h1 = der12 <= 1e-15 ? fmax(1e-6, h * 1e-3)
                               : pow(0.01 / der12, 1.0 / (double)w->m->order);
    *h_out = fmin(fmin(100.0 * h, h1), fmin(hmax, tf - t0));
    return MP_OK;
}

/* ---- the driver --------------------------------------------------------- */

/* A switching row counts an explicit step as stiff from this fraction of the
 * explicit method's stability boundary h |lambda| on. */
#ifndef MP_ODE_SWITCH_FRAC
#define MP_ODE_SWITCH_FRAC 0.8
#endif

/* Contract: the forward solve (t0 < tf) of mp_ode_solve. */
static int solve_forward(const mp_ode_method *m, const mp_ode_problem *p, double t0, double tf,
                         const double *y0, const mp_ode_options *o, mp_ode_result *r)
{
    size_t n = p->n, ne = o->n_events;
    int need_dense = o->n_eval > 0 || o->dense || ne > 0;
    int rc = MP_OK;
    mp_ode_ws w;
    double *buf = NULL, *g_old = NULL, *g_sub = NULL, *ytmp = NULL, *gtmp = NULL;
    ev_hit *hits = NULL;

    memset(r, 0, sizeof *r);
    memset(&w, 0, sizeof w);
    r->n = n;
    r->ncoef = m->ncoef;
    r->n_events = ne;
    r->t_fail = t0;
    if (n == 0 || !(tf > t0) || !isfinite(t0) || !isfinite(tf) || !(o->rtol > 0) ||
        !(o->max_steps > 0) || (!m->adaptive && !(o->h > 0)) || !(o->max_step > 0))
        return r->status = MP_EDOM;
    /* a fixed step below the spacing of floats at t would never advance t */
    double tmax = fmax(fabs(t0), fabs(tf));
    if (!m->adaptive && !(tmax + o->h > tmax)) return r->status = MP_EDOM;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(y0[i]) || !(o->atol[i] >= 0)) return r->status = MP_EDOM;

    if (ne) {
        r->ev_count = calloc(ne, sizeof(size_t));
        r->ev_cap = calloc(ne, sizeof(size_t));
        r->ev_t = calloc(ne, sizeof(double *));
        r->ev_y = calloc(ne, sizeof(double *));
        g_old = malloc((2 * ne + ne) * sizeof(double));
        hits = malloc(ne * MP_ODE_EVENT_SUBDIV * sizeof(ev_hit));
        if (!r->ev_count || !r->ev_cap || !r->ev_t || !r->ev_y || !g_old || !hits) {
            rc = MP_ENOMEM;
            goto done;
        }
        g_sub = g_old + ne;
        gtmp = g_sub + ne;
    }
    /* a switching row runs its two methods in turn; everything else is one method */
    const mp_ode_method *cur = m->nonstiff ? m->nonstiff : m;
    size_t nvec = 5 + m->nscratch + m->ncoef;
    buf = malloc(nvec * n * sizeof(double));
    if (!buf) { rc = MP_ENOMEM; goto done; }
    w.p = p; w.m = cur; w.o = o; w.n = n; w.ncoef = m->ncoef; w.t_start = t0; w.t_end = tf;
    w.y = buf; w.ynew = buf + n; w.f = buf + 2 * n; w.fnew = buf + 3 * n; ytmp = buf + 4 * n;
    w.k = buf + 5 * n;
    w.coef = w.k + m->nscratch * n;
    memset(w.coef, 0, m->ncoef * n * sizeof(double));
    if (m->nonstiff) {
        void *st = NULL;
        if (m->stiff->alloc) {
            w.m = m->stiff;
            if ((rc = m->stiff->alloc(&w)) != MP_OK) goto done;
            st = w.state;
            w.m = cur;
        }
        w.state2 = st; /* the stiff method's state while the non-stiff one runs */
        w.state = NULL;
    }
    if (cur->alloc && (rc = cur->alloc(&w)) != MP_OK) goto done;

    double t = t0;
    memcpy(w.y, y0, n * sizeof(double));
    if ((rc = mp_ode_ws_rhs(&w, t, w.y, w.f)) != MP_OK) goto done;

    size_t ie = 0; /* next t_eval index */
    if (o->n_eval == 0) {
        if ((rc = push_sample(r, t, w.y)) != MP_OK) goto done;
    } else {
        while (ie < o->n_eval && o->t_eval[ie] <= t0) {
            if ((rc = push_sample(r, o->t_eval[ie], w.y)) != MP_OK) goto done;
            ie++;
        }
    }
    if (ne) {
        if ((rc = o->events(t, w.y, g_old, o->events_data)) != MP_OK) goto done;
        for (size_t k = 0; k < ne; k++)
            if (!isfinite(g_old[k])) {
                w.bad_what = MP_ODE_BAD_EVENT;
                w.bad_index = k;
                rc = MP_ENONFINITE;
                goto done;
            }
    }

    double hmax = fmin(o->max_step, tf - t0);
    double h;
    if (!cur->adaptive) h = o->h;
    else if (o->first_step > 0) h = o->first_step;
    else if ((rc = first_step(&w, t0, tf, hmax, &h)) != MP_OK) goto done;
    h = fmin(h, hmax);

    double facold = 1e-4;
    int rejected = 0, stiff_count = 0, calm_count = 0;
    int nonfinite = 0; /* the last rejection was a non-finite trial stage */
    long attempts = 0;
    while (t < tf) {
        if (attempts >= o->max_steps) { rc = MP_EMAXSTEPS; break; }
        if (o->interrupt && attempts % MP_ODE_INTERRUPT_EVERY == MP_ODE_INTERRUPT_EVERY - 1 &&
            (rc = o->interrupt(o->interrupt_ctx)) != MP_OK)
            break;
        attempts++;
        int last = 0;
        if (cur->adaptive ? t + 1.01 * h >= tf : t + h * (1.0 + 1e-9) >= tf) {
            h = tf - t;
            while (t + h > tf) h = nextafter(h, 0.0); /* no stage beyond tf */
            last = 1;
        }
        if (cur->adaptive && !cur->self_controlled &&
            h <= 16.0 * DBL_EPSILON * fmax(fabs(t), 1e-300)) {
            rc = nonfinite ? MP_ENONFINITE : MP_ESTEP;
            break;
        }
        double err = 0.0, hnew = h;
        w.fnew_valid = 0;
        w.rho = 0.0;
        rc = cur->step(&w, t, h, &err);
        if (rc == MP_ENONFINITE && cur->adaptive && !cur->self_controlled) {
            /* a trial stage overflowed: reject and shrink as Hairer's codes do */
            h /= 10.0;
            rejected = nonfinite = 1;
            r->nreject++;
            rc = MP_OK;
            continue;
        }
        if (rc != MP_OK) break;
        if (cur->self_controlled) {
            last = last && w.h_taken >= h;
            h = w.h_taken;
            hnew = w.h_next;
        } else if (cur->adaptive) {
            if (!(err <= 1.0)) { /* rejected (also when err is NaN) */
                nonfinite = !isfinite(err);
                double fac = isfinite(err) ? fmin(1.0 / cur->fac_min,
                                                  pow(err, cur->expo) / cur->safety)
                                           : 10.0;
                h /= fac;
                rejected = 1;
                r->nreject++;
                continue;
            }
            double fac11 = pow(err, cur->expo);
            /* Lund stabilisation only for methods with beta > 0 (dopri5) */
            double fac = cur->beta > 0.0 ? fac11 / pow(facold, cur->beta) : fac11;
            fac = fmax(1.0 / cur->fac_max, fmin(1.0 / cur->fac_min, fac / cur->safety));
            hnew = h / fac;
            facold = fmax(err, 1e-4);
            if (rejected) hnew = fmin(hnew, h);
            rejected = nonfinite = 0;
        }
        double tnew = last ? tf : t + h;
        /* the interpolant is built only for a step that needs it: one holding a
         * t_eval point, with events to locate, or when all steps are kept */
        int dense_now = need_dense && (o->dense || ne > 0 ||
                                       (ie < o->n_eval && o->t_eval[ie] < tnew));
        if ((rc = cur->finish(&w, t, h, dense_now)) != MP_OK) break;
        /* Hairer's stiffness test on explicit steps: h |lambda| near the
         * stability boundary for 15 of the recent steps.  A switching row tests
         * against a fraction of the boundary: the step-size controller of a
         * stiff problem holds h |lambda| just inside it (dop853 on ROBER: ~5.3
         * against 6.1), where the test at the boundary itself rarely fires. */
        if (w.rho > 0.0) {
            double rho_stiff = m->nonstiff ? MP_ODE_SWITCH_FRAC * cur->stiff_rho : cur->stiff_rho;
            if (w.rho > rho_stiff) {
                calm_count = 0;
                if (++stiff_count >= 15) r->stiff = 1;
            } else if (++calm_count >= 6) {
                stiff_count = 0;
            }
        }
        double s_stop = 2.0;
        if (ne) {
            rc = ev_step(&w, r, o, t, h, g_old, g_sub, ytmp, gtmp, hits, &s_stop);
            if (rc != MP_OK) break;
        }
        double tend = s_stop <= 1.0 ? t + s_stop * h : tnew;
        if (o->n_eval) {
            while (ie < o->n_eval && o->t_eval[ie] <= tend) {
                double te = o->t_eval[ie];
                if (te == tnew) memcpy(ytmp, w.ynew, n * sizeof(double));
                else mp_ode_dense_eval(w.coef, w.ncoef, n, (te - t) / h, ytmp);
                if ((rc = push_sample(r, te, ytmp)) != MP_OK) goto done;
                ie++;
            }
        }
        if (o->dense && (rc = push_segment(r, t, h, w.coef)) != MP_OK) break;
        r->nsteps++;
        if (s_stop <= 1.0) {
            mp_ode_dense_eval(w.coef, w.ncoef, n, s_stop, ytmp);
            if (o->n_eval == 0 && (rc = push_sample(r, tend, ytmp)) != MP_OK) break;
            memcpy(w.y, ytmp, n * sizeof(double));
            t = tend;
            r->terminated = 1;
            break;
        }
        if (o->n_eval == 0 && (rc = push_sample(r, tnew, w.ynew)) != MP_OK) break;
        double *sw = w.y; w.y = w.ynew; w.ynew = sw;
        if (w.fnew_valid) { sw = w.f; w.f = w.fnew; w.fnew = sw; }
        t = tnew;
        h = fmin(cur->adaptive ? hnew : o->h, hmax);
        /* the switching row: to the stiff method when the test fires, back when
         * the stiff method's steps are within the explicit stability region */
        if (m->nonstiff) {
            const mp_ode_method *next = cur;
            if (cur == m->nonstiff && stiff_count >= 15) next = m->stiff;
            else if (cur == m->stiff && w.jnorm > 0 && h * w.jnorm < 0.5 * m->nonstiff->stiff_rho) {
                if (++calm_count >= 10) next = m->nonstiff;
            } else if (cur == m->stiff) {
                calm_count = 0;
            }
            if (next != cur) {
                void *sw2 = w.state; w.state = w.state2; w.state2 = sw2;
                cur = next;
                w.m = cur;
                /* the new method may write fewer interpolant slots: the rest are zero */
                memset(w.coef, 0, m->ncoef * n * sizeof(double));
                if (cur->restart) cur->restart(&w);
                if (!w.fnew_valid && (rc = mp_ode_ws_rhs(&w, t, w.y, w.f)) != MP_OK) break;
                stiff_count = calm_count = 0;
                facold = 1e-4;
                rejected = 0;
                r->nswitch++;
            }
        }
    }
    r->t_fail = t;

done:
    if (w.m && w.m->free) w.m->free(&w);
    if (m->nonstiff && w.state2) { /* the method not running at the end */
        const mp_ode_method *other = w.m == m->stiff ? m->nonstiff : m->stiff;
        w.state = w.state2;
        if (other->free) other->free(&w);
    }
    r->bad_what = w.bad_what;
    r->bad_index = w.bad_index;
    r->nfev = w.nfev;
    r->njev = w.njev;
    r->nlu = w.nlu;
    r->nreject += w.nreject_inner;
    r->status = rc;
    free(buf);
    free(g_old);
    free(hits);
    return rc;
}

/* ---- backwards in time: s = -t ---------------------------------------------- */

typedef struct {
    const mp_ode_problem *p;
    const mp_ode_options *o;
} neg_ctx;

/* dy/ds = -f(-s, y) */
static int neg_rhs(double s, const double *y, double *dyds, void *data)
{
    const neg_ctx *c = data;
    int rc = c->p->rhs(-s, y, dyds, c->p->data);
    for (size_t i = 0; i < c->p->n; i++) dyds[i] = -dyds[i];
    return rc;
}

/* d(-f)/dy at (-s, y) */
static int neg_jac(double s, const double *y, double *jac, void *data)
{
    const neg_ctx *c = data;
    int rc = c->p->jac(-s, y, jac, c->p->data);
    for (size_t i = 0; i < c->p->n * c->p->n; i++) jac[i] = -jac[i];
    return rc;
}

/* g(-s, y): a crossing's direction is along the integration, as in SciPy */
static int neg_events(double s, const double *y, double *g, void *data)
{
    const neg_ctx *c = data;
    return c->o->events(-s, y, g, c->o->events_data);
}

int mp_ode_solve(const mp_ode_method *m, const mp_ode_problem *p, double t0, double tf,
                 const double *y0, const mp_ode_options *o, mp_ode_result *r)
{
    if (!(tf < t0)) return solve_forward(m, p, t0, tf, y0, o, r);
    /* Contract: integrate backwards by the substitution s = -t; the result's
     * times are t (decreasing), its dense segments in s (r->backward). */
    neg_ctx c = {p, o};
    mp_ode_problem pn = *p;
    pn.rhs = neg_rhs;
    pn.jac = p->jac ? neg_jac : NULL;
    pn.data = &c;
    pn.nq = 0; /* y' = -f is not of the form q' = v */
    mp_ode_options on = *o;
    double *sev = NULL;
    if (o->n_eval) {
        sev = malloc(o->n_eval * sizeof(double));
        if (!sev) {
            memset(r, 0, sizeof *r);
            return r->status = MP_ENOMEM;
        }
        for (size_t i = 0; i < o->n_eval; i++) sev[i] = -o->t_eval[i];
        on.t_eval = sev;
    }
    if (o->n_events) {
        on.events = neg_events;
        on.events_data = &c;
    }
    int rc = solve_forward(m, &pn, -t0, -tf, y0, &on, r);
    free(sev);
    r->backward = 1;
    for (size_t i = 0; i < r->m; i++) r->t[i] = -r->t[i];
    for (size_t k = 0; k < r->n_events; k++)
        for (size_t i = 0; r->ev_count && i < r->ev_count[k]; i++) r->ev_t[k][i] = -r->ev_t[k][i];
    r->t_fail = -r->t_fail;
    return rc;
}
