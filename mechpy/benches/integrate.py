"""Bench: tolerance sweeps of the non-stiff problems, mechpy beside SciPy."""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Integrators: work against precision"
ORDER = 10


def _pendulum_problem():
    from scipy.special import ellipj, ellipk
    theta0, T = 2.5, 10.0
    k = np.sin(theta0 / 2)
    sn, cn, _, _ = ellipj(ellipk(k * k) - np.sqrt(9.81) * T, k * k)
    ref = np.array([2 * np.arcsin(k * sn), -2 * k * np.sqrt(9.81) * cn])

    def f(t, y):
        return [y[1], -9.81 * np.sin(y[0])]
    return "pendulum theta0=2.5, t=10 (exact elliptic)", mp.scenes.Pendulum(), f, \
        np.array([theta0, 0.0]), T, ref


def _vdp_problem():
    v = mp.scenes.VanDerPol(mu=1.0)
    y0, T = np.array([2.0, 0.0]), 20.0
    ref = mp.solve(v, (0, T), y0, rtol=1e-14, atol=1e-16).y[:, -1]
    check = mp.solve(v, (0, T), y0, method="gsl:rk8pd", rtol=1e-14, atol=1e-16).y[:, -1]
    assert np.max(np.abs(ref - check)) < 1e-10, "reference solutions disagree"

    def f(t, y):
        return [y[1], (1 - y[0] ** 2) * y[1] - y[0]]
    return "Van der Pol mu=1, t=20 (dop853 at 1e-14, checked by rk8pd)", v, f, y0, T, ref


def run(quick: bool):
    from scipy.integrate import odeint, solve_ivp
    rtols = [1e-4, 1e-7, 1e-10] if quick else [1e-3, 1e-5, 1e-7, 1e-9, 1e-11, 1e-13]
    rows = []
    for name, scene, f, y0, T, ref in (_pendulum_problem(), _vdp_problem()):
        for rtol in rtols:
            atol = rtol * 1e-3
            cases = [
                ("mechpy dop853 (C scene)", lambda: mp.solve(scene, (0, T), y0, rtol=rtol,
                                                              atol=atol)),
                ("mechpy dopri5 (C scene)", lambda: mp.solve(scene, (0, T), y0, method="dopri5",
                                                              rtol=rtol, atol=atol)),
                ("mechpy dop853 (Python rhs)", lambda: mp.solve(f, (0, T), y0, rtol=rtol,
                                                                 atol=atol)),
                ("scipy solve_ivp DOP853", lambda: solve_ivp(f, (0, T), y0, method="DOP853",
                                                             rtol=rtol, atol=atol)),
                ("scipy solve_ivp RK45", lambda: solve_ivp(f, (0, T), y0, method="RK45",
                                                           rtol=rtol, atol=atol)),
                ("scipy solve_ivp LSODA", lambda: solve_ivp(f, (0, T), y0, method="LSODA",
                                                            rtol=rtol, atol=atol)),
            ]
            for impl, fn in cases:
                if quick and "RK45" in impl and rtol < 1e-8:
                    continue
                s = fn()
                err = float(np.max(np.abs(s.y[:, -1] - ref)))
                t = median_time(fn, repeat=3 if impl.startswith("scipy") else 7, budget=1.0)
                rows.append(dict(problem=name, impl=impl, rtol=rtol, error=err, time=t,
                                 nfev=int(s.nfev)))
            yo = lambda: odeint(f, y0, [0, T], rtol=rtol, atol=atol, tfirst=True,  # noqa: E731
                                mxstep=10**7)
            err = float(np.max(np.abs(yo()[-1] - ref)))
            rows.append(dict(problem=name, impl="scipy odeint", rtol=rtol, error=err,
                             time=median_time(yo, repeat=5, budget=1.0)))
    return rows
