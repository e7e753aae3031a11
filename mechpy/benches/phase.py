"""Bench: a Van der Pol phase portrait (200x200 field + 10^4 trajectories) beside SciPy.

The portrait of :math:`\\ddot x - \\mu(1-x^2)\\dot x + x = 0` (mu = 1) is its
vector field on a 200x200 grid of (x, x_dot) in [-3, 3]^2 plus k trajectories
started on a regular grid of the same window and sampled at 201 times on
[0, 20].  mechpy evaluates the field in C (``mp.phase.vector_field``) and runs
the trajectories as one ensemble (``mp.solve_many``, DOP853); SciPy's way is a
Python right-hand side called on the grid arrays and a loop of ``solve_ivp``
(DOP853, same tolerances), of which a subset is timed and scaled to k.
Errors are the largest deviation of the sampled trajectories of that subset
from a tight reference (``solve_ivp`` DOP853, rtol = atol = 1e-13).
"""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Phase portrait: Van der Pol field and trajectory ensemble"
ORDER = 30

_MU = 1.0
_T = 20.0
_RTOL, _ATOL = 1e-8, 1e-10


def _vdp(t, y):
    """The Van der Pol right-hand side in Python (works on grid arrays too)."""
    return np.array([y[1], _MU * (1.0 - y[0] ** 2) * y[1] - y[0]])


def _starts(k):
    m = int(round(np.sqrt(k)))
    g = np.linspace(-3.0, 3.0, m)
    X, Y = np.meshgrid(g, g)
    return np.column_stack([X.ravel(), Y.ravel()])


def run(quick: bool):
    from scipy.integrate import solve_ivp
    rows = []
    vdp = mp.scenes.VanDerPol(_MU)

    # -- the vector field on a 200x200 grid
    g = np.linspace(-3.0, 3.0, 200)
    X, Y = np.meshgrid(g, g)
    name = "Van der Pol field on a 200x200 grid"
    U, V = mp.phase.vector_field(vdp, X, Y)
    F = _vdp(0.0, np.stack([X, Y]))
    t_field = median_time(lambda: mp.phase.vector_field(vdp, X, Y))
    t_field_sp = median_time(lambda: _vdp(0.0, np.stack([X, Y])))
    rows.append(dict(problem=name, impl="mechpy phase.vector_field (C scene)", time=t_field,
                     error=float(max(np.abs(U - F[0]).max(), np.abs(V - F[1]).max())), n=40_000,
                     note="error = difference from the NumPy field"))
    rows.append(dict(problem=name, impl="Python rhs called on the grid arrays (NumPy)",
                     time=t_field_sp, error=0.0, n=40_000))

    # -- 10^4 trajectories (quick: 2500), 201 samples each
    k = 2500 if quick else 10_000
    y0s = _starts(k)
    te = np.linspace(0.0, _T, 201)
    name = f"{k} Van der Pol trajectories, t = 0..{_T:g}, 201 samples, rtol={_RTOL:g}"
    sub = 10 if quick else 50
    idx = np.linspace(0, k - 1, sub).astype(int)
    ref = np.stack([solve_ivp(_vdp, (0.0, _T), y0s[i], method="DOP853", rtol=1e-13,
                              atol=1e-13, t_eval=te).y for i in idx])

    def ours():
        return mp.solve_many(vdp, (0.0, _T), y0s, t_eval=te, rtol=_RTOL, atol=_ATOL)
    e = ours()
    err_mp = float(np.abs(e.y[idx] - ref).max())
    t_traj = median_time(ours, repeat=3)
    rows.append(dict(problem=name, impl="mechpy solve_many dop853 (C scene, all threads)",
                     time=t_traj, error=err_mp, rtol=_RTOL, n=k,
                     note=f"error on the {sub} reference trajectories"))

    sp = []

    def loop():
        sp.clear()
        for i in idx:
            sp.append(solve_ivp(_vdp, (0.0, _T), y0s[i], method="DOP853", rtol=_RTOL,
                                atol=_ATOL, t_eval=te).y)
    t_loop = median_time(loop, repeat=1, warmup=0) * (k / sub)
    err_sp = float(np.abs(np.stack(sp) - ref).max())
    rows.append(dict(problem=name, impl="Python loop of scipy solve_ivp DOP853", time=t_loop,
                     error=err_sp, rtol=_RTOL, n=k,
                     note=f"{sub} trajectories timed, scaled to {k}"))
    diff = float(np.abs(e.y[idx] - np.stack(sp)).max())

    # -- the whole portrait
    name = f"Van der Pol portrait: 200x200 field + {k} trajectories"
    rows.append(dict(problem=name, impl="mechpy (vector_field + solve_many)",
                     time=t_field + t_traj, error=err_mp, n=k,
                     note=f"max |mechpy - scipy| over the timed subset {diff:.1e}"))
    rows.append(dict(problem=name, impl="NumPy field + loop of scipy solve_ivp",
                     time=t_field_sp + t_loop, error=err_sp, n=k,
                     note=f"solve_ivp: {sub} trajectories timed, scaled to {k}"))
    return rows
