/* Ensembles of independent solves over threads. */
#ifndef MP_ODE_ENSEMBLE_H
#define MP_ODE_ENSEMBLE_H

#include "ode/lanes.h"
#include "ode/ode.h"

/* Solve k problems (probs[i], from y0s[i*n]) from t0 to tf on `threads`
 * threads (the caller's included), keeping the o->n_eval samples at
 * o->t_eval of each: yout is k blocks of (n, n_eval).  out[i] is each
 * solve's outcome (status MP_OK, MP_EMAXSTEPS, ..., where, nfev).
 * Interrupts: o->interrupt is called from the calling thread only; a stop
 * reaches the other threads through a flag.  With lanes (not NULL; only when
 * mp_ode_lanes_supported) each thread runs a lane group (lanes.h) instead of
 * one mp_ode_solve per trajectory.  With results (not NULL) each
 * trajectory's result is kept in results[i] (the scalar path: whole; in
 * lanes: its event lists; the caller frees each with mp_ode_result_free), and with events_data trajectory
 * i's event functions and actions get events_data[i] as their data.  Returns MP_OK, or
 * MP_EINTR / MP_ECALLBACK / MP_ENOMEM when the ensemble was stopped. */
/* An ensemble as the caller describes it: one system (base, a scene row's
 * or a compiled system's or a callback's problem) and k parameter rows, and
 * what mp_ode_ensemble_build makes of it: each trajectory's problem and, when
 * the ensemble can run in SIMD lanes, the lane system.  The caller fills the
 * inputs; build allocates the outputs; mp_ode_ensemble_free frees them. */
typedef enum {
    MP_ENS_ROWS_NONE = 0, /* no rows: every trajectory runs base */
    MP_ENS_ROWS_SCENE,    /* a scene's parameter rows: the model binds each (its torque too) */
    MP_ENS_ROWS_DATA,     /* the row is the problem's data (a compiled system's parameters) */
    MP_ENS_ROWS_CALLER    /* the caller binds each row into probs[i] after the build */
} mp_ens_rows;

/* Why mp_ode_ensemble_build refused (MP_EDOM), for the caller's message. */
typedef enum {
    MP_ENS_OK = 0,
    MP_ENS_COLUMNS,   /* rows have the wrong number of columns (need: e->np_need) */
    MP_ENS_ROW,       /* row e->bad_row is outside the scene's domain */
    MP_ENS_SEPARABLE, /* an explicit symplectic method on a system that is not q'' = a(t, q) */
    MP_ENS_NO_LANES   /* lanes were required and cannot run this ensemble */
} mp_ens_why;

struct mp_model;
struct mp_rigid_torque;

typedef struct mp_ode_ensemble {
    /* in */
    const mp_ode_method *m;
    mp_ode_problem base;
    size_t k, n;
    const double *rows;                   /* (k, np) row-major, or NULL */
    size_t np;
    mp_ens_rows rows_kind;
    const struct mp_model *model;         /* the scene (NULL: not a scene) */
    const double *params;                 /* the system's own parameter vector (or NULL) */
    size_t nparams;
    const struct mp_rigid_torque *torque; /* a RigidBody scene's C torque (NULL: none) */
    mp_lane_rhs lane_rhs;                 /* a compiled system's lane rhs (NULL: none) */
    int holds_python;                     /* a trajectory calls Python: no lanes, one thread */
    const mp_impact *impacts;             /* the events, when they are all impacts (or NULL) */
    size_t n_impacts;
    int want_lanes;                       /* -1 when possible, 0 never, 1 always */
    /* out */
    mp_ode_problem *probs;                /* k problems */
    struct mp_rigid_torque *torques;      /* per-row torque bindings (or NULL) */
    mp_lane_system ls;
    const mp_lane_system *lanes;          /* &ls when the ensemble runs in lanes, else NULL */
    mp_ens_why why;
    size_t bad_row, np_need;
} mp_ode_ensemble;

/* Contract: the problems of e's k trajectories from its inputs, checked:
 * an explicit symplectic method needs a separable system; scene rows are
 * each checked by the model's one parameter check (mp_model_prepare) for a
 * state of n and bound (with the torque rebound to the row); a compiled
 * system's rows must have its parameter count; rows for the caller are left
 * to the caller (probs[i] = base).  Then the lane system (the scene's lane
 * rhs for these rows, or the compiled system's; the generic wrapper
 * otherwise) and whether lanes run: a system in C, a method row with a lane
 * kernel and options the lanes take (mp_ode_lanes_supported: events only as
 * impacts, which the lane system then carries), unless want_lanes is 0.  MP_OK; MP_EDOM with e->why; MP_ENOMEM. */
int mp_ode_ensemble_build(mp_ode_ensemble *e, double t0, double tf, const mp_ode_options *o);
void mp_ode_ensemble_free(mp_ode_ensemble *e);

int mp_ode_solve_many(const mp_ode_method *m, const mp_ode_problem *probs,
                      const mp_lane_system *lanes, size_t k, double t0, double tf,
                      const double *y0s, const mp_ode_options *o, int threads,
                      double *yout, mp_ode_outcome *out, mp_ode_result *results,
                      void *const *events_data,
                      void (*progress)(size_t done, size_t total, void *ctx), void *progress_ctx);

#endif
