/* The fixed-step methods' arithmetic, written once: classical rk4 and the
 * kick-drift-kick compositions (velocity Verlet, Yoshida), as always-inline
 * templates over the right-hand side F.
 *
 * The method rows (rk.c, geometric.c) instantiate them twice: for a checked
 * step with F the workspace's counted, checked evaluation, and for the
 * driver's fast blocks with the problem's rhs behind its pointer.  A scene
 * instantiates the blocks once more with its own rhs (MP_ODE_BLOCKS): a call
 * through a constant pointer into an always-inline body is a direct call the
 * compiler inlines, and a fixed dimension unrolls the loops, so that a block
 * of steps runs as a plain C loop with f written in it would.  Every
 * instantiation does the same operations in the same order: the results are
 * equal bit for bit whichever runs. */
#ifndef MP_ODE_FIXED_H
#define MP_ODE_FIXED_H

/* Self-contained (standard headers and MP_OK, defined before it is included):
 * generated systems (mechpy.symbolic) take this text too, from
 * mechpy._core.FIXED_STEPS_C, and instantiate the blocks with their rhs. */
#include <string.h>

#if defined(__GNUC__)
#define MP_ODE_INLINE static inline __attribute__((always_inline))
#else
#define MP_ODE_INLINE static inline
#endif

/* F's signature: ode.h's mp_ode_rhs. */
typedef int (*mp_ode_fixed_rhs)(double t, const double *y, double *dydt, void *data);

/* Contract: one rk4 step from (t, y) with k1 = f(t, y) into ynew (which may
 * be y); three evaluations of F (data ctx); s: 4n doubles of scratch.
 * Returns the first status of F that is not MP_OK. */
MP_ODE_INLINE int mp_ode_rk4_stages(mp_ode_fixed_rhs F, void *ctx, size_t n, double t, double h,
                                    const double *y, const double *k1, double *ynew, double *s)
{
    double *k2 = s, *k3 = k2 + n, *k4 = k3 + n, *yt = k4 + n;
    int rc;
    for (size_t i = 0; i < n; i++) yt[i] = y[i] + 0.5 * h * k1[i];
    if ((rc = F(t + 0.5 * h, yt, k2, ctx)) != MP_OK) return rc;
    for (size_t i = 0; i < n; i++) yt[i] = y[i] + 0.5 * h * k2[i];
    if ((rc = F(t + 0.5 * h, yt, k3, ctx)) != MP_OK) return rc;
    for (size_t i = 0; i < n; i++) yt[i] = y[i] + h * k3[i];
    if ((rc = F(t + h, yt, k4, ctx)) != MP_OK) return rc;
    for (size_t i = 0; i < n; i++)
        ynew[i] = y[i] + (h / 6.0) * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    return MP_OK;
}

/* The start of fixed step i of a solve from t0: counted, t0 + i h, never
 * summed step by step (a sum drifts by an ulp a step: after 2e5 steps of
 * 1e-4 the summed time is 1e-11 off and a last step makes up for it). */
MP_ODE_INLINE double mp_ode_fixed_time(double t0, long i, double h)
{
    return t0 + (double)i * h;
}

/* Contract: k rk4 steps of size h in place, step j starting at
 * t_j = mp_ode_fixed_time(t0, i0 + j, h) from (y, f = f(t_j, y)), each
 * ending with f = f(t_j + h, y): four evaluations a step, unchecked (the
 * driver checks the state after the block).  The state after step j goes
 * to ys + j n and its time t_{j+1} to ts[j] when ys is not NULL.  s: 4n
 * doubles of scratch. */
MP_ODE_INLINE int mp_ode_rk4_steps(mp_ode_fixed_rhs F, void *ctx, size_t n, double t0, long i0,
                                   double h, long k, double *y, double *f, double *s,
                                   double *ts, double *ys)
{
    for (long j = 0; j < k; j++) {
        double t = mp_ode_fixed_time(t0, i0 + j, h);
        int rc = mp_ode_rk4_stages(F, ctx, n, t, h, y, f, y, s);
        if (rc != MP_OK) return rc;
        if ((rc = F(t + h, y, f, ctx)) != MP_OK) return rc;
        if (ys) {
            memcpy(ys + (size_t)j * n, y, n * sizeof(double));
            ts[j] = mp_ode_fixed_time(t0, i0 + j + 1, h);
        }
    }
    return MP_OK;
}

/* Contract: s += inc with the sum kept to about twice the working precision
 * as s + *lo (Kahan's compensated summation; lo holds what the last rounding
 * of s dropped, 0 at the start): four additions for one.  Without it, the
 * rounding of every update of the state (an ulp of |q| or |v| a kick or a
 * drift) adds up over a long run as a random walk: Kepler e = 0.6 over 1000
 * orbits of yoshida6 at h = T/400 loses 2.6e-13 of its energy that way, 9.8e-15
 * with it (the same steps in 80-bit arithmetic: 3.1e-16). */
MP_ODE_INLINE void mp_ode_sum_add(double *s, double *lo, double inc)
{
    double y = inc + *lo, t = *s + y;
    *lo = y - (t - *s);
    *s = t;
}

/* Contract: one kick-drift-kick step of size h on y = (q, v) (nq each), with
 * f = f(t, y) on entry and f(t + h, y) on exit; one evaluation of F, whose
 * second half is a(t + h, q) (a separable problem).  With lo (2 nq values)
 * every update of q and v is compensated (mp_ode_sum_add): lo carries the
 * state's low-order part from step to step, so that y + lo is the state to
 * about twice the working precision (F sees y); lo NULL: plain updates
 * (always inlined, a constant NULL folds the test away).  When discarded is not NULL
 * (unchecked), the first half of that evaluation, which v replaces, leaves its
 * trace there (0 * value: NaN when one was not finite), so that the driver's
 * check of the state sees it too. */
MP_ODE_INLINE int mp_ode_kdk(mp_ode_fixed_rhs F, void *ctx, size_t nq, double t, double h, double *y,
                             double *lo, double *f, double *discarded)
{
    double *q = y, *v = y + nq;
    if (lo) {
        double *lq = lo, *lv = lo + nq;
        for (size_t i = 0; i < nq; i++) mp_ode_sum_add(&v[i], &lv[i], 0.5 * h * f[nq + i]);
        for (size_t i = 0; i < nq; i++) mp_ode_sum_add(&q[i], &lq[i], h * v[i]);
    } else {
        for (size_t i = 0; i < nq; i++) v[i] += 0.5 * h * f[nq + i];
        for (size_t i = 0; i < nq; i++) q[i] += h * v[i];
    }
    int rc = F(t + h, y, f, ctx);
    if (rc != MP_OK) return rc;
    if (lo) {
        for (size_t i = 0; i < nq; i++) mp_ode_sum_add(&v[i], &lo[nq + i], 0.5 * h * f[nq + i]);
    } else {
        for (size_t i = 0; i < nq; i++) v[i] += 0.5 * h * f[nq + i];
    }
    if (discarded) {
        double z = 0.0;
        for (size_t i = 0; i < nq; i++) z += 0.0 * f[i];
        *discarded += z;
    }
    memcpy(f, v, nq * sizeof(double)); /* q' = v at the new state */
    return MP_OK;
}

/* Contract: the composition c[0..ns) of kick-drift-kick steps over one step
 * h from (t, y, f), in place, lo the state's low-order part or NULL (as for
 * mp_ode_kdk, and discarded). */
MP_ODE_INLINE int mp_ode_compose(mp_ode_fixed_rhs F, void *ctx, size_t nq, double t, double h,
                                 const double *c, int ns, double *y, double *lo, double *f,
                                 double *discarded)
{
    for (int i = 0; i < ns; i++) {
        int rc = mp_ode_kdk(F, ctx, nq, t, c[i] * h, y, lo, f, discarded);
        if (rc != MP_OK) return rc;
        t += c[i] * h;
    }
    return MP_OK;
}

/* Contract: k steps of the composition c[0..ns) in place, step j from
 * t_j = mp_ode_fixed_time(t0, i0 + j, h), as mp_ode_rk4_steps does them (ns
 * evaluations a step, unchecked, the dropped values' trace added to
 * *discarded, samples to ts/ys when ys is given); lo: the state's low-order
 * part, carried, or NULL (mp_ode_kdk). */
MP_ODE_INLINE int mp_ode_compose_steps(mp_ode_fixed_rhs F, void *ctx, size_t nq, double t0,
                                       long i0, double h, const double *c, int ns, long k,
                                       double *y, double *lo, double *f, double *ts,
                                       double *ys, double *discarded)
{
    for (long j = 0; j < k; j++) {
        double t = mp_ode_fixed_time(t0, i0 + j, h);
        int rc = mp_ode_compose(F, ctx, nq, t, h, c, ns, y, lo, f, discarded);
        if (rc != MP_OK) return rc;
        if (ys) {
            memcpy(ys + (size_t)j * 2 * nq, y, 2 * nq * sizeof(double));
            ts[j] = mp_ode_fixed_time(t0, i0 + j + 1, h);
        }
    }
    return MP_OK;
}

/* The blocks of rhs (dimension N, NQ > 0 for a separable one), as
 * `link` functions name##_rk4 and name##_compose with the signatures of
 * ode.h's mp_ode_blocks: rhs evaluated with its data as the problem's, sizes
 * known when compiled, the state in locals for the block (registers: no store
 * to memory the compiler must assume the parameters share). */
#define MP_ODE_BLOCK_FNS(link, name, rhs, N, NQ)                                               \
    link int name##_rk4(void *d, double t0, long i0, double h, long k, double *y, double *f,   \
                        double *ts, double *ys)                                                \
    {                                                                                          \
        double s[4 * (N)], yl[N], fl[N];                                                       \
        memcpy(yl, y, sizeof yl);                                                              \
        memcpy(fl, f, sizeof fl);                                                              \
        int rc = mp_ode_rk4_steps(rhs, d, (N), t0, i0, h, k, yl, fl, s, ts, ys);               \
        memcpy(y, yl, sizeof yl);                                                              \
        memcpy(f, fl, sizeof fl);                                                              \
        return rc;                                                                             \
    }                                                                                          \
    link int name##_compose(void *d, double t0, long i0, double h, const double *c, int ns,   \
                            long k, double *y, double *lo, double *f, double *ts, double *ys,  \
                            double *discarded)                                                 \
    {                                                                                          \
        double yl[N], ll[N], fl[N], dl = 0.0;                                                  \
        int rc;                                                                                \
        memcpy(yl, y, sizeof yl);                                                              \
        memcpy(fl, f, sizeof fl);                                                              \
        if (lo) {                                                                              \
            memcpy(ll, lo, sizeof ll);                                                         \
            rc = mp_ode_compose_steps(rhs, d, (NQ), t0, i0, h, c, ns, k, yl, ll, fl, ts, ys,   \
                                      &dl);                                                    \
            memcpy(lo, ll, sizeof ll);                                                         \
        } else {                                                                               \
            rc = mp_ode_compose_steps(rhs, d, (NQ), t0, i0, h, c, ns, k, yl, NULL, fl, ts, ys, \
                                      &dl);                                                    \
        }                                                                                      \
        memcpy(y, yl, sizeof yl);                                                              \
        memcpy(f, fl, sizeof fl);                                                              \
        *discarded += dl;                                                                      \
        return rc;                                                                             \
    }

/* A scene's blocks for one of its right-hand sides: MP_ODE_BLOCK_FNS and the
 * mp_ode_blocks row `name` (ode.h) that binds them (mp_model_set_blocks). */
#define MP_ODE_BLOCKS(name, rhs, N, NQ)                                                          \
    MP_ODE_BLOCK_FNS(static, name, rhs, N, NQ)                                                 \
    static const mp_ode_blocks name = {rhs, name##_rk4, (NQ) > 0 ? name##_compose : NULL}

#endif
