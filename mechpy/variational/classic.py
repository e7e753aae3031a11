r"""The two classic problems of the calculus of variations beside their closed
forms: the brachistochrone (the cycloid) and the catenary (the cosh), solved
by the Newton solver of :mod:`mechpy.variational.functionals`.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._validate import as_array, as_scalar
from .functionals import _MAX_ITER, _TOL, _n_nodes, _solve

__all__ = ["brachistochrone", "Brachistochrone", "catenary", "Catenary"]


class Brachistochrone(NamedTuple):
    """Result of :func:`brachistochrone` (y measured downward; SI units).

    Attributes
    ----------
    x, y : ndarray, shape (n + 1,)
        The numerical curve (m), from (0, 0) to the end point.
    time : float
        Its descent time (s), the discrete functional's value.
    y_exact : ndarray, shape (n + 1,)
        The cycloid at the same x (m).
    x_cycloid, y_cycloid : ndarray
        The cycloid :math:`x = a(\\theta - \\sin\\theta)`,
        :math:`y = a(1 - \\cos\\theta)` sampled in theta (m), for plots.
    time_exact : float
        The cycloid's time :math:`\\theta_e\\sqrt{a/g}` (s).
    time_line : float
        The straight line's time :math:`\\sqrt{2(x_e^2 + y_e^2)/(g y_e)}` (s).
    radius : float
        The generating circle's radius a (m).
    theta_end : float
        The cycloid parameter at the end point (rad).
    iterations : int
        Newton iterations.

    Examples
    --------
    >>> b = mp.variational.brachistochrone(1.0, 0.5, n=100)
    >>> round(b.time, 5), round(float(b.time_exact), 5)          # the cycloid's theta_e sqrt(a/g)
    (0.56962, 0.56962)
    >>> bool(b.time < b.time_line)                          # faster than the straight line
    True
    """
    x: np.ndarray
    y: np.ndarray
    time: float
    y_exact: np.ndarray
    x_cycloid: np.ndarray
    y_cycloid: np.ndarray
    time_exact: float
    time_line: float
    radius: float
    theta_end: float
    iterations: int


def _cycloid_theta(ratio: float) -> float:
    """theta in (0, 2 pi) with (theta - sin theta) / (1 - cos theta) = ratio."""
    return float(_cycloid_solve(np.array([ratio]), 1.0, np.array([0.0]),
                                np.array([2 * np.pi]), ratio=True)[0])


def _t_minus_sin(t):
    """t - sin t without cancellation for small t."""
    t = np.asarray(t, dtype=np.float64)
    t2 = t * t
    series = t * t2 / 6 * (1 - t2 / 20 * (1 - t2 / 42 * (1 - t2 / 72 * (1 - t2 / 110))))
    return np.where(np.abs(t) < 0.1, series, t - np.sin(t))


def _cycloid_solve(target, a, lo, hi, ratio=False):
    """Safeguarded Newton (vectorised) for a (t - sin t) = target on [lo, hi],
    or, with ``ratio``, for (t - sin t) - target (1 - cos t) = 0.

    Each iteration works on the points not converged yet only: the whole array
    went through all 200 iterations when a few points (at the round-off
    floor) never met the test, 22 s for the 10^6 nodes of
    ``brachistochrone(2, 1, n=10**6)`` against 1 s for its solve."""
    lo, hi = lo.copy(), hi.copy()
    t = np.clip(np.cbrt(6 * target / a) if not ratio else 3 * target, lo, hi)
    act = np.arange(t.size)
    for _ in range(200):
        tt, tg, lo_a, hi_a = t[act], target[act], lo[act], hi[act]
        vers = 2 * np.sin(0.5 * tt) ** 2          # 1 - cos t
        if ratio:
            f = _t_minus_sin(tt) - tg * vers
            d = vers - tg * np.sin(tt)
        else:
            f = a * _t_minus_sin(tt) - tg
            d = a * vers
        lo_a = np.where(f < 0, tt, lo_a)
        hi_a = np.where(f > 0, tt, hi_a)
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = tt - f / d
        tn = np.where((tn >= lo_a) & (tn <= hi_a), tn, 0.5 * (lo_a + hi_a))
        tn = np.where(f == 0, tt, tn)
        done = (np.abs(tn - tt) <= 1e-15 * (1 + tt)) | (hi_a - lo_a <= 4e-16 * (1 + tt))
        t[act], lo[act], hi[act] = tn, lo_a, hi_a
        act = act[~done]
        if act.size == 0:
            break
    return t


def _cycloid_theta_of_x(x, a, theta_end):
    """Invert x = a (theta - sin theta) on [0, theta_end]."""
    x = np.asarray(x, dtype=np.float64)
    return _cycloid_solve(x, a, np.zeros_like(x), np.full_like(x, theta_end))


def brachistochrone(x_end: float, y_end: float, g: float = 9.81, n: int = 200, *,
                    tol: float = _TOL, max_iter: int = _MAX_ITER) -> Brachistochrone:
    r"""The curve of fastest descent from rest at (0, 0) to (x_end, y_end), y downward.

    Minimises the descent time

    .. math:: T[y] = \int_0^{x_e} \sqrt{\frac{1 + y'^2}{2 g y}}\,dx .

    The start is singular (:math:`y' \to \infty`, :math:`y \to 0`); the
    functional is written in the parameter s in [0, 1] with
    :math:`x = x_e s^3` and the unknown :math:`u = \sqrt{y}`, in which the
    cycloid is smooth and the integrand
    :math:`\sqrt{x'(s)^2 + 4u^2u'^2}/(\sqrt{2g}\,u)` is finite, so the
    midpoint rule keeps its second order: the time error is
    :math:`\approx 2.1\times10^{-4}/n^2` s for (2, 1) (measured:
    1.3e-5 s at n = 25, 2.1e-7 s at n = 200, ratio 4.0 per halving).

    Parameters
    ----------
    x_end, y_end : float
        End point (m); x_end > 0 and y_end > 0 (a point at or above the start
        cannot be reached from rest with a finite-time descent in this form),
        and x_end / y_end above about 1e-154 (below it the cycloid's radius
        overflows: a ValueError).
    g : float
        Gravitational acceleration (m/s^2).
    n : int
        Number of intervals (>= 4).

    Returns
    -------
    Brachistochrone
        Curve, time and the exact cycloid beside it (m, s).

    Examples
    --------
    >>> import mechpy as mp
    >>> r = mp.variational.brachistochrone(2.0, 1.0)
    >>> round(float(r.time_exact), 10), round(float(r.time_line), 5)
    (0.8055638295, 1.00964)
    """
    X = as_scalar(x_end, "x_end")
    Y = as_scalar(y_end, "y_end")
    g = as_scalar(g, "g", positive=True)
    n = _n_nodes(n)
    if not Y > 0:
        raise ValueError(f"the end point cannot be reached: y_end (downward) must be > 0, "
                         f"got {Y}; a bead starting from rest cannot rise to or above its "
                         "start along a curve")
    if not X > 0:
        raise ValueError(f"x_end must be > 0 (got {X}); mirror the problem for x_end < 0, "
                         "and x_end = 0 is a free fall")
    th = _cycloid_theta(X / Y)
    # a = Y / (1 - cos th) = X / (th - sin th): the second form stays finite when
    # th rounds to 2 pi (a very shallow drop, X / Y beyond ~1e16)
    with np.errstate(divide="ignore", over="ignore"):
        a = X / float(_t_minus_sin(th)) if X >= Y else Y / (2 * np.sin(0.5 * th) ** 2)
    if not np.isfinite(a):
        # th underflows (th ~ 3 X / Y): the radius ~ 2 Y^3 / (9 X^2) is beyond
        # the floating-point range
        raise ValueError(f"x_end / y_end = {X / Y:.3g} is too small: the cycloid through the "
                         "end point has a radius beyond the floating-point range (the drop is "
                         f"a free fall, time sqrt(2 y_end / g) = {np.sqrt(2 * Y / g):.6g} s)")
    s = np.linspace(0.0, 1.0, n + 1)
    u0 = np.sqrt(Y) * s
    u, _, info = _solve(("brachistochrone", [X, g]), s, u0, tol=tol, max_iter=max_iter)
    x = X * s ** 3
    y = u * u
    theta = _cycloid_theta_of_x(x, a, th)
    tc = np.linspace(0, th, 400)
    return Brachistochrone(x, y, info["J"], a * 2 * np.sin(0.5 * theta) ** 2, a * _t_minus_sin(tc),
                           a * 2 * np.sin(0.5 * tc) ** 2, th * np.sqrt(a / g),
                           np.sqrt(2 * (X * X + Y * Y) / (g * Y)), a, th, info["iterations"])


# ---------------------------------------------------------------------------
# catenary
# ---------------------------------------------------------------------------

class Catenary(NamedTuple):
    """Result of :func:`catenary` (lengths in m, energies per unit weight, m^2).

    Attributes
    ----------
    x, y : ndarray, shape (n + 1,)
        The hanging chain (y upward).
    y_exact : ndarray, shape (n + 1,)
        :math:`a\\cosh((x - x_0)/a) + c` at the same x.
    multiplier : float
        The Lagrange multiplier lambda of the length constraint
        (:math:`\\nabla U + \\lambda\\nabla\\ell = 0`); the tension per unit
        weight is :math:`T/w = y + \\lambda`, so exactly lambda = -c.
    multiplier_exact : float
        -c.
    a, x0, c : float
        The exact catenary's parameter (the horizontal tension over the
        weight per length, m), lowest-point abscissa and offset.
    horizontal_tension : float
        The numerical chain's horizontal tension per unit weight,
        :math:`(y + \\lambda)/\\sqrt{1 + y'^2}` averaged over the links (m).
    energy : float
        Potential energy per unit weight :math:`\\int y\\,ds` (m^2).
    length : float
        The polygon's length (m).
    iterations : int

    Examples
    --------
    >>> ch = mp.variational.catenary(-1.0, 1.0, 3.0, n=200)
    >>> round(float(ch.length), 6), round(float(ch.x0), 12), round(float(ch.y.min()), 4)
    (3.0, 0.0, -1.0053)
    >>> round(float(ch.a + ch.c), 4)          # the lowest point, at x0 = 0: y_exact(x0) = a + c
    -1.0053
    """
    x: np.ndarray
    y: np.ndarray
    y_exact: np.ndarray
    multiplier: float
    multiplier_exact: float
    a: float
    x0: float
    c: float
    horizontal_tension: float
    energy: float
    length: float
    iterations: int


def _end(p, name):
    a = as_array(p, name)
    if a.size == 1:
        return float(a.reshape(())), 0.0
    if a.shape != (2,):
        raise ValueError(f"{name} must be a point (x, y) or a number x (at y = 0), "
                         f"got shape {a.shape}")
    return float(a[0]), float(a[1])


def _catenary_exact(xa, ya, xb, yb, length):
    from scipy.optimize import brentq
    H, v = xb - xa, yb - ya
    ratio = np.sqrt(length * length - v * v) / H   # sinh(z) / z with z = H / (2a)
    z = brentq(lambda z: np.sinh(z) - ratio * z, 1e-12, 2 * np.log(2 * ratio) + 2,
               xtol=1e-15, rtol=1e-15, maxiter=300)
    a = H / (2 * z)
    x0 = 0.5 * (xa + xb) - a * np.arcsinh(v / (2 * a * np.sinh(z)))
    c = ya - a * np.cosh((xa - x0) / a)
    return a, x0, c


def catenary(a, b, length: float, n: int = 200, *, tol: float = _TOL,
             max_iter: int = _MAX_ITER) -> Catenary:
    r"""The hanging chain of fixed length between two points.

    Minimises the potential energy per unit weight at fixed length,

    .. math:: U[y] = \int_a^b y\sqrt{1 + y'^2}\,dx, \qquad
              \ell[y] = \int_a^b \sqrt{1 + y'^2}\,dx = \text{length},

    with a Lagrange multiplier (bordered Newton system).  The discrete
    problem is the chain of n straight links, second order in 1/n; the
    exact solution is :math:`y = a\cosh((x - x_0)/a) + c`.

    Parameters
    ----------
    a, b : float or (x, y)
        The suspension points (m): a number is the point (x, 0); b to the
        right of a.
    length : float
        Chain length (m), longer than the distance between the points.
    n : int
        Number of links (>= 4).

    Returns
    -------
    Catenary
        The chain, the exact cosh beside it and the multiplier.

    Examples
    --------
    A chain of length 3 between (-1, 0) and (1, 0): the exact catenary
    a cosh(x/a) + c with 2 a sinh(1/a) = 3, and the multiplier -c:

    >>> ch = mp.variational.catenary(-1.0, 1.0, 3.0, n=200)
    >>> round(float(2 * ch.a * np.sinh(1 / ch.a)), 10)
    3.0
    >>> bool(np.abs(ch.y - ch.y_exact).max() < 1e-4)
    True
    >>> round(float(ch.multiplier), 4), round(float(ch.multiplier_exact), 4)
    (1.6217, 1.6217)
    """
    xa, ya = _end(a, "a")
    xb, yb = _end(b, "b")
    L = as_scalar(length, "length", positive=True)
    n = _n_nodes(n)
    if not xb > xa:
        raise ValueError(f"b must be to the right of a, got x_a = {xa}, x_b = {xb}")
    span = np.hypot(xb - xa, yb - ya)
    if not L > span * (1 + 1e-9):
        raise ValueError(f"the chain (length {L}) is not longer than the distance between "
                         f"its ends ({span:.6g}): it cannot hang between them")
    A, x0, c = _catenary_exact(xa, ya, xb, yb, L)
    x = np.linspace(xa, xb, n + 1)
    # initial guess: a parabolic sag of the right length, lambda from a parabola
    t = (x - xa) / (xb - xa)
    line = ya + (yb - ya) * t

    def plen(d):
        y = line - 4 * d * t * (1 - t)
        return np.sum(np.hypot(np.diff(x), np.diff(y)))
    lo, hi = 0.0, L
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if plen(mid) < L else (lo, mid)
    d = 0.5 * (lo + hi)
    y0 = line - 4 * d * t * (1 - t)
    a0 = (xb - xa) ** 2 / (8 * d)
    lam0 = a0 - np.min(y0)
    y, lam, info = _solve(("potential", [1.0]), x, y0, [("arclength", [])], [L], [lam0],
                          True, tol, max_iter)
    lam = float(lam[0])
    h = np.diff(x)
    dy = np.diff(y)
    S = np.hypot(h, dy)
    ym = 0.5 * (y[1:] + y[:-1])
    return Catenary(x, y, A * np.cosh((x - x0) / A) + c, lam, -c, A, x0, c,
                    float(np.mean((ym + lam) * h / S)),
                    float(np.sum(ym * S)), float(np.sum(S)), info["iterations"])


