"""Normal modes: mechpy.modes.normal_modes beside scipy.linalg.eigh (dense
generalized problems) and beside scipy.linalg.eigh_tridiagonal (chains).

Error columns: for dense pairs the largest scaled residual
``||K v - w M v|| / ((||K|| + w ||M||) ||v||)`` of each result; for the
uniform fixed chain the largest error of omega against the closed form
``2 sqrt(k/m) sin(j pi / (2(N+1)))``, relative to the largest omega.
A 100-mass chain integrated in time (the SpringChain scene beside
``solve_ivp``) has the error of x(T) against the exact modal motion.
"""
from __future__ import annotations

import numpy as np

from .._timing import median_time

TITLE = "Normal modes (generalized symmetric eigenproblem, chains)"
ORDER = 60


def _dense_pair(n, rng):
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((n, n))
    return A @ A.T / n + 0.1 * np.eye(n), B @ B.T / n + np.eye(n)


def _paired(fa, fb, repeat):
    """Median times of fa and fb, measured alternately (after one warm-up
    each) so that a changing machine load affects both alike."""
    import time

    fa()
    fb()
    ta, tb = [], []
    for _ in range(repeat):
        for f, ts in ((fa, ta), (fb, tb)):
            t0 = time.perf_counter()
            f()
            ts.append(time.perf_counter() - t0)
    return float(np.median(ta)), float(np.median(tb))


def _residual(K, M, w, V):
    R = K @ V - (M @ V) * w
    scale = (np.linalg.norm(K, 2) + w * np.linalg.norm(M, 2)) * np.linalg.norm(V, axis=0)
    return float(np.max(np.linalg.norm(R, axis=0) / scale))


def run(quick: bool) -> list[dict]:
    import scipy.linalg as sl

    from ..modes import chain, normal_modes

    rng = np.random.default_rng(7)
    rows = []
    for n in ((200, 500) if quick else (500, 2000)):
        K, M = _dense_pair(n, rng)
        prob = f"K v = w M v, random SPD pair, n={n}"
        res = {}
        t_mp, t_sp = _paired(lambda: res.__setitem__("mp", normal_modes(K, M, method="dense")),
                             lambda: res.__setitem__("sp", sl.eigh(K, M)), 3 if quick else 7)
        m = res["mp"]
        ws, Vs = res["sp"]
        rows.append(dict(problem=prob, impl="mechpy normal_modes (LAPACK dsygvd, C)", time=t_mp,
                         error=_residual(K, M, m.omega ** 2, m.vectors), n=n,
                         ratio=t_sp / t_mp, note=f"{t_sp / t_mp:.2f}x scipy"))
        rows.append(dict(problem=prob, impl="scipy.linalg.eigh(K, M)", time=t_sp,
                         error=_residual(K, M, ws, Vs), n=n))

    N = 2000 if quick else 10_000
    kappa, mass = 1.0, 1.0
    prob = f"fixed chain, N={N}, all modes"
    exact = 2 * np.sqrt(kappa / mass) * np.sin(np.arange(1, N + 1) * np.pi / (2 * (N + 1)))
    Ks, Ms = chain(N, mass=mass, spring=kappa, sparse=True)
    K, M = chain(N, mass=mass, spring=kappa)

    def err(omega):
        return float(np.max(np.abs(omega - exact)) / exact[-1])

    res = {}
    t_mp = median_time(lambda: res.__setitem__("mp", normal_modes(K, M)), repeat=3, budget=10)
    t_mps = median_time(lambda: res.__setitem__("mps", normal_modes(Ks, Ms)), repeat=3, budget=10)
    md = np.diag(M)
    s = 1 / np.sqrt(md)

    def scipy_tri():
        w, U = sl.eigh_tridiagonal(np.diag(K) * s * s, np.diag(K, 1) * s[:-1] * s[1:])
        return w, U * s[:, None]

    t_tri = median_time(lambda: res.__setitem__("tri", scipy_tri()), repeat=3, budget=10)
    t_dense = median_time(lambda: res.__setitem__("dense", sl.eigh(K, M, eigvals_only=False)),
                          repeat=1, warmup=0)
    rows.append(dict(problem=prob, impl="mechpy normal_modes(K, M) (dense input, chain path)",
                     time=t_mp, error=err(res["mp"].omega), n=N, ratio=t_dense / t_mp,
                     note=f"{t_dense / t_mp:.0f}x dense eigh, {t_tri / t_mp:.2f}x eigh_tridiagonal"))
    rows.append(dict(problem=prob, impl="mechpy normal_modes(K, M) (scipy.sparse input)",
                     time=t_mps, error=err(res["mps"].omega), n=N,
                     note=f"{t_dense / t_mps:.0f}x dense eigh, {t_tri / t_mps:.2f}x eigh_tridiagonal"))
    rows.append(dict(problem=prob, impl="scipy.linalg.eigh_tridiagonal (scaled by hand)",
                     time=t_tri, error=err(np.sqrt(np.maximum(res["tri"][0], 0))), n=N))
    rows.append(dict(problem=prob, impl="scipy.linalg.eigh(K, M) (dense)", time=t_dense,
                     error=err(np.sqrt(np.maximum(res["dense"][0], 0))), n=N))
    rows += _chain_rows(quick)
    return rows


def _chain_rows(quick: bool) -> list[dict]:
    """A 100-mass fixed chain integrated in time: the SpringChain C scene
    beside solve_ivp(DOP853) on a vectorised NumPy right-hand side, errors
    against the exact modal motion (Modes.evolve)."""
    from scipy.integrate import solve_ivp

    from ..integrate import solve
    from ..scenes import SpringChain

    N, T = 100, 100.0
    masses = np.ones(N)
    masses[N // 2] = 3.0                       # a mass defect: no closed form, exact by modes
    sc = SpringChain(masses, 1.0)
    x = np.arange(N)
    q0 = np.exp(-0.5 * ((x - N / 3) / 5.0) ** 2)
    y0 = sc.initial_state(q0)
    md = sc.modes()
    exact = md.evolve(q0, np.zeros(N), T)
    t_ex = median_time(lambda: md.evolve(q0, np.zeros(N), T), repeat=5, budget=0.5)

    def f(_t, y):
        r = np.diff(np.concatenate([[0.0], y[:N], [0.0]]))   # spring extensions
        return np.concatenate([y[N:], np.diff(r) / masses])

    prob = f"SpringChain N={N} (mass defect), fixed ends, t={T:g}, exact by modes"
    rows = [dict(problem=prob, impl="mechpy Modes.evolve (exact, reference)", time=t_ex,
                 error=float("nan"), n=N)]
    for rtol in ((1e-6, 1e-10) if quick else (1e-5, 1e-7, 1e-9, 1e-11, 1e-13)):
        atol = rtol * 1e-2
        res = {}
        t_mp, t_sp = _paired(
            lambda: res.__setitem__("mp", solve(sc, (0.0, T), y0, rtol=rtol, atol=atol)),
            lambda: res.__setitem__("sp", solve_ivp(f, (0.0, T), y0, method="DOP853",
                                                    rtol=rtol, atol=atol)),
            3 if quick else 5)
        e_mp = float(np.max(np.abs(res["mp"].y[:N, -1] - exact)))
        e_sp = float(np.max(np.abs(res["sp"].y[:N, -1] - exact)))
        rows.append(dict(problem=prob, impl="mechpy dop853 (C scene SpringChain)", rtol=rtol,
                         time=t_mp, error=e_mp, nfev=int(res["mp"].nfev), n=N,
                         ratio=t_sp / t_mp, note=f"{t_sp / t_mp:.1f}x solve_ivp"))
        rows.append(dict(problem=prob, impl="scipy solve_ivp DOP853 (NumPy rhs)", rtol=rtol,
                         time=t_sp, error=e_sp, nfev=int(res["sp"].nfev), n=N))
    return rows
