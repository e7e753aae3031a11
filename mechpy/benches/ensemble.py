"""Bench: ensembles (solve_many) and the fixed-step overhead, beside SciPy and plain C."""
import os
import shutil
import subprocess
import tempfile
import time

import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Ensembles and overhead"
ORDER = 15

# The plain loops the fixed-step methods are measured against: the same
# arithmetic with f inlined, argv[3] choosing rk4 (0), verlet (1) or yoshida4 (2)
# (whose updates are compensated sums, as mechpy's: s += x kept as s + lo).
_PLAIN_FIXED = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
static void f(double t, const double *y, double *d) { (void)t; d[0] = y[1]; d[1] = -9.81 * sin(y[0]); }
static const double Y4[3] = {1.3512071919596576340476878089715, -1.7024143839193152680953756179429,
                             1.3512071919596576340476878089715};
static void add(double *s, double *lo, double x) { double y = x + *lo, t = *s + y; *lo = y - (t - *s); *s = t; }
int main(int argc, char **argv) {
    long n = atol(argv[1]); double h = atof(argv[2]); int m = argc > 3 ? atoi(argv[3]) : 0;
    double y[2] = {1.0, 0.0}, lo[2] = {0.0, 0.0}, k1[2], k2[2], k3[2], k4[2], yt[2], t = 0;
    struct timespec a, b; clock_gettime(CLOCK_MONOTONIC, &a);
    f(t, y, k1);
    for (long s = 0; s < n; s++) {
        if (m == 0) {
            for (int i = 0; i < 2; i++) yt[i] = y[i] + 0.5 * h * k1[i];
            f(t + 0.5 * h, yt, k2);
            for (int i = 0; i < 2; i++) yt[i] = y[i] + 0.5 * h * k2[i];
            f(t + 0.5 * h, yt, k3);
            for (int i = 0; i < 2; i++) yt[i] = y[i] + h * k3[i];
            f(t + h, yt, k4);
            for (int i = 0; i < 2; i++) y[i] += h / 6 * (k1[i] + 2 * (k2[i] + k3[i]) + k4[i]);
            f(t + h, y, k1);
        } else if (m == 1) {
            y[1] += 0.5 * h * k1[1]; y[0] += h * y[1];
            f(t, y, k1);
            y[1] += 0.5 * h * k1[1];
        } else {
            for (int j = 0; j < 3; j++) {
                double c = Y4[j] * h;
                add(&y[1], &lo[1], 0.5 * c * k1[1]); add(&y[0], &lo[0], c * y[1]);
                f(t, y, k1);
                add(&y[1], &lo[1], 0.5 * c * k1[1]);
            }
        }
        t += h;
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    printf("%.9f %.17g %.17g\n", (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec), y[0], y[1]);
    return 0;
}
"""

FIXED = ("rk4", "verlet", "yoshida4")  # argv[3] of the plain loop: the index


def _plain_fixed(nsteps, h):
    """{method: (median seconds, final state)} of the plain C loops, or None without cc."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if not cc:
        return None
    out = {}
    with tempfile.TemporaryDirectory() as d:
        src, exe = os.path.join(d, "fixed.c"), os.path.join(d, "fixed")
        with open(src, "w") as fh:
            fh.write(_PLAIN_FIXED)
        subprocess.run([cc, "-O2", src, "-o", exe, "-lm"], check=True)
        for i, meth in enumerate(FIXED):
            times, y = [], None
            for _ in range(5):
                res = subprocess.run([exe, str(nsteps), repr(h), str(i)], capture_output=True,
                                     text=True, check=True).stdout.split()
                times.append(float(res[0]))
                y = np.array([float(res[1]), float(res[2])])
            out[meth] = float(np.median(times)), y
    return out


def _compiled_pendulum():
    """The plain loops' pendulum, theta'' = -9.81 sin(theta), as a compiled
    Lagrangian (mp.lagrangian): its fixed-step blocks are the engine's with the
    generated rhs inlined.  None without a C compiler."""
    import sympy as sp
    th, = mp.coordinates("theta")
    try:
        return mp.lagrangian(th.diff() ** 2 / 2 + sp.Float(9.81) * sp.cos(th), [th])
    except mp.symbolic.CompileError:
        return None


def _numbalsoda_many():
    """numbalsoda's dop853 inside a numba ``prange`` loop over the trajectories,
    with a numba ``cfunc`` pendulum: the fastest ensemble a user writes today
    (None without numba and numbalsoda, the ``bench`` extra)."""
    try:
        import numba
        import numbalsoda
        from numba import cfunc, types
    except ImportError:
        return None
    sig = types.void(types.double, types.CPointer(types.double), types.CPointer(types.double),
                     types.voidptr)

    @cfunc(sig, nopython=True)
    def rhs(t, u, du, p):
        du[0] = u[1]
        du[1] = -9.81 * np.sin(u[0])
    ptr, dop853 = rhs.address, numbalsoda.dop853

    @numba.njit(parallel=True)
    def many(y0s, te, rtol, atol, out):
        for i in numba.prange(y0s.shape[0]):
            usol, ok = dop853(ptr, y0s[i], te, rtol=rtol, atol=atol)
            out[i] = usol.T

    def solve(y0s, te, rtol, atol, threads):
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        out = np.empty((y0s.shape[0], y0s.shape[1], te.size))
        many(y0s, te, rtol, atol, out)
        return out
    return solve


def run(quick: bool):
    from scipy.integrate import solve_ivp
    rows = []
    p = mp.scenes.Pendulum()
    k = 2000 if quick else 10_000
    y0s = np.column_stack([np.linspace(0.1, 3.0, k), np.zeros(k)])
    te = np.linspace(0, 10, 11)
    rtol, atol = 1e-8, 1e-10
    name = f"{k} pendulum trajectories, t=10, rtol=1e-8 (11 samples each)"
    ref = mp.solve_many(p, (0, 10), y0s, t_eval=te, rtol=1e-13, atol=1e-15, lanes=False).y

    def err(y):
        return float(np.max(np.abs(y[:, :, -1] - ref[:, :, -1])))
    for lanes, tag in ((True, "lanes"), (False, "scalar")):
        for th in (1, 2):
            fn = lambda th=th, lanes=lanes: mp.solve_many(  # noqa: E731
                p, (0, 10), y0s, t_eval=te, rtol=rtol, atol=atol, threads=th, lanes=lanes)
            rows.append(dict(problem=name, impl=f"mechpy solve_many, {tag}, {th} thread(s)",
                             path=f"ensemble-{tag}-{th}", time=median_time(fn, repeat=5),
                             error=err(fn().y)))
    nbs = _numbalsoda_many()
    if nbs is not None:
        for th in (1, 2):
            fn = lambda th=th: nbs(y0s, te, rtol, atol, th)  # noqa: E731
            out = fn()   # the first call compiles
            rows.append(dict(problem=name, impl=f"numbalsoda dop853 in numba prange, {th} "
                             "thread(s)", path=f"ensemble-numbalsoda-{th}",
                             time=median_time(fn, repeat=5), error=err(out)))
    sub = 20 if quick else 100

    def f(t, y):
        return [y[1], -9.81 * np.sin(y[0])]

    idx = [i * (k // sub) for i in range(sub)]

    def loop():
        return [solve_ivp(f, (0, 10), y0s[i], method="DOP853", rtol=rtol, atol=atol,
                          t_eval=te).y for i in idx]
    t_loop = median_time(loop, repeat=1, warmup=0) * (k / sub)
    rows.append(dict(problem=name, impl="Python loop of scipy solve_ivp DOP853",
                     path="ensemble-loop", time=t_loop,
                     error=float(np.max([np.abs(y[:, -1] - ref[i, :, -1]).max()
                                         for i, y in zip(idx, loop())])),
                     note=f"{sub} trajectories timed, scaled to {k}"))

    # the fixed-step methods on a C scene beside plain C loops doing the same arithmetic
    nsteps, h = (200_000 if quick else 2_000_000), 1e-4
    T = nsteps * h
    plain = _plain_fixed(nsteps, h)
    own = _compiled_pendulum()
    for meth in FIXED:
        name = f"{meth}, h=1e-4, {nsteps} steps, pendulum (C scene)"
        fn = lambda meth=meth: mp.solve(p, (0, T), [1.0, 0.0], method=meth, h=h,  # noqa: E731
                                        t_eval=[T])
        ours = fn().y[:, -1]
        rows.append(dict(problem=name, impl=f"mechpy solve {meth} (C scene)", path=meth,
                         time=median_time(fn), error=float("nan")))
        if own is not None:
            fn = lambda meth=meth: mp.solve(own, (0, T), [1.0, 0.0], method=meth,  # noqa: E731
                                            h=h, t_eval=[T])
            rows.append(dict(problem=name, impl=f"mechpy solve {meth} (compiled Lagrangian)",
                             path=f"{meth}-compiled", time=median_time(fn),
                             error=float(np.max(np.abs(fn().y[:, -1] - ours))),
                             note="error = difference from the C scene's result"))
        if plain is not None:
            rows.append(dict(problem=name, impl="plain C loop (cc -O2)", path=f"plain-c-{meth}",
                             time=plain[meth][0],
                             error=float(np.max(np.abs(plain[meth][1] - ours))),
                             note="error = difference from mechpy's result"))
    return rows
