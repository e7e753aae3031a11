"""Bench: events that change the state: impact oscillators (mp.events.impact in
C, in solve_many) against SciPy's only way, a solve_ivp loop that stops at each
impact and restarts, at equal error (against a tight reference that is itself
checked against SciPy's loop)."""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Events that change the state"
ORDER = 17
T = 5.0          # impact oscillator: about five impacts per trajectory


def _scipy_one(e, rtol, atol, theta0=1.0):
    """solve_ivp, stopped at each impact and restarted with the velocity reflected."""
    from scipy.integrate import solve_ivp

    def f(t, y):
        return [y[1], -9.81 * np.sin(y[0])]

    def wall(t, y):
        return y[0]
    wall.terminal, wall.direction = True, -1
    t0, y, nfev = 0.0, [theta0, 0.0], 0
    while True:
        r = solve_ivp(f, (t0, T), y, method="DOP853", rtol=rtol, atol=atol, events=wall)
        nfev += r.nfev
        if r.status != 1:
            return r.y[:, -1], nfev
        t0 = r.t_events[0][0]
        y = [0.0, -e * r.y_events[0][0][1]]


def run(quick: bool):
    rows = []
    k = 2000 if quick else 10_000
    es = np.linspace(0.5, 0.95, k)
    pend = mp.scenes.Pendulum()
    y0s = np.tile([1.0, 0.0], (k, 1))
    name = (f"{k} impact oscillators (a pendulum from 1 rad striking a wall at theta = 0, "
            f"e in [0.5, 0.95]), t = {T} s")

    def ours(rtol, th, lanes=None):
        return mp.solve_many(pend, (0, T), y0s, t_eval=[T], rtol=rtol, atol=rtol * 1e-2,
                             threads=th, events=mp.events.impact("theta", restitution=es),
                             lanes=lanes)
    ref = ours(1e-13, 2).y[:, :, -1]
    sub = 10 if quick else 40
    idx = np.linspace(0, k - 1, sub).astype(int)
    # the reference checked against SciPy's restart loop at the same tight tolerance
    check = np.array([_scipy_one(es[i], 1e-13, 1e-15)[0] for i in idx])
    rows.append(dict(problem=name, impl="reference (mechpy rtol 1e-13) vs SciPy's restart loop "
                     "at rtol 1e-13", path="events-ref", time=float("nan"),
                     error=float(np.max(np.abs(check - ref[idx])))))

    def err(y):
        return float(np.max(np.abs(y - ref)))
    for rtol in (1e-6, 1e-8, 1e-10):
        for th in (1, 2):
            fn = lambda rtol=rtol, th=th: ours(rtol, th)    # noqa: E731
            rows.append(dict(problem=name, impl=f"mechpy solve_many + impact (C), lanes, {th} "
                             f"thread(s)", path=f"events-mechpy-{th}", rtol=rtol,
                             time=median_time(fn, repeat=3), error=err(fn().y[:, :, -1])))
        fn = lambda rtol=rtol: ours(rtol, 1, False)    # noqa: E731
        rows.append(dict(problem=name, impl="mechpy solve_many + impact (C), one solve per "
                         "trajectory, 1 thread", path="events-mechpy-scalar", rtol=rtol,
                         time=median_time(fn, repeat=3), error=err(fn().y[:, :, -1])))

        def loop(rtol=rtol):
            return [_scipy_one(es[i], rtol, rtol * 1e-2)[0] for i in idx]
        got = loop()
        rows.append(dict(problem=name, impl="solve_ivp DOP853, stopped and restarted at each "
                         "impact (Python loop)", path="events-scipy", rtol=rtol,
                         time=median_time(loop, repeat=1, warmup=0) * (k / sub),
                         error=float(np.max(np.abs(np.array(got) - ref[idx]))),
                         note=f"{sub} trajectories timed, scaled to {k}"))
    return rows


def targets(rows):
    """mechpy at equal or smaller error against the restart loop (1 thread)."""
    out = []
    mine = [r for r in rows if r.get("path") == "events-mechpy-1"]
    ref = [r for r in rows if r.get("path") == "events-scipy"]
    pairs = []
    for q in ref:
        fit = [r["time"] for r in mine if r["error"] <= q["error"]]
        if fit:
            pairs.append(q["time"] / min(fit))
    if pairs:
        out.append(dict(target="impact oscillators: solve_many + impact vs a solve_ivp "
                        "restart loop, equal error", problem=ref[0]["problem"], goal=">= 100x",
                        worst=min(pairs), median=float(np.median(pairs)), n=len(pairs)))
    scalar = {r["rtol"]: r["time"] for r in rows if r.get("path") == "events-mechpy-scalar"}
    lanes = [scalar[r["rtol"]] / r["time"] for r in mine if r["rtol"] in scalar]
    if lanes:
        out.append(dict(target="impact oscillators in lanes vs one solve per trajectory, "
                        "1 thread", problem=mine[0]["problem"], goal=">= 2x",
                        worst=min(lanes), median=float(np.median(lanes)), n=len(lanes)))
    return out
