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

typedef struct ode_run ode_run; /* one forward solve in progress (below) */

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

/* Append t to event k's rest list (r->rs_t: came to rest, lifted off, ...). */
static int push_rest(mp_ode_result *r, size_t k, double t)
{
    if (!r->rs_t) return MP_OK;
    if (grow((void **)&r->rs_t[k], &r->rs_cap[k], r->rs_count[k] + 1, sizeof(double)) != MP_OK)
        return MP_ENOMEM;
    r->rs_t[k][r->rs_count[k]++] = t;
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
    if (r->rs_t)
        for (size_t k = 0; k < r->n_events; k++) free(r->rs_t[k]);
    free(r->rs_t);
    free(r->rs_count);
    free(r->rs_cap);
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

/* Whether g is strictly on the side an event of direction dir is crossed
 * from (dir 0: either side, g not zero): where an event that has acted must
 * have been seen before it can fire again. */
static int before_crossing(double g, int dir)
{
    return dir < 0 ? g > 0.0 : dir > 0 ? g < 0.0 : g != 0.0;
}

typedef struct { double s; size_t k; } ev_hit;

static int ev_cmp(const void *a, const void *b)
{
    double x = ((const ev_hit *)a)->s, y = ((const ev_hit *)b)->s;
    return x < y ? -1 : x > y;
}

static const mp_impact *ev_impact(const ode_run *s, size_t k);
static double ev_rho(const ode_run *s, const mp_impact *im, double t, const double *y,
                     double *wall);

/* an impact's relative velocity on the step's interpolant at fraction s */
typedef struct {
    const ode_run *s;
    ev_ctx *c;
    const mp_impact *im;
} ev_rho_ctx;

static int ev_rho_at(void *ctx, double sf, double *rho)
{
    ev_rho_ctx *r = ctx;
    double wv[3];
    mp_ode_dense_eval(r->c->w->coef, r->c->w->ncoef, r->c->w->n, sf, r->c->ytmp);
    *rho = ev_rho(r->s, r->im, r->c->t + sf * r->c->h, r->c->ytmp, wv);
    return MP_OK;
}

/* Contract: where an impact's g = side (q - wall) has its extremum inside
 * [a, b] of the step: the root of its relative velocity rho = g' (rho(a) and
 * rho(b) of opposite signs) on the interpolant, *sm; g there in *gm. */
static int ev_extremum(const ode_run *s, ev_ctx *c, const mp_impact *im, size_t k, double a,
                       double rho_a, double b, double rho_b, double *sm, double *gm)
{
    ev_rho_ctx rc = {s, c, im};
    int st = mp_ode_event_root(ev_rho_at, &rc, c->t, c->h, a, rho_a, b, rho_b, sm);
    return st != MP_OK ? st : ev_at(c, *sm, k, gm);
}

/* Contract: event k acted at the step's start (or stands at zero there) and
 * is not yet seen before its crossing; at the first sub-point s1 g is still
 * not there (g1).  Did g leave zero and come back within [0, s1]?  For an
 * impact the relative velocity says: leaving (rho > 0 at the start), back
 * (rho < 0 at s1), g's maximum between them.  For another event g is looked
 * at halfway back towards the start, down to a few ulps of t.  *sa (-1:
 * no) is a point where g is before its crossing (ga) and [*sa, *sb] brackets
 * the crossing after it (gb); *sa = -2 when g was not seen to leave but the
 * state was (an impact's rate, or the field f at the start pointing away from
 * the surface, unlike a kick's): a return too small for g to resolve. */
static int ev_returned(ode_run *s, ev_ctx *c, size_t k, double s1, double g1, double *sa,
                       double *ga, double *sb, double *gb);

/* Find every crossing in the accepted step [t, t + h]; s->g_old holds g at t
 * and is updated to g at the step end (first: t is the solve's start).  Sets
 * *s_stop <= 1 when a terminal event fires or an action event crosses (the
 * step is truncated there; *act = the action event's index, else -1; a
 * terminal count reached stops instead, *act = -1, r->stop_reason saying
 * which).  On the first step (first != 0) an event that is exactly zero at t0
 * occurs at t0 when it leaves zero in its direction (any way for direction 0),
 * as SciPy's solve_ivp reports it; a zero at a later step's start is the
 * crossing the step before reported.  An event that acted (or stood at zero
 * where an action restarted the solve) is disarmed: it fires again only after
 * g has been seen on the side its crossing starts from, wherever the wall is
 * (ev_returned looks inside the first sub-interval).  An impact is also
 * crossed where g touches zero between two sub-points (a grazing impact): g's
 * minimum there is found on the interpolant from its velocity. */
static int ev_step(ode_run *s, double t, double h, int first, double *s_stop, long *act);

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
struct ode_run {
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
    double *rho_old, *rho_sub; /* ... an impact's relative velocity where g_old, g_sub are */
    double *rho_end;          /* ... at the step's end */
    unsigned char *inner;     /* ... whether it is needed inside the step (ev_step) */
    double *act_t;            /* per event: the time of its last action (with act_n) */
    long *act_n;              /* per event: its actions applied */
    unsigned char *armed;     /* per event: 0 after it acted, until g is before its crossing */
    mp_ode_problem prob;      /* the problem on its current branch (switches taken) */
    const mp_ode_options *user; /* the caller's options (s->o: with the driver's own events) */
    mp_ode_options swo;       /* ... the options with them: a switch, a lift-off */
    long k_sw, k_lift;        /* their indices in swo (-1: none) */
    int *sw_int;              /* its terminal and direction arrays (2 ne') */
    unsigned char *sw_act;    /* its has_action array (ne') */
    /* resting on a wall: the impact event resting (-1: none), the problem
     * whose f follows the wall (w.p while resting), scratch for f, and an
     * accumulation point to record once the solve passes it (acc_k >= 0) */
    long resting;
    mp_ode_problem rprob;
    double *fscr;
    long acc_k;
    double acc_t;
    long unresolved;          /* an event back at its surface too soon to resolve (-1) */
    const mp_impact **imps;   /* per caller's event: its impact (options' impact_of) */
    const double *wall_p;     /* ... the parameters its moving wall reads */
};

/* ---- events: impacts, crossings, rest ----------------------------------- */

/* event k's impact (a user event the options say is one), or NULL */
static const mp_impact *ev_impact(const ode_run *s, size_t k)
{
    return s->imps && k < s->user->n_events ? s->imps[k] : NULL;
}

/* an impact's velocity relative to its wall at (t, y), side-signed (g' for
 * g = side (q - wall), q' = v); wall[0..2] the wall at t */
static double ev_rho(const ode_run *s, const mp_impact *im, double t, const double *y,
                     double *wall)
{
    mp_impact_wall(im, t, s->wall_p, 1, wall);
    return im->side * (y[im->iv] - wall[1]);
}

static int ev_returned(ode_run *s, ev_ctx *c, size_t k, double s1, double g1, double *sa,
                       double *ga, double *sb, double *gb)
{
    const mp_impact *im = ev_impact(s, k);
    int dk = s->o->direction[k], rc;
    *sa = -1.0;
    if (im) {
        double sm, gm;
        if (!(s->rho_old[k] > 0.0 && s->rho_sub[k] < 0.0)) return MP_OK;
        if ((rc = ev_extremum(s, c, im, k, 0.0, s->rho_old[k], s1, s->rho_sub[k], &sm, &gm)))
            return rc;
        if (before_crossing(gm, dk)) *sa = sm, *ga = gm, *sb = s1, *gb = g1;
        else *sa = -2.0; /* left the wall and came back, too little for g to show */
        return MP_OK;
    }
    /* down to a few ulps of t (not the time resolution: a return found below
     * that is an accumulation, which the action's gap check then ends) */
    double res = 4.0 * DBL_EPSILON * fabs(c->t);
    double sp = s1, gp = g1;
    for (int i = 0; i < 80; i++) {
        double sh = 0.5 * sp, gh;
        if (!(sh * fabs(c->h) > res) || sh == 0.0) break;
        if ((rc = ev_at(c, sh, k, &gh)) != MP_OK) return rc;
        if (before_crossing(gh, dk)) {
            *sa = sh, *ga = gh, *sb = sp, *gb = gp;
            return MP_OK;
        }
        sp = sh, gp = gh;
    }
    /* not seen: did the action send the state away from the surface (along f,
     * the state at s1 would be before the crossing), or through it (a kick)?
     * Away, and back at s1 without g showing it: a return too small to resolve */
    mp_ode_ws *w = &s->w;
    double d = s1 * c->h;
    for (size_t i = 0; i < w->n; i++) c->ytmp[i] = w->y[i] + d * w->f[i];
    if ((rc = s->o->events(c->t + d, c->ytmp, c->gtmp, s->o->events_data)) != MP_OK) return rc;
    if (before_crossing(c->gtmp[k], dk)) *sa = -2.0;
    return MP_OK;
}

/* record a hit of event k at step fraction s */
static void ev_hit_add(ode_run *s, size_t *nh, double sf, size_t k)
{
    s->hits[*nh].s = sf;
    s->hits[*nh].k = k;
    ++*nh;
}

static int ev_step(ode_run *s, double t, double h, int first, double *s_stop, long *act)
{
    mp_ode_ws *w = &s->w;
    mp_ode_result *r = s->r;
    const mp_ode_options *o = s->o;
    size_t ne = o->n_events, nh = 0;
    double *g_old = s->g_old, *g_sub = s->g_sub;
    ev_ctx c = {w, o, t, h, s->ytmp, s->gtmp};
    *s_stop = 2.0;
    *act = -1;
    s->unresolved = -1;
    /* an impact's rate inside the step only where it is read: after an action
     * (ev_returned), or where it turns from approaching to leaving over the
     * step (a minimum inside: grazing) */
    int any_inner = 0;
    for (size_t k = 0; s->imps && k < ne; k++) {
        const mp_impact *im = ev_impact(s, k);
        double wv[3];
        if (!im) continue;
        s->rho_end[k] = ev_rho(s, im, t + h, w->ynew, wv);
        s->inner[k] = !s->armed[k] || (s->rho_old[k] < 0.0 && s->rho_end[k] > 0.0);
        any_inner |= s->inner[k];
    }
    for (int j = 1; j <= MP_ODE_EVENT_SUBDIV; j++) {
        double s0 = (double)(j - 1) / MP_ODE_EVENT_SUBDIV, s1 = (double)j / MP_ODE_EVENT_SUBDIV;
        const double *y1 = w->ynew;
        if (j < MP_ODE_EVENT_SUBDIV) {
            mp_ode_dense_eval(w->coef, w->ncoef, w->n, s1, s->ytmp);
            y1 = s->ytmp;
        }
        int rc = o->events(t + s1 * h, y1, g_sub, o->events_data);
        if (rc != MP_OK) return rc;
        for (size_t k = 0; any_inner && k < ne; k++) { /* before ytmp is overwritten below */
            const mp_impact *im = ev_impact(s, k);
            double wv[3];
            if (im && s->inner[k])
                s->rho_sub[k] = j == MP_ODE_EVENT_SUBDIV ? s->rho_end[k]
                                                         : ev_rho(s, im, t + s1 * h, y1, wv);
        }
        for (size_t k = 0; k < ne; k++) {
            if (!isfinite(g_sub[k])) {
                w->bad_what = MP_ODE_BAD_EVENT;
                w->bad_index = k;
                return MP_ENONFINITE;
            }
            int dk = o->direction[k];
            const mp_impact *im = ev_impact(s, k);
            double root;
            if ((long)k == s->resting) { /* on its wall: g is round-off, never a crossing */
            } else if (first && j == 1 && g_old[k] == 0.0) { /* zero at t0 */
                if (dk == 0 || (dk > 0 ? g_sub[k] >= 0.0 : g_sub[k] <= 0.0))
                    ev_hit_add(s, &nh, 0.0, k);
            } else if (!s->armed[k]) { /* acted: it must leave towards its crossing's start */
                if (before_crossing(g_sub[k], dk)) {
                    s->armed[k] = 1;
                } else if (j == 1) {
                    double sa, ga = 0.0, sb = 0.0, gb = 0.0;
                    if ((rc = ev_returned(s, &c, k, s1, g_sub[k], &sa, &ga, &sb, &gb)))
                        return rc;
                    if (sa >= 0.0) {
                        s->armed[k] = 1;
                        if (crosses(ga, gb, dk)) {
                            if ((rc = ev_root(&c, k, sa, ga, sb, gb, &root)) != MP_OK) return rc;
                            ev_hit_add(s, &nh, root, k);
                        }
                    } else if (sa == -2.0) { /* an accumulation at the step's start */
                        s->unresolved = (long)k;
                        ev_hit_add(s, &nh, 0.0, k);
                    }
                }
            } else if (crosses(g_old[k], g_sub[k], dk)) {
                if ((rc = ev_root(&c, k, s0, g_old[k], s1, g_sub[k], &root)) != MP_OK) return rc;
                ev_hit_add(s, &nh, root, k);
            } else if (im && s->inner[k] && dk <= 0 && g_old[k] > 0.0 && g_sub[k] > 0.0 &&
                       s->rho_old[k] < 0.0 && s->rho_sub[k] > 0.0) {
                /* approaching, then leaving: g's minimum inside may reach the wall */
                double sm, gm;
                if ((rc = ev_extremum(s, &c, im, k, s0, s->rho_old[k], s1, s->rho_sub[k], &sm,
                                      &gm)) != MP_OK)
                    return rc;
                if (gm <= 0.0) {
                    if ((rc = ev_root(&c, k, s0, g_old[k], sm, gm, &root)) != MP_OK) return rc;
                    ev_hit_add(s, &nh, root, k);
                }
            }
            g_old[k] = g_sub[k];
            /* (rho inside the step is read only where inner: set there) */
            if (im) s->rho_old[k] = j == MP_ODE_EVENT_SUBDIV ? s->rho_end[k] : s->rho_sub[k];
        }
    }
    qsort(s->hits, nh, sizeof *s->hits, ev_cmp);
    for (size_t i = 0; i < nh; i++) {
        size_t k = s->hits[i].k;
        double sf = s->hits[i].s;
        mp_ode_dense_eval(w->coef, w->ncoef, w->n, sf, s->ytmp);
        /* the driver's own events (a switch, a lift-off) are not reported */
        int rc = k < r->n_events ? push_event(r, k, t + sf * h, s->ytmp) : MP_OK;
        if (rc != MP_OK) return rc;
        int with_action = o->has_action && o->has_action[k];
        if (o->terminal[k] > 0 && r->ev_count[k] >= (size_t)o->terminal[k]) {
            *s_stop = sf;
            r->stop_reason = with_action ? MP_ODE_STOP_MAX_EVENTS : MP_ODE_STOP_TERMINAL;
            r->stop_event = k;
            r->stop_count = (long)r->ev_count[k];
            break;
        }
        if (with_action) {
            *s_stop = sf;
            *act = (long)k;
            break;
        }
    }
    return MP_OK;
}

/* f of a body resting on impact k's wall: the problem's own f, the
 * coordinate's rate and acceleration the wall's (the contact force acts on
 * that coordinate alone: mp_impact's rest) */
static int rest_rhs(double t, const double *y, double *f, void *data)
{
    ode_run *s = data;
    const mp_impact *im = ev_impact(s, (size_t)s->resting);
    int rc = s->prob.rhs(t, y, f, s->prob.data);
    double wv[3];
    mp_impact_wall(im, t, s->wall_p, 1, wv);
    f[im->iq] = wv[1];
    f[im->iv] = wv[2];
    return rc;
}

/* its Jacobian: the problem's, the two rows of the wall zero */
static int rest_jac(double t, const double *y, double *jac, void *data)
{
    ode_run *s = data;
    const mp_impact *im = ev_impact(s, (size_t)s->resting);
    size_t n = s->w.n;
    int rc = s->prob.jac(t, y, jac, s->prob.data);
    memset(jac + im->iq * n, 0, n * sizeof(double));
    memset(jac + im->iv * n, 0, n * sizeof(double));
    return rc;
}

/* The lift-off's g while resting: the acceleration away from the wall that
 * the body would have without the contact (side-signed, relative to the
 * wall's); the contact force pushes while it is < 0. */
static int lift_g(ode_run *s, double t, const double *y, double *g)
{
    const mp_impact *im = ev_impact(s, (size_t)s->resting);
    int rc = s->prob.rhs(t, y, s->fscr, s->prob.data);
    s->w.nfev++;
    double wv[3];
    mp_impact_wall(im, t, s->wall_p, 1, wv);
    *g = im->side * (s->fscr[im->iv] - wv[2]);
    return rc;
}

/* Contract: the body of impact event k comes to rest on its wall at t (the
 * accumulation t_left later): (q, v) put on the wall, the solve goes on with
 * f following it (rest_rhs) and the lift-off as an event; the rest list
 * records t + t_left, and the event list records the accumulation point once
 * the solve passes it (t_left > 0; accept_step).  MP_OK or MP_ENOMEM. */
static int rest_enter(ode_run *s, size_t k, double t, double t_left)
{
    const mp_impact *im = ev_impact(s, k);
    double wv[3];
    mp_impact_wall(im, t, s->wall_p, 1, wv);
    s->w.y[im->iq] = wv[0];
    s->w.y[im->iv] = wv[1];
    s->resting = (long)k;
    s->rprob = s->prob;
    s->rprob.rhs = rest_rhs;
    s->rprob.jac = s->prob.jac ? rest_jac : NULL;
    s->rprob.data = s;
    s->rprob.blocks = NULL;
    s->rprob.replayable = 0;
    s->w.p = &s->rprob;
    s->o = &s->swo; /* the lift-off among the events */
    if (t_left > 0.0) {
        s->acc_k = (long)k;
        s->acc_t = t + t_left;
    }
    return push_rest(s->r, k, t + t_left);
}

/* Contract: the accumulation point recorded in the event list of the resting
 * impact, at acc_t (<= the step's end t + h; or at t_at when it lifts off
 * first), its state on the interpolant put on the wall.  MP_OK or MP_ENOMEM. */
static int rest_record_accumulation(ode_run *s, double t, double h, double t_at)
{
    const mp_impact *im = ev_impact(s, (size_t)s->acc_k);
    double ta = fmin(s->acc_t, t_at), wv[3];
    mp_ode_dense_eval(s->w.coef, s->w.ncoef, s->w.n, h != 0.0 ? (ta - t) / h : 0.0, s->ytmp);
    mp_impact_wall(im, ta, s->wall_p, 1, wv);
    s->ytmp[im->iq] = wv[0];
    s->ytmp[im->iv] = wv[1];
    int rc = push_event(s->r, (size_t)s->acc_k, ta, s->ytmp);
    s->acc_k = -1;
    return rc;
}

/* Contract: the resting body lifts off at (t, y): (q, v) on the wall, f the
 * problem's own again; the lift-off in the impact's event and rest lists.
 * MP_OK or MP_ENOMEM. */
static int rest_leave(ode_run *s, double t, double *y)
{
    size_t k = (size_t)s->resting;
    const mp_impact *im = ev_impact(s, k);
    double wv[3];
    mp_impact_wall(im, t, s->wall_p, 1, wv);
    y[im->iq] = wv[0];
    y[im->iv] = wv[1];
    int rc = MP_OK;
    if (s->acc_k >= 0) rc = rest_record_accumulation(s, t, 0.0, t);
    s->resting = -1;
    s->w.p = &s->prob;
    s->o = s->k_sw >= 0 ? &s->swo : s->user;
    if (rc == MP_OK) rc = push_event(s->r, k, t, y);
    return rc == MP_OK ? push_rest(s->r, k, t) : rc;
}

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
    size_t ne = s->k_lift >= 0 ? s->swo.n_events : s->o->n_events, nu = s->user->n_events;
    mp_ode_result *r = s->r;
    if (!ne) return MP_OK;
    r->ev_count = calloc(ne, sizeof(size_t));
    r->ev_cap = calloc(ne, sizeof(size_t));
    r->ev_t = calloc(ne, sizeof(double *));
    r->ev_y = calloc(ne, sizeof(double *));
    s->g_old = malloc(7 * ne * sizeof(double));
    s->hits = malloc(ne * MP_ODE_EVENT_SUBDIV * sizeof(ev_hit));
    s->act_n = calloc(ne, sizeof(long));
    s->armed = malloc(2 * ne);
    if (!r->ev_count || !r->ev_cap || !r->ev_t || !r->ev_y || !s->g_old || !s->hits ||
        !s->act_n || !s->armed)
        return MP_ENOMEM;
    memset(s->armed, 1, ne);
    s->act_t = s->g_old + 3 * ne;
    s->g_sub = s->g_old + ne;
    s->gtmp = s->g_sub + ne;
    s->rho_old = s->g_old + 4 * ne;
    s->rho_sub = s->g_old + 5 * ne;
    s->rho_end = s->g_old + 6 * ne;
    s->inner = s->armed + ne;
    memset(s->rho_old, 0, 3 * ne * sizeof(double));
    memset(s->inner, 0, ne);
    if (s->k_lift >= 0 && nu) { /* an impact may rest: its rest list */
        r->rs_count = calloc(nu, sizeof(size_t));
        r->rs_cap = calloc(nu, sizeof(size_t));
        r->rs_t = calloc(nu, sizeof(double *));
        if (!r->rs_count || !r->rs_cap || !r->rs_t) return MP_ENOMEM;
    }
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

/* Contract: g and the impacts' relative velocities at (t, w.y) into g_old and
 * rho_old (a non-finite g is MP_ENONFINITE naming the event).  MP_OK or the
 * failure. */
static int events_at(ode_run *s, double t)
{
    mp_ode_ws *w = &s->w;
    const mp_ode_options *o = s->o;
    int rc = o->events(t, w->y, s->g_old, o->events_data);
    if (rc != MP_OK) return rc;
    for (size_t k = 0; k < o->n_events; k++) {
        const mp_impact *im = ev_impact(s, k);
        double wv[3];
        if (!isfinite(s->g_old[k])) {
            w->bad_what = MP_ODE_BAD_EVENT;
            w->bad_index = k;
            return MP_ENONFINITE;
        }
        if (im) s->rho_old[k] = ev_rho(s, im, t, w->y, wv);
    }
    return MP_OK;
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
    if (ne && (rc = events_at(s, t0)) != MP_OK) return rc;
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

/* Contract: whether impact event k's body, just after its action at t (the
 * state before it in s->ytmp, after it in w->y), comes to rest on the wall
 * (mp_ode_impact_rests: the force pushes it into the wall and the flights
 * left are below resolution); *t_left the time to the accumulation.  f(t, y)
 * is left in w->f, *pushed = whether the force pushes the body back into the
 * wall.  1 rests, 0 not, or a negative failure status. */
static int impact_rests(ode_run *s, size_t k, double t, double *t_left, int *pushed)
{
    mp_ode_ws *w = &s->w;
    const mp_impact *im = ev_impact(s, k);
    double wv[3];
    int rc = mp_ode_ws_rhs(w, t, w->y, w->f);
    if (rc != MP_OK) return -rc;
    double rho = ev_rho(s, im, t, w->y, wv), rho_in = -ev_rho(s, im, t, s->ytmp, wv);
    double e = rho_in > 0.0 ? rho / rho_in : 1.0;
    double a = im->side * (w->f[im->iv] - wv[2]);
    *pushed = a < 0.0;
    double x = fmax(fabs(wv[0]), fabs(w->y[im->iq]));
    return mp_ode_impact_rests(t, w->t_start, rho, a, e, x,
                               mp_ode_weight(w->o->atol[im->iq], w->o->rtolv[im->iq], x), t_left);
}

/* Contract: event k's action at (s->t, w->y), the state just before it (also
 * in s->ytmp): the action replaces y in place (a non-finite value is
 * MP_ENONFINITE, naming the action), the state after it is a sample (with no
 * t_eval), and the integration restarts there: f(t, y), g(t, y), the
 * controller and the first step afresh (a fixed-step method counts its steps
 * from t), the method's history forgotten; event k, and any event standing at
 * zero there, disarmed (ev_step).  An impact whose flights left cannot be
 * resolved (impact_rests) puts its body to rest on the wall (rest_enter), or
 * where it may not rest (mp_impact's rest) ends the solve there as an
 * accumulation (Zeno) does; the lift-off event takes it off again.  An action
 * that leaves the state where event k fires again at once (two actions within
 * the root finder's tolerance) is MP_EEVENT; crossings accumulating (Zeno:
 * the gap between two actions below the time resolution) end the solve at
 * that point, as a terminal event does (r->stop_reason MP_ODE_STOP_ZENO), or
 * put an impact's body to rest.  MP_OK or the failure. */
static int apply_action(ode_run *s, size_t k)
{
    mp_ode_ws *w = &s->w;
    mp_ode_result *r = s->r;
    const mp_ode_options *o = s->o;
    size_t n = w->n, ne = o->n_events;
    double t = s->t;
    const mp_impact *im = ev_impact(s, k);
    long was_resting = s->resting;
    int rc, zeno = 0;
    double gap = 0.0, t_left = 0.0;
    if (s->unresolved == (long)k) { /* back at once, too little to resolve: accumulated */
        rc = MP_TERMINATED;
    } else {
        rc = mp_ode_action_gap(t, s->act_t[k], s->act_n[k], w->t_start, s->h, &gap);
        if (rc == MP_EEVENT) {
            r->stop_event = k;
            return rc;
        }
    }
    s->unresolved = -1;
    if (rc != MP_OK) r->stop_event = k;
    zeno = rc == MP_TERMINATED;
    if (zeno && !(im && im->rest)) {
        r->stop_reason = MP_ODE_STOP_ZENO;
        r->stop_count = (long)r->ev_count[k];
        r->zeno_gap = gap;
        r->terminated = 1;
        return MP_OK;
    }
    if ((long)k == s->k_lift) rc = rest_leave(s, t, w->y);
    else rc = o->action(t, w->y, k, o->action_data);
    if (rc != MP_OK) return rc;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(w->y[i])) {
            w->bad_what = MP_ODE_BAD_ACTION;
            w->bad_index = k;
            return MP_ENONFINITE;
        }
    s->act_t[k] = t;
    s->act_n[k]++;
    int rest = 0;
    if (im) {
        int pushed = 0;
        rest = impact_rests(s, k, t, &t_left, &pushed);
        if (rest < 0) return -rest;
        rest |= zeno && pushed; /* impacts closer than the time resolution, pushed back */
        if ((rest && !im->rest) || (zeno && !rest)) { /* an accumulation, no rest: the end */
            r->stop_event = k;
            r->stop_reason = MP_ODE_STOP_ZENO;
            r->stop_count = (long)r->ev_count[k];
            r->zeno_gap = gap;
            r->terminated = 1;
            r->n_actions++;
            return o->n_eval == 0 ? push_sample(r, t, w->y) : MP_OK;
        }
        if (rest && (rc = rest_enter(s, k, t, t_left)) != MP_OK) return rc;
    }
    if (k < r->n_events) { /* an event's action: the state before and after are samples */
        r->n_actions++;
        if (o->n_eval == 0 && (rc = push_sample(r, t, w->y)) != MP_OK) return rc;
    } else if ((long)k == s->k_sw && o->n_eval == 0) { /* a switch: the sample at its time
                                                         * is the state after it */
        memcpy(r->y + (r->m - 1) * n, w->y, n * sizeof(double));
    }
    /* restart from (t, y): as at the start, the history forgotten (f is
     * impact_rests' where it did not move y) */
    if (!(im && !rest) && (rc = mp_ode_ws_rhs(w, t, w->y, w->f)) != MP_OK) return rc;
    if ((rc = events_at(s, t)) != MP_OK) return rc;
    for (size_t q = 0; q < ne; q++) /* left on its surface, or past it: disarmed */
        if ((q == k || s->g_old[q] == 0.0) && !before_crossing(s->g_old[q], o->direction[q]))
            s->armed[q] = 0;
    if ((long)k == s->k_lift && was_resting >= 0) s->armed[was_resting] = 0;
    s->c = mp_ode_ctl_start();
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
    if (s->resting >= 0) { /* resting: (q, v) exactly on the wall at the step's end */
        const mp_impact *im = ev_impact(s, (size_t)s->resting);
        double wv[3];
        mp_impact_wall(im, tnew, s->wall_p, 1, wv);
        w->ynew[im->iq] = wv[0];
        w->ynew[im->iv] = wv[1];
    }
    if (o->n_events && (rc = ev_step(s, t, h, r->nsteps == 0, &s_stop, &act)) != MP_OK)
        return rc;
    double tend = s_stop <= 1.0 ? t + s_stop * h : tnew;
    if ((rc = output_step(r, o, w, t, h, tnew, tend, &s->ie, s->ytmp)) != MP_OK) return rc;
    if (s->acc_k >= 0 && s->acc_t <= tend &&
        (rc = rest_record_accumulation(s, t, h, tend)) != MP_OK)
        return rc;
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
    free(s->armed);
    free(s->fscr);
    free(s->imps);
}

/* The events of a solve with the driver's own: the caller's events, then the
 * switch's g (1 once no switch is ahead), then the lift-off's (-1 while no
 * body rests on a wall). */
static int drv_events(double t, const double *y, double *g, void *data)
{
    ode_run *s = data;
    size_t ne = s->user->n_events;
    if (ne) {
        int rc = s->user->events(t, y, g, s->user->events_data);
        if (rc != MP_OK) return rc;
    }
    if (s->k_sw >= 0) g[s->k_sw] = s->prob.sw ? s->prob.sw->g(t, y, s->prob.data) : 1.0;
    if (s->k_lift >= 0) {
        if (s->resting < 0) g[s->k_lift] = -1.0;
        else return lift_g(s, t, y, &g[s->k_lift]);
    }
    return MP_OK;
}

/* The caller's actions, or the switch's: its act, then the branch after it.
 * (The lift-off's is apply_action's rest_leave.) */
static int drv_action(double t, double *y, size_t k, void *data)
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

/* Contract: s->o with the driver's own events after the caller's: a switch
 * of the problem ahead (downwards, with an action, never terminal, not
 * reported) and, when an impact may rest on its wall, the lift-off (upwards:
 * the contact force would pull).  The caller's options themselves when there
 * is neither.  MP_OK or MP_ENOMEM (freed by free_run). */
static int driver_options(ode_run *s)
{
    const mp_ode_options *o = s->user;
    size_t ne = o->n_events, nd = 0;
    int can_rest = 0;
    if (o->impact_of && ne) {
        if (!(s->imps = malloc(ne * sizeof *s->imps))) return MP_ENOMEM;
        for (size_t k = 0; k < ne; k++) {
            s->imps[k] = o->impact_of(k, &s->wall_p, o->events_data);
            can_rest |= s->imps[k] && s->imps[k]->rest && o->has_action && o->has_action[k];
        }
    }
    s->k_sw = s->prob.sw ? (long)(ne + nd++) : -1;
    s->k_lift = can_rest ? (long)(ne + nd++) : -1;
    if (!nd) return MP_OK;
    size_t nt = ne + nd;
    s->sw_int = malloc(2 * nt * sizeof(int));
    s->sw_act = calloc(nt, 1);
    if (!s->sw_int || !s->sw_act) return MP_ENOMEM;
    if (can_rest && !(s->fscr = malloc(s->prob.n * sizeof(double)))) return MP_ENOMEM;
    for (size_t k = 0; k < ne; k++) {
        s->sw_int[k] = o->terminal[k];
        s->sw_int[nt + k] = o->direction[k];
        s->sw_act[k] = o->has_action ? o->has_action[k] : 0;
    }
    for (size_t k = ne; k < nt; k++) {
        s->sw_int[k] = 0;
        s->sw_int[nt + k] = (long)k == s->k_sw ? -1 : +1;
        s->sw_act[k] = 1;
    }
    s->swo = *o;
    s->swo.n_events = nt;
    s->swo.events = drv_events;
    s->swo.events_data = s;
    s->swo.terminal = s->sw_int;
    s->swo.direction = s->sw_int + nt;
    s->swo.has_action = s->sw_act;
    s->swo.action = drv_action;
    s->swo.action_data = s;
    /* the lift-off alone is looked for only while a body rests (rest_enter):
     * until then the caller's events as they are */
    if (s->k_sw >= 0) s->o = &s->swo;
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
    s.resting = s.acc_k = s.unresolved = -1;
    rc = driver_options(&s); /* a switch ahead, a lift-off: crossed as events */
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
    on.impact_of = NULL; /* backwards an impact is a general event: v is not g' in s */
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
