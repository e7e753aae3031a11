"""Rigid bodies: the free asymmetric body (exact elliptic reference) and the
heavy top, mechpy's solvers beside ``scipy.integrate.solve_ivp`` (DOP853) at
the same tolerance, plus the invariant drift of every method over a long run."""
from __future__ import annotations

import numpy as np

TITLE = "Rigid bodies: Euler's equations and the heavy top beside solve_ivp"
ORDER = 70

I = np.array([1.0, 2.0, 3.0])
W0 = np.array([0.3, 1.0, -0.4])


def _euler(t, w):
    return [(I[1] - I[2]) / I[0] * w[1] * w[2], (I[2] - I[0]) / I[1] * w[2] * w[0],
            (I[0] - I[1]) / I[2] * w[0] * w[1]]


def run(quick: bool) -> list[dict]:
    from scipy.integrate import solve_ivp

    from .. import rigid, solve
    from .._timing import median_time
    from ..scenes import RigidBody

    body = RigidBody(I)
    tf = 50.0 if quick else 500.0
    ex = rigid.free_rotation(I, W0, [tf])[0]
    rows = []
    for rtol in (1e-8, 1e-11):
        f_mp = lambda: solve(body, (0, tf), W0, rtol=rtol, atol=rtol * 1e-2)  # noqa: E731
        f_sp = lambda: solve_ivp(_euler, (0, tf), W0, method="DOP853", rtol=rtol,  # noqa: E731
                                 atol=rtol * 1e-2)
        for impl, f in (("mechpy dop853", f_mp), ("scipy DOP853", f_sp)):
            r = f()
            rows.append(dict(problem=f"free body to t={tf:g}, rtol={rtol:g}", impl=impl,
                             time=median_time(f, repeat=3),
                             error=float(np.abs(r.y[:, -1] - ex).max()), n=len(r.t)))
    # invariant drift per method over a long run
    n = 10**5 if quick else 10**6
    h = 0.01
    L0 = np.linalg.norm(I * W0)
    for m in ("rigid:split", "rigid:split4", "rk4", "verlet" if False else "gauss4"):
        f = lambda m=m: solve(body, (0, n * h), W0, method=m, h=h,  # noqa: E731
                              t_eval=np.linspace(0, n * h, 11))
        r = f()
        L = np.linalg.norm(I[:, None] * r.y, axis=0)
        E = body.energy(r.y)
        rows.append(dict(problem=f"|L| drift, {n} steps h={h}", impl=m, time=median_time(f, repeat=1),
                         error=float(np.abs(L / L0 - 1).max()), n=n,
                         note=f"energy drift {np.abs(E / E[0] - 1).max():.1e}"))
    return rows
