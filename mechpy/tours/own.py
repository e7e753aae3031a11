"""Tour section: a system of your own, the double pendulum, from its
Lagrangian: built (SymPy -> C -> compiled and cached), solved, and compared
with what a SymPy user writes today (Euler-Lagrange with SymPy, lambdify,
solve_ivp), in error and in time; its build and cache times."""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np

TITLE = "Your own system, compiled: the double pendulum from its Lagrangian"
ORDER = 90


def run(out: Path) -> None:
    from scipy.integrate import solve_ivp

    import mechpy as mp
    from mechpy._timing import median_time
    from mechpy.benches.own import DP_PARAMS, DP_T, DP_Y0, cache_build_time, \
        double_pendulum_lagrangian, double_pendulum_sympy

    from . import line

    # the first build in an empty cache folder, then the same system again
    L, q = double_pendulum_lagrangian()
    old = os.environ.get("MECHPY_CACHE_DIR")
    with tempfile.TemporaryDirectory(prefix="mechpy-cache-") as cache:
        os.environ["MECHPY_CACHE_DIR"] = cache
        try:
            t0 = time.perf_counter()
            scene = mp.lagrangian(L, q, params=DP_PARAMS)
            t1 = time.perf_counter()
            mp.lagrangian(L, q, params=DP_PARAMS)
            t2 = time.perf_counter()
            fresh = min(cache_build_time(cache, "L, q = double_pendulum_lagrangian()",
                                         "mp.lagrangian(L, q, params=DP_PARAMS)")
                        for _ in range(2))
        finally:
            if old is None:
                del os.environ["MECHPY_CACHE_DIR"]
            else:
                os.environ["MECHPY_CACHE_DIR"] = old
    t0s = time.perf_counter()
    f = double_pendulum_sympy()
    t_sympy = time.perf_counter() - t0s
    line("mp.lagrangian: first build (derive, C, cc)", f"{t1 - t0:.2f} s",
         ref=f"SymPy solve + lambdify {t_sympy:.2f} s")
    line("mp.lagrangian: the same system again", f"{(t2 - t1) * 1e3:.1f} ms",
         ref=f"from the cache; in a new process {fresh * 1e3:.1f} ms (best of 2)")

    # the reference: dop853 at rtol 1e-14, checked by rk8pd and by the
    # lambdified equations (derived independently by SymPy's solve)
    ref = mp.solve(scene, (0, DP_T), DP_Y0, rtol=1e-14, atol=1e-16).y[:, -1]
    rk8 = mp.solve(scene, (0, DP_T), DP_Y0, method="gsl:rk8pd", rtol=1e-14,
                   atol=1e-16).y[:, -1]
    lam = solve_ivp(f, (0, DP_T), DP_Y0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    line(f"theta1, theta2 at t = {DP_T:g} (rad)", f"{ref[0]:.10f}, {ref[1]:.10f}",
         ref=f"rk8pd differs by {np.abs(rk8 - ref).max():.0e}, lambdified DOP853 (1e-12) "
             f"by {np.abs(lam - ref).max():.0e}")

    for rtol in (1e-7, 1e-10):
        f_mp = lambda: mp.solve(scene, (0, DP_T), DP_Y0, rtol=rtol,  # noqa: E731
                                atol=rtol * 1e-3)
        f_sp = lambda: solve_ivp(f, (0, DP_T), DP_Y0, method="DOP853",  # noqa: E731
                                 rtol=rtol, atol=rtol * 1e-3)
        e_mp = np.abs(f_mp().y[:, -1] - ref).max()
        e_sp = np.abs(f_sp().y[:, -1] - ref).max()
        line(f"dop853 rtol {rtol:g}: error at t = {DP_T:g}", f"{e_mp:.1e}",
             ref=f"lambdify + solve_ivp {e_sp:.1e}",
             t_mp=median_time(f_mp, repeat=7), t_ref=median_time(f_sp, repeat=3),
             ref_name="lambdify + solve_ivp")

    s = mp.solve(scene, (0, 100), DP_Y0, rtol=1e-12, atol=1e-14,
                 t_eval=np.linspace(0, 100, 2001))
    E = scene.energy(s.y)
    line("energy over t = 100, dop853 rtol 1e-12", f"relative drift "
         f"{np.abs(E / E[0] - 1).max():.1e}")
    modes = scene.small_oscillations([0.0, 0.0])
    w2 = DP_PARAMS["g"] / DP_PARAMS["l1"] * np.array([2 - np.sqrt(2), 2 + np.sqrt(2)])
    line("small oscillations: omega^2 (1/s^2)", " ".join(f"{w:.12f}" for w in modes.omega ** 2),
         ref="(g/l)(2 -+ sqrt 2)", err=np.abs(modes.omega ** 2 - w2).max())
