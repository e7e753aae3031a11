/* mechpy integrator engine: one problem type, one driver loop, a table of methods.
 *
 * A method is one `const mp_ode_method` row (REBOUND's integrator table):
 * adding a method is adding one file and one row in methods.c, never another
 * copy of the driver loop (driver.c).  Workspaces are allocated once per solve
 * and freed on every path; nothing here is global and mutable. */
#ifndef MP_ODE_H
#define MP_ODE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "mp_status.h"

/* Right-hand side dy/dt = f(t, y).  Returns MP_OK or a status that stops the
 * solve (MP_ECALLBACK when a user callback failed, ...). */
typedef int (*mp_ode_rhs)(double t, const double *y, double *dydt, void *data);
/* Jacobian df/dy, row-major n x n: jac[i*n + j] = d f_i / d y_j. */
typedef int (*mp_ode_jac)(double t, const double *y, double *jac, void *data);
/* All event functions at once: g[k] = g_k(t, y). */
typedef int (*mp_ode_events)(double t, const double *y, double *g, void *data);
/* An event's action: at the located crossing of event k the state y (n
 * values) is replaced in place, and the integration restarts from it.
 * MP_OK or a status that stops the solve. */
typedef int (*mp_ode_action)(double t, double *y, size_t k, void *data);
/* A wall that moves: w[0], w[1], w[2] = its position, velocity and
 * acceleration at t, for the trajectory's parameters p[j * ps] (a SymPy
 * expression of t printed as C and compiled with the system). */
typedef void (*mp_wall_fn)(double t, const double *p, size_t ps, double *w);

/* An impact (mechpy.events.impact), the one event the engine knows by value
 * (so that it runs without the GIL, and in the SIMD lanes): the event
 * g = side (y[iq] - wall(t)), and its action y[iq] = wall(t),
 * y[iv] - wall'(t) = -e (y[iv] - wall'(t)) (the coordinate exactly at the
 * wall, its velocity relative to the wall reflected and scaled by the
 * restitution).  The wall stands at `wall`, or moves as wall_fn says.  e is
 * the trajectory's parameter e_param (>= 0), else its row e_rows[i] (one per
 * trajectory of an ensemble), else the constant e.  max_events > 0 ends a
 * trajectory at that crossing (a terminal count; the lanes' own, the scalar
 * path has the options' terminal).  rest = 1: the coordinate's acceleration
 * is not coupled to the other coordinates' (no mass-matrix term between
 * them), so that it may rest on the wall with a contact force acting on it
 * alone (the driver's resting mode); 0: an accumulation ends the solve. */
typedef struct mp_impact {
    size_t iq, iv;
    double wall, side, e;
    const double *e_rows;
    long e_param;
    int max_events;
    mp_wall_fn wall_fn;
    int rest;
} mp_impact;

/* Contract: the wall of im at t into w[0..2] (position, velocity,
 * acceleration), p the trajectory's parameters at stride ps (read only by a
 * moving wall). */
static inline void mp_impact_wall(const mp_impact *im, double t, const double *p, size_t ps,
                                  double *w)
{
    if (im->wall_fn) {
        im->wall_fn(t, p, ps, w);
        return;
    }
    w[0] = im->wall;
    w[1] = w[2] = 0.0;
}

/* The impact's g for the coordinate's value x, the wall at wall. */
static inline double mp_impact_g(const mp_impact *im, double x, double wall)
{
    return im->side * (x - wall);
}

/* The impact's restitution for trajectory i with parameter e_param's value
 * p_e (read only when e_param >= 0). */
static inline double mp_impact_e(const mp_impact *im, size_t i, double p_e)
{
    return im->e_param >= 0 ? p_e : im->e_rows ? im->e_rows[i] : im->e;
}

/* The impact's action on a state whose component c is y[c * stride], the
 * wall w[0..2] (mp_impact_wall) at the impact's time. */
static inline void mp_impact_apply(const mp_impact *im, double e, const double *w, double *y,
                                   size_t stride)
{
    y[im->iv * stride] = w[1] - e * (y[im->iv * stride] - w[1]);
    y[im->iq * stride] = w[0];
}

/* Interrupt check, called every few hundred steps; non-zero stops the solve. */
typedef int (*mp_ode_interrupt)(void *ctx);

/* A scene's own fixed-step blocks (ode/fixed.h's MP_ODE_BLOCKS): the
 * method rows' blocks with `rhs` inlined.  They serve a problem only while
 * its rhs is this one (a wrapper that replaces rhs leaves them unused). */
typedef struct mp_ode_blocks {
    mp_ode_rhs rhs;
    /* k rk4 steps in place, step j from t0 + (i0 + j) h, as ode/fixed.h's
     * mp_ode_rk4_steps */
    int (*rk4)(void *data, double t0, long i0, double h, long k, double *y, double *f,
               double *ts, double *ys);
    /* k steps of the composition c[0..ns), as mp_ode_compose_steps, lo the
     * state's low-order part or NULL (uncompensated) (compose NULL: rhs is
     * not separable) */
    int (*compose)(void *data, double t0, long i0, double h, const double *c, int ns, long k,
                   double *y, double *lo, double *f, double *ts, double *ys, double *discarded);
} mp_ode_blocks;

/* A switch of a problem's right-hand side: a scene's discontinuity that the
 * engine crosses (a rocket's burn-out).  When g(t, y) reaches 0 from above
 * (located as an event: no step straddles it) the action act replaces the
 * state in place (may be NULL), and the problem continues with rhs and jac,
 * and with the switch next (NULL: none).  A state with g <= 0 is already past
 * the switch (mp_ode_problem_at).  g and act take the problem's data. */
typedef struct mp_ode_switch {
    double (*g)(double t, const double *y, const void *data);
    void (*act)(double t, double *y, const void *data);
    mp_ode_rhs rhs;
    mp_ode_jac jac;
    const struct mp_ode_switch *next;
} mp_ode_switch;

typedef struct mp_ode_problem {
    size_t n;         /* dimension */
    mp_ode_rhs rhs;
    mp_ode_jac jac;   /* optional: NULL means finite differences where needed */
    void *data;       /* handed to rhs and jac */
    /* Second-order split for symplectic methods: when nq > 0 the state is
     * (q[nq], v[nq]) with q' = v and v' = a(t, q) independent of v, so the
     * second half of rhs(t, (q, v)) is the acceleration.  0: not separable. */
    size_t nq;
    /* jac returns the same matrix everywhere (SciPy's array jac): it is not
     * counted as an evaluation (njev), as SciPy counts none. */
    int jac_const;
    /* rhs is plain C with no side effects (no Python, no state of its own):
     * calling it again at the same point gives the same values, so the
     * fixed-step fast path may run a block of steps unchecked and replay it
     * checked.  0: every stage is checked as it comes. */
    int replayable;
    /* optional: the scene's own fixed-step blocks (used while rhs is theirs) */
    const mp_ode_blocks *blocks;
    /* optional: the switch ahead (NULL: none); rhs and jac are the branch
     * before it */
    const mp_ode_switch *sw;
    /* optional: the Jacobian's band (SciPy's jac_sparsity, LSODA's lband and
     * uband): when banded, df_i/dy_j is zero for i - j > ml and for j - i > mu,
     * i and j counted in the order perm gives (the states perm[0], perm[1],
     * ...: a bandwidth-reducing order, reverse Cuthill-McKee's; NULL: their
     * own).  Finite differences then perturb columns ml + mu + 1 apart
     * together (mp_ode_ws_jac), and radau factorises in band form where that
     * is the cheaper (an analytic Jacobian's entries outside the band are not
     * read there).  0: dense. */
    int banded;
    size_t ml, mu;
    const size_t *perm;
} mp_ode_problem;

/* Contract: the problem p on the branch of the state (t, y): the switches it is
 * past (g <= 0) taken, without their actions (a state given past a switch is
 * where it is). */
void mp_ode_problem_at(mp_ode_problem *p, double t, const double *y);

typedef struct mp_ode_options {
    double rtol;              /* > 0: the least of rtolv (Newton's and GSL's one tolerance) */
    const double *rtolv;      /* n relative tolerances > 0 (SciPy's per-component rtol) */
    const double *atol;       /* n values >= 0 */
    double first_step;        /* 0: Hairer's automatic guess */
    double max_step;          /* may be inf */
    double h;                 /* step of fixed-step methods */
    long max_steps;           /* budget of attempted steps */
    const double *t_eval;     /* ordered along the integration, inside the interval, or NULL */
    size_t n_eval;
    int dense;                /* keep every step's interpolant */
    size_t n_events;
    mp_ode_events events;
    void *events_data;
    const int *terminal;      /* per event: 0 never, k > 0 stop at the k-th occurrence */
    const int *direction;     /* per event: -1, 0, +1 (SciPy's meaning) */
    /* per event: 1 when it has an action (NULL: none has).  An action event
     * replaces the state at each crossing and the integration restarts there;
     * its terminal count k > 0 (max_events) ends the solve at the k-th crossing,
     * the action not applied. */
    const unsigned char *has_action;
    mp_ode_action action;
    void *action_data;
    /* event k's impact when it is one (NULL: a general event), *params the
     * trajectory's parameters that a moving wall reads; events_data is the
     * trajectory's.  NULL: no event is an impact.  With it the driver knows
     * g' (no grazing crossing is missed), which way g leaves the wall after
     * an action, and when a body rests on it. */
    const mp_impact *(*impact_of)(size_t k, const double **params, void *events_data);
    mp_ode_interrupt interrupt;
    void *interrupt_ctx;
} mp_ode_options;

/* What produced a non-finite value (mp_ode_result.bad_what). */
enum {
    MP_ODE_BAD_RHS = 0,    /* f gave NaN or inf */
    MP_ODE_BAD_EVENT = 1,  /* an event function did */
    MP_ODE_BAD_JAC = 2,    /* the Jacobian did */
    MP_ODE_BAD_ACTION = 3, /* an event's action did */
    MP_ODE_BAD_STATE = 4,  /* a step's new state did, f being finite (an f bounded at inf) */
    MP_ODE_BAD_ERR = 5     /* a step's scaled norm overflowed, its inputs being finite */
};

/* Why events ended a solve (mp_ode_result.stop_reason): a terminal event; an
 * action event's count (max_events); its crossings accumulating (Zeno: the
 * solve ends at the accumulation point, as at a terminal event). */
enum { MP_ODE_STOP_NONE = 0, MP_ODE_STOP_TERMINAL, MP_ODE_STOP_MAX_EVENTS, MP_ODE_STOP_ZENO,
       MP_ODE_STOP_TO_SCALAR /* a lane's body came to rest: solved again on the scalar path */ };

/* Growable output storage of one solve.  Freed by mp_ode_result_free. */
typedef struct mp_ode_result {
    int status;               /* MP_OK or the failure */
    int terminated;           /* a terminal event ended the solve */
    long nfev, njev, nlu, nsteps, nreject;
    int stiff;                /* Hairer's stiffness test fired on an explicit method */
    long nswitch;             /* method switches of a switching row */
    double t_fail;            /* where a failure happened */
    int bad_what;             /* MP_ENONFINITE: MP_ODE_BAD_RHS, _EVENT, ... (above) */
    size_t bad_index;         /* ... and the component (or event) that was not finite */
    int stop_reason;          /* a terminal or action event ended it (MP_ODE_STOP_*) */
    size_t stop_event;        /* ... which event (and, for MP_EEVENT, the one re-firing) */
    long n_actions;           /* actions applied (every event) */
    long stop_count;          /* the stopping event's crossings */
    double zeno_gap;          /* MP_ODE_STOP_ZENO: the last two crossings' distance in t */
    int backward;             /* t0 > tf: times are t, dense segments are in s = -t */
    size_t n;
    /* samples: rows of (t, y[n]); with t_eval these are the t_eval points reached */
    size_t m, mcap;
    double *t, *y;
    /* dense output: segment k covers [seg_t[k], seg_t[k] + seg_h[k]] */
    size_t ncoef, nseg, segcap;
    double *seg_t, *seg_h, *seg_c; /* seg_c: nseg blocks of ncoef * n */
    /* events: per event function, its crossing times and states */
    size_t n_events;
    size_t *ev_count, *ev_cap;
    double **ev_t, **ev_y;
    /* per impact event, where it rested: the times it came to rest on the
     * wall and lifted off, alternating (an odd count: resting at the end);
     * NULL when no event can rest */
    size_t *rs_count, *rs_cap;
    double **rs_t;
} mp_ode_result;

/* How a solve ended: what the binding turns into a status and a message. */
typedef struct mp_ode_outcome {
    int status;       /* MP_OK, MP_TERMINATED (a terminal event) or the failure */
    int stiff;        /* Hairer's stiffness test fired */
    int bad_what;     /* MP_ENONFINITE: see mp_ode_result */
    size_t bad_index;
    double t_fail;    /* where it failed */
    long nfev;
    int stop_reason;  /* see mp_ode_result */
    size_t stop_event;
    long n_actions, stop_count;
    double zeno_gap;
} mp_ode_outcome;

/* The outcome of a finished solve. */
void mp_ode_result_outcome(const mp_ode_result *r, mp_ode_outcome *out);

typedef struct mp_ode_ws mp_ode_ws;

/* The lane kernels of the lane driver (lanes.c): a method row names the one
 * that runs its step MP_LANES trajectories at a time, or none. */
enum { MP_LANE_NONE = 0, MP_LANE_RK4, MP_LANE_DOPRI5, MP_LANE_DOP853 };

/* One integration method: a row of the table in methods.c. */
typedef struct mp_ode_method {
    const char *name;
    int order;          /* classical order of the propagated solution */
    int adaptive;       /* has an error estimate (else fixed step h) */
    int implicit;
    int symplectic;
    int needs_jacobian; /* uses df/dy (analytic or finite differences) */
    int compensated;    /* its updates of the state are compensated sums (ode/fixed.h's
                           mp_ode_sum_add), the state's low-order part in ws->lo */
    int dense_order;    /* order of its interpolant */
    int lanes;          /* its lane kernel (MP_LANE_*): ensembles run it in SIMD lanes;
                           MP_LANE_NONE: one trajectory at a time */
    int rigid;          /* a rigid-body splitting: runs on the RigidBody scene only (its
                           steps are the scene's exact free rotations) */
    int scalar_rtol;    /* takes one rtol, not one per component (GSL's control scales
                           its error by a single eps_rel) */
    size_t ncoef;       /* coefficient vectors of the interpolant */
    size_t nscratch;    /* n-vectors of scratch the step needs */
    /* step-size controller (Hairer): expo = 1/(q+1), beta (PI), bounds, safety */
    double expo, beta, fac_min, fac_max, safety;
    int self_controlled;  /* takes its own accepted steps (GSL evolve); sets ws->h_next */
    double stiff_rho;     /* explicit methods: h|lambda| of their stability boundary */
    const void *extra;    /* method data (e.g. the GSL step type) */
    int (*alloc)(mp_ode_ws *w);   /* optional per-solve state */
    void (*free)(mp_ode_ws *w);
    /* One attempt from (t, y, f) with step h into ynew; *err is the scaled
     * error norm (<= 1 accepts) for adaptive methods. */
    int (*step)(mp_ode_ws *w, double t, double h, double *err);
    /* After acceptance: fnew = f(t + h, ynew) when the method or the dense
     * output needs it, and the interpolant's coefficients when need_dense. */
    int (*finish)(mp_ode_ws *w, double t, double h, int need_dense);
    /* Optional, for a fixed-step row whose steps depend on (t, h, y, f) alone:
     * k steps of size h from (w->y, w->f) in place, step j from the counted
     * time t0 + (i0 + j) h (ode/fixed.h's mp_ode_fixed_time, as the driver
     * counts a fixed-step solve's times), ending with f = f(t_k, y_k); the
     * same arithmetic as k calls of step and finish.  The state after step j
     * is written to ys + j n and its time to ts[j] when ys is not NULL.  The
     * stages are not checked (the driver's fast path checks the state after
     * the block; values a step computes and drops leave their trace in
     * w->discarded); f is called directly (ode/fixed.h), or inlined in the
     * problem's own blocks; nfev counts k times the row's evaluations. */
    int (*block)(mp_ode_ws *w, double t0, long i0, double h, long k, double *ts, double *ys);
    /* Optional: forget history (a switching row changed method). */
    void (*restart)(mp_ode_ws *w);
    /* A switching row ("auto"): the driver runs `nonstiff` and `stiff` in
     * turn, as its stiffness tests decide; step/finish are then unused. */
    const struct mp_ode_method *nonstiff, *stiff;
} mp_ode_method;

/* The per-solve workspace every method works in. */
struct mp_ode_ws {
    const mp_ode_problem *p;
    const mp_ode_method *m;
    const mp_ode_options *o;
    size_t n;
    double *y, *ynew, *f, *fnew; /* f = f(t, y); fnew = f(t + h, ynew) after finish */
    double *lo, *lonew;          /* the low-order parts of y and ynew (compensated summation,
                                    ode/fixed.h's mp_ode_sum_add): the state is y + lo to about
                                    twice the working precision.  Written by the rows that
                                    compensate (yoshida4, yoshida6), else zero; the driver
                                    swaps them with y and ynew, zeroes lo where it sets y */
    int fnew_valid;              /* finish computed fnew */
    double *k;                   /* nscratch * n */
    double *coef;                /* ncoef * n: the last accepted step's interpolant; slots a
                                    method does not write are zero (the driver clears them
                                    whenever the running method changes) */
    double t_start, t_end;       /* the integration interval: f is never called outside it */
    double h_taken, h_next;      /* self-controlled methods */
    double rho;                  /* explicit methods: h |lambda| estimate of the last step */
    double jnorm;                /* implicit methods: ||J||_inf of their last Jacobian */
    size_t ncoef;                /* vectors in coef (the row's, padded with zeros) */
    long nfev, njev, nlu, nreject_inner;
    double discarded;            /* a block's 0 * (values it computes and drops): NaN when
                                    one was not finite (else 0) */
    int bad_what;                /* the last non-finite value found (see mp_ode_result) */
    size_t bad_index;
    void *state;                 /* method's own state (alloc/free) */
    void *state2;                /* a switching row's idle method's state */
};

/* Contract: MP_ENONFINITE, recording that dydt[i] of the right-hand side is
 * not finite (w->bad_what, w->bad_index). */
int mp_ode_ws_bad_rhs(mp_ode_ws *w, size_t i);

/* Contract: bit 63 of the result is set exactly when x is NaN or +-inf.  A
 * non-finite double's exponent field is all ones (0x7ff), and adding one to
 * the field carries into bit 63; a finite one's (at most 0x7fe) does not.
 * ORed over a vector, bit 63 says whether any value is not finite. */
static inline uint64_t mp_ode_nonfinite_bit(double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return (b & UINT64_C(0x7ff0000000000000)) + UINT64_C(0x0010000000000000);
}

/* Systems up to this size have their evaluations checked by scalar loads
 * (mp_ode_first_nonfinite). */
#define MP_ODE_SCALAR_CHECK_N 16

/* Contract: the index i of the first of v[0], v[s], ..., v[(n - 1) s] that is
 * NaN or inf, n when all are finite: one OR of integers over the values
 * (mp_ode_nonfinite_bit), read one by one, then a search only when it is set.
 * For a step's new state (driver.c, the lanes at stride W). */
static inline size_t mp_ode_first_nonfinite_at(const double *v, size_t n, size_t s)
{
    uint64_t any = 0;
    for (size_t i = 0; i < n; i++) any |= mp_ode_nonfinite_bit(v[i * s]);
    if (any >> 63)
        for (size_t i = 0; i < n; i++)
            if (!isfinite(v[i * s])) return i;
    return n;
}

/* Contract: the index of the first of v[0..n) that is NaN or inf, n when all
 * are finite (f's values: every evaluation).  One OR of integers over the
 * values (mp_ode_nonfinite_bit): one branch, not one per value, and it
 * vectorises without -ffast-math.  (A sum of 0 * v[i] does too, but its chain
 * of dependent additions costs the heavy top's solve 4% and the spherical
 * pendulum's 3%, measured side by side.)  Up to MP_ODE_SCALAR_CHECK_N values
 * are read one by one: f has just stored them one by one, and a 16-byte load
 * of two separate 8-byte stores waits for them to reach the cache (measured:
 * the heavy top's solve 3-8% slower with the SIMD loads at n = 6). */
static inline size_t mp_ode_first_nonfinite(const double *v, size_t n)
{
    if (n <= MP_ODE_SCALAR_CHECK_N) return mp_ode_first_nonfinite_at(v, n, 1);
    uint64_t any = 0;
#pragma omp simd reduction(| : any)
    for (size_t i = 0; i < n; i++) any |= mp_ode_nonfinite_bit(v[i]);
    return any >> 63 ? mp_ode_first_nonfinite_at(v, n, 1) : n;
}

/* Contract: MP_ENONFINITE, recording the first NaN or inf of a step's new
 * state w->ynew (MP_ODE_BAD_STATE), which has one. */
static inline int mp_ode_ws_bad_state(mp_ode_ws *w)
{
    w->bad_what = MP_ODE_BAD_STATE;
    w->bad_index = mp_ode_first_nonfinite_at(w->ynew, w->n, 1);
    return MP_ENONFINITE;
}

/* Contract: records that a step's scaled norm (its error estimate, radau's
 * Newton increment) overflowed from finite inputs (MP_ODE_BAD_ERR): the
 * method rejects the step as for a non-finite stage. */
static inline void mp_ode_ws_bad_norm(mp_ode_ws *w)
{
    w->bad_what = MP_ODE_BAD_ERR;
    w->bad_index = 0;
}

/* Contract: dydt = f(t, y), counted in nfev; MP_ENONFINITE (with the first
 * offending component in w->bad_index) when a value is NaN or inf.  Every
 * evaluation of f goes through here.  The one pass over dydt is the only
 * check of a stage: a non-finite value in a trial stage makes the driver
 * reject the step; at an accepted state it ends the solve.  (The fixed-step
 * blocks alone call f directly: the driver checks their state afterwards.)
 * Inline: it is called for every stage of every step. */
static inline int mp_ode_ws_rhs(mp_ode_ws *w, double t, const double *y, double *dydt)
{
    int rc = w->p->rhs(t, y, dydt, w->p->data);
    w->nfev++;
    if (rc != MP_OK) return rc;
    size_t i = mp_ode_first_nonfinite(dydt, w->n);
    if (i < w->n) return mp_ode_ws_bad_rhs(w, i);
    return MP_OK;
}

/* mp_ode_ws_rhs as an rhs over data = the workspace: the checked steps of
 * the fixed-step templates (ode/fixed.h). */
static inline int mp_ode_ws_eval(double t, const double *y, double *dydt, void *w)
{
    return mp_ode_ws_rhs(w, t, y, dydt);
}

/* Jacobian df/dy (row-major) at (t, y): the problem's own when it has one,
 * else forward differences with increments sqrt(eps) * max(|y_j|, atol_j/rtol);
 * f0 = f(t, y) must be given for the differences.  A banded problem's
 * differences take ml + mu + 1 evaluations, its entries outside the band
 * zero (dense: n evaluations).  Counts njev. */
int mp_ode_ws_jac(mp_ode_ws *w, double t, const double *y, const double *f0, double *jac,
                  double *scratch_y, double *scratch_f);

/* max(|a|, |b|) as a select, for the error weights atol + rtol max(|y0|, |y1|):
 * fmax's value wherever a (the step's start, finite) is not NaN, without
 * fmax's library call, which the error loops can neither inline nor
 * vectorise. */
static inline double mp_ode_absmax(double a, double b)
{
    a = fabs(a);
    b = fabs(b);
    return b > a ? b : a;
}

/* fmin and fmax as selects, without their library calls (the controller's
 * arithmetic on every step): their values wherever b is not NaN, a NaN a
 * giving b as fmin and fmax give it.  Every caller's b is a finite number or
 * a bound (hmax <= inf). */
static inline double mp_ode_min(double a, double b) { return a < b ? a : b; }
static inline double mp_ode_max(double a, double b) { return a > b ? a : b; }

/* Hairer's RMS error norm: sqrt(mean((e_i / (atol_i + rtol_i max(|y0_i|, |y1_i|)))^2)). */
double mp_ode_err_norm(const mp_ode_ws *w, const double *e, const double *y0, const double *y1);

/* Dense-output evaluation shared by every method: the interpolant is
 * y(t0 + s h) = c1 + s (c2 + (1-s) (c3 + s (c4 + (1-s) (c5 + ...)))),
 * with c = ncoef vectors of length n. */
void mp_ode_dense_eval(const double *coef, size_t ncoef, size_t n, double s, double *out);
/* The cubic Hermite interpolant in that form (4 vectors) from y0, y1, f0, f1. */
void mp_ode_dense_hermite(size_t n, double h, const double *y0, const double *y1,
                          const double *f0, const double *f1, double *coef);

/* A finish for methods without an interpolant of their own: fnew = f(t+h,
 * ynew) (the next step's first stage) and the cubic Hermite interpolant. */
int mp_ode_finish_fnew_hermite(mp_ode_ws *w, double t, double h, int need_dense);

/* The table. */
extern const mp_ode_method *const mp_ode_methods[];
const mp_ode_method *mp_ode_method_find(const char *name);

/* MP_OK when a solve of m from t0 to tf (either way) with options o is in the
 * domain every solve checks at its start: t0 != tf, t0 finite, tf finite or,
 * for an adaptive method, infinite (the solve then ends at a terminal event or
 * its budget, as SciPy's solve_ivp with t_span = (t0, inf)), rtol > 0, a
 * budget, max_step > 0, for a fixed-step method h > 0 large enough to advance
 * t; else MP_EDOM.  (The state's checks - n, y0, atol - are the solve's own.) */
int mp_ode_span_ok(const mp_ode_method *m, double t0, double tf, const mp_ode_options *o);

/* Integrate from t0 to tf (tf < t0 integrates backwards: the driver solves
 * dy/ds = -f(-s, y) for s = -t from -t0 to -tf, maps t_eval, events and the
 * Jacobian, and returns times t; dense segments stay in s, r->backward = 1).
 * t_eval must be ordered along the integration.  The result is initialised
 * here; free it with mp_ode_result_free whatever the status.  Returns
 * r->status for integration failures (EMAXSTEPS, ESTEP, ...) as well. */
int mp_ode_solve(const mp_ode_method *m, const mp_ode_problem *p, double t0, double tf,
                 const double *y0, const mp_ode_options *o, mp_ode_result *r);
void mp_ode_result_free(mp_ode_result *r);
/* A result that holds only event lists (the lane driver's): n states, n_events
 * empty lists.  MP_OK or MP_ENOMEM (free it with mp_ode_result_free). */
int mp_ode_result_events_init(mp_ode_result *r, size_t n, size_t n_events);
/* Append (t, y) to event k's list.  MP_OK or MP_ENOMEM. */
int mp_ode_result_push_event(mp_ode_result *r, size_t k, double t, const double *y);

/* Evaluate stored dense output at times tq (any order); out is nq rows of n. */
int mp_ode_result_dense_eval(size_t n, size_t ncoef, size_t nseg, const double *seg_t,
                             const double *seg_h, const double *seg_c, const double *tq,
                             size_t nq, double *out);

#endif
