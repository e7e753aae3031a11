/* The one driver loop of every integration method: step-size control,
 * budget, interrupts, output at t_eval from dense output, events, storage. */
#include "ode/ode.h"
#include "ode/control.h"
#include "ode/fixed.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MP_ODE_INTERRUPT_EVERY 256   /* steps between interrupt checks */

/* ---- small helpers ------------------------------------------------------ */

void mp_ode_problem_at(mp_ode_problem *p, double t, const double *y)
{
    while (p->sw && !(p->sw->g(t, y, p->data) > 0.0)) {
        p->rhs = p->sw->rhs;
        p->jac = p->sw->jac;
        p->blocks = NULL;
        p->sw = p->sw->next;
    }
}

int mp_ode_ws_bad_rhs(mp_ode_ws *w, size_t i)
{
    w->bad_what = MP_ODE_BAD_RHS;
    w->bad_index = i;
    return MP_ENONFINITE;
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
    /* columns `width` apart share no row of the band: one evaluation
     * perturbs them all (Curtis, Powell and Reid's grouping); dense, each
     * column is a group of its own */
    size_t ml = n - 1, mu = n - 1;
    const size_t *perm = NULL; /* the band's order: state perm[c] is its c-th */
    if (w->p->banded && w->p->ml + w->p->mu + 1 < n) {
        ml = w->p->ml;
        mu = w->p->mu;
        perm = w->p->perm;
        memset(jac, 0, n * n * sizeof(double));
    }
    size_t width = ml + mu + 1;
    memcpy(scratch_y, y, n * sizeof(double));
    for (size_t g = 0; g < width && g < n; g++) {
        for (size_t c = g; c < n; c += width) {
            size_t j = perm ? perm[c] : c;
            double scale = fmax(fabs(y[j]), w->o->atol[j] / w->o->rtolv[j]);
            if (!(scale > 0)) scale = 1.0;
            scratch_y[j] = y[j] + sqrt(DBL_EPSILON) * scale;
        }
        int rc = mp_ode_ws_rhs(w, t, scratch_y, scratch_f);
        if (rc != MP_OK) return rc;
        for (size_t c = g; c < n; c += width) {
            size_t j = perm ? perm[c] : c;
            double d = scratch_y[j] - y[j]; /* the increment actually representable */
            size_t r0 = c > mu ? c - mu : 0, r1 = c + ml < n ? c + ml + 1 : n;
            for (size_t r = r0; r < r1; r++) {
                size_t i = perm ? perm[r] : r;
                jac[i * n + j] = (scratch_f[i] - f0[i]) / d;
            }
            scratch_y[j] = y[j];
        }
    }
    return MP_OK;
}

double mp_ode_err_norm(const mp_ode_ws *w, const double *e, const double *y0, const double *y1)
{
    return mp_ode_rms_norm(w->o, w->n, 1, e, y0, y1);
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

/* Contract: fnew = f(t + h, ynew) unless the step left it (w->fnew_valid), it
 * being the next step's first stage; with need_dense also the cubic Hermite
 * interpolant.  The finish of every method without an interpolant of its own. */
int mp_ode_finish_fnew_hermite(mp_ode_ws *w, double t, double h, int need_dense)
{
    if (!w->fnew_valid) {
        int rc = mp_ode_ws_rhs(w, t + h, w->ynew, w->fnew);
        if (rc != MP_OK) return rc;
        w->fnew_valid = 1;
    }
    if (need_dense) mp_ode_dense_hermite(w->n, h, w->y, w->ynew, w->f, w->fnew, w->coef);
    return MP_OK;
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

/* Contract: room in r for `more` samples beyond r->m.  MP_OK or MP_ENOMEM. */
static int reserve_samples(mp_ode_result *r, size_t more)
{
    size_t cap_t = r->mcap, cap_y = r->mcap;
    if (grow((void **)&r->t, &cap_t, r->m + more, sizeof(double)) != MP_OK) return MP_ENOMEM;
    if (grow((void **)&r->y, &cap_y, r->m + more, r->n * sizeof(double)) != MP_OK)
        return MP_ENOMEM;
    r->mcap = cap_t < cap_y ? cap_t : cap_y;
    return MP_OK;
}

/* One sample (t, y) appended: inline, the capacity test before any call and
 * the copy a loop (a state of a few components, once per step). */
static inline int push_sample(mp_ode_result *r, double t, const double *y)
{
    if (r->m >= r->mcap && reserve_samples(r, 1) != MP_OK) return MP_ENOMEM;
    r->t[r->m] = t;
    double *dst = r->y + r->m * r->n;
    for (size_t i = 0; i < r->n; i++) dst[i] = y[i];
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

int mp_ode_result_events_init(mp_ode_result *r, size_t n, size_t n_events)
{
    memset(r, 0, sizeof *r);
    r->n = n;
    r->n_events = n_events;
    if (!n_events) return MP_OK;
    r->ev_count = calloc(n_events, sizeof(size_t));
    r->ev_cap = calloc(n_events, sizeof(size_t));
    r->ev_t = calloc(n_events, sizeof(double *));
    r->ev_y = calloc(n_events, sizeof(double *));
    return r->ev_count && r->ev_cap && r->ev_t && r->ev_y ? MP_OK : MP_ENOMEM;
}

int mp_ode_result_push_event(mp_ode_result *r, size_t k, double t, const double *y)
{
    return push_event(r, k, t, y);
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

/* Contract: out = r's status (MP_TERMINATED for a terminal event), where and
 * what failed, and its evaluation count. */
void mp_ode_result_outcome(const mp_ode_result *r, mp_ode_outcome *out)
{
    out->status = r->status == MP_OK && r->terminated ? MP_TERMINATED : r->status;
    out->stiff = r->stiff;
    out->bad_what = r->bad_what;
    out->bad_index = r->bad_index;
    out->t_fail = r->t_fail;
    out->nfev = r->nfev;
    out->stop_reason = r->stop_reason;
    out->stop_event = r->stop_event;
    out->n_actions = r->n_actions;
    out->stop_count = r->stop_count;
    out->zeno_gap = r->zeno_gap;
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

/* g_k at step fraction s for mp_ode_event_root */
typedef struct {
    ev_ctx *c;
    size_t k;
} ev_root_ctx;

static int ev_root_g(void *ctx, double s, double *gs)
{
    ev_root_ctx *r = ctx;
    return ev_at(r->c, s, r->k, gs);
}

/* Root of g_k on [a, b] in step-fraction s (control.h's mp_ode_event_root). */
static int ev_root(ev_ctx *c, size_t k, double a, double ga, double b, double gb, double *root)
{
    ev_root_ctx rc = {c, k};
    return mp_ode_event_root(ev_root_g, &rc, c->t, c->h, a, ga, b, gb, root);
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
 * is updated to g at the step end (first: t is the solve's start or where an
 * action restarted it).  Sets *s_stop <= 1 when a terminal event
 * fires or an action event crosses (the step is truncated there; *act = the
 * action event's index, else -1; a terminal count reached stops instead,
 * *act = -1, r->stop_reason saying which).  On the first step (first != 0) an
 * event that is exactly zero at t0 occurs at t0 when it leaves zero in its
 * direction (any way for direction 0), as SciPy's solve_ivp reports it; a
 * zero at a later step's start is the crossing the step before reported (but
 * after an action the state is new: first again). */
static int ev_step(mp_ode_ws *w, mp_ode_result *r, const mp_ode_options *o, double t, double h,
                   int first, double probe, double *g_old, double *g_sub, double *ytmp,
                   double *gtmp, ev_hit *hits, double *s_stop, long *act)
{
    size_t ne = o->n_events, nh = 0;
    ev_ctx c = {w, o, t, h, ytmp, gtmp};
    *s_stop = 2.0;
    *act = -1;
    double s_from = 0.0; /* where the search starts (after a restart's probe) */
    if (first == 2) {
        /* After an action the state is new: an event exactly zero there is
         * probed just after it (at t + probe, far inside the shortest interval
         * between two actions that is not an accumulation), and occurs there
         * when g has left zero in its direction (the action left the state on
         * the event surface, moving across it); otherwise its search starts at
         * the probe (a bounce shorter than a sub-interval is found). */
        int zero = 0;
        for (size_t k = 0; k < ne; k++) zero |= g_old[k] == 0.0;
        if (zero) {
            s_from = fmin(probe / h, 0.5 / MP_ODE_EVENT_SUBDIV);
            mp_ode_dense_eval(w->coef, w->ncoef, w->n, s_from, ytmp);
            int rc = o->events(t + s_from * h, ytmp, g_sub, o->events_data);
            if (rc != MP_OK) return rc;
            for (size_t k = 0; k < ne; k++) {
                if (g_old[k] != 0.0) continue;
                int dk = o->direction[k];
                if (dk == 0 ? g_sub[k] != 0.0 : dk > 0 ? g_sub[k] > 0.0 : g_sub[k] < 0.0) {
                    hits[nh].s = 0.0;
                    hits[nh].k = k;
                    nh++;
                }
                g_old[k] = g_sub[k];
            }
        }
    }
    for (int j = 1; j <= MP_ODE_EVENT_SUBDIV; j++) {
        double s0 = (double)(j - 1) / MP_ODE_EVENT_SUBDIV, s1 = (double)j / MP_ODE_EVENT_SUBDIV;
        if (j == 1) s0 = s_from;
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
            int dk = o->direction[k];
            if (first == 1 && j == 1 && g_old[k] == 0.0) { /* zero at t0 */
                if (dk == 0 || (dk > 0 ? g_sub[k] >= 0.0 : g_sub[k] <= 0.0)) {
                    hits[nh].s = 0.0;
                    hits[nh].k = k;
                    nh++;
                }
            } else if (crosses(g_old[k], g_sub[k], dk)) {
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
        int rc = k < r->n_events ? push_event(r, k, t + s * h, ytmp) : MP_OK; /* a switch: not */
        if (rc != MP_OK) return rc;
        int with_action = o->has_action && o->has_action[k];
        if (o->terminal[k] > 0 && r->ev_count[k] >= (size_t)o->terminal[k]) {
            *s_stop = s;
            r->stop_reason = with_action ? MP_ODE_STOP_MAX_EVENTS : MP_ODE_STOP_TERMINAL;
            r->stop_event = k;
            r->stop_count = (long)r->ev_count[k];
            break;
        }
        if (with_action) {
            *s_stop = s;
            *act = (long)k;
            break;
        }
    }
    return MP_OK;
}

/* ---- the first step: Hairer's hinit ------------------------------------- */

/* Contract: Hairer's first step (control.h's hinit, whose Euler probe runs
 * here: a probe that overflows is retried ten times shorter, up to 20 times)
 * from (t0, y, f), at most hmax and tf - t0.  MP_OK or the probe's failure. */
static int first_step(mp_ode_ws *w, double t0, double tf, double hmax, double *h_out)
{
    size_t n = w->n;
    const mp_ode_options *o = w->o;
    double dnf, h = mp_ode_hinit_trial(o, n, 1, w->y, w->f, hmax, tf - t0, &dnf);
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
    *h_out = mp_ode_hinit_final(o, n, 1, w->y, w->f, f1, h, dnf, w->m->order, hmax, tf - t0);
    return MP_OK;
}

/* ---- output -------------------------------------------------------------- */

/* Contract: the output of an accepted step [t, t + h] ending at tnew, or at
 * tend < tnew where a terminal event cut it: the t_eval rows up to tend from
 * the interpolant (the step's end itself exactly), from index *ie on, and the
 * step's segment when every step is kept.  MP_OK or MP_ENOMEM. */
static int output_step(mp_ode_result *r, const mp_ode_options *o, const mp_ode_ws *w, double t,
                       double h, double tnew, double tend, size_t *ie, double *ytmp)
{
    size_t n = w->n;
    for (; *ie < o->n_eval && o->t_eval[*ie] <= tend; ++*ie) {
        double te = o->t_eval[*ie];
        if (te == tnew) memcpy(ytmp, w->ynew, n * sizeof(double));
        else mp_ode_dense_eval(w->coef, w->ncoef, n, (te - t) / h, ytmp);
        int rc = push_sample(r, te, ytmp);
        if (rc != MP_OK) return rc;
    }
    return o->dense ? push_segment(r, t, h, w->coef) : MP_OK;
}

/* ---- step-size control and method switching ------------------------------ */

/* Contract: control.h's controller for the scalar driver (the powers taken
 * here).  1: accepted, *hnew the next step; 0: rejected, *h the retry. */
static int control(const mp_ode_method *cur, mp_ode_ctl *c, double err, double *h,
                   double *hnew)
{
    double fac11 = mp_ode_err_pow(err, cur->expo);
    double fold = cur->beta > 0.0 ? pow(c->facold, cur->beta) : 1.0;
    return mp_ode_control(cur, c, err, fac11, fold, h, hnew);
}

/* Contract: the switching row m after an accepted step ending at t, next step
 * h: to the stiff method when the stiffness test fired, back when the stiff
 * method's steps are within the explicit stability region.  On a switch the
 * methods' states are swapped, the interpolant cleared, f(t, y) made current
 * and the controller restarted.  MP_OK or the right-hand side's failure. */
static int switch_method(const mp_ode_method *m, mp_ode_ws *w, const mp_ode_method **cur,
                         mp_ode_ctl *c, double t, double h, mp_ode_result *r)
{
    const mp_ode_method *next = *cur;
    if (*cur == m->nonstiff && c->stiff_count >= 15) next = m->stiff;
    else if (*cur == m->stiff && w->jnorm > 0 && h * w->jnorm < 0.5 * m->nonstiff->stiff_rho) {
        if (++c->calm_count >= 10) next = m->nonstiff;
    } else if (*cur == m->stiff) {
        c->calm_count = 0;
    }
    if (next == *cur) return MP_OK;
    void *sw = w->state; w->state = w->state2; w->state2 = sw;
    *cur = next;
    w->m = next;
    /* the new method may write fewer interpolant slots: the rest are zero */
    memset(w->coef, 0, m->ncoef * w->n * sizeof(double));
    if (next->restart) next->restart(w);
    int rc = w->fnew_valid ? MP_OK : mp_ode_ws_rhs(w, t, w->y, w->f);
    if (rc != MP_OK) return rc;
    *c = mp_ode_ctl_start();
    r->nswitch++;
    return MP_OK;
}

/* ---- the driver --------------------------------------------------------- */

/* A switching row counts an explicit step as stiff from this fraction of the
 * explicit method's stability boundary h |lambda| on. */
#ifndef MP_ODE_SWITCH_FRAC
#define MP_ODE_SWITCH_FRAC 0.8
#endif

/* One forward solve in progress: what the loop reads and writes besides the
 * method's workspace. */
typedef struct {
    const mp_ode_method *m;   /* the row asked for (a switching row: the pair) */
    const mp_ode_method *cur; /* the method running */
    const mp_ode_options *o;
    mp_ode_result *r;
    mp_ode_ws w;
    mp_ode_ctl c;
    double t, tf, h, hmax;    /* where the solve is, its end, the next step, the largest */
    double t0;                /* its start */
    long nfixed;              /* fixed steps taken: the next starts at t0 + nfixed h */
    size_t ie;                /* the next t_eval index */
    long attempts;            /* steps attempted (the budget) */
    int need_dense;           /* some step may need the interpolant */
    int fast;                 /* the fixed-step fast path may run (fixed_block) */
    long checked_until;       /* ... not before this many attempts (a block replayed) */
    double *buf, *ytmp, *save;                  /* the vectors: one block */
    double *g_old, *g_sub, *gtmp; ev_hit *hits; /* events: one block, and the hits */
    double *act_t;            /* per event: the time of its last action (with act_n) */
    long *act_n;              /* per event: its actions applied */
    int restarted;            /* an action restarted the solve: its point is a new start */
    mp_ode_problem prob;      /* the problem on its current branch (switches taken) */
    const mp_ode_options *user; /* the caller's options (s->o: with the switch as an event) */
    mp_ode_options swo;       /* ... the options with it */
    int *sw_int;              /* its terminal and direction arrays (2 (ne + 1)) */
    unsigned char *sw_act;    /* its has_action array (ne + 1) */
} ode_run;

int mp_ode_span_ok(const mp_ode_method *m, double t0, double tf, const mp_ode_options *o)
{
    if (!(t0 != tf) || !isfinite(t0) || isnan(tf) || (!isfinite(tf) && !m->adaptive) ||
        !(o->rtol > 0) || !(o->max_steps > 0) || (!m->adaptive && !(o->h > 0)) ||
        !(o->max_step > 0))
        return MP_EDOM;
    /* a fixed step below the spacing of floats at t would never advance t */
    double tmax = fmax(fabs(t0), fabs(tf));
    if (!m->adaptive && !(tmax + o->h > tmax)) return MP_EDOM;
    return MP_OK;
}

/* Contract: MP_OK when the arguments of a forward solve are in its domain:
 * n > 0, t0 < tf, mp_ode_span_ok, y0 finite, atol >= 0 and rtolv >= rtol;
 * else MP_EDOM. */
static int check_args(const mp_ode_method *m, const mp_ode_problem *p, double t0, double tf,
                      const double *y0, const mp_ode_options *o)
{
    if (p->n == 0 || !(tf > t0) || mp_ode_span_ok(m, t0, tf, o) != MP_OK) return MP_EDOM;
    for (size_t i = 0; i < p->n; i++)
        if (!isfinite(y0[i]) || !(o->atol[i] >= 0) || !(o->rtolv[i] >= o->rtol)) return MP_EDOM;
    return MP_OK;
}

/* Contract: the storage of a solve with events: r's per-event lists (empty)
 * and s's buffers for g at the step start, at sub-points, scratch, and the
 * crossings of one step.  Nothing without events.  MP_OK or MP_ENOMEM (what
 * was allocated is freed by free_run and mp_ode_result_free). */
static int alloc_events(ode_run *s)
{
    size_t ne = s->o->n_events;
    mp_ode_result *r = s->r;
    if (!ne) return MP_OK;
    r->ev_count = calloc(ne, sizeof(size_t));
    r->ev_cap = calloc(ne, sizeof(size_t));
    r->ev_t = calloc(ne, sizeof(double *));
    r->ev_y = calloc(ne, sizeof(double *));
    s->g_old = malloc(4 * ne * sizeof(double));
    s->hits = malloc(ne * MP_ODE_EVENT_SUBDIV * sizeof(ev_hit));
    s->act_n = calloc(ne, sizeof(long));
    if (!r->ev_count || !r->ev_cap || !r->ev_t || !r->ev_y || !s->g_old || !s->hits ||
        !s->act_n)
        return MP_ENOMEM;
    s->act_t = s->g_old + 3 * ne;
    s->g_sub = s->g_old + ne;
    s->gtmp = s->g_sub + ne;
    return MP_OK;
}

/* Contract: the workspace of a solve of m on [t0, tf]: its vectors (y, ynew,
 * f, fnew, scratch, the fast path's saved state, the method's scratch and
 * interpolant, zeroed) in one block, and the method's own state; a switching
 * row also allocates its stiff method's state, kept in w.state2 while the
 * non-stiff one runs.  MP_OK or the allocation's failure (freed by free_run). */
static int alloc_workspace(ode_run *s, const mp_ode_problem *p, double t0, double tf)
{
    const mp_ode_method *m = s->m;
    mp_ode_ws *w = &s->w;
    size_t n = p->n, nvec = 10 + m->nscratch + m->ncoef;
    s->buf = malloc(nvec * n * sizeof(double));
    if (!s->buf) return MP_ENOMEM;
    w->p = p; w->m = s->cur; w->o = s->o; w->n = n; w->ncoef = m->ncoef;
    w->t_start = t0; w->t_end = tf;
    w->y = s->buf; w->ynew = s->buf + n; w->f = s->buf + 2 * n; w->fnew = s->buf + 3 * n;
    s->ytmp = s->buf + 4 * n;
    s->save = s->buf + 5 * n; /* 3n: y, f and lo at the start of a fast block */
    w->lo = s->buf + 8 * n;
    w->lonew = s->buf + 9 * n;
    memset(w->lo, 0, 2 * n * sizeof(double));
    w->k = s->buf + 10 * n;
    w->coef = w->k + m->nscratch * n;
    memset(w->coef, 0, m->ncoef * n * sizeof(double));
    int rc;
    if (m->nonstiff) {
        void *st = NULL;
        if (m->stiff->alloc) {
            w->m = m->stiff;
            if ((rc = m->stiff->alloc(w)) != MP_OK) return rc;
            st = w->state;
            w->m = s->cur;
        }
        w->state2 = st; /* the stiff method's state while the non-stiff one runs */
        w->state = NULL;
    }
    return s->cur->alloc ? s->cur->alloc(w) : MP_OK;
}

/* Contract: the start of the solve at (t0, y0): f(t0, y0), the first output
 * (y0 itself, or the t_eval points at t0), g at t0 when there are events (a
 * non-finite g is MP_ENONFINITE), and the first step (fixed h, the user's
 * first_step, or Hairer's guess), at most hmax.  MP_OK or the failure. */
static int start_run(ode_run *s, double t0, const double *y0)
{
    mp_ode_ws *w = &s->w;
    const mp_ode_options *o = s->o;
    size_t n = w->n, ne = o->n_events;
    int rc;
    s->t = s->t0 = t0;
    s->nfixed = 0;
    memcpy(w->y, y0, n * sizeof(double));
    if ((rc = mp_ode_ws_rhs(w, t0, w->y, w->f)) != MP_OK) return rc;
    if (o->n_eval == 0) {
        if ((rc = push_sample(s->r, t0, w->y)) != MP_OK) return rc;
    } else {
        for (; s->ie < o->n_eval && o->t_eval[s->ie] <= t0; s->ie++)
            if ((rc = push_sample(s->r, o->t_eval[s->ie], w->y)) != MP_OK) return rc;
    }
    if (ne) {
        if ((rc = o->events(t0, w->y, s->g_old, o->events_data)) != MP_OK) return rc;
        for (size_t k = 0; k < ne; k++)
            if (!isfinite(s->g_old[k])) {
                w->bad_what = MP_ODE_BAD_EVENT;
                w->bad_index = k;
                return MP_ENONFINITE;
            }
    }
    s->hmax = fmin(o->max_step, s->tf - t0);
    if (!s->cur->adaptive) s->h = o->h;
    else if (o->first_step > 0) s->h = o->first_step;
    else if ((rc = first_step(w, t0, s->tf, s->hmax, &s->h)) != MP_OK) return rc;
    s->h = fmin(s->h, s->hmax);
    return MP_OK;
}

/* Contract: Hairer's stiffness test on an explicit step with estimate w.rho =
 * h |lambda| > 0: near the stability boundary for 15 of the recent steps sets
 * r->stiff.  A switching row tests against a fraction of the boundary: the
 * step-size controller of a stiff problem holds h |lambda| just inside it
 * (dop853 on ROBER: ~5.3 against 6.1), where the test at the boundary itself
 * rarely fires. */
static void stiffness_test(ode_run *s)
{
    double rho_stiff = s->m->nonstiff ? MP_ODE_SWITCH_FRAC * s->cur->stiff_rho
                                      : s->cur->stiff_rho;
    mp_ode_stiffness_test(&s->c, s->w.rho, rho_stiff, &s->r->stiff);
}

/* Contract: event k's action at (s->t, w->y), the state just before it: the
 * action replaces y in place (a non-finite value is MP_ENONFINITE, naming
 * the action), the state after it is a sample (with no t_eval), and the
 * integration restarts there: f(t, y), g(t, y), the controller and the
 * first step afresh (a fixed-step method counts its steps from t), the
 * method's history forgotten.  An action that leaves the state where event k
 * fires again at once (two actions within the root finder's tolerance) is
 * MP_EEVENT; crossings accumulating (Zeno: the gap between two actions below
 * MP_ODE_ZENO_FRAC of the time since the start) end the solve at that point,
 * as a terminal event does (r->stop_reason MP_ODE_STOP_ZENO).  MP_OK or the
 * failure. */
static int apply_action(ode_run *s, size_t k)
{
    mp_ode_ws *w = &s->w;
    mp_ode_result *r = s->r;
    const mp_ode_options *o = s->o;
    size_t n = w->n, ne = o->n_events;
    double t = s->t;
    int rc;
    double gap = 0.0;
    rc = mp_ode_action_gap(t, s->act_t[k], s->act_n[k], w->t_start, s->h, &gap);
    if (rc != MP_OK) r->stop_event = k;
    if (rc == MP_EEVENT) return rc;
    if (rc == MP_TERMINATED) {
        r->stop_reason = MP_ODE_STOP_ZENO;
        r->stop_count = (long)r->ev_count[k];
        r->zeno_gap = gap;
        r->terminated = 1;
        return MP_OK;
    }
    if ((rc = o->action(t, w->y, k, o->action_data)) != MP_OK) return rc;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(w->y[i])) {
            w->bad_what = MP_ODE_BAD_ACTION;
            w->bad_index = k;
            return MP_ENONFINITE;
        }
    s->act_t[k] = t;
    s->act_n[k]++;
    if (k < r->n_events) { /* an event's action: the state before and after are samples */
        r->n_actions++;
        if (o->n_eval == 0 && (rc = push_sample(r, t, w->y)) != MP_OK) return rc;
    } else if (o->n_eval == 0) { /* a switch: the sample at its time is the state after it */
        memcpy(r->y + (r->m - 1) * n, w->y, n * sizeof(double));
    }
    /* restart from (t, y): as at the start, the history forgotten */
    if ((rc = mp_ode_ws_rhs(w, t, w->y, w->f)) != MP_OK) return rc;
    if ((rc = o->events(t, w->y, s->g_old, o->events_data)) != MP_OK) return rc;
    for (size_t q = 0; q < ne; q++)
        if (!isfinite(s->g_old[q])) {
            w->bad_what = MP_ODE_BAD_EVENT;
            w->bad_index = q;
            return MP_ENONFINITE;
        }
    s->c = mp_ode_ctl_start();
    s->restarted = 1;
    memset(w->coef, 0, w->ncoef * n * sizeof(double));
    if (s->cur->restart) s->cur->restart(w);
    s->t0 = t;
    s->nfixed = 0;
    s->hmax = fmin(o->max_step, s->tf - t);
    if (!s->cur->adaptive) s->h = o->h;
    else if (o->first_step > 0) s->h = o->first_step;
    else if ((rc = first_step(w, t, s->tf, s->hmax, &s->h)) != MP_OK) return rc;
    s->h = fmin(s->h, s->hmax);
    return MP_OK;
}

/* Contract: the rest of an accepted step [t, t + h] ending at tnew (tf on
 * the last step), the next one to be hnew (adaptive): the method's finish
 * (with the interpolant only when a t_eval point, events or dense output need
 * it), the stiffness test, events, output; then (t, y, f) move to the step's
 * end, or to a terminal event's point (r->terminated), and a switching row
 * may change method.  MP_OK or the failure. */
static int accept_step(ode_run *s, double h, double hnew, double tnew)
{
    mp_ode_ws *w = &s->w;
    mp_ode_result *r = s->r;
    const mp_ode_options *o = s->o;
    size_t n = w->n;
    double t = s->t;
    int rc, dense_now = s->need_dense && (o->dense || o->n_events > 0 ||
                                          (s->ie < o->n_eval && o->t_eval[s->ie] < tnew));
    if ((rc = s->cur->finish(w, t, h, dense_now)) != MP_OK) return rc;
    if (w->rho > 0.0) stiffness_test(s);
    double s_stop = 2.0;
    long act = -1;
    /* a zero of g at the start (or where an action restarted the solve) that g
     * leaves in its direction is an event there */
    int fresh = r->nsteps == 0 ? 1 : s->restarted ? 2 : 0;
    s->restarted = 0;
    double probe = mp_ode_restart_probe(t, w->t_start);
    if (o->n_events && (rc = ev_step(w, r, o, t, h, fresh, probe, s->g_old, s->g_sub, s->ytmp,
                                     s->gtmp, s->hits, &s_stop, &act)) != MP_OK)
        return rc;
    double tend = s_stop <= 1.0 ? t + s_stop * h : tnew;
    if ((rc = output_step(r, o, w, t, h, tnew, tend, &s->ie, s->ytmp)) != MP_OK) return rc;
    r->nsteps++;
    if (s_stop <= 1.0) { /* the step ends at the event's point: the state just before it */
        mp_ode_dense_eval(w->coef, w->ncoef, n, s_stop, s->ytmp);
        if (o->n_eval == 0 && (rc = push_sample(r, tend, s->ytmp)) != MP_OK) return rc;
        memcpy(w->y, s->ytmp, n * sizeof(double));
        memset(w->lo, 0, n * sizeof(double)); /* a new state: no low-order part */
        s->t = tend;
        if (act < 0) { /* a terminal event: the solve ends here */
            r->terminated = 1;
            return MP_OK;
        }
        return apply_action(s, (size_t)act);
    }
    if (o->n_eval == 0 && (rc = push_sample(r, tnew, w->ynew)) != MP_OK) return rc;
    double *sw = w->y; w->y = w->ynew; w->ynew = sw;
    sw = w->lo; w->lo = w->lonew; w->lonew = sw;
    if (w->fnew_valid) { sw = w->f; w->f = w->fnew; w->fnew = sw; }
    s->t = tnew;
    s->nfixed += !s->cur->adaptive;
    s->h = mp_ode_min(s->cur->adaptive ? hnew : o->h, s->hmax);
    /* the switching row: to the stiff method when the test fires, back when
     * the stiff method's steps are within the explicit stability region */
    return s->m->nonstiff ? switch_method(s->m, w, &s->cur, &s->c, s->t, s->h, r) : MP_OK;
}

/* Contract: the fixed-step fast path, for a row with a block (ode.h) on a
 * replayable problem, with no events and no dense output.  Runs in one block
 * the steps that need nothing of the driver but the step itself (not the last
 * one, none reaching the next t_eval point, none at an interrupt poll, within
 * the budget), with the stage checks off, and checks once at the block's end
 * that y, f and the values the steps dropped are finite.  A non-finite value
 * or a failure puts everything back as it was at the block's start (y, lo, f,
 * counts, samples) and leaves the block to the checked loop, which stops
 * where and as it always does: results and counts are the checked loop's,
 * bit for bit. */
static void fixed_block(ode_run *s)
{
    mp_ode_ws *w = &s->w;
    mp_ode_result *r = s->r;
    const mp_ode_options *o = s->o;
    size_t n = w->n;
    if (s->attempts < s->checked_until) return;
    /* the steps before the next interrupt poll (attempts % EVERY == EVERY - 1) */
    long k = 0, kmax = MP_ODE_INTERRUPT_EVERY - 1 - s->attempts % MP_ODE_INTERRUPT_EVERY;
    if (kmax > o->max_steps - s->attempts) kmax = o->max_steps - s->attempts;
    double t = s->t, h = s->h, tout = s->ie < o->n_eval ? o->t_eval[s->ie] : INFINITY;
    for (; k < kmax; k++) { /* the steps run_loop would take as not the last, no output due */
        double tn = mp_ode_fixed_time(s->t0, s->nfixed + k + 1, h);
        if (!(t + h * (1.0 + 1e-9) < s->tf && tn < tout)) break;
        t = tn;
    }
    if (k == 0) return;
    int every = o->n_eval == 0; /* every step is a sample */
    if (every && reserve_samples(r, (size_t)k) != MP_OK) return; /* the checked loop reports */
    long nfev0 = w->nfev;
    memcpy(s->save, w->y, n * sizeof(double));
    memcpy(s->save + n, w->f, n * sizeof(double));
    memcpy(s->save + 2 * n, w->lo, n * sizeof(double));
    w->discarded = 0.0;
    int rc = s->cur->block(w, s->t0, s->nfixed, h, k, every ? r->t + r->m : NULL,
                           every ? r->y + r->m * n : NULL);
    int bad = rc != MP_OK || !isfinite(w->discarded);
    for (size_t i = 0; i < n && !bad; i++) bad = !isfinite(w->y[i]) || !isfinite(w->f[i]);
    if (bad) { /* back to the block's start: the checked loop runs it, and the failing step */
        memcpy(w->y, s->save, n * sizeof(double));
        memcpy(w->f, s->save + n, n * sizeof(double));
        memcpy(w->lo, s->save + 2 * n, n * sizeof(double));
        w->nfev = nfev0;
        s->checked_until = s->attempts + k + 1;
        return;
    }
    if (every) r->m += (size_t)k;
    r->nsteps += k;
    s->t = t;
    s->nfixed += k;
    s->attempts += k;
}

/* Contract: MP_OK when the new state w->ynew of a step is finite, else
 * mp_ode_ws_bad_state.  The controlled methods (dopri5, dop853) fold the same
 * test into their error loops, which read ynew anyway. */
static inline int check_state(mp_ode_ws *w)
{
    return mp_ode_first_nonfinite_at(w->ynew, w->n, 1) < w->n ? mp_ode_ws_bad_state(w) : MP_OK;
}

/* Contract: the loop of a forward solve from start_run's state to tf: each
 * attempt within the budget (every MP_ODE_INTERRUPT_EVERY-th first polls for
 * an interrupt) steps, lets the controller accept or reject the step (a
 * non-finite trial stage rejects it with h / 10), and completes an accepted
 * one (accept_step); fixed steps run in fast blocks where they can.  MP_OK at
 * tf or at a terminal event, else the failure; r->t_fail is where it stopped. */
static int run_loop(ode_run *s)
{
    mp_ode_ws *w = &s->w;
    mp_ode_result *r = s->r;
    const mp_ode_options *o = s->o;
    int rc = MP_OK;
    while (s->t < s->tf) {
        if (s->fast) fixed_block(s);
        const mp_ode_method *cur = s->cur;
        double t = s->t, h = s->h;
        if (s->attempts >= o->max_steps) { rc = MP_EMAXSTEPS; break; }
        if (o->interrupt && s->attempts % MP_ODE_INTERRUPT_EVERY == MP_ODE_INTERRUPT_EVERY - 1 &&
            (rc = o->interrupt(o->interrupt_ctx)) != MP_OK)
            break;
        s->attempts++;
        int last, controlled = cur->adaptive && !cur->self_controlled;
        /* a step below the floor is raised (radau's too: it never steps past what is
         * asked); a retry below it ends the solve, radau's within its own step */
        int below = cur->adaptive && mp_ode_step_floor(&s->c, t, o->max_step, &h);
        h = mp_ode_step_span(cur->adaptive, t, h, s->tf, &last);
        if (below && controlled && !last) { /* the last lands on tf */
            rc = s->c.nonfinite ? MP_ENONFINITE : MP_ESTEP;
            break;
        }
        double err = 0.0, hnew = h;
        w->fnew_valid = 0;
        w->rho = 0.0;
        rc = cur->step(w, t, h, &err);
        /* the new state itself: it can overflow where f stays finite (an f
         * bounded at infinity), and an error estimate scaled by that state does
         * not see it (the controlled methods' steps check it themselves) */
        if (rc == MP_OK && !controlled) rc = check_state(w);
        if (rc == MP_ENONFINITE && controlled) {
            /* a trial stage or the state overflowed: reject and shrink as Hairer's
             * codes do */
            s->h = mp_ode_control_nonfinite(&s->c, h);
            r->nreject++;
            rc = MP_OK;
            continue;
        }
        if (rc != MP_OK) break;
        if (cur->self_controlled) {
            last = last && w->h_taken >= h;
            h = w->h_taken;
            hnew = w->h_next;
        } else if (controlled && !control(cur, &s->c, err, &h, &hnew)) {
            if (s->c.nonfinite) mp_ode_ws_bad_norm(w); /* err overflowed: f and y are finite */
            s->h = h; /* rejected: retry with the smaller step */
            r->nreject++;
            continue;
        }
        /* a fixed step's end is counted, t0 + (i + 1) h: a sum of steps drifts */
        double tnew = last ? s->tf
                    : cur->adaptive ? t + h : mp_ode_fixed_time(s->t0, s->nfixed + 1, h);
        if ((rc = accept_step(s, h, hnew, tnew)) != MP_OK || r->terminated)
            break;
    }
    r->t_fail = s->t;
    return rc;
}

/* Contract: free what a solve allocated (the methods' states, the vectors,
 * the event buffers; r keeps its own arrays) and record in r the counts, the
 * origin of a non-finite value and the status rc. */
static void free_run(ode_run *s, int rc)
{
    mp_ode_ws *w = &s->w;
    const mp_ode_method *m = s->m;
    mp_ode_result *r = s->r;
    if (w->m && w->m->free) w->m->free(w);
    if (m->nonstiff && w->state2) { /* the method not running at the end */
        const mp_ode_method *other = w->m == m->stiff ? m->nonstiff : m->stiff;
        w->state = w->state2;
        if (other->free) other->free(w);
    }
    r->bad_what = w->bad_what;
    r->bad_index = w->bad_index;
    r->nfev = w->nfev;
    r->njev = w->njev;
    r->nlu = w->nlu;
    r->nreject += w->nreject_inner;
    r->status = rc;
    free(s->buf);
    free(s->g_old);
    free(s->hits);
    free(s->act_n);
    free(s->sw_int);
    free(s->sw_act);
}

/* The events of a solve whose problem has a switch: the caller's events, then
 * the switch's g (1 once no switch is ahead). */
static int sw_events(double t, const double *y, double *g, void *data)
{
    const ode_run *s = data;
    size_t ne = s->user->n_events;
    if (ne) {
        int rc = s->user->events(t, y, g, s->user->events_data);
        if (rc != MP_OK) return rc;
    }
    g[ne] = s->prob.sw ? s->prob.sw->g(t, y, s->prob.data) : 1.0;
    return MP_OK;
}

/* The caller's actions, or the switch's: its act, then the branch after it. */
static int sw_action(double t, double *y, size_t k, void *data)
{
    ode_run *s = data;
    if (k < s->user->n_events) return s->user->action(t, y, k, s->user->action_data);
    const mp_ode_switch *sw = s->prob.sw;
    if (sw->act) sw->act(t, y, s->prob.data);
    s->prob.rhs = sw->rhs;
    s->prob.jac = sw->jac;
    s->prob.blocks = NULL;
    s->prob.sw = sw->next;
    return MP_OK;
}

/* Contract: s->o for a problem with a switch ahead: the caller's options with
 * the switch as one more event (downwards, with an action, never terminal,
 * not reported).  MP_OK or MP_ENOMEM (freed by free_run). */
static int switch_options(ode_run *s)
{
    const mp_ode_options *o = s->user;
    size_t ne = o->n_events;
    s->sw_int = malloc(2 * (ne + 1) * sizeof(int));
    s->sw_act = calloc(ne + 1, 1);
    if (!s->sw_int || !s->sw_act) return MP_ENOMEM;
    for (size_t k = 0; k < ne; k++) {
        s->sw_int[k] = o->terminal[k];
        s->sw_int[ne + 1 + k] = o->direction[k];
        s->sw_act[k] = o->has_action ? o->has_action[k] : 0;
    }
    s->sw_int[ne] = 0;
    s->sw_int[2 * ne + 1] = -1;
    s->sw_act[ne] = 1;
    s->swo = *o;
    s->swo.n_events = ne + 1;
    s->swo.events = sw_events;
    s->swo.events_data = s;
    s->swo.terminal = s->sw_int;
    s->swo.direction = s->sw_int + ne + 1;
    s->swo.has_action = s->sw_act;
    s->swo.action = sw_action;
    s->swo.action_data = s;
    s->o = &s->swo;
    return MP_OK;
}

/* Contract: the forward solve (t0 < tf) of mp_ode_solve: the arguments
 * checked, the storage allocated, the start, the loop; everything freed on
 * every path, the counts and the status in r. */
static int solve_forward(const mp_ode_method *m, const mp_ode_problem *p, double t0, double tf,
                         const double *y0, const mp_ode_options *o, mp_ode_result *r)
{
    ode_run s;
    memset(r, 0, sizeof *r);
    memset(&s, 0, sizeof s);
    r->n = p->n;
    r->ncoef = m->ncoef;
    r->n_events = o->n_events;
    r->t_fail = t0;
    int rc = check_args(m, p, t0, tf, y0, o);
    if (rc != MP_OK) return r->status = rc;
    s.m = m;
    s.cur = m->nonstiff ? m->nonstiff : m; /* a switching row runs its two methods in turn */
    s.o = s.user = o;
    s.r = r;
    s.tf = tf;
    s.c = mp_ode_ctl_start();
    s.prob = *p;
    mp_ode_problem_at(&s.prob, t0, y0); /* the branch y0 is on */
    if (s.prob.sw) rc = switch_options(&s); /* a switch ahead: crossed as an event */
    o = s.o;
    s.need_dense = o->n_eval > 0 || o->dense || o->n_events > 0;
    s.fast = m->block && p->replayable && o->n_events == 0 && !o->dense;
    if (rc == MP_OK && (rc = alloc_events(&s)) == MP_OK &&
        (rc = alloc_workspace(&s, &s.prob, t0, tf)) == MP_OK &&
        (rc = start_run(&s, t0, y0)) == MP_OK)
        rc = run_loop(&s);
    free_run(&s, rc);
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

/* the action at t = -s */
static int neg_action(double s, double *y, size_t k, void *data)
{
    const neg_ctx *c = data;
    return c->o->action(-s, y, k, c->o->action_data);
}

int mp_ode_solve(const mp_ode_method *m, const mp_ode_problem *p, double t0, double tf,
                 const double *y0, const mp_ode_options *o, mp_ode_result *r)
{
    if (!(tf < t0)) return solve_forward(m, p, t0, tf, y0, o, r);
    /* Contract: integrate backwards by the substitution s = -t; the result's
     * times are t (decreasing), its dense segments in s (r->backward). */
    /* a switch is crossed forwards only: backwards the problem keeps the
     * branch of (t0, y0) (a rocket coasting back never refuels) */
    mp_ode_problem pb = *p;
    mp_ode_problem_at(&pb, t0, y0);
    pb.sw = NULL;
    neg_ctx c = {&pb, o};
    mp_ode_problem pn = pb;
    pn.rhs = neg_rhs;
    pn.jac = pb.jac ? neg_jac : NULL;
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
    if (o->action) {
        on.action = neg_action;
        on.action_data = &c;
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
