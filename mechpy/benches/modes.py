"""Normal modes: mechpy.modes.normal_modes beside scipy.linalg.eigh (dense
generalized problems) and beside scipy.linalg.eigh_tridiagonal (chains).

Error columns: for dense pairs the largest scaled residual
``||K v - w M v|| / ((||K|| + w ||M||) ||v||)`` of each result; for the
uniform fixed chain the largest error of omega against the closed form
``2 sqrt(k/m) sin(j pi / (2(N+1)))``, relative to the largest omega.
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
    return rows
