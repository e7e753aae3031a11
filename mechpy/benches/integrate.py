"""Bench: tolerance sweeps of the non-stiff problems, mechpy beside SciPy.

Every problem is run at each tolerance on every path mechpy offers (C scene,
Python right-hand side, C callback compiled by numba) beside SciPy's
``solve_ivp`` (RK45, DOP853, LSODA), ``odeint`` and, when installed,
numbalsoda driven by the very same numba ``cfunc``.  Rows carry ``path`` and
``method`` so that :func:`mechpy.bench.targets` can pair them.
"""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Integrators: work against precision"
ORDER = 10

ARENSTORF_Y0 = np.array([0.994, 0.0, 0.0, -2.00158510637908252240537862224])
ARENSTORF_T = 17.0652165601579625588917206249  # Hairer, Norsett, Wanner I, II.0


def _pendulum():
    from scipy.special import ellipj, ellipk
    theta0, T = 2.5, 10.0
    k = np.sin(theta0 / 2)
    sn, cn, _, _ = ellipj(ellipk(k * k) - np.sqrt(9.81) * T, k * k)
    ref = np.array([2 * np.arcsin(k * sn), -2 * k * np.sqrt(9.81) * cn])

    def f(t, y):
        return [y[1], -9.81 * np.sin(y[0])]

    def c(t, y, dy, p):
        dy[0] = y[1]
        dy[1] = -9.81 * np.sin(y[0])
    return dict(name="pendulum theta0=2.5, t=10 (exact elliptic)", scene=mp.scenes.Pendulum(),
                f=f, c=c, y0=np.array([theta0, 0.0]), T=T, ref=ref)


def _vdp():
    v = mp.scenes.VanDerPol(mu=1.0)
    y0, T = np.array([2.0, 0.0]), 20.0
    ref = mp.solve(v, (0, T), y0, rtol=1e-14, atol=1e-16).y[:, -1]
    check = mp.solve(v, (0, T), y0, method="gsl:rk8pd", rtol=1e-14, atol=1e-16).y[:, -1]
    assert np.max(np.abs(ref - check)) < 1e-10, "reference solutions disagree"

    def f(t, y):
        return [y[1], (1 - y[0] ** 2) * y[1] - y[0]]

    def c(t, y, dy, p):
        dy[0] = y[1]
        dy[1] = (1 - y[0] * y[0]) * y[1] - y[0]
    return dict(name="Van der Pol mu=1, t=20 (dop853 at 1e-14, checked by rk8pd)", scene=v,
                f=f, c=c, y0=y0, T=T, ref=ref)


def _arenstorf():
    mu = 0.012277471

    def f(t, y):
        m1 = 1 - mu
        d1 = ((y[0] + mu) ** 2 + y[1] ** 2) ** 1.5
        d2 = ((y[0] - m1) ** 2 + y[1] ** 2) ** 1.5
        return [y[2], y[3], y[0] + 2 * y[3] - m1 * (y[0] + mu) / d1 - mu * (y[0] - m1) / d2,
                y[1] - 2 * y[2] - m1 * y[1] / d1 - mu * y[1] / d2]

    def c(t, y, dy, p):
        m1 = 1 - mu
        a, b = y[0] + mu, y[0] - m1
        r1 = a * a + y[1] * y[1]
        r2 = b * b + y[1] * y[1]
        d1 = r1 * np.sqrt(r1)
        d2 = r2 * np.sqrt(r2)
        dy[0] = y[2]
        dy[1] = y[3]
        dy[2] = y[0] + 2 * y[3] - m1 * a / d1 - mu * b / d2
        dy[3] = y[1] - 2 * y[2] - m1 * y[1] / d1 - mu * y[1] / d2
    return dict(name="Arenstorf orbit, one period (published period): closure error",
                scene=mp.scenes.RestrictedThreeBody(mu), f=f, c=c, y0=ARENSTORF_Y0,
                T=ARENSTORF_T, ref=ARENSTORF_Y0)


def kepler_exact(e, t, mu=1.0, a=1.0):
    """Kepler orbit from pericentre at time t: Kepler's equation by Newton."""
    n = np.sqrt(mu / a ** 3)
    M = n * t
    E = M + e * np.sin(M)
    for _ in range(50):
        E -= (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
    den = 1 - e * np.cos(E)
    b = np.sqrt(1 - e * e)
    return np.array([a * (np.cos(E) - e), a * b * np.sin(E), -a * n * np.sin(E) / den,
                     a * n * b * np.cos(E) / den])


def _kepler():
    e, T = 0.6, 5.25 * 2 * np.pi
    k = mp.scenes.Kepler()

    def f(t, y):
        r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
        return [y[2], y[3], -y[0] / r3, -y[1] / r3]

    def c(t, y, dy, p):
        r2 = y[0] * y[0] + y[1] * y[1]
        r3 = r2 * np.sqrt(r2)
        dy[0] = y[2]
        dy[1] = y[3]
        dy[2] = -y[0] / r3
        dy[3] = -y[1] / r3
    return dict(name="Kepler e=0.6, 5.25 orbits (Kepler's equation)", scene=k, f=f, c=c,
                y0=k.initial_state(e), T=T, ref=kepler_exact(e, T))


def _cfuncs(problems):
    """Compile each problem's C right-hand side with numba (None without numba)."""
    try:
        from numba import cfunc, types
    except ImportError:
        return None
    sig = types.void(types.double, types.CPointer(types.double), types.CPointer(types.double),
                     types.voidptr)
    return [cfunc(sig, nopython=True, fastmath=False)(pr["c"]) for pr in problems]


def _numbalsoda():
    try:
        import numbalsoda
    except ImportError:
        return None
    return numbalsoda


def _call_cost(cfs, nbs):
    """The fixed cost of a call: a tiny solve (pendulum, t in (0, 1), rtol 1e-3,
    default output) by mechpy (C scene), numbalsoda (the same right-hand side as
    a numba cfunc) and solve_ivp, each dop853 with atol 1e-10."""
    from scipy.integrate import solve_ivp
    pr = _pendulum()
    scene, f = pr["scene"], pr["f"]
    y0 = np.array([1.0, 0.0])
    name = "call cost: pendulum, t in (0, 1), rtol=1e-3, dop853"
    ref = mp.solve(scene, (0, 1), y0, rtol=1e-13, atol=1e-15).y[:, -1]
    cases = [("mechpy solve (C scene)", "call-mechpy",
              lambda: mp.solve(scene, (0, 1), y0, rtol=1e-3)),
             ("mechpy solve (C scene), t_eval=[tf]", "call-mechpy-teval",
              lambda: mp.solve(scene, (0, 1), y0, rtol=1e-3, t_eval=[1.0])),
             ("scipy solve_ivp DOP853", "call-scipy",
              lambda: solve_ivp(f, (0, 1), y0, method="DOP853", rtol=1e-3, atol=1e-10))]
    if nbs is not None:
        addr, tt = cfs[0].address, np.array([0.0, 1.0])
        cases.append(("numbalsoda dop853 (numba cfunc)", "call-numbalsoda",
                      lambda: nbs.dop853(addr, y0, tt, rtol=1e-3, atol=1e-10)))
    rows = []
    for impl, path, fn in cases:
        out = fn()
        y1 = out[0][-1] if path == "call-numbalsoda" else out.y[:, -1]
        rows.append(dict(problem=name, impl=impl, path=path, rtol=1e-3,
                         error=float(np.max(np.abs(y1 - ref))),
                         time=median_time(fn, repeat=7, budget=1.0)))
    return rows


def targets(rows) -> list[dict]:
    """The call cost: mechpy's tiny solve against numbalsoda's (goal <= 2x), and
    one output point, t_eval=[tf], against the default output (goal <= 1.1x)."""
    by = {r["path"]: r for r in rows if (r.get("path") or "").startswith("call-")}
    out = []
    if "call-mechpy" in by and "call-numbalsoda" in by:
        v = by["call-mechpy"]["time"] / by["call-numbalsoda"]["time"]
        out.append(dict(target="call cost: mechpy / numbalsoda (tiny solve)",
                        problem=by["call-mechpy"]["problem"], goal="<= 2x", worst=v, median=v,
                        n=1))
    if "call-mechpy" in by and "call-mechpy-teval" in by:
        v = by["call-mechpy-teval"]["time"] / by["call-mechpy"]["time"]
        out.append(dict(target="one output point: t_eval=[tf] / default output (tiny solve)",
                        problem=by["call-mechpy"]["problem"], goal="<= 1.1x", worst=v,
                        median=v, n=1))
    return out


def run(quick: bool):
    from scipy.integrate import odeint, solve_ivp
    rtols = [1e-4, 1e-7, 1e-10] if quick else [1e-3, 1e-5, 1e-7, 1e-9, 1e-11, 1e-13]
    problems = [_pendulum(), _vdp(), _arenstorf(), _kepler()]
    cfs = _cfuncs(problems)
    nbs = _numbalsoda() if cfs is not None else None
    rows = _call_cost(cfs, nbs)
    for ip, pr in enumerate(problems):
        scene, f, y0, T, ref = pr["scene"], pr["f"], pr["y0"], pr["T"], pr["ref"]
        for rtol in rtols:
            atol = rtol * 1e-3
            cases = [
                ("mechpy dop853 (C scene)", "c-scene", "dop853",
                 lambda: mp.solve(scene, (0, T), y0, rtol=rtol, atol=atol)),
                ("mechpy dopri5 (C scene)", "c-scene", "dopri5",
                 lambda: mp.solve(scene, (0, T), y0, method="dopri5", rtol=rtol, atol=atol)),
                ("mechpy dop853 (Python rhs)", "python", "dop853",
                 lambda: mp.solve(f, (0, T), y0, rtol=rtol, atol=atol)),
                ("mechpy dopri5 (Python rhs)", "python", "dopri5",
                 lambda: mp.solve(f, (0, T), y0, method="dopri5", rtol=rtol, atol=atol)),
                ("scipy solve_ivp DOP853", "scipy", "dop853",
                 lambda: solve_ivp(f, (0, T), y0, method="DOP853", rtol=rtol, atol=atol)),
                ("scipy solve_ivp RK45", "scipy", "dopri5",
                 lambda: solve_ivp(f, (0, T), y0, method="RK45", rtol=rtol, atol=atol)),
                ("scipy solve_ivp LSODA", "scipy", "lsoda",
                 lambda: solve_ivp(f, (0, T), y0, method="LSODA", rtol=rtol, atol=atol)),
            ]
            if cfs is not None:
                cf = cfs[ip]
                cases.append(("mechpy dop853 (C callback, numba cfunc)", "cfunc", "dop853",
                              lambda: mp.solve(cf, (0, T), y0, rtol=rtol, atol=atol)))
            for impl, path, method, fn in cases:
                if rtol < 1e-8 and method == "dopri5" and path in ("python", "scipy"):
                    continue  # a 5th-order method at 1e-9 and below takes seconds in Python
                s = fn()
                err = float(np.max(np.abs(s.y[:, -1] - ref)))
                t = median_time(fn, repeat=3 if path in ("scipy", "python") else 7, budget=1.0)
                rows.append(dict(problem=pr["name"], impl=impl, path=path, method=method,
                                 rtol=rtol, error=err, time=t, nfev=int(s.nfev)))
            yo = lambda: odeint(f, y0, [0, T], rtol=rtol, atol=atol, tfirst=True,  # noqa: E731
                                mxstep=10**7)
            err = float(np.max(np.abs(yo()[-1] - ref)))
            rows.append(dict(problem=pr["name"], impl="scipy odeint", path="odeint",
                             method="lsoda", rtol=rtol, error=err,
                             time=median_time(yo, repeat=5, budget=1.0)))
            if nbs is not None:
                addr, tt = cfs[ip].address, np.array([0.0, T])
                for meth in ("dop853", "lsoda"):
                    solver = getattr(nbs, meth)
                    fn = lambda solver=solver: solver(addr, y0, tt, rtol=rtol,  # noqa: E731
                                                      atol=atol, mxstep=10**7)
                    u, ok = fn()
                    rows.append(dict(problem=pr["name"], impl=f"numbalsoda {meth} (numba cfunc)",
                                     path="numbalsoda", method=meth, rtol=rtol,
                                     error=float(np.max(np.abs(u[-1] - ref))) if ok
                                     else float("nan"),
                                     time=median_time(fn, repeat=7, budget=1.0)))
    return rows
