/* Ensembles in SIMD lanes: MP_LANES trajectories advance in lock-step
 * through one vectorised Runge-Kutta step, each lane with its own time,
 * step size, controller, step budget, t_eval output and status.
 *
 * State is laid out structure-of-arrays: component c of lane l is
 * y[c * MP_LANES + l]; per-lane parameters likewise par[j * MP_LANES + l].
 * A lane that finishes (or fails) takes the next trajectory at once.
 *
 * The lane driver (lanes.c) is compiled twice, for AVX2+FMA and portable;
 * mp_ode_lanes_run picks one at run time (__builtin_cpu_supports). */
#ifndef MP_ODE_LANES_H
#define MP_ODE_LANES_H

#include <math.h> /* first: it defines __GLIBC__, tested below */
#include <stddef.h>

#include "ode/ode.h"

/* Lanes of one group: eight, two AVX2 registers of four doubles per operation
 * (measured faster than four: the per-lane bookkeeping of a step is shared by
 * more lanes, and two independent registers hide the latency of each). */
#define MP_LANES 8

/* A scene's lane right-hand side: f = f(t, y) for MP_LANES states at once,
 * t (MP_LANES,), y and f (n * MP_LANES, SoA), par (np * MP_LANES, SoA: the
 * lane's parameter row).  status[l] receives MP_OK or lane l's failure (what
 * the scene's scalar rhs returns for that state).  Every lane is computed;
 * the driver ignores lanes that are idle. */
typedef void (*mp_lane_rhs)(const double *t, const double *y, double *f, const double *par,
                            int *status);

/* Building blocks of lane rhs functions in the scene files: the function
 * attribute compiling one body for AVX2+FMA and portable (a resolver picks at
 * load time), and sin/cos/exp/pow with glibc's vector variants (libmvec), which a
 * `#pragma omp simd` loop over the lanes calls four at a time.  Without GCC on
 * x86-64 both reduce to the plain functions. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__GLIBC__) && \
    !defined(__SANITIZE_ADDRESS__)
#define MP_LANE_FN __attribute__((target_clones("arch=x86-64-v3", "default")))
__attribute__((__simd__("notinbranch"), const, nothrow)) double mp_lane_sin(double) __asm__("sin");
__attribute__((__simd__("notinbranch"), const, nothrow)) double mp_lane_cos(double) __asm__("cos");
__attribute__((__simd__("notinbranch"), const, nothrow)) double mp_lane_exp(double) __asm__("exp");
__attribute__((__simd__("notinbranch"), const, nothrow)) double mp_lane_pow(double, double)
    __asm__("pow");
#else
#define MP_LANE_FN
#define mp_lane_sin sin
#define mp_lane_cos cos
#define mp_lane_exp exp
#define mp_lane_pow pow
#endif

/* Loop over the lanes of a group (vectorised). */
#define MP_LANE_LOOP _Pragma("omp simd") for (int l = 0; l < MP_LANES; l++)

/* What an ensemble runs in lanes: the lane rhs (NULL: each trajectory's own
 * scalar problem through a gather/call/scatter wrapper) and its parameters,
 * row i of trajectory i at params + i * pstride (pstride 0: one row for all),
 * and its impacts (ode.h's mp_impact, each reached downwards; each lane
 * jumps on its own; the event lists go to the trajectories' results). */
typedef struct mp_lane_system {
    mp_lane_rhs rhs;
    const double *params;
    size_t np, pstride;
    const mp_impact *impacts;
    size_t n_impacts;
} mp_lane_system;

/* How a lane group gets its work and reports it (ensemble.c's threads):
 * take() returns the next trajectory index (>= k: none left, or stopped);
 * done(i) is called when trajectory i's outcome and samples are written and
 * returns non-zero to stop the group (an interrupt); interrupt() is polled
 * every few hundred lock-step steps. */
typedef struct mp_lane_feed {
    size_t (*take)(void *ctx);
    int (*done)(void *ctx, size_t i);
    int (*interrupt)(void *ctx);
    void *ctx;
} mp_lane_feed;

/* Whether method m integrates from t0 to tf with options o in lanes (a row
 * with a lane kernel; t_eval given; no dense output; no events unless
 * lane_events, the lanes running them (impacts); the checks every solve makes
 * at its start pass).  Others take the scalar path. */
int mp_ode_lanes_supported(const mp_ode_method *m, const mp_ode_options *o, double t0, double tf,
                           int lane_events);

/* Contract: one thread's lane group: trajectories i = feed->take() (k in all)
 * from y0s[i * n] with problems probs[i] (the generic wrapper's) or ls->rhs,
 * from t0 to tf (backwards when tf < t0), samples at o->t_eval into yout's
 * (n, n_eval) block i (NaN where not reached), out[i] as mp_ode_solve's
 * outcome, with impacts results[i] its event lists (mp_ode_result_events_init
 * here; the caller frees them).  Only for a method mp_ode_lanes_supported accepts.  Returns MP_OK,
 * MP_EINTR when the feed stopped it, or MP_ENOMEM. */
int mp_ode_lanes_run(const mp_ode_method *m, const mp_ode_problem *probs,
                     const mp_lane_system *ls, size_t k, double t0, double tf, const double *y0s,
                     const mp_ode_options *o, double *yout, mp_ode_outcome *out,
                     mp_ode_result *results, const mp_lane_feed *feed);

/* The two builds of lanes.c (mp_ode_lanes_run dispatches). */
int mp_ode_lanes_run_avx2(const mp_ode_method *m, const mp_ode_problem *probs,
                          const mp_lane_system *ls, size_t k, double t0, double tf,
                          const double *y0s, const mp_ode_options *o, double *yout,
                          mp_ode_outcome *out, mp_ode_result *results,
                          const mp_lane_feed *feed);
int mp_ode_lanes_run_base(const mp_ode_method *m, const mp_ode_problem *probs,
                          const mp_lane_system *ls, size_t k, double t0, double tf,
                          const double *y0s, const mp_ode_options *o, double *yout,
                          mp_ode_outcome *out, mp_ode_result *results,
                          const mp_lane_feed *feed);

#endif
