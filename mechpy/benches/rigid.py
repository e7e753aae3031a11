"""Rigid bodies: the free asymmetric body against its exact elliptic solution,
mechpy's solvers beside ``scipy.integrate.solve_ivp`` (DOP853) at the same
tolerance and at the same error, a driven body with its torque as a C
callback, and the invariant drift (|L| and energy) of every method over a long
run."""
from __future__ import annotations

import numpy as np

TITLE = "Rigid bodies: Euler's equations beside solve_ivp, invariant drift per method"
ORDER = 70

I = np.array([1.0, 2.0, 3.0])
W0 = np.array([0.3, 1.0, -0.4])


def _euler(t, w):
    return [(I[1] - I[2]) / I[0] * w[1] * w[2], (I[2] - I[0]) / I[1] * w[2] * w[0],
            (I[0] - I[1]) / I[2] * w[0] * w[1]]


def _driven_py(t, w):
    tau = (0.3 * np.cos(1.7 * t), 0.2 * np.sin(0.9 * t), -0.05 * w[2])
    e = _euler(t, w)
    return [e[0] + tau[0] / I[0], e[1] + tau[1] / I[1], e[2] + tau[2] / I[2]]


def _numba_torque():
    """The driven body's torque as a numba cfunc, or None without numba."""
    try:
        import numba
        from numba import types
    except ImportError:
        return None
    sig = types.void(types.double, types.CPointer(types.double), types.CPointer(types.double),
                     types.voidptr)

    @numba.cfunc(sig)
    def torque(t, y, tau, ud):
        tau[0] = 0.3 * np.cos(1.7 * t)
        tau[1] = 0.2 * np.sin(0.9 * t)
        tau[2] = -0.05 * y[2]

    return torque


def run(quick: bool) -> list[dict]:
    from scipy.integrate import solve_ivp

    from .. import rigid, solve
    from .._timing import median_time
    from ..scenes import RigidBody

    body = RigidBody(I)
    rows = []
    # 1. same tolerance: final-time error against the exact solution
    tf = 50.0 if quick else 500.0
    ex = rigid.free_rotation(I, W0, [tf])[0]
    for rtol in (1e-8, 1e-11):
        f_mp = lambda: solve(body, (0, tf), W0, rtol=rtol, atol=rtol * 1e-2)  # noqa: E731
        f_sp = lambda: solve_ivp(_euler, (0, tf), W0, method="DOP853", rtol=rtol,  # noqa: E731
                                 atol=rtol * 1e-2)
        for impl, f in (("mechpy dop853 (C scene)", f_mp), ("scipy DOP853", f_sp)):
            r = f()
            rows.append(dict(problem=f"free body to t={tf:g}, rtol={rtol:g}", impl=impl,
                             rtol=rtol, time=median_time(f, repeat=7),
                             error=float(np.abs(r.y[:, -1] - ex).max()), n=len(r.t),
                             nfev=int(r.nfev)))
    # 2. same error: the fixed-step geometric method beside SciPy tuned to match it
    h = 0.01
    f_sp4 = lambda: solve(body, (0, tf), W0, method="rigid:split4", h=h)  # noqa: E731
    e4 = float(np.abs(f_sp4().y[:, -1] - ex).max())
    rt = 1e-8
    while rt > 1e-13:  # SciPy's loosest tolerance reaching the split's error
        r = solve_ivp(_euler, (0, tf), W0, method="DOP853", rtol=rt, atol=rt * 1e-2)
        if np.abs(r.y[:, -1] - ex).max() <= e4:
            break
        rt /= 3.0
    f_ref = lambda: solve_ivp(_euler, (0, tf), W0, method="DOP853", rtol=rt,  # noqa: E731
                              atol=rt * 1e-2)
    problem = f"free body to t={tf:g}, same error"
    rows.append(dict(problem=problem, impl=f"mechpy rigid:split4 h={h}", error=e4,
                     time=median_time(f_sp4, repeat=3), n=int(round(tf / h))))
    rows.append(dict(problem=problem, impl=f"scipy DOP853 rtol={rt:.1e}",
                     error=float(np.abs(f_ref().y[:, -1] - ex).max()),
                     time=median_time(f_ref, repeat=3), n=len(f_ref().t)))
    # 3. a driven body: torque(t, omega) as a numba cfunc (C, GIL released)
    tq = _numba_torque()
    if tq is not None:
        driven = RigidBody(I, torque=tq)
        td = 20.0 if quick else 200.0
        ref = solve(driven, (0, td), W0, rtol=1e-13, atol=1e-14).y[:, -1]
        f_mp = lambda: solve(driven, (0, td), W0, rtol=1e-10, atol=1e-12)  # noqa: E731
        f_sp = lambda: solve_ivp(_driven_py, (0, td), W0, method="DOP853", rtol=1e-10,  # noqa: E731
                                 atol=1e-12)
        for impl, f in (("mechpy dop853 (numba cfunc torque)", f_mp),
                        ("scipy DOP853 (Python torque)", f_sp)):
            rows.append(dict(problem=f"driven body to t={td:g}, rtol=1e-10", impl=impl,
                             rtol=1e-10, time=median_time(f, repeat=3),
                             error=float(np.abs(f().y[:, -1] - ref).max()),
                             note="reference: mechpy dop853 at rtol 1e-13"))
    # 4. invariant drift per method over a long run (error column: |L| drift)
    n = 10**5 if quick else 10**6
    T = n * h
    t_eval = np.linspace(0, T, 1001)
    L0, E0 = np.linalg.norm(I * W0), body.energy(W0)
    exT = rigid.free_rotation(I, W0, [T])[0]
    runs = [("rigid:split", dict(h=h)), ("rigid:split4", dict(h=h)), ("rk4", dict(h=h)),
            ("gauss4", dict(h=h)), ("dop853", dict(rtol=1e-10, atol=1e-12))]
    for m, kw in runs:
        f = lambda m=m, kw=kw: solve(body, (0, T), W0, method=m, t_eval=t_eval, **kw)  # noqa: E731
        r = f()
        L = np.linalg.norm(I[:, None] * r.y, axis=0)
        dE = np.abs(body.energy(r.y) / E0 - 1)
        impl = m if "h" in kw else f"{m} rtol=1e-10"
        rows.append(dict(problem=f"|L| drift over t={T:g} ({n} steps of h={h})", impl=impl,
                         time=median_time(f, repeat=1, warmup=0),
                         error=float(np.abs(L / L0 - 1).max()), n=int(r.nsteps),
                         note=(f"energy error first/last tenth {dE[:100].max():.1e}/"
                               f"{dE[-100:].max():.1e}; omega(T) error "
                               f"{np.abs(r.y[:, -1] - exT).max():.1e}")))
    return rows
