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
 * one mp_ode_solve per trajectory.  Returns MP_OK, or MP_EINTR / MP_ECALLBACK /
 * MP_ENOMEM when the ensemble was stopped. */
int mp_ode_solve_many(const mp_ode_method *m, const mp_ode_problem *probs,
                      const mp_lane_system *lanes, size_t k, double t0, double tf,
                      const double *y0s, const mp_ode_options *o, int threads,
                      double *yout, mp_ode_outcome *out,
                      void (*progress)(size_t done, size_t total, void *ctx), void *progress_ctx);

#endif
