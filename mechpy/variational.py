r"""Lagrangian mechanics: the calculus of variations, least action, constraint forces.

The work runs in C (``csrc/variational.c``): a functional

.. math:: J[y] = \int_a^b F(x, y, y')\,dx, \qquad y(a) = y_a,\ y(b) = y_b,

is discretised on nodes :math:`x_0 < \dots < x_n` by the midpoint rule,
:math:`J_h = \sum_i h_i F(\bar x_i, (y_i + y_{i+1})/2, (y_{i+1} - y_i)/h_i)`
(second order), and the discrete Euler-Lagrange equations
:math:`\partial J_h/\partial y_j = 0` are solved by Newton's method.  Their
Hessian is tridiagonal, so an iteration costs O(n); a line search (on J when
minimising, on the residual otherwise) and an iteration budget make the
solver safe, and a failure raises :class:`mechpy.ConvergenceError`.  Integral
constraints :math:`\int G_k\,dx = c_k` enter through Lagrange multipliers
(a bordered tridiagonal system, still O(n)).

Public functions
----------------
minimize_functional
    Any functional F(x, y, y') given as a vectorised Python callable.
brachistochrone, catenary
    The two classic problems beside their closed forms (cycloid, cosh).
stationary_path, variational_integrate
    The path of stationary discrete action between two configurations, and
    the (symplectic) variational integrator of the same discrete action,
    for a scene (``Pendulum``, ``Duffing``) or a Lagrangian ``L(q, qdot)``.
lagrangian, generalized_momenta, cyclic_coordinates
    Momenta :math:`p_i = \partial L/\partial\dot q_i` and cyclic coordinates.
constraint_forces, pendulum_tension, CentralForce, RotatingHoop
    Forces of constraint from Lagrange multipliers.
"""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from . import _core
from ._validate import as_array, as_int, as_scalar

__all__ = ["minimize_functional", "Extremal", "brachistochrone", "Brachistochrone",
           "catenary", "Catenary", "stationary_path", "StationaryPath",
           "variational_integrate", "VariationalTrajectory", "lagrangian",
           "generalized_momenta", "cyclic_coordinates", "constraint_forces",
           "pendulum_tension", "CentralForce", "RotatingHoop"]

_TOL = 1e-10
_MAX_ITER = 100


# ---------------------------------------------------------------------------
# integrands
# ---------------------------------------------------------------------------

def _fd_integrand(f: Callable) -> Callable:
    """Wrap a vectorised ``f(x, y, p)`` into the C solver's integrand: the
    six arrays F, F_y, F_p, F_yy, F_yp, F_pp by central differences (fourth
    order for F_y, F_p, F_yy, F_pp; second order for F_yp)."""
    def ev(x, y, p):
        out = np.asarray(f(x, y, p), dtype=np.float64)
        return np.broadcast_to(out, y.shape)

    def derivs(x, y, p):
        hy = 1e-3 * (1.0 + np.abs(y))
        hp = 1e-3 * (1.0 + np.abs(p))
        f0 = ev(x, y, p)
        y1, y_1, y2, y_2 = ev(x, y + hy, p), ev(x, y - hy, p), ev(x, y + 2 * hy, p), \
            ev(x, y - 2 * hy, p)
        p1, p_1, p2, p_2 = ev(x, y, p + hp), ev(x, y, p - hp), ev(x, y, p + 2 * hp), \
            ev(x, y, p - 2 * hp)
        fy = (8 * (y1 - y_1) - (y2 - y_2)) / (12 * hy)
        fp = (8 * (p1 - p_1) - (p2 - p_2)) / (12 * hp)
        fyy = (16 * (y1 + y_1) - (y2 + y_2) - 30 * f0) / (12 * hy * hy)
        fpp = (16 * (p1 + p_1) - (p2 + p_2) - 30 * f0) / (12 * hp * hp)
        fyp = (ev(x, y + hy, p + hp) - ev(x, y + hy, p - hp) - ev(x, y - hy, p + hp)
               + ev(x, y - hy, p - hp)) / (4 * hy * hp)
        return np.stack([f0, fy, fp, fyy, fyp, fpp])
    return derivs


def _scene_integrand(scene):
    """The C built-in integrand (name, params) of a scene's Lagrangian."""
    from .scenes import Duffing, Pendulum
    p = scene.params
    if isinstance(scene, Pendulum):
        return ("pendulum", [p["g"], p["length"], p["damping"], p["drive_amplitude"],
                             p["drive_frequency"]])
    if isinstance(scene, Duffing):
        return ("duffing", [p["alpha"], p["beta"], p["delta"], p["gamma"], p["omega"]])
    raise TypeError(f"{type(scene).__name__} has no Lagrangian of the form L(t, q, qdot) "
                    "here; use Pendulum, Duffing or a callable L(q, qdot)")


def _system_integrand(system):
    """(spec for the C core, vectorised numpy F(t, q, qdot)) of a scene or callable."""
    from .scenes import Scene
    if isinstance(system, Scene):
        spec = _scene_integrand(system)
        L = lagrangian(system)
        return spec, L
    if callable(system):
        def F(t, q, qd):
            return system(q, qd)
        return _fd_integrand(F), F
    raise TypeError("system must be a scene (Pendulum, Duffing) or a callable L(q, qdot), "
                    f"got {type(system).__name__}")


def _derivs(spec, x, y, p):
    """The six derivative arrays of an integrand spec at points (numpy)."""
    if callable(spec):
        return spec(x, y, p)
    name, params = spec
    k = np.asarray(params, dtype=np.float64)
    x, y, p = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (x, y, p)))
    if name == "pendulum":
        g, L, b, A, W = k
        e, drive = np.exp(b * x), L * L * A * np.cos(W * x)
        return np.stack([e * (0.5 * L * L * p * p + g * L * np.cos(y) + drive * y),
                         e * (-g * L * np.sin(y) + drive), e * L * L * p,
                         -e * g * L * np.cos(y), 0 * e, e * L * L + 0 * y])
    al, be, de, ga, om = k
    e, drive = np.exp(de * x), ga * np.cos(om * x)
    return np.stack([e * (0.5 * p * p - 0.5 * al * y * y - 0.25 * be * y ** 4 + drive * y),
                     e * (-al * y - be * y ** 3 + drive), e * p, e * (-al - 3 * be * y * y),
                     0 * e, e + 0 * y])


def _velocity(spec, t, q, p, v0):
    """Invert p = dL/dqdot(t, q, v) for v by Newton (vectorised)."""
    v = np.array(v0, dtype=np.float64)
    for _ in range(50):
        d = _derivs(spec, t, q, v)
        dv = (d[2] - p) / d[5]
        v = v - dv
        if np.all(np.abs(dv) <= 1e-13 * (1 + np.abs(v))):
            break
    return v


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
    """
    x: np.ndarray
    y: np.ndarray
    value: float
    multipliers: np.ndarray
    iterations: int
    residual: float


def _n_nodes(n) -> int:
    n = as_int(n, "n")
    if n < 4:
        raise ValueError(f"n (the number of intervals) is too small: need n >= 4, got {n}")
    return n


def _solve(spec, x, y0, cons=(), values=(), lam0=(), stationary=False, tol=_TOL,
           max_iter=_MAX_ITER):
    tol = as_scalar(tol, "tol", positive=True)
    max_iter = as_int(max_iter, "max_iter", minimum=1)
    return _core.variational_solve(spec, x, y0, list(cons), np.asarray(values, float),
                                   np.asarray(lam0, float), bool(stationary), tol, max_iter)


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
    """
    if not callable(F):
        raise TypeError("F must be a callable F(x, y, yp)")
    a, b = (as_scalar(v, "x_span") for v in _pair(x_span, "x_span"))
    ya, yb = (as_scalar(v, "y_ends") for v in _pair(y_ends, "y_ends"))
    if not b > a:
        raise ValueError(f"x_span must be increasing, got ({a}, {b})")
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
        cons.append(_fd_integrand(G))
        vals.append(as_scalar(v, f"constraints[{i}] value"))
    lam0 = np.zeros(len(cons)) if multipliers is None else \
        as_array(multipliers, "multipliers", shape=(len(cons),), allow_empty=True)
    y, lam, info = _solve(_fd_integrand(F), x, y0, cons, vals, lam0,
                          stationary, tol, max_iter)
    return Extremal(x, y, info["J"], lam, info["iterations"], info["residual"])


def _pair(v, name):
    a = np.asarray(v)
    if a.shape != (2,):
        raise ValueError(f"{name} must be a pair of numbers, got shape {a.shape}")
    return a.tolist()


# ---------------------------------------------------------------------------
# brachistochrone
# ---------------------------------------------------------------------------

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
    or, with ``ratio``, for (t - sin t) - target (1 - cos t) = 0."""
    lo, hi = lo.copy(), hi.copy()
    t = np.clip(np.cbrt(6 * target / a) if not ratio else 3 * target, lo, hi)
    for _ in range(200):
        vers = 2 * np.sin(0.5 * t) ** 2          # 1 - cos t
        if ratio:
            f = _t_minus_sin(t) - target * vers
            d = vers - target * np.sin(t)
        else:
            f = a * _t_minus_sin(t) - target
            d = a * vers
        lo = np.where(f < 0, t, lo)
        hi = np.where(f > 0, t, hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            tn = t - f / d
        tn = np.where((tn >= lo) & (tn <= hi), tn, 0.5 * (lo + hi))
        tn = np.where(f == 0, t, tn)
        done = np.all((np.abs(tn - t) <= 1e-15 * (1 + t)) | (hi - lo <= 4e-16 * (1 + t)))
        t = tn
        if done:
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
        cannot be reached from rest with a finite-time descent in this form).
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
    >>> r = mp.variational.brachistochrone(2.0, 1.0)
    >>> round(r.time_exact, 10), round(r.time_line, 5)
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
    a = X / float(_t_minus_sin(th)) if X >= Y else Y / (2 * np.sin(0.5 * th) ** 2)
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


# ---------------------------------------------------------------------------
# least action
# ---------------------------------------------------------------------------

class StationaryPath(NamedTuple):
    """Result of :func:`stationary_path`.

    Attributes
    ----------
    t : ndarray, shape (n + 1,)
        Times (s).
    q : ndarray, shape (n + 1,)
        The path of stationary discrete action.
    p : ndarray, shape (n + 1,)
        Discrete generalized momenta: :math:`p_0 = -D_1L_d(q_0, q_1)`,
        :math:`p_k = D_2L_d(q_{k-1}, q_k)`.
    qdot : ndarray, shape (n + 1,)
        Velocities from :math:`\\partial L/\\partial\\dot q = p`.
    action : float
        The discrete action :math:`S_h = \\sum_k h L_d` (units of L times s).
    iterations : int
    """
    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    qdot: np.ndarray
    action: float
    iterations: int


def _discrete_momenta(spec, t, q):
    h = np.diff(t)
    tm, qm, vm = 0.5 * (t[1:] + t[:-1]), 0.5 * (q[1:] + q[:-1]), np.diff(q) / h
    d = _derivs(spec, tm, qm, vm)
    p = np.empty_like(q)
    p[0] = -(0.5 * h[0] * d[1][0] - d[2][0])
    p[1:] = 0.5 * h * d[1] + d[2]
    v0 = np.concatenate([vm[:1], vm])
    return p, _velocity(spec, t, q, p, v0)


def stationary_path(scene_or_lagrangian, q_a: float, q_b: float, T: float, n: int = 200, *,
                    t0: float = 0.0, guess=None, tol: float = _TOL,
                    max_iter: int = _MAX_ITER) -> StationaryPath:
    r"""The path of stationary discrete action from q(t0) = q_a to q(t0 + T) = q_b.

    .. math:: S_h = \sum_{k=0}^{n-1} h\,L\Big(t_k + \tfrac h2, \frac{q_k + q_{k+1}}2,
              \frac{q_{k+1} - q_k}h\Big), \qquad \frac{\partial S_h}{\partial q_k} = 0,

    solved by Newton's method on the residual (the action need not be a
    minimum: past a conjugate point it is a saddle).  Second order in h.

    Parameters
    ----------
    scene_or_lagrangian : Pendulum, Duffing or callable ``L(q, qdot)``
        A scene (its Lagrangian runs in C; per unit mass for the pendulum:
        :math:`e^{bt}(\tfrac12\ell^2\dot\theta^2 + g\ell\cos\theta + \ell^2A\cos(\Omega t)\theta)`,
        whose Euler-Lagrange equation is the scene's equation of motion), or
        a vectorised Python callable of one coordinate (e.g. the harmonic
        oscillator ``lambda q, v: 0.5 * v**2 - 0.5 * q**2``).
    q_a, q_b : float
        End configurations.
    T : float
        Duration (s), > 0.
    n : int
        Number of time steps (>= 4).
    guess : array (n + 1,), optional
        Initial path; the straight line by default.

    Returns
    -------
    StationaryPath
    """
    spec, _ = _system_integrand(scene_or_lagrangian)
    qa, qb = as_scalar(q_a, "q_a"), as_scalar(q_b, "q_b")
    T = as_scalar(T, "T", positive=True)
    t0 = as_scalar(t0, "t0")
    n = _n_nodes(n)
    t = t0 + np.linspace(0.0, T, n + 1)
    if guess is None:
        q0 = qa + (qb - qa) * (t - t0) / T
    else:
        q0 = as_array(guess, "guess", shape=(n + 1,)).copy()
        q0[0], q0[-1] = qa, qb
    q, _, info = _solve(spec, t, q0, stationary=True, tol=tol, max_iter=max_iter)
    p, qd = _discrete_momenta(spec, t, q)
    return StationaryPath(t, q, p, qd, info["J"], info["iterations"])


class VariationalTrajectory(NamedTuple):
    """Result of :func:`variational_integrate`.

    Attributes
    ----------
    t, q, p, qdot : ndarray, shape (n + 1,)
        Times (s), positions, momenta and velocities (from p).
    energy : ndarray, shape (n + 1,)
        The energy function :math:`h = \\dot q\\,\\partial L/\\partial\\dot q - L`
        (for a scene: the scene's own ``energy``).
    """
    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    qdot: np.ndarray
    energy: np.ndarray


def variational_integrate(system, t_span, q0: float, qdot0: float, h: float
                          ) -> VariationalTrajectory:
    r"""Integrate with the variational integrator of the midpoint discrete Lagrangian.

    .. math:: L_d(q_0, q_1) = h\,L\big(\tfrac{q_0 + q_1}2, \tfrac{q_1 - q_0}h\big),\quad
              p_k = -D_1L_d(q_k, q_{k+1}),\quad p_{k+1} = D_2L_d(q_k, q_{k+1})

    (the same discrete action as :func:`stationary_path`).  The map
    :math:`(q_k, p_k) \mapsto (q_{k+1}, p_{k+1})` is symplectic and second
    order; for a conservative system the energy error stays bounded
    (O(h^2)) over exponentially long times instead of drifting.

    Parameters
    ----------
    system : Pendulum, Duffing or callable ``L(q, qdot)``
    t_span : (t0, t1)
    q0, qdot0 : float
        Initial position and velocity.
    h : float
        Step (s); the last step ends at or after t1 (n = ceil((t1 - t0)/h)).

    Returns
    -------
    VariationalTrajectory
    """
    from .scenes import Scene
    spec, F = _system_integrand(system)
    t0, t1 = (as_scalar(v, "t_span") for v in _pair(t_span, "t_span"))
    if not t1 > t0:
        raise ValueError("t_span must be increasing")
    h = as_scalar(h, "h", positive=True)
    q0, v0 = as_scalar(q0, "q0"), as_scalar(qdot0, "qdot0")
    n = int(np.ceil((t1 - t0) / h - 1e-9))
    p0 = float(_derivs(spec, np.array([t0]), np.array([q0]), np.array([v0]))[2][0])
    q, p = _core.variational_integrate(spec, t0, h, n, q0, p0)
    t = t0 + h * np.arange(n + 1)
    v = np.empty_like(q)
    v[0] = v0
    if n:
        v[1:] = _velocity(spec, t[1:], q[1:], p[1:], np.diff(q) / h)
    if isinstance(system, Scene):
        E = system.energy(np.stack([q, v]))
    else:
        E = v * p - np.asarray(F(t, q, v), dtype=float)
    return VariationalTrajectory(t, q, p, v, E)


# ---------------------------------------------------------------------------
# Lagrangians, momenta, cyclic coordinates
# ---------------------------------------------------------------------------

def lagrangian(scene) -> Callable:
    r"""The Lagrangian ``L(q, qdot, t=0)`` of a scene, as a vectorised callable.

    Pendulum (per unit mass, J/kg):
    :math:`e^{bt}(\tfrac12\ell^2\dot\theta^2 + g\ell\cos\theta + \ell^2A\cos(\Omega t)\,\theta)`;
    Duffing: :math:`e^{\delta t}(\tfrac12\dot x^2 - \tfrac12\alpha x^2 - \tfrac14\beta x^4
    + \gamma\cos(\omega t)\,x)`.  The factor :math:`e^{bt}` (Caldirola-Kanai)
    makes the damped equation of motion an Euler-Lagrange equation.
    HeavyTop (J), coordinates q = (phi, theta, psi) of shape (3, ...):
    :math:`\tfrac{I_1}{2}(\dot\theta^2 + \dot\phi^2\sin^2\theta)
    + \tfrac{I_3}{2}(\dot\psi + \dot\phi\cos\theta)^2 - Mgl\cos\theta`.
    """
    from .scenes import HeavyTop
    if isinstance(scene, HeavyTop):
        return _heavy_top_lagrangian(scene)
    spec = _scene_integrand(scene)

    def L(q, qdot, t=0.0):
        return _derivs(spec, t, q, qdot)[0]
    L.__doc__ = f"Lagrangian of {scene!r}."
    return L


def _heavy_top_lagrangian(top):
    p = top.params
    I1, I3, Mgl = p["I1"], p["I3"], p["mass"] * p["g"] * p["l"]

    def L(q, qdot, t=0.0):
        th = np.asarray(q, dtype=float)[1]
        phd, thd, psd = np.asarray(qdot, dtype=float)[:3]
        return (0.5 * I1 * (thd ** 2 + (phd * np.sin(th)) ** 2)
                + 0.5 * I3 * (psd + phd * np.cos(th)) ** 2 - Mgl * np.cos(th))
    L.__doc__ = f"Lagrangian of {top!r} (J)."
    return L


def _split(q, qdot):
    q = as_array(q, "q")
    qdot = as_array(qdot, "qdot")
    if q.shape != qdot.shape:
        raise ValueError(f"q and qdot must have the same shape, got {q.shape} and {qdot.shape}")
    return q, qdot


def _partials(L, q, qdot, which):
    """dL/dq_i (which = 0) or dL/dqdot_i (which = 1) by 4th-order central
    differences; q of shape (d, ...) or (...) for one coordinate."""
    q, qdot = _split(q, qdot)
    one = q.ndim == 0
    if one:
        q, qdot = q[None], qdot[None]
    base = [q, qdot]
    out = np.empty_like(q)
    for i in range(q.shape[0]):
        z = base[which]
        hh = 1e-3 * (1 + np.abs(z[i]))
        vals = []
        for k in (1, -1, 2, -2):
            zz = z.copy()
            zz[i] = z[i] + k * hh
            args = [q, qdot]
            args[which] = zz
            if one:
                args = [a[0] for a in args]
            val = np.asarray(L(*args), dtype=float)
            if not one and q.shape[0] == 1 and val.shape == q.shape:
                val = val[0]     # a one-coordinate L that keeps the leading axis
            vals.append(val)
        out[i] = (8 * (vals[0] - vals[1]) - (vals[2] - vals[3])) / (12 * hh)
    return out[0] if one else out


def generalized_momenta(L: Callable, q, qdot) -> np.ndarray:
    r"""Generalized momenta :math:`p_i = \partial L/\partial\dot q_i`.

    Parameters
    ----------
    L : callable ``L(q, qdot)`` or a scene
        Vectorised: q and qdot of shape (d, ...) (or scalars for one
        coordinate); a one-coordinate scene takes q of any shape (samples of
        it), a HeavyTop q = (phi, theta, psi) of shape (3, ...).
    q, qdot : array_like
        Coordinates and velocities, same shape.

    Returns
    -------
    ndarray
        Same shape as q (units of L times s per unit of q).
    """
    from .scenes import HeavyTop, Scene
    if isinstance(L, Scene) and not isinstance(L, HeavyTop):  # one coordinate: any shape
        q, qdot = _split(q, qdot)
        return _partials(lagrangian(L), q[None], qdot[None], 1)[0]
    return _partials(_as_lagrangian(L), q, qdot, 1)


def cyclic_coordinates(L: Callable, q, qdot, *, atol: float = 1e-8) -> tuple:
    r"""Indices i of the coordinates that L does not depend on,
    :math:`\partial L/\partial q_i = 0` (so that :math:`p_i` is conserved),
    tested at the sample states (q, qdot) of shape (d, ...)."""
    q, qdot = _split(q, qdot)
    if q.ndim == 0:
        q, qdot = q[None], qdot[None]
    dLdq = _partials(_as_lagrangian(L), q, qdot, 0)
    scale = np.max(np.abs(_partials(_as_lagrangian(L), q, qdot, 1))) + 1.0
    flat = np.abs(dLdq.reshape(q.shape[0], -1))
    return tuple(int(i) for i in range(q.shape[0]) if np.all(flat[i] <= atol * scale))


def _as_lagrangian(L):
    from .scenes import Scene
    if isinstance(L, Scene):
        return lagrangian(L)
    if not callable(L):
        raise TypeError("L must be a callable L(q, qdot) or a scene")
    return L


class CentralForce:
    r"""A particle in the plane under an attractive inverse-square force.

    .. math:: L(r, \varphi, \dot r, \dot\varphi) = \tfrac12 m(\dot r^2 + r^2\dot\varphi^2)
              + \frac{k}{r}

    Coordinates q = (r, phi): phi is cyclic, so
    :math:`p_\varphi = m r^2\dot\varphi` (the angular momentum) is conserved.
    Units: m (kg), k (J m).
    """

    def __init__(self, m: float = 1.0, k: float = 1.0):
        self.m = as_scalar(m, "m", positive=True)
        self.k = as_scalar(k, "k", positive=True)

    def __call__(self, q, qdot):
        r, _ = q
        rd, phid = qdot
        return 0.5 * self.m * (rd * rd + r * r * phid * phid) + self.k / r

    def rhs(self, t, y):
        """d/dt of the state (r, phi, r_dot, phi_dot), for :func:`mechpy.solve`."""
        r, _, rd, phid = y
        return [rd, phid, r * phid * phid - self.k / (self.m * r * r), -2 * rd * phid / r]

    def momenta(self, y):
        """(p_r, p_phi) = (m r_dot, m r^2 phi_dot) for states (4, ...)."""
        y = np.asarray(y, dtype=float)
        return np.stack([self.m * y[2], self.m * y[0] ** 2 * y[3]])


class RotatingHoop:
    r"""A bead on a hoop of radius R spun at a constant rate omega about its
    vertical diameter; theta is measured from the bottom.

    .. math:: L = \tfrac12 mR^2(\dot\theta^2 + \omega^2\sin^2\theta) + mgR\cos\theta

    The hoop's rotation is imposed (phi = omega t is not a coordinate): the
    energy is not conserved, but L has no explicit time, so the energy function
    :math:`h = \tfrac12 mR^2(\dot\theta^2 - \omega^2\sin^2\theta) - mgR\cos\theta`
    (the Jacobi integral) is.  Units: SI.
    """

    def __init__(self, R: float = 1.0, omega: float = 5.0, g: float = 9.81, m: float = 1.0):
        self.R = as_scalar(R, "R", positive=True)
        self.omega = as_scalar(omega, "omega")
        self.g = as_scalar(g, "g", positive=True)
        self.m = as_scalar(m, "m", positive=True)

    def __call__(self, q, qdot):
        m, R, w, g = self.m, self.R, self.omega, self.g
        return 0.5 * m * R * R * (qdot ** 2 + (w * np.sin(q)) ** 2) + m * g * R * np.cos(q)

    def rhs(self, t, y):
        """d/dt (theta, theta_dot), for :func:`mechpy.solve`."""
        th, thd = y
        return [thd, np.sin(th) * (self.omega ** 2 * np.cos(th) - self.g / self.R)]

    def jacobi_integral(self, y):
        """h(theta, theta_dot) (J) for states (2, ...)."""
        th, thd = np.asarray(y, dtype=float)
        m, R, w = self.m, self.R, self.omega
        return 0.5 * m * R * R * (thd ** 2 - (w * np.sin(th)) ** 2) - m * self.g * R * np.cos(th)

    def normal_force(self, t, y) -> np.ndarray:
        r"""The hoop's force on the bead from Lagrange multipliers, shape (3, ...).

        The bead is a free particle in Cartesian coordinates with two
        constraints, :math:`|\mathbf r|^2 = R^2` and
        :math:`-\sin(\omega t)x + \cos(\omega t)y = 0` (the hoop's plane);
        :func:`constraint_forces` gives the multipliers.  Returned are the
        components (radial outward, azimuthal along the rotation, vertical
        plane tangent) in N: the radial one is
        :math:`-mR(\dot\theta^2 + \omega^2\sin^2\theta) - mg\cos\theta`, the
        azimuthal one :math:`2mR\omega\dot\theta\cos\theta` (the Coriolis
        push), the tangential one 0.
        """
        t = np.asarray(t, dtype=float)
        th, thd = np.asarray(y, dtype=float)
        R, w, m, g = self.R, self.omega, self.m, self.g
        c, s = np.cos(w * t), np.sin(w * t)
        st, ct = np.sin(th), np.cos(th)
        pos = R * np.stack([st * c, st * s, -ct])
        vel = R * thd * np.stack([ct * c, ct * s, st]) + R * w * st * np.stack([-s, c, 0 * c])
        J = np.stack([np.moveaxis(pos, 0, -1),
                      np.moveaxis(np.stack([-s, c, 0 * c]), 0, -1)], axis=-2)   # (..., 2, 3)
        bias = np.stack([np.sum(vel * vel, axis=0),
                         -2 * w * (c * vel[0] + s * vel[1])], axis=-1)
        F = np.moveaxis(np.stack([0 * c + 0 * th, 0 * th, -m * g + 0 * th]), 0, -1)
        _, N = constraint_forces(m, F, J, bias)
        N = np.moveaxis(N, -1, 0)
        rhat = pos / R
        phat = np.stack([-s, c, 0 * c]) + 0 * pos
        that = np.stack([ct * c, ct * s, st])
        return np.stack([np.sum(N * rhat, 0), np.sum(N * phat, 0), np.sum(N * that, 0)])


# ---------------------------------------------------------------------------
# constraint forces
# ---------------------------------------------------------------------------

def constraint_forces(mass, force, jac, bias):
    r"""Lagrange multipliers and forces of holonomic constraints g(x, t) = 0.

    For :math:`M\ddot{\mathbf x} = \mathbf F + J^T\boldsymbol\lambda` with
    :math:`J = \partial g/\partial\mathbf x` and
    :math:`\ddot g = J\ddot{\mathbf x} + \mathbf b = 0`:

    .. math:: (J M^{-1} J^T)\,\boldsymbol\lambda = -(J M^{-1}\mathbf F + \mathbf b)

    Parameters
    ----------
    mass : float or array (..., d)
        Masses (a diagonal mass matrix), > 0 (kg).
    force : array (..., d)
        Applied forces (N).
    jac : array (..., k, d)
        Constraint Jacobians.
    bias : array (..., k)
        :math:`\mathbf b = \dot J\dot{\mathbf x} + \partial_t(\dots)`, the part
        of :math:`\ddot g` without the acceleration.

    Returns
    -------
    lam : ndarray (..., k)
        Multipliers.
    f : ndarray (..., d)
        Constraint forces :math:`J^T\lambda` (N).
    """
    m = as_array(mass, "mass", positive=True)
    F = as_array(force, "force", min_ndim=1)
    J = as_array(jac, "jac", min_ndim=2)
    b = as_array(bias, "bias", min_ndim=1)
    if J.shape[-1] != F.shape[-1] or J.shape[-2] != b.shape[-1]:
        raise ValueError(f"shapes do not match: jac {J.shape}, force {F.shape}, bias {b.shape}")
    Minv = 1.0 / np.broadcast_to(m, F.shape)
    A = np.einsum("...kd,...d,...ld->...kl", J, Minv, J)
    rhs = -(np.einsum("...kd,...d->...k", J, Minv * F) + b)
    lam = np.linalg.solve(A, rhs[..., None])[..., 0]
    return lam, np.einsum("...kd,...k->...d", J, lam)


def pendulum_tension(scene, y, mass: float = 1.0) -> np.ndarray:
    r"""The string tension of a pendulum along states y (2, ...) (N).

    From the Lagrange multiplier of the constraint :math:`x^2 + y^2 = \ell^2`
    on the bob in Cartesian coordinates (:func:`constraint_forces`); the
    tangential damping and drive forces do not contribute.  Newton's radial
    equation gives the same :math:`T = m(g\cos\theta + \ell\dot\theta^2)`.

    Parameters
    ----------
    scene : mechpy.scenes.Pendulum
    y : array (2, ...)
        States (theta, theta_dot), e.g. ``Solution.y``.
    mass : float
        Bob mass (kg).
    """
    from .scenes import Pendulum
    if not isinstance(scene, Pendulum):
        raise TypeError("scene must be a mechpy.scenes.Pendulum")
    m = as_scalar(mass, "mass", positive=True)
    y = as_array(y, "y", min_ndim=1)
    if y.shape[0] != 2:
        raise ValueError(f"y must have 2 components along its first axis, got {y.shape}")
    g, ell = scene.params["g"], scene.params["length"]
    th, thd = y
    pos = ell * np.stack([np.sin(th), -np.cos(th)], axis=-1)
    vel = ell * thd[..., None] * np.stack([np.cos(th), np.sin(th)], axis=-1)
    F = np.zeros_like(pos)
    F[..., 1] = -m * g
    lam, _ = constraint_forces(m, F, pos[..., None, :], np.sum(vel * vel, -1)[..., None])
    return -lam[..., 0] * ell
