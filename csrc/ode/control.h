/* The engine's step-size policy, written once for both widths: the driver
 * (driver.c, one trajectory) and the lane driver (lanes.c, MP_LANES
 * trajectories in lock-step) call these for each trajectory, so that a lane
 * repeats the scalar loop's arithmetic bit for bit.
 *
 * Vectors are read with a stride: 1 for the driver's contiguous state,
 * MP_LANES for a lane of the lane driver's structure-of-arrays state (lane l's
 * component c at c * MP_LANES + l).  Everything here is inline: the functions
 * run on every step of every trajectory. */
#ifndef MP_ODE_CONTROL_H
#define MP_ODE_CONTROL_H

#include <float.h>
#include <math.h>
#include <stddef.h>

#include "ode/ode.h"

/* The controller's memory between the steps of one trajectory. */
typedef struct mp_ode_ctl {
    double facold;      /* the last accepted error (Lund stabilisation) */
    int rejected;       /* the last attempt was rejected */
    int nonfinite;      /* ... because of a non-finite trial stage */
    int stiff_count, calm_count; /* Hairer's stiffness test; a switching row's */
} mp_ode_ctl;

/* The controller at a trajectory's start (and after a switching row's switch). */
static inline mp_ode_ctl mp_ode_ctl_start(void) { return (mp_ode_ctl){1e-4, 0, 0, 0, 0}; }

/* x^(1/8), dop853's controller power, as three square roots: each one
 * correctly rounded instruction where pow is a call of about 100 instructions
 * on every step (4% of the spherical pendulum's solve).  Both widths take it
 * (mp_ode_err_pow; the lanes' loop), so that a lane repeats a lone solve. */
#define MP_ODE_ROOT8_EXPO 0.125
static inline double mp_ode_root8(double x) { return sqrt(sqrt(sqrt(x))); }

/* Contract: err^expo, the controller's power: mp_ode_root8 for expo = 1/8,
 * else pow. */
static inline double mp_ode_err_pow(double err, double expo)
{
    return expo == MP_ODE_ROOT8_EXPO ? mp_ode_root8(err) : pow(err, expo);
}

/* Contract: Hairer's controller for a method with its own error estimate.
 * fac11 = err^expo and fold = facold^beta (1 when beta = 0) are the caller's
 * (the lanes take the powers of eight lanes at once).  Returns 1 when the
 * step (scaled error err) is accepted, with *hnew the next step; 0 when
 * rejected (also for a NaN err), with *h the step to retry. */
static inline int mp_ode_control(const mp_ode_method *m, mp_ode_ctl *c, double err,
                                 double fac11, double fold, double *h, double *hnew)
{
    if (!(err <= 1.0)) {
        c->nonfinite = !isfinite(err);
        double fac = isfinite(err) ? fmin(1.0 / m->fac_min, fac11 / m->safety) : 10.0;
        *h /= fac;
        c->rejected = 1;
        return 0;
    }
    /* Lund stabilisation only for methods with beta > 0 (dopri5) */
    double fac = m->beta > 0.0 ? fac11 / fold : fac11;
    /* accepted: 0 <= err <= 1, so fac11, fold and fac are finite */
    fac = mp_ode_max(mp_ode_min(fac / m->safety, 1.0 / m->fac_min), 1.0 / m->fac_max);
    *hnew = *h / fac;
    c->facold = mp_ode_max(err, 1e-4);
    if (c->rejected) *hnew = mp_ode_min(*hnew, *h);
    c->rejected = c->nonfinite = 0;
    return 1;
}

/* Contract: a trial stage was not finite: reject the step and retry with a
 * tenth of it, as Hairer's codes do (a step floor reached after this is
 * reported as MP_ENONFINITE, see mp_ode_step_floor). */
static inline double mp_ode_control_nonfinite(mp_ode_ctl *c, double h)
{
    c->rejected = c->nonfinite = 1;
    return h / 10.0;
}

/* Contract: Hairer's stiffness test after an accepted explicit step whose
 * estimate h |lambda| is rho > 0: beyond rho_stiff for 15 of the recent steps
 * sets *stiff; 6 calm steps in a row forget the count. */
static inline void mp_ode_stiffness_test(mp_ode_ctl *c, double rho, double rho_stiff, int *stiff)
{
    if (rho > rho_stiff) {
        c->calm_count = 0;
        if (++c->stiff_count >= 15) *stiff = 1;
    } else if (++c->calm_count >= 6) {
        c->stiff_count = 0;
    }
}

/* Contract: the step to attempt from t with the planned step h towards tf:
 * the rest of the interval (never a stage beyond tf) when this is the last
 * step (*last = 1): an adaptive step within 1% of tf, a fixed one within
 * 1e-9 h of it; else h. */
static inline double mp_ode_step_span(int adaptive, double t, double h, double tf, int *last)
{
    *last = 0;
    if (adaptive ? t + 1.01 * h >= tf : t + h * (1.0 + 1e-9) >= tf) {
        h = tf - t;
        while (t + h > tf) h = nextafter(h, 0.0); /* no stage beyond tf */
        *last = 1;
    }
    return h;
}

/* Contract: the step-size floor for an adaptive step h planned at t (16 eps
 * |t|, below which t + h does not advance t reliably; SciPy's is 10 ulps).  A
 * step below it that is not the retry of a rejected step (a first_step, an
 * accepted step's proposal) is raised to it, as SciPy raises it, unless
 * max_step hmax is below the floor too (SciPy's max_step wins).  Returns 1
 * when the step stays below it: the solve ends with MP_ESTEP, or MP_ENONFINITE
 * when the steps shrank because trial stages were not finite.  The caller
 * asks this before mp_ode_step_span and ends the solve only when the step is
 * not the last (*last), which lands on tf however short the rest of the span:
 * a span of a few ulps of t0 is solved, as in SciPy. */
static inline int mp_ode_step_floor(const mp_ode_ctl *c, double t, double hmax, double *h)
{
    double hmin = 16.0 * DBL_EPSILON * mp_ode_max(fabs(t), 1e-300);
    if (*h < hmin && !c->rejected && hmin <= hmax) *h = hmin;
    return *h < hmin;
}

/* Contract: the error weight of one component, atol + rtol ay with ay = |y|
 * (or max(|y0|, |y1|) over a step, or the larger of two magnitudes): every
 * error norm, first-step guess and event tolerance of the engine scales by
 * it, in both widths (a lane loop inlines and vectorises it as it did the
 * expression), so that its form is written here only. */
static inline double mp_ode_weight(double atol, double rtol, double ay)
{
    return atol + rtol * ay;
}

/* Hairer's RMS error norm sqrt(mean((e_i / (atol_i + rtol_i max(|y0_i|,
 * |y1_i|)))^2)) over n components at stride s. */
static inline double mp_ode_rms_norm(const mp_ode_options *o, size_t n, size_t s,
                                     const double *e, const double *y0, const double *y1)
{
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double sc = mp_ode_weight(o->atol[i], o->rtolv[i], mp_ode_absmax(y0[i * s], y1[i * s]));
        double q = e[i * s] / sc;
        sum += q * q;
    }
    return sqrt(sum / (double)n);
}

/* Contract: the first half of Hairer's first-step guess (hinit) from (y, f)
 * at stride s: the trial step for the explicit Euler probe, at most hmax and
 * span = tf - t0; *dnf = the mean square of f scaled by the tolerances (for
 * mp_ode_hinit_final). */
static inline double mp_ode_hinit_trial(const mp_ode_options *o, size_t n, size_t s,
                                        const double *y, const double *f, double hmax,
                                        double span, double *dnf)
{
    double sf2 = 0.0, sy2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double sk = mp_ode_weight(o->atol[i], o->rtolv[i], fabs(y[i * s]));
        double qf = f[i * s] / sk, qy = y[i * s] / sk;
        sf2 += qf * qf;
        sy2 += qy * qy;
    }
    *dnf = sf2 / (double)n;
    double dny = sy2 / (double)n;
    double h = (*dnf <= 1e-10 || dny <= 1e-10) ? 1e-6 : sqrt(dny / *dnf) * 0.01;
    return fmin(h, fmin(hmax, span));
}

/* Contract: the second half of hinit: from the Euler probe of step h (f1 =
 * f(t0 + h, y + h f)) the estimate of the second derivative, and the first
 * step of a method of the given order, at most 100 h, hmax and span. */
static inline double mp_ode_hinit_final(const mp_ode_options *o, size_t n, size_t s,
                                        const double *y, const double *f, const double *f1,
                                        double h, double dnf, int order, double hmax,
                                        double span)
{
    double der2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double sk = mp_ode_weight(o->atol[i], o->rtolv[i], fabs(y[i * s]));
        double d = (f1[i * s] - f[i * s]) / sk;
        der2 += d * d;
    }
    der2 = sqrt(der2 / (double)n) / h;
    double der12 = fmax(fabs(der2), sqrt(dnf));
    double h1 = der12 <= 1e-15 ? fmax(1e-6, h * 1e-3) : pow(0.01 / der12, 1.0 / (double)order);
    return fmin(fmin(100.0 * h, h1), fmin(hmax, span));
}

/* Contract: the root of g on [a, b] in step fraction s, g(a) and g(b) of
 * opposite signs (or g(b) == 0), for a step from t of size h: the Illinois
 * variant of regula falsi, to round-off in t; g(ctx, s, &gs) returns MP_OK or
 * a status that stops the search.  *root is on the side past the crossing
 * (the sign of g has changed there).  The event location of both drivers. */
static inline int mp_ode_event_root(int (*g)(void *ctx, double s, double *gs), void *ctx,
                                    double t, double h, double a, double ga, double b,
                                    double gb, double *root)
{
    double tol = 4.0 * DBL_EPSILON * (fabs(t) + fabs(h)) / fabs(h);
    int side = 0;
    if (gb == 0.0) {
        *root = b;
        return MP_OK;
    }
    for (int it = 0; it < 200 && (b - a) > tol; it++) {
        double s = (a * gb - b * ga) / (gb - ga);
        if (!(s > a && s < b)) s = 0.5 * (a + b);
        double gs;
        int rc = g(ctx, s, &gs);
        if (rc != MP_OK) return rc;
        if (gs == 0.0) {
            a = b = s;
            break;
        }
        if ((gs > 0) == (gb > 0)) {
            b = s;
            gb = gs;
            if (side == -1) ga *= 0.5;
            side = -1;
        } else {
            a = s;
            ga = gs;
            if (side == 1) gb *= 0.5;
            side = 1;
        }
    }
    *root = b;
    return MP_OK;
}

/* Accumulation of an action event's crossings (Zeno): two actions closer in
 * t than this fraction of the time since the solve's start end it there. */
#define MP_ODE_ZENO_FRAC 1e-12

/* Sub-intervals of a step searched for event crossings (both widths). */
#define MP_ODE_EVENT_SUBDIV 4

/* Contract: the shortest time between two actions that a solve started at
 * t_start tells apart at t: MP_ODE_ZENO_FRAC of the time since the start,
 * and never below 64 ulps of t (where the time grid itself stops). */
static inline double mp_ode_time_resolution(double t, double t_start)
{
    return fmax(MP_ODE_ZENO_FRAC * (t - t_start), 64.0 * DBL_EPSILON * fabs(t));
}

/* What an action event's new crossing at t means, its previous action at
 * t_prev (n_prev actions before), the solve started at t_start, the step h:
 * MP_OK (apply the action), MP_EEVENT (it fires again at once: within the
 * root finder's tolerance of the last action) or MP_TERMINATED (Zeno: the
 * gap below the time resolution; *gap set). */
static inline int mp_ode_action_gap(double t, double t_prev, long n_prev, double t_start,
                                    double h, double *gap)
{
    if (n_prev <= 0) return MP_OK;
    *gap = t - t_prev;
    if (*gap <= 8.0 * DBL_EPSILON * (fabs(t) + fabs(h))) return MP_EEVENT;
    if (*gap <= mp_ode_time_resolution(t, t_start)) return MP_TERMINATED;
    return MP_OK;
}

/* Contract: whether a body leaves an impact's wall at t with the relative
 * velocity rho >= 0 (side-signed: > 0 away from the wall) and the relative
 * acceleration a (side-signed) comes to rest on it: the force pushes it back
 * (a < 0) and the flights left cannot be resolved: rho = 0 (restitution 0),
 * or with e < 1 (e = rho over the speed it arrived with) the next flight's
 * height rho^2 / (2 |a|) within 16 ulps of the wall's position x or within
 * xtol, the solve's absolute tolerance on the coordinate there (atol + rtol
 * |x|: a bounce the integration does not resolve), or all the flights left,
 * 2 rho / (|a| (1 - e)), within the time resolution.  *t_left is the time to
 * the accumulation (the sum of those flights: exact for a constant a).  An
 * elastic impact (e >= 1) never accumulates. */
static inline int mp_ode_impact_rests(double t, double t_start, double rho, double a, double e,
                                      double x, double xtol, double *t_left)
{
    *t_left = 0.0;
    if (!(a < 0.0) || !(rho >= 0.0)) return 0;
    if (rho == 0.0) return 1;
    if (!(e < 1.0)) return 0;
    *t_left = 2.0 * rho / (-a * (1.0 - e));
    return rho * rho / (-2.0 * a) <= fmax(16.0 * DBL_EPSILON * fabs(x), xtol) ||
           *t_left <= mp_ode_time_resolution(t, t_start);
}

#endif
