"""Bench: the variational solvers beside SciPy's optimisers, solve_bvp and solve_ivp."""

import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Lagrangian mechanics: extremal paths"
ORDER = 80

G = 9.81


def _brach_scipy(n, X=2.0, Y=1.0):
    """The same discrete functional (s, u = sqrt y) by L-BFGS-B with its gradient."""
    from scipy.optimize import minimize
    s = np.linspace(0, 1, n + 1)
    h = s[1] - s[0]
    sm = 0.5 * (s[1:] + s[:-1])
    A = (3 * X * sm * sm) ** 2
    c = 1 / np.sqrt(2 * G)
    ua, ub = 0.0, np.sqrt(Y)

    def fg(z):
        u = np.concatenate([[ua], z, [ub]])
        um, up = 0.5 * (u[1:] + u[:-1]), np.diff(u) / h
        R = np.sqrt(A + 4 * um * um * up * up)
        F = c * R / um
        Fu = c * (4 * um * up * up / R - R / um) / um
        Fp = c * 4 * um * um * up / R / um
        gi = h * (0.5 * Fu) - Fp
        gj = h * (0.5 * Fu) + Fp
        grad = gi[1:] + gj[:-1]
        return h * F.sum(), grad
    z0 = (np.sqrt(Y) * s)[1:-1]
    r = minimize(fg, z0, jac=True, method="L-BFGS-B",
                 bounds=[(1e-9, None)] * (n - 1), options=dict(ftol=1e-15, gtol=1e-12,
                                                               maxiter=20000, maxfun=40000))
    return r.fun


def _pendulum_refs():
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq
    qa, qb, T = 0.2, -0.5, 1.0

    def f(t, y):
        return [y[1], -G * np.sin(y[0])]

    def miss(v):
        return solve_ivp(f, (0, T), [qa, v], method="DOP853", rtol=1e-13, atol=1e-13).y[0, -1] - qb
    v = brentq(miss, -10, 5, xtol=1e-14)
    sol = solve_ivp(f, (0, T), [qa, v], method="DOP853", rtol=1e-13, atol=1e-13,
                    dense_output=True).sol
    return qa, qb, T, sol


def _compiled_double_pendulum():
    """The double pendulum (unit masses and lengths) as users build it:
    ``mp.lagrangian`` of its SymPy Lagrangian, compiled to C; None without a
    C compiler."""
    from .own import double_pendulum_lagrangian
    L, q = double_pendulum_lagrangian()
    try:
        return mp.lagrangian(L, q, params=dict(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=G))
    except mp.symbolic.CompileError:
        return None


def _dp_lagrangian(q, v):
    return (v[0] ** 2 + 0.5 * v[1] ** 2 + v[0] * v[1] * np.cos(q[0] - q[1])
            + 2 * G * np.cos(q[0]) + G * np.cos(q[1]))


def _dp_rhs(t, y):
    q1, q2, v1, v2 = y
    c, s = np.cos(q1 - q2), np.sin(q1 - q2)
    f1 = -s * v2 * v2 - 2 * G * np.sin(q1)
    f2 = s * v1 * v1 - G * np.sin(q2)
    det = 2 - c * c                       # M = [[2, c], [c, 1]]
    return [v1, v2, (f1 - c * f2) / det, (2 * f2 - c * f1) / det]


def _dp_bvp(qa, qb, T, nodes=11):
    """solve_bvp's pieces for the double pendulum's path from the angles qa to
    qb in time T: (f, bc, t, guess), the guess the uniform motion between them."""
    def bc(ya, yb):
        return np.r_[ya[:2] - qa, yb[:2] - qb]

    def f(t, y):
        return np.array(_dp_rhs(t, y))
    t = np.linspace(0, T, nodes)
    guess = np.vstack([qa[:, None] + np.outer(qb - qa, t / T),
                       np.repeat(((qb - qa) / T)[:, None], nodes, axis=1)])
    return f, bc, t, guess


def _double_pendulum_rows(quick: bool):
    """d = 2: the compiled Lagrangian (C), the Python Lagrangian (finite
    differences through the callback) and solve_ivp on the same system."""
    from scipy.integrate import solve_bvp, solve_ivp
    V = mp.variational
    rows = []
    q0, v0, T = np.array([1.0, 0.5]), np.array([0.0, 0.0]), 5.0
    ref = solve_ivp(_dp_rhs, (0, T), np.r_[q0, v0], method="DOP853", rtol=1e-13,
                    atol=1e-13).y[:2, -1]
    prob = f"double pendulum (d = 2), {T:g} s from rest"
    dp = _compiled_double_pendulum()
    for h in ((0.01, 0.001) if quick else (0.01, 0.001, 0.0001)):
        if dp is None:
            break
        r = V.variational_integrate(dp, (0, T), q0, v0, h)
        rows.append(dict(problem=prob, impl="mechpy variational_integrate, compiled L (C)",
                         n=len(r.t) - 1, error=float(np.max(np.abs(r.q[:, -1] - ref))),
                         time=median_time(lambda: V.variational_integrate(dp, (0, T), q0,
                                                                          v0, h))))
    r = V.variational_integrate(_dp_lagrangian, (0, T), q0, v0, 0.01)
    rows.append(dict(problem=prob, impl="mechpy variational_integrate, Python L",
                     n=len(r.t) - 1, error=float(np.max(np.abs(r.q[:, -1] - ref))),
                     time=median_time(lambda: V.variational_integrate(
                         _dp_lagrangian, (0, T), q0, v0, 0.01), repeat=1, budget=5.0)))
    for tol in ((1e-6, 1e-9) if quick else (1e-4, 1e-6, 1e-8, 1e-10)):
        s = solve_ivp(_dp_rhs, (0, T), np.r_[q0, v0], method="DOP853", rtol=tol, atol=tol)
        rows.append(dict(problem=prob, impl=f"scipy solve_ivp DOP853 rtol {tol:g}",
                         n=len(s.t) - 1, error=float(np.max(np.abs(s.y[:2, -1] - ref))),
                         time=median_time(lambda: solve_ivp(_dp_rhs, (0, T), np.r_[q0, v0],
                                                            method="DOP853", rtol=tol,
                                                            atol=tol))))

    # the path of stationary action between two configurations
    qa, qb, Tp = np.array([0.4, -0.3]), np.array([-0.2, 0.5]), 0.8
    prob = "double pendulum (d = 2) least-action path, 0.8 s"

    f, bc, tt, guess = _dp_bvp(qa, qb, Tp)
    fine = solve_bvp(f, bc, tt, guess, tol=1e-12, max_nodes=200000)
    for n in ((400,) if quick else (400, 1600)):
        for impl, system in (("compiled L (C)", dp), ("Python L", _dp_lagrangian)):
            if system is None:
                continue
            r = V.stationary_path(system, qa, qb, Tp, n)
            rows.append(dict(problem=prob, impl=f"mechpy stationary_path, {impl}", n=n,
                             error=float(np.max(np.abs(r.q - fine.sol(r.t)[:2]))),
                             time=median_time(lambda: V.stationary_path(system, qa, qb, Tp,
                                                                        n), repeat=3),
                             note=f"{r.iterations} iterations"))
    for tol in ((1e-6,) if quick else (1e-4, 1e-6, 1e-8)):
        b = solve_bvp(f, bc, tt, guess, tol=tol, max_nodes=100000)
        tq = np.linspace(0, Tp, 201)
        rows.append(dict(problem=prob, impl=f"scipy solve_bvp tol {tol:g}", n=len(b.x),
                         error=float(np.max(np.abs(b.sol(tq)[:2] - fine.sol(tq)[:2]))),
                         time=median_time(lambda: solve_bvp(f, bc, tt, guess, tol=tol,
                                                            max_nodes=100000), repeat=3)))
    return rows


def run(quick: bool):
    from scipy.integrate import solve_bvp
    V = mp.variational
    rows = []
    exact = 0.8055638295163989
    for n in ((100, 400) if quick else (100, 400, 1600)):
        r = V.brachistochrone(2.0, 1.0, n=n)
        rows.append(dict(problem="brachistochrone (2, 1)", impl="mechpy Newton (C, tridiagonal)",
                         n=n, time=median_time(lambda: V.brachistochrone(2.0, 1.0, n=n)),
                         error=abs(r.time - exact), note=f"{r.iterations} iterations"))
        if n <= 400:
            t = median_time(lambda: _brach_scipy(n), repeat=1, budget=5.0)
            rows.append(dict(problem="brachistochrone (2, 1)",
                             impl="scipy minimize L-BFGS-B (same discretisation, gradient)",
                             n=n, time=t, error=abs(_brach_scipy(n) - exact)))

    qa, qb, T, ref = _pendulum_refs()
    p = mp.scenes.Pendulum()
    for n in ((100, 1000) if quick else (100, 1000, 10000)):
        sp = V.stationary_path(p, qa, qb, T, n=n)
        rows.append(dict(problem="pendulum least-action path, 1 s", impl="mechpy stationary_path",
                         n=n, time=median_time(lambda: V.stationary_path(p, qa, qb, T, n=n)),
                         error=float(np.max(np.abs(sp.q - ref(sp.t)[0])))))
    for tol in ((1e-6, 1e-9) if quick else (1e-4, 1e-6, 1e-8, 1e-10)):
        def f(t, y):
            return np.vstack([y[1], -G * np.sin(y[0])])

        def bc(ya, yb):
            return np.array([ya[0] - qa, yb[0] - qb])
        tt = np.linspace(0, T, 11)
        guess = np.vstack([qa + (qb - qa) * tt / T, np.zeros_like(tt)])
        b = solve_bvp(f, bc, tt, guess, tol=tol, max_nodes=100000)
        tq = np.linspace(0, T, 201)
        rows.append(dict(problem="pendulum least-action path, 1 s", impl=f"scipy solve_bvp tol {tol:g}",
                         n=len(b.x), time=median_time(lambda: solve_bvp(f, bc, tt, guess, tol=tol,
                                                                         max_nodes=100000),
                                                      repeat=3),
                         error=float(np.max(np.abs(b.sol(tq)[0] - ref(tq)[0])))))

    # catenary: the bordered Newton beside SLSQP on the same chain of links
    from scipy.optimize import minimize
    L = 3.0
    for n in ((50,) if quick else (50, 100)):
        c = V.catenary(0.0, 2.0, L, n=n)
        rows.append(dict(problem="catenary span 2, length 3", impl="mechpy bordered Newton", n=n,
                         time=median_time(lambda: V.catenary(0.0, 2.0, L, n=n)),
                         error=float(np.max(np.abs(c.y - c.y_exact)))))
        x = np.linspace(0, 2, n + 1)

        def full(z):
            return np.concatenate([[0.0], z, [0.0]])

        def energy(z):
            y = full(z)
            return np.sum(0.5 * (y[1:] + y[:-1]) * np.hypot(np.diff(x), np.diff(y)))

        def length(z):
            return np.sum(np.hypot(np.diff(x), np.diff(full(z)))) - L
        z0 = -0.9 * np.sin(np.pi * x[1:-1] / 2)

        def slsqp():
            return minimize(energy, z0, method="SLSQP", constraints=[dict(type="eq", fun=length)],
                            options=dict(ftol=1e-12, maxiter=1000))
        s = slsqp()
        rows.append(dict(problem="catenary span 2, length 3", impl="scipy minimize SLSQP", n=n,
                         time=median_time(slsqp, repeat=1, budget=5.0),
                         error=float(np.max(np.abs(full(s.x) - c.y_exact)))))
    rows += _double_pendulum_rows(quick)
    return rows
