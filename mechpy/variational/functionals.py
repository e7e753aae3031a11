r"""Extremals of a functional :math:`J[y] = \int_a^b F(x, y, y')\,dx` with fixed ends.

The discretisation (midpoint rule) and the Newton solver run in C
(``csrc/variational.c``); this module holds the Python face of a general
functional and the finite-difference derivatives of a Python integrand or
Lagrangian of any number of coordinates.
"""
from __future__ import annotations

import inspect
from typing import Callable, NamedTuple

import numpy as np

from .. import _core
from .._validate import as_array, as_int, as_scalar

__all__ = ["minimize_functional", "Extremal"]

_TOL = 1e-10
_MAX_ITER = 100
# relative pivot of d2L/dqdot2 below which it counts as singular: exact
# derivatives (C) and fourth-order finite differences (Python callables)
_SING_TOL_EXACT = 1e-12
_SING_TOL_FD = 1e-9


# ---------------------------------------------------------------------------
# finite-difference derivatives of a Python integrand
# ---------------------------------------------------------------------------

def _fd_spec(f: Callable, d: int) -> tuple:
    """The C core's integrand spec ``("python", cb, d)`` of a vectorised
    ``f(x, y, p) -> (M,)`` with x (M,), y and p (M, d).

    ``cb(x, y, p)`` returns the (m, K) values, K = 1 + 2d + 3d^2: F, F_y,
    F_p, F_yy, F_yp, F_pp by central differences of step
    1e-3 (1 + |z|): fourth order for the gradient and the pure second
    derivatives, second order for the mixed ones (exact for an F quadratic in
    its arguments).  All perturbed points go to ``f`` in one call."""
    nz = 2 * d
    pairs = np.array([(j, k) for j in range(nz) for k in range(j + 1, nz)],
                     dtype=np.intp).reshape(-1, 2)
    # the stencil: row 0 the point, then +-1, +-2 steps in each variable, then
    # the four (+-1, +-1) corners of each pair
    S = np.zeros((1 + 4 * nz + 4 * len(pairs), nz))
    for j in range(nz):
        S[1 + 4 * j: 5 + 4 * j, j] = (1, -1, 2, -2)
    for i, (j, k) in enumerate(pairs):
        rows = slice(1 + 4 * nz + 4 * i, 5 + 4 * nz + 4 * i)
        S[rows, j] = (1, 1, -1, -1)
        S[rows, k] = (1, -1, 1, -1)
    P = S.shape[0]
    single = 1 + 4 * np.arange(nz)            # rows of +1 in each variable
    corner = 1 + 4 * nz + 4 * np.arange(len(pairs))
    jj, kk = pairs[:, 0], pairs[:, 1]

    def cb(x, y, p):
        m = x.shape[0]
        z = np.concatenate([y, p], axis=1)                    # (m, 2d)
        dz = 1e-3 * (1.0 + np.abs(z))
        Zf = (z[None] + S[:, None, :] * dz[None]).reshape(P * m, nz)
        vals = np.asarray(f(np.tile(x, P), Zf[:, :d], Zf[:, d:]), dtype=np.float64)
        V = np.broadcast_to(vals, (P * m,)).reshape(P, m)
        f0, h = V[0], dz.T                                    # (m,), (nz, m)
        a, b, c, e = V[single], V[single + 1], V[single + 2], V[single + 3]
        hess = np.empty((nz, nz, m))
        grad = (8 * (a - b) - (c - e)) / (12 * h)
        hess[np.arange(nz), np.arange(nz)] = (16 * (a + b) - (c + e) - 30 * f0) / (12 * h * h)
        mixed = (V[corner] - V[corner + 1] - V[corner + 2] + V[corner + 3]) / (4 * h[jj] * h[kk])
        hess[jj, kk] = mixed
        hess[kk, jj] = mixed
        hess = np.moveaxis(hess, 2, 0)
        return np.concatenate([f0[:, None], grad.T, hess[:, :d, :d].reshape(m, -1),
                               hess[:, :d, d:].reshape(m, -1),
                               hess[:, d:, d:].reshape(m, -1)], axis=1)
    return ("python", cb, d)


def _takes_time(L: Callable) -> bool:
    """Does the callable take a third positional argument (the time)?"""
    try:
        sig = inspect.signature(L)
    except (TypeError, ValueError):
        return False
    n = 0
    for p in sig.parameters.values():
        if p.kind == p.VAR_POSITIONAL:
            return True
        if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD):
            n += 1
    return n >= 3


def _lagrangian_fn(L: Callable, d: int, scalar: bool) -> Callable:
    """A user's ``L(q, qdot[, t])`` (q of shape (d, M), or (M,) when
    ``scalar``) as ``f(t, Q, V)`` with Q, V of shape (M, d), returning (M,)."""
    takes_t = _takes_time(L)

    def f(t, Q, V):
        q, v = (Q[:, 0], V[:, 0]) if scalar else (Q.T, V.T)
        out = L(q, v, t) if takes_t else L(q, v)
        out = np.asarray(out, dtype=np.float64)
        if out.size == t.shape[0] and out.shape != t.shape:
            out = out.reshape(t.shape)        # e.g. (1, M) from a one-coordinate L
        if out.ndim and out.shape != t.shape:
            raise ValueError("the Lagrangian must return one value per sample: for q of "
                             f"shape {q.shape} a result of shape {t.shape}, got {out.shape}")
        return out
    return f


# ---------------------------------------------------------------------------
# a general functional
# ---------------------------------------------------------------------------

class Extremal(NamedTuple):
    """Result of :func:`minimize_functional`.

    Attributes
    ----------
    x, y : ndarray, shape (n + 1,)
        Nodes and the extremal's values there.
    value : float
        :math:`J_h[y]` at the extremal.
    multipliers : ndarray, shape (k,)
        Lagrange multipliers of the k integral constraints (stationarity:
        :math:`\\nabla J + \\sum_k \\lambda_k \\nabla G_k = 0`).
    iterations : int
        Newton iterations.
    residual : float
        Max norm of the discrete Euler-Lagrange residual at the end.

    Examples
    --------
    The extremal of J = int (y'^2/2 + y) dx on [0, 1] with y(0) = y(1) = 0 solves
    y'' = 1: y = x (x - 1) / 2, and J = -1/24.

    >>> ext = mp.variational.minimize_functional(lambda x, y, yp: yp**2 / 2 + y,
    ...                                          (0.0, 1.0), (0.0, 0.0), n=100)
    >>> round(float(ext.y[50]), 8), 0.5 * (0.5 - 1) / 2
    (-0.125, -0.125)
    >>> round(ext.value, 4), round(-1 / 24, 4)     # the midpoint rule: O(h^2)
    (-0.0417, -0.0417)
    >>> ext.multipliers.shape, bool(ext.residual < 1e-8)
    ((0,), True)
    """
    x: np.ndarray
    y: np.ndarray
    value: float
    multipliers: np.ndarray
    iterations: int
    residual: float


#: The most intervals a discretised functional takes (the budget of
#: ``variational_integrate``'s steps, MAX_STEPS, too): about 160 bytes each and
#: 1 s per 10^6 for a built-in integrand, while the midpoint rule's error,
#: O(h^2), reaches round-off near n = 10^5 for a smooth extremal.
_MAX_INTERVALS = 10_000_000


def _n_nodes(n) -> int:
    n = as_int(n, "n")
    if n < 4:
        raise ValueError(f"n (the number of intervals) is too small: need n >= 4, got {n}")
    if n > _MAX_INTERVALS:
        raise ValueError(
            f"n = {n} intervals is beyond the budget of {_MAX_INTERVALS:.0e} (about "
            f"{160 * n / 1e9:.3g} GB of workspace): the midpoint rule's error, O(1/n^2), "
            "reaches round-off near n = 1e5 for a smooth extremal; take a smaller n")
    return n


def _solve(spec, x, y0, cons=(), values=(), lam0=(), stationary=False, tol=_TOL,
           max_iter=_MAX_ITER):
    tol = as_scalar(tol, "tol", positive=True)
    max_iter = as_int(max_iter, "max_iter", minimum=1)
    return _core.variational_solve(spec, x, y0, list(cons), np.asarray(values, float),
                                   np.asarray(lam0, float), bool(stationary), tol, max_iter)


def _pair(v, name):
    a = np.asarray(v)
    if a.shape != (2,):
        raise ValueError(f"{name} must be a pair of numbers, got shape {a.shape}")
    return a.tolist()


def _integrand(F: Callable) -> tuple:
    """The spec of a one-function integrand F(x, y, yp)."""
    def f(x, Y, P):
        out = np.asarray(F(x, Y[:, 0], P[:, 0]), dtype=np.float64)
        return np.broadcast_to(out, x.shape)
    return _fd_spec(f, 1)


def _singular_end(F: Callable, a: float, b: float, ya: float, yb: float):
    """The end ("a" or "b") at which F is singular along the straight line
    between the end points, or None.

    Singular: F is not finite at the end point itself, or it grows by more
    than 10x between 1e-6 and 1e-9 of the interval from it (a power law
    x^-1/3 or steeper, as the brachistochrone's x^-1/2 on the line: 31.6x);
    a smooth integrand changes by about 1e-6 relative there."""
    slope = (yb - ya) / (b - a)
    L = b - a
    for name, e, ye, sign in (("a", a, ya, 1.0), ("b", b, yb, -1.0)):
        xs = np.array([e, e + sign * 1e-6 * L, e + sign * 1e-9 * L])
        ys = ye + slope * (xs - e)
        try:
            with np.errstate(all="ignore"):
                v = np.broadcast_to(np.asarray(F(xs, ys, np.full(3, slope)), dtype=np.float64),
                                    (3,))
        except (ZeroDivisionError, FloatingPointError, ValueError):
            return name
        if not np.all(np.isfinite(v)) or abs(v[2]) > 10.0 * abs(v[1]) + 1e-300:
            return name
    return None


def minimize_functional(F: Callable, x_span, y_ends, n: int = 200, *, constraints=(),
                        guess=None, multipliers=None, stationary: bool = False,
                        tol: float = _TOL,
                        max_iter: int = _MAX_ITER) -> Extremal:
    r"""Extremal of :math:`J[y] = \int_a^b F(x, y, y')\,dx` with fixed ends.

    .. math:: \frac{\partial F}{\partial y} - \frac{d}{dx}\frac{\partial F}{\partial y'}
              + \sum_k \lambda_k \Big(\frac{\partial G_k}{\partial y}
              - \frac{d}{dx}\frac{\partial G_k}{\partial y'}\Big) = 0

    solved on n uniform intervals by Newton's method (midpoint rule, second
    order in h; tridiagonal Hessian, O(n) per iteration).

    Parameters
    ----------
    F : callable ``F(x, y, yp)``
        Vectorised over arrays; its derivatives are taken by central
        differences.
    x_span : (a, b)
        Interval, a < b.
    y_ends : (y_a, y_b)
        Fixed end values.
    n : int
        Number of intervals (>= 4).
    constraints : sequence of (G, value)
        Integral constraints :math:`\int_a^b G(x, y, y')\,dx = c`.
    guess : array (n + 1,), optional
        Initial path (its ends are replaced by ``y_ends``); a straight line
        by default.
    multipliers : array (k,), optional
        Initial Lagrange multipliers (zeros by default; give a guess when F
        is linear in y', where lambda = 0 makes the Newton matrix singular).
    stationary : bool
        Look for any stationary point (Newton on the residual) rather than a
        minimum (descent on J with a positive-definite shifted Hessian).
        Constrained problems always use the residual.
    tol, max_iter : float, int
        Relative step tolerance and Newton budget.

    Returns
    -------
    Extremal
        Units are those of x, y and F.

    Raises
    ------
    ConvergenceError
        The budget ran out or no step improved the merit function.
    NotPositiveDefiniteError
        (Minimisation only.)  The stationary path found is not a minimum: the
        second variation, the Hessian of the discrete functional there, has
        a negative eigenvalue (counted by one banded :math:`LDL^T`, O(n)).  So
        it is a saddle or a maximum, as past a conjugate point (Jacobi:
        :math:`F = y'^2 - k^2 y^2` on [0, L] has a minimum iff
        :math:`kL < \pi`) or where :math:`F_{y'y'} < 0`.  Before this check
        such a point came back as the minimum.  ``stationary=True`` returns
        it without the check.
    ValueError
        F is singular at an end point (not finite there, or growing like a
        power of the distance to it along the straight line between the
        ends), as the brachistochrone's :math:`\sqrt{(1 + y'^2)/(2gy)}` is at
        its start.  The midpoint rule's first cell then dominates the
        discrete functional: before this check it returned a descent time
        8.5% below the cycloid's with a residual of 1e-13 and no warning, and
        for n >= 400 its finite differences stepped to y < 0.  Write the
        problem in a parameter in which the integrand is finite (as
        :func:`brachistochrone` does with x = x_e s^3 and u = sqrt(y)).

    Examples
    --------
    The shortest curve from (0, 0) to (1, 1), J = int sqrt(1 + y'^2) dx: the
    straight line, of length sqrt(2):

    >>> ext = mp.variational.minimize_functional(lambda x, y, yp: np.sqrt(1 + yp**2),
    ...                                          (0.0, 1.0), (0.0, 1.0), n=50)
    >>> round(ext.value, 10), round(2 ** 0.5, 10)
    (1.4142135624, 1.4142135624)
    >>> round(float(np.abs(ext.y - ext.x).max()), 8)
    0.0
    """
    if not callable(F):
        raise TypeError("F must be a callable F(x, y, yp)")
    a, b = (as_scalar(v, "x_span") for v in _pair(x_span, "x_span"))
    ya, yb = (as_scalar(v, "y_ends") for v in _pair(y_ends, "y_ends"))
    if not b > a:
        raise ValueError(f"x_span must be increasing, got ({a}, {b})")
    end = _singular_end(F, a, b, ya, yb)
    if end is not None:
        xe, ye = (a, ya) if end == "a" else (b, yb)
        raise ValueError(
            f"F is singular at the end point x = {xe}, y = {ye} (not finite there, or growing "
            "without bound towards it): the midpoint rule cannot resolve an integrable "
            "singularity and would return a value below the true extremum with a small "
            "residual. Change variables so that the integrand is finite at the ends (for the "
            "brachistochrone use mechpy.variational.brachistochrone, which writes it in "
            "x = x_e s^3, u = sqrt(y))")
    n = _n_nodes(n)
    x = np.linspace(a, b, n + 1)
    if guess is None:
        y0 = ya + (yb - ya) * (x - a) / (b - a)
    else:
        y0 = as_array(guess, "guess", shape=(n + 1,)).copy()
        y0[0], y0[-1] = ya, yb
    cons, vals = [], []
    for i, c in enumerate(constraints):
        try:
            G, v = c
        except (TypeError, ValueError):
            raise TypeError(f"constraints[{i}] must be a pair (G, value)") from None
        if not callable(G):
            raise TypeError(f"constraints[{i}][0] must be a callable G(x, y, yp)")
        cons.append(_integrand(G))
        vals.append(as_scalar(v, f"constraints[{i}] value"))
    lam0 = np.zeros(len(cons)) if multipliers is None else \
        as_array(multipliers, "multipliers", shape=(len(cons),), allow_empty=True)
    try:
        y, lam, info = _solve(_integrand(F), x, y0, cons, vals, lam0,
                              stationary, tol, max_iter)
    except _core.NotPositiveDefiniteError as e:     # mechpy.errors' class, from the table
        raise _core.NotPositiveDefiniteError(
            f"minimize_functional: no minimum found: {e}. Jacobi's condition: a minimum "
            "needs F_y'y' > 0 along the path and no point conjugate to x = a inside "
            f"({a}, {b}); past a conjugate point J has no minimum with these ends. "
            "Pass stationary=True to get the stationary path itself") from None
    return Extremal(x, y, info["J"], lam, info["iterations"], info["residual"])
