#!/usr/bin/env python3
"""Bit-for-bit check of the engine across a refactoring.

    .venv/bin/python scripts/golden.py record before.pkl    # on the old build
    .venv/bin/python scripts/golden.py compare before.pkl   # on the new build

Every method on every scene it accepts (forwards, backwards, with t_eval, dense
output, events, a small budget), Python and compiled systems, and ensembles
(lanes and the scalar path, params, backwards, budgets, stiffness hints) are
solved; their states, counts, statuses and messages are recorded.  `compare`
reports every case whose outcome differs in a single bit (NaN equal to NaN).
"""
from __future__ import annotations

import pickle
import sys
import warnings

import numpy as np

import mechpy as mp
from mechpy import scenes as S


def _scenes():
    yield "pendulum", S.Pendulum(), [2.5, 0.0]
    yield "pendulum_driven", S.Pendulum(damping=0.1, drive_amplitude=0.5,
                                        drive_frequency=0.7), [1.0, 0.0]
    yield "vdp5", S.VanDerPol(mu=5.0), [2.0, 0.0]
    yield "duffing", S.Duffing(alpha=-1.0, beta=1.0, delta=0.2, gamma=0.3, omega=1.2), [1.0, 0.0]
    yield "kepler", S.Kepler(), [1.0, 0.0, 0.0, 1.2]
    yield "r3b", S.RestrictedThreeBody(), [0.994, 0.0, 0.0, -2.00158510637908]
    yield "foucault", S.Foucault(latitude=45.0, length=10.0), [0.1, 0.0, 0.0, 0.0]
    yield "rigid", S.RigidBody(moments=(1.0, 2.0, 3.0)), [0.1, 1.0, 0.1]
    yield "rigid_q", S.RigidBody(moments=(1.0, 2.0, 3.0), orientation=True), \
        [0.1, 1.0, 0.1, 1.0, 0.0, 0.0, 0.0]
    yield "top", S.HeavyTop(I1=1.0, I3=0.5, mass=1.0, l=0.5), [0.0, 0.5, 0.0, 0.0, 0.0, 10.0]
    yield "chain", S.SpringChain(masses=[1.0, 2.0, 1.5], springs=[1.0, 2.0, 1.0, 3.0]), \
        [0.1, 0.0, -0.1, 0.0, 0.2, 0.0]
    yield "rocket", S.Rocket(exhaust_speed=2500.0, burn_rate=10.0, m0=1000.0, m_dry=200.0,
                             g=9.81), [0.0, 0.0, 1000.0]

    def lorenz(t, y):
        return [10.0 * (y[1] - y[0]), y[0] * (28.0 - y[2]) - y[1], y[0] * y[1] - 8.0 / 3.0 * y[2]]
    yield "python_lorenz", lorenz, [1.0, 1.0, 1.0]


def _compiled():
    th, = mp.coordinates("theta")
    import sympy as sp
    g, L = sp.symbols("g L", positive=True)
    return mp.lagrangian(sp.Rational(1, 2) * L**2 * th.diff()**2 + g * L * sp.cos(th),
                         [th], params={"g": 9.81, "L": 1.0})


def _pack(sol):
    out = {}
    for key in ("t", "y", "status", "message", "success", "nfev", "njev", "nlu", "nsteps",
                "nreject", "t_events", "y_events"):
        v = sol.get(key) if isinstance(sol, dict) else getattr(sol, key, None)
        if isinstance(v, list):
            v = [np.asarray(a) for a in v]
        out[key] = v
    if isinstance(sol, dict) and sol.get("sol") is not None:
        t = np.asarray(sol["t"])
        tq = np.linspace(t[0], t[-1], 7)
        out["dense"] = np.asarray(sol["sol"](tq))
    return out


def _run(fn):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return _pack(fn())
    except Exception as exc:  # an error is an outcome too
        return {"error": f"{type(exc).__name__}: {exc}"}


def cases():
    methods = [m["name"] for m in mp.methods()]
    table = {m["name"]: m for m in mp.methods()}
    systems = list(_scenes())
    try:
        systems.append(("compiled_pendulum", _compiled(), [1.0, 0.0]))
    except Exception as exc:  # no compiler: say so, record the rest
        print("compiled system skipped:", exc, file=sys.stderr)
    for name, sysm, y0 in systems:
        for m in methods:
            info = table[m]
            kw = {} if info["adaptive"] else {"h": 0.01}
            if not info["adaptive"] and name == "rocket":
                kw = {"h": 0.5}
            span = (0.0, 60.0) if name == "rocket" else (0.0, 3.0)
            rt = dict(rtol=1e-6, atol=1e-9)
            # a budget keeps the slow pairs (implicit Euler on a Python rhs) short: how
            # a solve ends on its budget is compared as any other outcome
            base = dict(method=m, **kw, **rt, max_steps=20000, errors="status")
            yield (name, m, "plain"), lambda s=sysm, y=y0, b=base, sp=span: mp.solve(s, sp, y, **b)
            yield (name, m, "back"), lambda s=sysm, y=y0, b=base, sp=span: mp.solve(
                s, (sp[1], sp[0]), y, **b)
            yield (name, m, "t_eval"), lambda s=sysm, y=y0, b=base, sp=span: mp.solve(
                s, sp, y, t_eval=np.linspace(sp[0], sp[1], 11), **b)
            yield (name, m, "dense"), lambda s=sysm, y=y0, b=base, sp=span: mp.solve(
                s, sp, y, dense_output=True, **b)

            def ev(t, y):
                return y[0] - 0.5 * y[0] * 0 - 0.01
            ev.terminal = 0
            yield (name, m, "events"), lambda s=sysm, y=y0, b=base, sp=span: mp.solve(
                s, sp, y, events=[ev], **b)
            yield (name, m, "budget"), lambda s=sysm, y=y0, b=base, sp=span: mp.solve(
                s, sp, y, **dict(b, max_steps=7))
    # ensembles
    rng = np.random.default_rng(7)
    for name, sysm, y0 in systems:
        y0s = np.asarray(y0, float) * (1.0 + 0.1 * rng.standard_normal((19, len(y0))))
        span = (0.0, 60.0) if name == "rocket" else (0.0, 3.0)
        tev = np.linspace(span[0], span[1], 9)
        for m in ("dopri5", "dop853", "rk4", "radau", "gsl:rkf45", "verlet"):
            info = table[m]
            kw = {} if info["adaptive"] else {"h": 0.01}
            for lanes in (None, False):
                base = dict(method=m, rtol=1e-6, atol=1e-9, lanes=lanes, threads=2, **kw,
                            max_steps=20000, errors="status")
                yield (name, m, f"many{lanes}"), lambda s=sysm, a=y0s, b=base, sp=span, te=tev: \
                    mp.solve_many(s, sp, a, t_eval=te, **b)
                yield (name, m, f"many_back{lanes}"), lambda s=sysm, a=y0s, b=base, sp=span, \
                    te=tev: mp.solve_many(s, (sp[1], sp[0]), a, t_eval=te[::-1], **b)
                yield (name, m, f"many_budget{lanes}"), lambda s=sysm, a=y0s, b=base, sp=span, \
                    te=tev: mp.solve_many(s, sp, a, t_eval=te, **dict(b, max_steps=9))
    pend = S.Pendulum()
    par = np.column_stack([np.linspace(5, 15, 19), np.ones(19), np.linspace(0, 0.3, 19),
                           np.zeros(19), np.zeros(19)])
    y0s = np.column_stack([np.linspace(0.1, 3.0, 19), np.zeros(19)])
    for m in ("dopri5", "dop853", "rk4", "radau"):
        kw = {} if table[m]["adaptive"] else {"h": 0.01}
        for lanes in (None, False):
            yield ("pendulum", m, f"params{lanes}"), lambda m=m, kw=kw, lanes=lanes: mp.solve_many(
                pend, (0, 5), y0s, params=par, t_eval=np.linspace(0, 5, 6), method=m,
                lanes=lanes, **kw)
    stiff = S.VanDerPol(mu=1000.0)
    for lanes in (None, False):
        yield ("vdp1000", "dop853", f"stiff{lanes}"), lambda lanes=lanes: mp.solve_many(
            stiff, (0, 30), np.tile([2.0, 0.0], (9, 1)), t_eval=[0, 30], lanes=lanes,
            errors="status", max_steps=100000)


def record():
    return {key: _run(fn) for key, fn in cases()}


def _same(a, b):
    if type(a) is not type(b):
        if isinstance(a, (np.ndarray, float, int, np.generic)) and \
                isinstance(b, (np.ndarray, float, int, np.generic)):
            a, b = np.asarray(a), np.asarray(b)
        else:
            return False
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, (np.ndarray, np.generic)):   # the bits (NaN equal to NaN)
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
    return a == b


def main(argv):
    if len(argv) != 3 or argv[1] not in ("record", "compare"):
        print(__doc__)
        return 2
    now = record()
    with open(argv[2] + ".now", "wb") as f:   # this build's, to compare again at leisure
        pickle.dump(now, f)
    if argv[1] == "record":
        with open(argv[2], "wb") as f:
            pickle.dump(now, f)
        print(f"recorded {len(now)} cases")
        return 0
    with open(argv[2], "rb") as f:
        before = pickle.load(f)
    bad = [k for k in before if k not in now or not _same(before[k], now[k])]
    extra = [k for k in now if k not in before]
    for k in bad:
        print("DIFFERS:", k)
        a, b = before[k], now.get(k)
        if isinstance(a, dict) and isinstance(b, dict):
            for f in a:
                if not _same(a[f], b.get(f)):
                    print("   ", f, repr(a[f])[:200], "->", repr(b.get(f))[:200])
    print(f"{len(before)} cases, {len(bad)} differ, {len(extra)} new")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
