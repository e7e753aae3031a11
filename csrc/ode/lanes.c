/* The lane driver: MP_LANES trajectories of an ensemble in lock-step lanes of
 * one vectorised explicit Runge-Kutta step (dopri5, dop853, rk4).
 *
 * Each lane runs driver.c's loop for one trajectory: the step-size policy is
 * the one both drivers call (control.h: Hairer's first step, the controller
 * with the method row's constants, rejection of non-finite trial stages, the
 * step-size floor, the last step, the stiffness test, the error norm); the
 * budget, t_eval output from the method's interpolant and the statuses are
 * the driver's; only the stages are done MP_LANES lanes at a time.  A lane whose
 * trajectory ends takes the next one before the next step.
 *
 * This file is compiled twice (csrc/meson.build): with -mavx2 -mfma as
 * mp_ode_lanes_run_avx2 and portable as mp_ode_lanes_run_base; MP_LANES_RUN
 * names the build. */
#include "ode/lanes.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ode/control.h"
#include "ode/dop853_tableau.h"
#include "ode/dopri5_tableau.h"
#include "ode/fixed.h"

#ifndef MP_LANES_RUN
#error "MP_LANES_RUN names this build of the lane driver (csrc/meson.build)"
#endif

#define W MP_LANES
#define LANES_INTERRUPT_EVERY 256 /* lock-step attempts between interrupt polls */

/* the row's lane kernel (ode.h's MP_LANE_*) */
enum { LANE_RK4 = MP_LANE_RK4, LANE_DOPRI5 = MP_LANE_DOPRI5, LANE_DOP853 = MP_LANE_DOP853 };

/* One thread's lane group: the SoA workspace and each lane's driver state. */
typedef struct {
    const mp_ode_method *m;
    int kind, adaptive;
    const mp_ode_problem *probs;
    const mp_lane_system *ls;
    const mp_ode_options *o;
    const mp_lane_feed *feed;
    size_t k, n, nW, nt;
    double dir, s0, sf, hmax; /* the solve runs in s = dir t, s0 < sf */
    const double *y0s, *sev;  /* sev: t_eval in s */
    double *yout;
    mp_ode_outcome *out;
    mp_ode_result *results;   /* with impacts: each trajectory's event lists */
    size_t nimp;              /* impacts (ls->n_impacts) */
    double *g_old, *act_t;    /* per impact and lane [q * W + l]: g at t, the last action */
    double *rho_old;          /* ... g's rate dg/ds at t */
    long *act_n;              /* ... the actions applied */
    long *armed;              /* ... 0 after it acted, until g > 0 is seen (driver.c's) */
    double *y, *ynew, *f, *fnew, *kbuf, *coef, *par, *gy, *gf;
    int stop, exhausted;
    /* per lane */
    int active[W];
    size_t idx[W], ie[W], bad_index[W];
    double t[W], h[W];
    double tz[W];             /* where the lane's fixed steps are counted from (t0, an action) */
    long nfix[W];             /* ... and how many it took since */
    int first[W];             /* the lane's first step: a zero of g at t0 is an event there */
    long act_k[W];            /* an impact that acted: which, and the rate it arrived at */
    double rho_in[W];
    long attempts[W], nfev[W];
    mp_ode_ctl ctl[W]; /* each lane's controller (control.h) */
    int stiff[W], bad_what[W];
} lane_group;

/* ---- evaluation ------------------------------------------------------------ */

/* Contract: each lane's scalar problem at (t[l], lane l of y) into lane l
 * of f, for the lanes in on; st[l] its status. */
static void lane_eval_generic(lane_group *g, const double *t, const double *y, double *f,
                              const int *on, int *st)
{
    size_t n = g->n;
    for (int l = 0; l < W; l++) {
        if (!on[l]) continue;
        const mp_ode_problem *p = &g->probs[g->idx[l]];
        for (size_t c = 0; c < n; c++) g->gy[c] = y[c * W + l];
        st[l] = p->rhs(t[l], g->gy, g->gf, p->data);
        for (size_t c = 0; c < n; c++) f[c * W + l] = g->gf[c];
    }
}

/* Contract: f = f(dir s, y) (times dir) for the lanes with on[l]: through the
 * scene's lane rhs, else each lane's scalar problem (gather, call, scatter).
 * Counts nfev per lane; rc[l] = the lane's status, MP_ENONFINITE (recording
 * the component) for a NaN or inf, as mp_ode_ws_rhs does.  A lane that fails
 * is taken out of on. */
static inline void lane_eval(lane_group *g, const double *s, const double *y, double *f,
                             int *on, int *rc)
{
    double tn[W];
    uint64_t probe[W] = {0};
    const double *t = s; /* t = dir s: s itself forwards */
    int st[W], fails = 0, nonfinite = 0;
    size_t n = g->n;
    MP_LANE_LOOP st[l] = MP_OK;
    if (g->dir < 0) {
        MP_LANE_LOOP tn[l] = -s[l];
        t = tn;
    }
    if (g->ls->rhs) g->ls->rhs(t, y, f, g->par, st);
    else lane_eval_generic(g, t, y, f, on, st);
    if (g->dir < 0)
        for (size_t i = 0; i < g->nW; i++) f[i] = -f[i];
    for (size_t c = 0; c < g->nW; c += W) /* bit 63: some value not finite (ode.h) */
        MP_LANE_LOOP probe[l] |= mp_ode_nonfinite_bit(f[c + l]);
    MP_LANE_LOOP {
        g->nfev[l] += on[l];
        rc[l] = on[l] ? st[l] : rc[l];
        fails |= st[l];
        nonfinite |= (int)(probe[l] >> 63);
    }
    if (fails == 0 && !nonfinite) return; /* all well */
    for (int l = 0; l < W; l++) {
        if (!on[l]) continue;
        if (st[l] == MP_OK && probe[l] >> 63)
            for (size_t c = 0; c < n; c++)
                if (!isfinite(f[c * W + l])) {
                    g->bad_what[l] = MP_ODE_BAD_RHS;
                    g->bad_index[l] = c;
                    st[l] = MP_ENONFINITE;
                    break;
                }
        rc[l] = st[l];
        if (st[l] != MP_OK) on[l] = 0;
    }
}

/* Contract: driver.c's check of a step's new state, for lane l: a NaN or inf
 * in it is the lane's MP_ENONFINITE (MP_ODE_BAD_STATE, naming the first such
 * component). */
static void lane_check_state(lane_group *g, int l, int *rc)
{
    size_t c = mp_ode_first_nonfinite_at(g->ynew + l, g->n, W);
    if (c < g->n) {
        g->bad_what[l] = MP_ODE_BAD_STATE;
        g->bad_index[l] = c;
        *rc = MP_ENONFINITE;
    }
}

/* out = y + h sum_j a[j] K[j] over the non-zero a[j], lane by lane (the scalar
 * stage_point's order of operations).  Always inlined with a constant row. */
static inline __attribute__((always_inline)) void
lane_stage(size_t nW, const double *y, const double *h, const double *a, double *const *K,
           size_t ns, double *out)
{
    for (size_t c = 0; c < nW; c += W) {
        double sum[W] = {0.0};
#pragma GCC unroll 16
        for (size_t j = 0; j < ns; j++)
            if (a[j] != 0.0) {
                MP_LANE_LOOP sum[l] += a[j] * K[j][c + l];
            }
        MP_LANE_LOOP out[c + l] = y[c + l] + h[l] * sum[l];
    }
}

/* out[l] = sum_j w[j] K[j][c + l] over the non-zero w[j] (constant rows fold). */
static inline __attribute__((always_inline)) void
lane_dot(const double *w, double *const *K, size_t ns, size_t c, double *out)
{
    MP_LANE_LOOP out[l] = 0.0;
#pragma GCC unroll 16
    for (size_t j = 0; j < ns; j++)
        if (w[j] != 0.0) {
            MP_LANE_LOOP out[l] += w[j] * K[j][c + l];
        }
}

/* ---- output and the end of a lane -------------------------------------------- */

/* Contract: column j of trajectory idx[l]'s (n, nt) block = lane l of the SoA
 * vector v. */
static void lane_sample(lane_group *g, int l, size_t j, const double *v)
{
    double *dst = g->yout + g->idx[l] * g->n * g->nt;
    for (size_t c = 0; c < g->n; c++) dst[c * g->nt + j] = v[c * W + l];
}

/* Contract: lane l's trajectory ends with status st at its current time
 * (reason, k, gap: events that ended it, as mp_ode_result's stop_reason):
 * its outcome, NaN for the samples not reached, the lane idle; then the
 * feed's done (a stop request sets g->stop). */
static void lane_end_ev(lane_group *g, int l, int st, int reason, size_t k, double gap)
{
    size_t i = g->idx[l];
    long count = g->results && reason ? (long)g->results[i].ev_count[k] : 0, acts = 0;
    for (size_t q = 0; q < g->nimp; q++) acts += g->act_n[q * W + (size_t)l];
    g->out[i] = (mp_ode_outcome){.status = st, .stiff = g->stiff[l], .bad_what = g->bad_what[l],
                                 .bad_index = g->bad_index[l], .t_fail = g->dir * g->t[l],
                                 .nfev = g->nfev[l], .stop_reason = reason, .stop_event = k,
                                 .n_actions = acts, .stop_count = count, .zeno_gap = gap};
    double *dst = g->yout + i * g->n * g->nt;
    for (size_t j = g->ie[l]; j < g->nt; j++)
        for (size_t c = 0; c < g->n; c++) dst[c * g->nt + j] = NAN;
    g->active[l] = 0;
    if (g->feed->done(g->feed->ctx, i) != 0) g->stop = 1;
}

/* Contract: lane l's trajectory ends with status st at its current time:
 * its outcome, NaN for the samples not reached, the lane idle; then the
 * feed's done (a stop request sets g->stop). */
static void lane_end(lane_group *g, int l, int st) { lane_end_ev(g, l, st, 0, 0, 0.0); }

/* Component c of lane l's interpolant at step fraction s (mp_ode_dense_eval's
 * form). */
static double lane_interp(const lane_group *g, int l, size_t c, double s)
{
    size_t nc = g->m->ncoef, nW = g->nW, o = c * W + (size_t)l;
    double s1 = 1.0 - s, acc = g->coef[(nc - 1) * nW + o];
    for (size_t q = nc - 1; q-- > 0;) acc = g->coef[q * nW + o] + ((q % 2 == 0) ? s : s1) * acc;
    return acc;
}

/* impact im's wall for lane l at s (time dir s): w[0..2] (its parameters
 * the lane's, at stride W) */
static inline __attribute__((always_inline)) void lane_wall(const lane_group *g, int l,
                                                            const mp_impact *im, double s,
                                                            double *w)
{
    mp_impact_wall(im, g->dir * s, g->par + l, W, w);
}

/* Contract: the t_eval samples of lane l's accepted step [t, t + h] ending at
 * tnew (or cut at tend < tnew by an event, exact_end 0): the step end itself
 * exactly, the others from the interpolant in coef (mp_ode_dense_eval's form,
 * lane by lane). */
static inline __attribute__((always_inline)) void lane_output(lane_group *g, int l, double h,
                                                             double tnew, int exact_end)
{
    size_t nc = g->m->ncoef, nW = g->nW;
    for (; g->ie[l] < g->nt && g->sev[g->ie[l]] <= tnew; g->ie[l]++) {
        size_t j = g->ie[l];
        double te = g->sev[j];
        double *dst = g->yout + g->idx[l] * g->n * g->nt;
        if (te == tnew && exact_end) {
            lane_sample(g, l, j, g->ynew);
            continue;
        }
        double s = (te - g->t[l]) / h, s1 = 1.0 - s;
        for (size_t c = 0; c < g->n; c++) {
            size_t o = c * W + (size_t)l;
            double acc = g->coef[(nc - 1) * nW + o];
            for (size_t q = nc - 1; q-- > 0;) acc = g->coef[q * nW + o] + ((q % 2 == 0) ? s : s1) * acc;
            dst[c * g->nt + j] = acc;
        }
    }
}

/* ---- the start of a trajectory ----------------------------------------------- */

/* Contract: Hairer's first step (control.h's hinit, driver.c's first_step)
 * for the lanes in on, whose y and f = f(s0, y) are set: h[l], or the lane
 * ends with the failure of its explicit Euler trial. */
static void lane_first_step(lane_group *g, int *on)
{
    size_t n = g->n;
    const mp_ode_options *o = g->o;
    double dnf[W] = {0}, ts[W], span[W];
    int pend[W], rc[W], ev[W];
    for (int l = 0; l < W; l++) { /* from the lane's time: the start, or an action's */
        pend[l] = on[l];
        span[l] = g->sf - g->t[l];
        if (on[l])
            g->h[l] = mp_ode_hinit_trial(o, n, W, g->y + l, g->f + l, g->hmax, span[l], &dnf[l]);
    }
    for (int tries = 0;; tries++) { /* an explicit Euler trial that overflows: shorter */
        int any = 0;
        for (int l = 0; l < W; l++) {
            ev[l] = pend[l];
            if (!pend[l]) continue;
            any = 1;
            while (g->t[l] + g->h[l] > g->sf) g->h[l] = nextafter(g->h[l], 0.0);
            for (size_t c = 0; c < n; c++)
                g->ynew[c * W + l] = g->y[c * W + l] + g->h[l] * g->f[c * W + l];
            ts[l] = g->t[l] + g->h[l];
        }
        if (!any) break;
        lane_eval(g, ts, g->ynew, g->fnew, ev, rc);
        for (int l = 0; l < W; l++) {
            if (!pend[l]) continue;
            if (rc[l] != MP_ENONFINITE || tries == 20) {
                pend[l] = 0;
                if (rc[l] != MP_OK) {
                    on[l] = 0;
                    lane_end(g, l, rc[l]);
                }
            } else {
                g->h[l] *= 0.1;
            }
        }
    }
    for (int l = 0; l < W; l++)
        if (on[l])
            g->h[l] = mp_ode_hinit_final(o, n, W, g->y + l, g->f + l, g->fnew + l, g->h[l],
                                         dnf[l], g->m->order, g->hmax, span[l]);
}

/* Contract: the lanes in fresh have just been given trajectories idx[l]:
 * their state, parameters and driver state from the start, f(s0, y0), the
 * samples at t0 and the first step; a lane that fails there ends. */
static void lane_start(lane_group *g, int *fresh)
{
    size_t n = g->n, np = g->ls->np;
    int rc[W], on[W];
    double ts[W];
    for (int l = 0; l < W; l++) {
        on[l] = fresh[l];
        ts[l] = g->s0;
        if (!fresh[l]) continue;
        size_t i = g->idx[l];
        const double *y0 = g->y0s + i * n, *row = g->ls->params + i * g->ls->pstride;
        for (size_t j = 0; j < np; j++) g->par[j * W + l] = row[j];
        g->t[l] = g->tz[l] = g->s0;
        g->nfix[l] = 0;
        g->first[l] = 1;
        g->ie[l] = 0;
        g->attempts[l] = g->nfev[l] = 0;
        for (size_t q = 0; q < g->nimp; q++) {
            const mp_impact *im = &g->ls->impacts[q];
            size_t a = q * W + (size_t)l;
            double wv[3];
            lane_wall(g, l, im, g->s0, wv);
            g->g_old[a] = mp_impact_g(im, y0[im->iq], wv[0]);
            g->rho_old[a] = g->dir * im->side * (y0[im->iv] - wv[1]);
            g->act_n[a] = 0;
            g->armed[a] = 1;
        }
        if (g->results && mp_ode_result_events_init(&g->results[i], n, g->nimp) != MP_OK)
            g->stop = 1; /* out of memory: the group stops (MP_EINTR's path) */
        g->ctl[l] = mp_ode_ctl_start();
        g->stiff[l] = g->bad_what[l] = 0;
        g->bad_index[l] = 0;
        int finite = 1;
        for (size_t c = 0; c < n; c++) {
            g->y[c * W + l] = y0[c];
            finite &= isfinite(y0[c]) != 0;
        }
        if (!finite) {
            on[l] = 0;
            lane_end(g, l, MP_EDOM);
        }
    }
    lane_eval(g, ts, g->y, g->fnew, on, rc); /* fnew: f of the running lanes stays */
    for (int l = 0; l < W; l++) {
        if (!fresh[l]) continue;
        if (g->active[l] && !on[l]) lane_end(g, l, rc[l]);
        if (!on[l]) continue;
        for (size_t c = 0; c < n; c++) g->f[c * W + l] = g->fnew[c * W + l];
        for (; g->ie[l] < g->nt && g->sev[g->ie[l]] <= g->s0; g->ie[l]++)
            lane_sample(g, l, g->ie[l], g->y);
        if (!g->adaptive) g->h[l] = g->o->h;
        else if (g->o->first_step > 0) g->h[l] = g->o->first_step;
    }
    if (g->adaptive && !(g->o->first_step > 0)) lane_first_step(g, on);
    for (int l = 0; l < W; l++)
        if (on[l]) g->h[l] = fmin(g->h[l], g->hmax);
}

/* ---- the methods' steps -------------------------------------------------------- */

/* Hairer's stiffness estimate h |lambda| from two stages at one time, for the
 * lanes in on (rho of the others is left as it is): rk.c's stiffness_ratio,
 * the same sums in the same order, every lane at once. */
static void lanes_rho(const lane_group *g, const int *on, const double *fa, const double *fb,
                      const double *a, const double *b, double *rho)
{
    double num[W] = {0.0}, den[W] = {0.0};
    for (size_t c = 0; c < g->nW; c += W)
        MP_LANE_LOOP {
            double df = fa[c + l] - fb[c + l], dy = a[c + l] - b[c + l];
            num[l] += df * df;
            den[l] += dy * dy;
        }
    MP_LANE_LOOP {
        double r = den[l] > 0.0 ? fabs(g->h[l]) * sqrt(num[l] / den[l]) : 0.0;
        rho[l] = on[l] ? r : rho[l];
    }
}

/* Contract (every lane step): one attempt of the lanes in on from (t, y, f)
 * with steps h into ynew; rc[l] the lane's failure, err[l] its scaled error
 * norm, rho[l] its stiffness estimate (0: none). */
static void rk4_lanes(lane_group *g, int *on, int *rc, double *err, double *rho)
{
    size_t nW = g->nW;
    double *k2 = g->kbuf, *k3 = k2 + nW, *k4 = k3 + nW, *yt = k4 + nW, ts[W], hh[W];
    const double *y = g->y, *k1 = g->f;
    for (int l = 0; l < W; l++) {
        ts[l] = g->t[l] + 0.5 * g->h[l];
        hh[l] = 0.5 * g->h[l];
        err[l] = rho[l] = 0.0;
    }
    for (size_t i = 0; i < nW; i++) yt[i] = y[i] + hh[i % W] * k1[i];
    lane_eval(g, ts, yt, k2, on, rc);
    for (size_t i = 0; i < nW; i++) yt[i] = y[i] + hh[i % W] * k2[i];
    lane_eval(g, ts, yt, k3, on, rc);
    for (int l = 0; l < W; l++) ts[l] = g->t[l] + g->h[l];
    for (size_t i = 0; i < nW; i++) yt[i] = y[i] + g->h[i % W] * k3[i];
    lane_eval(g, ts, yt, k4, on, rc);
    for (size_t i = 0; i < nW; i++)
        g->ynew[i] = y[i] + (g->h[i % W] / 6.0) * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
}

/* The stage vectors of a dopri5 or dop853 step (kind) in kbuf: K[0] = f,
 * the FSAL stage (dopri5's 7th, dop853's 13th) fnew, dop853's three dense
 * output stages after it.  Inlined with a constant kind. */
static inline __attribute__((always_inline)) void lane_K(const lane_group *g, int kind,
                                                          double **K)
{
    int dp = kind == LANE_DOPRI5;
    size_t nW = g->nW, last = dp ? 6 : 12, all = dp ? 7 : 16;
    K[0] = g->f;
    for (size_t s = 1; s < all; s++) K[s] = g->kbuf + (s < last ? s - 1 : s - 2) * nW;
    K[last] = g->fnew;
}

/* Contract: stage s of a tableau (row a, node c) for the lanes in on: yt =
 * y + h sum_j a[j] K[j], then K[s] = f(t + c h, yt).  Always inlined: with a
 * constant row the zero tests of lane_stage fold. */
static inline __attribute__((always_inline)) void
lane_rk_stage(lane_group *g, const double *a, double c, double *const *K, size_t s, double *yt,
              int *on, int *rc)
{
    double ts[W];
    lane_stage(g->nW, g->y, g->h, a, K, s, yt);
    for (int l = 0; l < W; l++) ts[l] = g->t[l] + c * g->h[l];
    lane_eval(g, ts, yt, K[s], on, rc);
}

static void dopri5_lanes(lane_group *g, int *on, int *rc, double *err, double *rho)
{
    size_t nW = g->nW;
    double *K[7], *yt = g->kbuf + 5 * nW, ts[W];
    lane_K(g, LANE_DOPRI5, K);
    lane_rk_stage(g, dp_a[1], dp_c[1], K, 1, yt, on, rc);
    lane_rk_stage(g, dp_a[2], dp_c[2], K, 2, yt, on, rc);
    lane_rk_stage(g, dp_a[3], dp_c[3], K, 3, yt, on, rc);
    lane_rk_stage(g, dp_a[4], dp_c[4], K, 4, yt, on, rc);
    lane_rk_stage(g, dp_a[5], dp_c[5], K, 5, yt, on, rc);
    lane_stage(nW, g->y, g->h, dp_a[6], K, 6, g->ynew);
    for (int l = 0; l < W; l++) ts[l] = g->t[l] + g->h[l];
    lane_eval(g, ts, g->ynew, K[6], on, rc); /* FSAL */
    lanes_rho(g, on, K[6], K[5], g->ynew, yt, rho); /* stages 6, 7 both at t + h */
    for (size_t c = 0; c < nW; c += W) {
        double e[W];
        lane_dot(dp_e, K, 7, c, e);
        MP_LANE_LOOP yt[c + l] = g->h[l] * e[l];
    }
    for (int l = 0; l < W; l++)
        if (on[l]) err[l] = mp_ode_rms_norm(g->o, g->n, W, yt + l, g->y + l, g->ynew + l);
}

static void dop853_lanes(lane_group *g, int *on, int *rc, double *err, double *rho)
{
    size_t nW = g->nW, n = g->n;
    double *K[16], *yt = g->kbuf + 14 * nW;
    lane_K(g, LANE_DOP853, K);
#define D8(s) lane_rk_stage(g, mp_dop853_a[s], mp_dop853_c[s], K, s, yt, on, rc)
    D8(1); D8(2); D8(3); D8(4); D8(5); D8(6); D8(7); D8(8); D8(9); D8(10); D8(11);
#undef D8
    lane_stage(nW, g->y, g->h, mp_dop853_b, K, 12, g->ynew);
    double e5s[W] = {0.0}, e3s[W] = {0.0};
    for (size_t c = 0; c < n; c++) {
        double e5[W], e3[W], at = g->o->atol[c], rtol = g->o->rtolv[c];
        const double *y = g->y + c * W, *y1 = g->ynew + c * W;
        lane_dot(mp_dop853_e5, K, 12, c * W, e5);
        lane_dot(mp_dop853_e3, K, 12, c * W, e3);
        MP_LANE_LOOP {
            double sk = mp_ode_weight(at, rtol, mp_ode_absmax(y[l], y1[l])); /* y finite: running */
            double r = 1.0 / sk, q5 = e5[l] * r, q3 = e3[l] * r;
            e5s[l] += q5 * q5;
            e3s[l] += q3 * q3;
        }
    }
    for (int l = 0; l < W; l++) {
        double deno = e5s[l] + 0.01 * e3s[l];
        if (deno <= 0.0) deno = 1.0;
        err[l] = fabs(g->h[l]) * e5s[l] / sqrt(deno * (double)n);
        rho[l] = 0.0;
    }
}

/* Contract (every lane finish): for the accepted lanes in on, fnew = f(t + h,
 * ynew) and, for those with dense[l], the interpolant in coef; rc[l] a lane's
 * failure, rho[l] its stiffness estimate where the finish makes it. */
static void finish_lanes(lane_group *g, int *on, const int *dense, int *rc, double *rho)
{
    size_t nW = g->nW;
    double ts[W];
    int any_dense = 0, dn[W];
    for (int l = 0; l < W; l++) {
        ts[l] = g->t[l] + g->h[l];
        dn[l] = on[l] && dense[l];
        any_dense |= dn[l];
    }
    double *c = g->coef;
    if (g->kind == LANE_DOPRI5) { /* fnew is stage 7 */
        if (!any_dense) return;
        double *K[7];
        lane_K(g, LANE_DOPRI5, K);
        for (size_t b = 0; b < nW; b += W) {
            double d[W];
            lane_dot(dp_d, K, 7, b, d);
            MP_LANE_LOOP {
                size_t i = b + (size_t)l;
                double h = g->h[l], dy = g->ynew[i] - g->y[i], c3 = h * K[0][i] - dy;
                c[i] = g->y[i];
                c[nW + i] = dy;
                c[2 * nW + i] = c3;
                c[3 * nW + i] = dy - h * K[6][i] - c3;
                c[4 * nW + i] = h * d[l];
            }
        }
        return;
    }
    lane_eval(g, ts, g->ynew, g->fnew, on, rc);
    if (g->kind == LANE_RK4) {
        if (!any_dense) return;
        for (size_t i = 0; i < nW; i++) { /* mp_ode_dense_hermite, lane by lane */
            double h = g->h[i % W], dy = g->ynew[i] - g->y[i], c3 = h * g->f[i] - dy;
            c[i] = g->y[i];
            c[nW + i] = dy;
            c[2 * nW + i] = c3;
            c[3 * nW + i] = dy - h * g->fnew[i] - c3;
        }
        return;
    }
    double *K[16], *yt = g->kbuf + 14 * nW;
    lane_K(g, LANE_DOP853, K);
    lanes_rho(g, on, K[12], K[11], g->ynew, yt, rho);
    any_dense = 0;
    for (int l = 0; l < W; l++) {
        dn[l] = on[l] && dense[l];
        any_dense |= dn[l];
    }
    if (!any_dense) return;
    for (size_t s = 13; s < 16; s++)
        lane_rk_stage(g, mp_dop853_a[s], mp_dop853_c[s], K, s, yt, dn, rc);
    for (size_t b = 0; b < nW; b += W) {
        MP_LANE_LOOP {
            size_t i = b + (size_t)l;
            double h = g->h[l], dy = g->ynew[i] - g->y[i];
            c[i] = g->y[i];
            c[nW + i] = dy;
            c[2 * nW + i] = h * K[0][i] - dy;
            c[3 * nW + i] = 2.0 * dy - h * (K[12][i] + K[0][i]);
        }
#pragma GCC unroll 4
        for (int r = 0; r < 4; r++) {
            double d[W];
            lane_dot(mp_dop853_d[r], K, 16, b, d);
            MP_LANE_LOOP c[(size_t)(4 + r) * nW + b + (size_t)l] = g->h[l] * d[l];
        }
    }
    for (int l = 0; l < W; l++) /* a dense stage that failed ends its lane */
        if (on[l] && dense[l] && !dn[l]) on[l] = 0;
}

/* ---- the controller and one lock-step attempt ------------------------------------ */

/* ---- impacts ------------------------------------------------------------------------ */

/* impact q's g (or its rate dg/ds) on lane l's interpolant at step fraction s */
typedef struct {
    const lane_group *g;
    int l;
    const mp_impact *im;
} lane_g_ctx;

static int lane_g_at(void *ctx, double s, double *gs)
{
    const lane_g_ctx *c = ctx;
    double wv[3];
    lane_wall(c->g, c->l, c->im, c->g->t[c->l] + s * c->g->h[c->l], wv);
    *gs = mp_impact_g(c->im, lane_interp(c->g, c->l, c->im->iq, s), wv[0]);
    return MP_OK;
}

static int lane_rho_at(void *ctx, double s, double *rs)
{
    const lane_g_ctx *c = ctx;
    double wv[3];
    lane_wall(c->g, c->l, c->im, c->g->t[c->l] + s * c->g->h[c->l], wv);
    *rs = c->g->dir * c->im->side * (lane_interp(c->g, c->l, c->im->iv, s) - wv[1]);
    return MP_OK;
}

/* Contract: g's extremum inside [a, b] (its rate ra, rb of opposite signs) on
 * lane l's interpolant: *sm and g there, *gm (driver.c's ev_extremum). */
static void lane_extremum(lane_g_ctx *c, double a, double ra, double b, double rb, double *sm,
                          double *gm)
{
    const lane_group *g = c->g;
    *sm = b; /* lane_rho_at cannot fail: the root is always set */
    mp_ode_event_root(lane_rho_at, c, g->t[c->l], g->h[c->l], a, ra, b, rb, sm);
    lane_g_at(c, *sm, gm);
}

/* Contract: the first crossing of impact q in lane l's accepted step, as
 * driver.c's ev_step finds it (sub-points, disarmed after an action until
 * g > 0 is seen or its maximum inside the first sub-interval is, a grazing
 * minimum from g's rate): its step fraction, or 2 for none.  Updates q's g,
 * rate and armed state to the step's end. */
static double lane_crossing(lane_group *g, int l, size_t q)
{
    const mp_impact *im = &g->ls->impacts[q];
    lane_g_ctx c = {g, l, im};
    size_t a = q * W + (size_t)l;
    double g0 = g->g_old[a], r0 = g->rho_old[a], hit = 2.0, t = g->t[l], h = g->h[l];
    double g_end, r_end, we[3];
    lane_wall(g, l, im, t + h, we);
    g_end = mp_impact_g(im, g->ynew[im->iq * W + (size_t)l], we[0]);
    r_end = g->dir * im->side * (g->ynew[im->iv * W + (size_t)l] - we[1]);
    /* the rate inside the step only where it is read (driver.c's ev_step) */
    int inner = !g->armed[a] || (r0 < 0.0 && r_end > 0.0);
    for (int j = 1; j <= MP_ODE_EVENT_SUBDIV; j++) {
        double s0 = (double)(j - 1) / MP_ODE_EVENT_SUBDIV, s1 = (double)j / MP_ODE_EVENT_SUBDIV;
        double g1 = g_end, r1 = r_end, wv[3], root = s1, sm, gm;
        if (j < MP_ODE_EVENT_SUBDIV) {
            lane_wall(g, l, im, t + s1 * h, wv);
            g1 = mp_impact_g(im, lane_interp(g, l, im->iq, s1), wv[0]);
            r1 = inner ? g->dir * im->side * (lane_interp(g, l, im->iv, s1) - wv[1]) : NAN;
        }
        if (hit > 1.0) {
            if (g->first[l] && j == 1 && g0 == 0.0) {
                if (g1 <= 0.0) hit = 0.0;
            } else if (!g->armed[a]) {
                if (g1 > 0.0) {
                    g->armed[a] = 1;
                } else if (j == 1 && r0 > 0.0 && r1 < 0.0) { /* back within it? */
                    lane_extremum(&c, 0.0, r0, s1, r1, &sm, &gm);
                    if (gm > 0.0) {
                        g->armed[a] = 1;
                        mp_ode_event_root(lane_g_at, &c, t, h, sm, gm, s1, g1, &root);
                        hit = root;
                    }
                }
            } else if (g0 > 0.0 && g1 <= 0.0) {
                mp_ode_event_root(lane_g_at, &c, t, h, s0, g0, s1, g1, &root);
                hit = root;
            } else if (inner && g0 > 0.0 && g1 > 0.0 && r0 < 0.0 && r1 > 0.0) { /* grazing */
                lane_extremum(&c, s0, r0, s1, r1, &sm, &gm);
                if (gm <= 0.0) {
                    mp_ode_event_root(lane_g_at, &c, t, h, s0, g0, sm, gm, &root);
                    hit = root;
                }
            }
        }
        g0 = g1;
        r0 = r1;
    }
    g->g_old[a] = g0;
    g->rho_old[a] = r0;
    return hit;
}

/* Contract: the impacts of lane l's accepted step [t, t + h] ending at tnew,
 * as driver.c's events and actions do them: the first crossing
 * (lane_crossing); the samples up to it, the state just before it in the
 * trajectory's event list; then max_events or a re-firing at once end the
 * lane, and an accumulation (Zeno) ends it or, for an impact that may rest,
 * hands the trajectory to the scalar path (MP_ODE_STOP_TO_SCALAR: solved
 * again there); else the action, and the lane is left at the impact with its
 * state after it, to restart (lane_restart).  Returns 1 when the lane
 * restarts there, 2 when it ended, 0 when no impact cut the step (the
 * impacts' g moved to the step end). */
__attribute__((noinline, cold)) static int lane_impacts(lane_group *g, int l, double tnew)
{
    size_t n = g->n, i = g->idx[l];
    double t = g->t[l], h = g->h[l], s_hit = 2.0;
    size_t k_hit = 0;
    for (size_t q = 0; q < g->nimp; q++) {
        double s = lane_crossing(g, l, q);
        if (s < s_hit) {
            s_hit = s;
            k_hit = q;
        }
    }
    g->first[l] = 0;
    if (s_hit > 1.0) return 0;
    double tend = s_hit >= 1.0 ? tnew : t + s_hit * h;
    lane_output(g, l, h, tend, 0);
    for (size_t c = 0; c < n; c++) g->gy[c] = lane_interp(g, l, c, s_hit);
    g->t[l] = tend;
    const mp_impact *im = &g->ls->impacts[k_hit];
    size_t a = k_hit * W + (size_t)l;
    if (g->results &&
        mp_ode_result_push_event(&g->results[i], k_hit, g->dir * tend, g->gy) != MP_OK) {
        g->stop = 1;
        return 2;
    }
    if (im->max_events > 0 && g->results &&
        g->results[i].ev_count[k_hit] >= (size_t)im->max_events) {
        for (size_t c = 0; c < n; c++) g->y[c * W + (size_t)l] = g->gy[c];
        lane_end_ev(g, l, MP_TERMINATED, MP_ODE_STOP_MAX_EVENTS, k_hit, 0.0);
        return 2;
    }
    double gap = 0.0, wv[3];
    int st = mp_ode_action_gap(tend, g->act_t[a], g->act_n[a], g->s0, h, &gap);
    if (st != MP_OK) {
        for (size_t c = 0; c < n; c++) g->y[c * W + (size_t)l] = g->gy[c];
        int scalar = st == MP_TERMINATED && im->rest && g->dir > 0.0;
        lane_end_ev(g, l, scalar ? MP_OK : st,
                    scalar ? MP_ODE_STOP_TO_SCALAR : st == MP_TERMINATED ? MP_ODE_STOP_ZENO : 0,
                    k_hit, gap);
        return 2;
    }
    double p_e = im->e_param >= 0 ? g->par[(size_t)im->e_param * W + (size_t)l] : 0.0;
    lane_wall(g, l, im, tend, wv);
    g->rho_in[l] = -g->dir * im->side * (g->gy[im->iv] - wv[1]);
    mp_impact_apply(im, mp_impact_e(im, i, p_e), wv, g->gy, 1);
    for (size_t c = 0; c < n; c++) g->y[c * W + (size_t)l] = g->gy[c];
    for (size_t q = 0; q < g->nimp; q++) {
        const mp_impact *iq = &g->ls->impacts[q];
        size_t b = q * W + (size_t)l;
        lane_wall(g, l, iq, tend, wv);
        g->g_old[b] = mp_impact_g(iq, g->gy[iq->iq], wv[0]);
        g->rho_old[b] = g->dir * iq->side * (g->gy[iq->iv] - wv[1]);
        if ((q == k_hit || g->g_old[b] == 0.0) && !(g->g_old[b] > 0.0)) g->armed[b] = 0;
    }
    g->act_t[a] = tend;
    g->act_n[a]++;
    g->act_k[l] = (long)k_hit;
    return 1;
}

/* Contract: the lanes in act, left at an impact with their state after it
 * (lane_impacts), restart there as driver.c's apply_action restarts a solve:
 * f afresh, the controller and the first step afresh, fixed steps counted
 * from the impact; a lane whose f fails ends, and one whose body comes to rest
 * on the wall (mp_ode_impact_rests, as driver.c's impact_rests decides it) is
 * handed to the scalar path. */
__attribute__((noinline, cold)) static void lane_restart(lane_group *g, int *act)
{
    int rc[W];
    double ts[W];
    for (int l = 0; l < W; l++) ts[l] = g->t[l];
    lane_eval(g, ts, g->y, g->fnew, act, rc);
    for (int l = 0; l < W; l++) {
        if (!act[l]) continue;
        if (rc[l] != MP_OK) {
            lane_end(g, l, rc[l]);
            act[l] = 0;
            continue;
        }
        const mp_impact *im = &g->ls->impacts[g->act_k[l]];
        size_t b = (size_t)g->act_k[l] * W + (size_t)l;
        double wv[3], t_left;
        lane_wall(g, l, im, g->t[l], wv);
        double rho = g->rho_old[b], rin = g->rho_in[l], e = rin > 0.0 ? rho / rin : 1.0;
        double acc = im->side * (g->fnew[im->iv * W + (size_t)l] - wv[2]);
        double x = fmax(fabs(wv[0]), fabs(g->y[im->iq * W + (size_t)l]));
        double xtol = mp_ode_weight(g->o->atol[im->iq], g->o->rtolv[im->iq], x);
        if (g->dir > 0.0 &&
            mp_ode_impact_rests(g->t[l], g->s0, rho, acc, e, x, xtol, &t_left)) { /* driver.c's */
            lane_end_ev(g, l, MP_OK, MP_ODE_STOP_TO_SCALAR, (size_t)g->act_k[l], 0.0);
            act[l] = 0;
            continue;
        }
        for (size_t c = 0; c < g->n; c++) g->f[c * W + l] = g->fnew[c * W + l];
        g->ctl[l] = mp_ode_ctl_start();
        g->tz[l] = g->t[l];
        g->nfix[l] = 0;
        if (!g->adaptive) g->h[l] = g->o->h;
        else if (g->o->first_step > 0) g->h[l] = g->o->first_step;
    }
    if (g->adaptive && !(g->o->first_step > 0)) lane_first_step(g, act);
    for (int l = 0; l < W; l++)
        if (act[l]) {
            g->h[l] = fmin(g->h[l], fmin(g->o->max_step, g->sf - g->t[l]));
            if (!(g->t[l] < g->sf)) lane_end(g, l, MP_OK);
        }
}

/* Contract: one attempted step of every active lane, as one iteration of
 * driver.c's loop for each: budget, last step, step floor, the step, control,
 * finish, stiffness test, output, advance; a lane that ends calls lane_end. */
static void lane_attempt(lane_group *g)
{
    int on[W], rc[W], last[W] = {0}, acc[W], dense[W] = {0}, act[W] = {0};
    double err[W] = {0.0}, rho[W], hnew[W] = {0.0}, tnew[W] = {0.0};
    for (int l = 0; l < W; l++) {
        on[l] = g->active[l];
        rc[l] = MP_OK;
        acc[l] = 0;
        rho[l] = 0.0;
        if (!on[l]) continue;
        if (g->attempts[l] >= g->o->max_steps) {
            on[l] = 0;
            lane_end(g, l, MP_EMAXSTEPS);
            continue;
        }
        g->attempts[l]++;
        int below = g->adaptive && mp_ode_step_floor(&g->ctl[l], g->t[l], g->o->max_step, &g->h[l]);
        g->h[l] = mp_ode_step_span(g->adaptive, g->t[l], g->h[l], g->sf, &last[l]);
        if (below && !last[l]) {
            on[l] = 0;
            lane_end(g, l, g->ctl[l].nonfinite ? MP_ENONFINITE : MP_ESTEP);
        }
    }
    int att[W];
    memcpy(att, on, sizeof att);
    if (g->kind == LANE_DOPRI5) dopri5_lanes(g, on, rc, err, rho);
    else if (g->kind == LANE_DOP853) dop853_lanes(g, on, rc, err, rho);
    else rk4_lanes(g, on, rc, err, rho);
    double fac11[W], fold[W], expo = g->m->expo, beta = g->m->beta; /* the controller's powers */
    if (g->adaptive) {
        if (expo == MP_ODE_ROOT8_EXPO) { /* control.h's mp_ode_err_pow, lane by lane */
            MP_LANE_LOOP fac11[l] = mp_ode_root8(err[l]);
        } else {
            MP_LANE_LOOP fac11[l] = mp_lane_pow(err[l], expo);
        }
        if (beta > 0.0) {
            MP_LANE_LOOP fold[l] = mp_lane_pow(g->ctl[l].facold, beta);
        } else {
            MP_LANE_LOOP fold[l] = 1.0;
        }
    }
    for (int l = 0; l < W; l++) {
        if (!att[l]) continue;
        if (rc[l] == MP_OK) lane_check_state(g, l, &rc[l]);
        if (rc[l] == MP_ENONFINITE && g->adaptive) { /* a trial stage or the state overflowed */
            g->h[l] = mp_ode_control_nonfinite(&g->ctl[l], g->h[l]);
            continue;
        }
        if (rc[l] != MP_OK) {
            lane_end(g, l, rc[l]);
            continue;
        }
        if (g->adaptive &&
            !mp_ode_control(g->m, &g->ctl[l], err[l], fac11[l], fold[l], &g->h[l], &hnew[l])) {
            if (g->ctl[l].nonfinite) { /* err overflowed: f and y are finite (driver.c) */
                g->bad_what[l] = MP_ODE_BAD_ERR;
                g->bad_index[l] = 0;
            }
            continue;
        }
        acc[l] = 1;
        /* a fixed step's end is counted, as driver.c counts it: t0 + (i + 1) h, from
         * the start or the last action */
        tnew[l] = last[l]      ? g->sf
                : g->adaptive ? g->t[l] + g->h[l]
                              : mp_ode_fixed_time(g->tz[l], g->nfix[l] + 1, g->h[l]);
        dense[l] = g->nimp > 0 || (g->ie[l] < g->nt && g->sev[g->ie[l]] < tnew[l]);
    }
    memcpy(on, acc, sizeof on);
    finish_lanes(g, on, dense, rc, rho);
    for (int l = 0; l < W; l++) {
        if (!acc[l]) continue;
        if (!on[l]) {
            lane_end(g, l, rc[l]);
            continue;
        }
        if (rho[l] > 0.0) /* Hairer's stiffness test */
            mp_ode_stiffness_test(&g->ctl[l], rho[l], g->m->stiff_rho, &g->stiff[l]);
        int cut = g->nimp ? lane_impacts(g, l, tnew[l]) : 0;
        if (cut) {
            act[l] = cut == 1; /* cut at an impact: the lane restarts there (below) */
            continue;
        }
        lane_output(g, l, g->h[l], tnew[l], 1);
        for (size_t c = 0; c < g->n; c++) {
            size_t i = c * W + (size_t)l;
            g->y[i] = g->ynew[i];
            g->f[i] = g->fnew[i];
        }
        g->t[l] = tnew[l];
        g->nfix[l]++;
        /* fmin(next, hmax) as a select (fmin is a call in this loop): the same value,
         * both being positive and finite */
        double hn = g->adaptive ? hnew[l] : g->o->h;
        g->h[l] = hn < g->hmax ? hn : g->hmax;
        if (!(g->t[l] < g->sf)) lane_end(g, l, MP_OK);
    }
    int any = 0;
    for (int l = 0; l < W; l++) any |= act[l];
    if (any) lane_restart(g, act);
}

/* ---- the group's loop --------------------------------------------------------------- */

/* Contract: give every idle lane the next trajectory and start it, until the
 * lanes are full or the feed has none left. */
static void lane_refill(lane_group *g)
{
    for (;;) {
        int fresh[W] = {0}, any = 0;
        for (int l = 0; l < W && !g->exhausted && !g->stop; l++) {
            if (g->active[l]) continue;
            size_t i = g->feed->take(g->feed->ctx);
            if (i >= g->k) {
                g->exhausted = 1;
                break;
            }
            g->idx[l] = i;
            g->active[l] = fresh[l] = any = 1;
        }
        if (!any) return;
        lane_start(g, fresh);
    }
}

int MP_LANES_RUN(const mp_ode_method *m, const mp_ode_problem *probs, const mp_lane_system *ls,
                 size_t k, double t0, double tf, const double *y0s, const mp_ode_options *o,
                 double *yout, mp_ode_outcome *out, mp_ode_result *results,
                 const mp_lane_feed *feed)
{
    lane_group g;
    memset(&g, 0, sizeof g);
    g.m = m;
    g.kind = m->lanes;
    g.adaptive = m->adaptive;
    g.probs = probs;
    g.ls = ls;
    g.o = o;
    g.feed = feed;
    g.k = k;
    g.n = probs[0].n;
    g.nW = g.n * W;
    g.nt = o->n_eval;
    g.dir = tf < t0 ? -1.0 : 1.0;
    g.s0 = g.dir * t0;
    g.sf = g.dir * tf;
    g.hmax = fmin(o->max_step, g.sf - g.s0);
    g.y0s = y0s;
    g.yout = yout;
    g.out = out;
    g.nimp = ls->n_impacts;
    g.results = g.nimp ? results : NULL;
    size_t nvec = 4 + m->nscratch + m->ncoef;
    double *buf = calloc(nvec * g.nW + ls->np * W + g.nt + 2 * g.n + 3 * g.nimp * W,
                         sizeof(double));
    long *acts = g.nimp ? calloc(2 * g.nimp * W, sizeof(long)) : NULL;
    if (!buf || (g.nimp && !acts)) {
        free(buf);
        free(acts);
        return MP_ENOMEM;
    }
    g.act_n = acts;
    g.y = buf;
    g.ynew = g.y + g.nW;
    g.f = g.ynew + g.nW;
    g.fnew = g.f + g.nW;
    g.kbuf = g.fnew + g.nW;
    g.coef = g.kbuf + m->nscratch * g.nW;
    g.par = g.coef + m->ncoef * g.nW;
    double *sev = g.par + ls->np * W;
    g.gy = sev + g.nt;
    g.gf = g.gy + g.n;
    g.g_old = g.gf + g.n;
    g.act_t = g.g_old + g.nimp * W;
    g.rho_old = g.act_t + g.nimp * W;
    g.armed = acts ? acts + g.nimp * W : NULL;
    for (size_t j = 0; j < g.nt; j++) sev[j] = g.dir * o->t_eval[j];
    g.sev = sev;
    long iter = 0;
    for (;;) {
        lane_refill(&g);
        if (g.stop) break;
        int any = 0;
        for (int l = 0; l < W; l++) any |= g.active[l];
        if (!any) break;
        if (++iter % LANES_INTERRUPT_EVERY == 0 && feed->interrupt(feed->ctx) != MP_OK) {
            g.stop = 1;
            break;
        }
        lane_attempt(&g);
        if (g.stop) break;
    }
    free(buf);
    free(acts);
    return g.stop ? MP_EINTR : MP_OK;
}
