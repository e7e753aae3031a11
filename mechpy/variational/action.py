r"""Least action with any number of coordinates: the stationary path between
two configurations and the variational integrator of the same discrete action.

The discrete action of the midpoint rule,

.. math:: S_h = \sum_{k=0}^{n-1} L_d(q_k, q_{k+1}), \qquad
          L_d(q_k, q_{k+1}) = h\,L\Big(t_k + \tfrac h2, \frac{q_k + q_{k+1}}2,
          \frac{q_{k+1} - q_k}h\Big),

is made stationary in C (``csrc/variational.c``): between fixed ends by
Newton's method on all interior nodes at once (a block-tridiagonal Hessian of
d x d blocks, banded LU, O(n d^3) per iteration), or step by step from
initial data (the variational integrator, a d x d Newton per step).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import _core
from .._validate import as_array, as_int, as_scalar
from ..scenes import Scene
from .functionals import (_MAX_ITER, _SING_TOL_EXACT, _SING_TOL_FD, _TOL, _fd_spec,
                          _lagrangian_fn, _n_nodes, _pair)
from .lagrangians import _scene_spec, _spec_dim

__all__ = ["stationary_path", "stationary_paths", "StationaryPath", "variational_integrate",
           "VariationalTrajectory", "MAX_STEPS"]

#: Default step budget of :func:`variational_integrate` (about 80 MB per
#: array of one coordinate).
MAX_STEPS = 10_000_000


def _system(system, q_like: np.ndarray):
    """(spec, d, scene energy or None, singularity tolerance) of a scene or a
    Python Lagrangian; a callable's d comes from the coordinates q_like."""
    if isinstance(system, Scene) or getattr(system, "_lagrangian_c", None) is not None:
        spec = _scene_spec(system)
        energy = system.energy if spec[0] == "scene" else None  # a row's own energy
        return spec, _spec_dim(spec), energy, _SING_TOL_EXACT
    if callable(system):
        scalar = q_like.ndim == 0
        d = 1 if scalar else q_like.shape[0]
        return (_fd_spec(_lagrangian_fn(system, d, scalar), d), d, None, _SING_TOL_FD)
    raise TypeError("system must be a scene (Pendulum, Duffing, HeavyTop, a scene from "
                    "mp.lagrangian) or a callable L(q, qdot[, t]), got "
                    f"{type(system).__name__}")


def _coords(v, name: str) -> np.ndarray:
    a = as_array(v, name)
    if a.ndim > 1:
        raise ValueError(f"{name} must be a number or a vector of coordinates (d,), got "
                         f"shape {a.shape}")
    return a


def _check_dim(a: np.ndarray, name: str, d: int) -> np.ndarray:
    """a (scalar or (d,)) as a (d,) vector; a scalar only for d = 1."""
    if a.size != d or (a.ndim == 0 and d != 1):
        raise ValueError(f"{name} must have {d} coordinate(s) for this system, got shape "
                         f"{a.shape}")
    return a.reshape(d)


def _shape_out(a: np.ndarray, scalar: bool) -> np.ndarray:
    """Points (m, d) as the public layout: (m,) for a scalar coordinate, else (d, m)."""
    return np.ascontiguousarray(a[:, 0] if scalar else a.T)


class StationaryPath(NamedTuple):
    """Result of :func:`stationary_path`.

    Attributes
    ----------
    t : ndarray, shape (n + 1,)
        Times (s).
    q : ndarray, shape (n + 1,) or (d, n + 1)
        The path of stationary discrete action (one row per coordinate;
        1-D for scalar end points).
    p : ndarray, same shape as q
        Discrete generalized momenta: :math:`p_0 = -D_1L_d(q_0, q_1)`,
        :math:`p_k = D_2L_d(q_{k-1}, q_k)`.
    qdot : ndarray, same shape as q
        Velocities from :math:`\\partial L/\\partial\\dot q = p`.
    action : float
        The discrete action :math:`S_h = \\sum_k h L_d` (units of L times s).
    iterations : int

    Examples
    --------
    >>> path = mp.variational.stationary_path(lambda q, v: 0.5 * v**2 - 0.5 * q**2, 0.0, 1.0, 1.0,
    ...                                       n=100)
    >>> path.t.shape, path.q.shape
    ((101,), (101,))
    >>> round(float(path.qdot[0]), 4), round(float(1 / np.sin(1.0)), 4)   # q'(0) = 1 / sin 1
    (1.1884, 1.1884)
    >>> bool(np.allclose(path.p, path.qdot))                              # p = dL/dv = v
    True
    """
    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    qdot: np.ndarray
    action: float
    iterations: int


def stationary_path(scene_or_lagrangian, q_a, q_b, T: float, n: int = 200, *,
                    t0: float = 0.0, guess=None, tol: float = _TOL,
                    max_iter: int = _MAX_ITER) -> StationaryPath:
    r"""The path of stationary discrete action from q(t0) = q_a to q(t0 + T) = q_b.

    .. math:: S_h = \sum_{k=0}^{n-1} h\,L\Big(t_k + \tfrac h2, \frac{q_k + q_{k+1}}2,
              \frac{q_{k+1} - q_k}h\Big), \qquad \frac{\partial S_h}{\partial q_k} = 0,

    solved by Newton's method on the residual (the action need not be a
    minimum: past a conjugate point it is a saddle).  With d coordinates the
    Hessian is block-tridiagonal (d x d blocks; banded LU, O(n d^3) per
    iteration).  Second order in h.

    Parameters
    ----------
    scene_or_lagrangian : scene or callable ``L(q, qdot[, t])``
        A scene whose Lagrangian runs in C: Pendulum (per unit mass,
        :math:`e^{bt}(\tfrac12\ell^2\dot\theta^2 + g\ell\cos\theta + \ell^2A\cos(\Omega t)\theta)`,
        whose Euler-Lagrange equation is the scene's equation of motion),
        Duffing, HeavyTop (q = (phi, theta, psi)) or a compiled scene from
        ``mp.lagrangian`` (any d); or a vectorised Python callable, its
        derivatives by finite differences: q and qdot of shape (d, m) for end
        points of shape (d,), of shape (m,) for scalar end points (e.g. the
        harmonic oscillator ``lambda q, v: 0.5 * v**2 - 0.5 * q**2``); a third
        argument, if it takes one, receives the times (m,).
    q_a, q_b : float or array (d,)
        End configurations.
    T : float
        Duration (s), > 0.
    n : int
        Number of time steps (>= 4).
    t0 : float
        Start time (s).
    guess : array (n + 1,) or (d, n + 1), optional
        Initial path (its ends are replaced by q_a, q_b); the straight line
        by default.
    tol, max_iter : float, int
        Relative step tolerance and Newton budget.

    Returns
    -------
    StationaryPath
        Arrays of shape (n + 1,) for scalar ends, (d, n + 1) otherwise.

    Raises
    ------
    ConvergenceError
        Newton's method did not converge within max_iter.
    SingularityError
        :math:`\partial^2L/\partial\dot q^2` is singular along the path (the
        velocities do not follow from the momenta).

    Notes
    -----
    A boundary-value problem may have several stationary paths (the
    pendulum from 0 back to 0 in a time T has 2k + 1 of them once
    :math:`\omega_0 T > k\pi`: at rest and k pairs of swings); Newton's
    method returns the one its ``guess`` leads to, and says nothing of the
    others.  :func:`stationary_paths` looks for them from several starts.

    Examples
    --------
    The harmonic oscillator L = v^2/2 - q^2/2 from q(0) = 0 to q(1) = 1: the path
    q = sin t / sin 1, and the action [q q']/2 = cot(1)/2:

    >>> path = mp.variational.stationary_path(lambda q, v: 0.5 * v**2 - 0.5 * q**2, 0.0, 1.0, 1.0)
    >>> round(float(path.q[100]), 5), round(float(np.sin(0.5) / np.sin(1.0)), 5)
    (0.56975, 0.56975)
    >>> round(path.action, 5), round(float(0.5 / np.tan(1.0)), 5)
    (0.32105, 0.32105)
    """
    qa, qb = _coords(q_a, "q_a"), _coords(q_b, "q_b")
    spec, d, _, sing_tol = _system(scene_or_lagrangian, qa)
    scalar = qa.ndim == 0 and qb.ndim == 0
    qa, qb = _check_dim(qa, "q_a", d), _check_dim(qb, "q_b", d)
    T = as_scalar(T, "T", positive=True)
    t0 = as_scalar(t0, "t0")
    n = _n_nodes(n)
    t = t0 + np.linspace(0.0, T, n + 1)
    if guess is None:
        q0 = qa + (qb - qa) * ((t - t0) / T)[:, None]
    else:
        g = as_array(guess, "guess", shape=(n + 1,) if scalar else (d, n + 1))
        q0 = g.reshape(n + 1, 1).copy() if scalar else np.ascontiguousarray(g.T)
        q0[0], q0[-1] = qa, qb
    tol = as_scalar(tol, "tol", positive=True)
    max_iter = as_int(max_iter, "max_iter", minimum=1)
    q, _, info = _core.variational_solve(spec, t, q0, [], np.zeros(0), np.zeros(0), True,
                                         tol, max_iter)
    p = _core.variational_momenta(spec, t, q)
    vm = np.diff(q, axis=0) / np.diff(t)[:, None]
    v, _ = _core.variational_velocities(spec, t, q, p, np.concatenate([vm[:1], vm]),
                                        sing_tol)
    return StationaryPath(t, _shape_out(q, scalar), _shape_out(p, scalar),
                          _shape_out(v, scalar), info["J"], info["iterations"])


def stationary_paths(scene_or_lagrangian, q_a, q_b, T: float, n: int = 200, *,
                     velocities=None, t0: float = 0.0, atol: float = 1e-6, tol: float = _TOL,
                     max_iter: int = _MAX_ITER) -> list:
    r"""The distinct paths of stationary action between q_a and q_b found by
    shooting from several initial velocities.

    Each initial velocity v starts :func:`variational_integrate` from q_a
    over [t0, t0 + T]; that trajectory (its end replaced by q_b) is the
    guess of one :func:`stationary_path` solve.  Solves that fail
    (:class:`~mechpy.ConvergenceError`, :class:`~mechpy.SingularityError`)
    are skipped, and paths within ``atol`` (max norm) of one found before
    are the same path.

    Parameters
    ----------
    scene_or_lagrangian, q_a, q_b, T, n, t0, tol, max_iter
        As for :func:`stationary_path`.
    velocities : array_like (k,) or (k, d), optional
        Initial velocities to shoot with (rad/s or the coordinates' unit per
        s); by default 17 values :math:`\bar v + j\,\pi/T`, j = -8..8, around
        the straight line's :math:`\bar v = (q_b - q_a)/T` (along every
        coordinate at once for d > 1).
    atol : float
        Distance below which two paths are the same.

    Returns
    -------
    list of StationaryPath
        The distinct paths, by increasing action (empty if none converged).

    Examples
    --------
    The pendulum (g/l = 1) from 0 back to 0 in T = 4.5 s, between pi and
    2 pi: at rest, and a swing to either side.

    >>> import mechpy as mp
    >>> paths = mp.variational.stationary_paths(mp.scenes.Pendulum(g=1.0), 0.0, 0.0, 4.5)
    >>> len(paths)
    3
    """
    from ..errors import ConvergenceError, SingularityError
    qa, qb = _coords(q_a, "q_a"), _coords(q_b, "q_b")
    T = as_scalar(T, "T", positive=True)
    n = _n_nodes(n)
    atol = as_scalar(atol, "atol", positive=True)
    vbar = (qb - qa) / T
    if velocities is None:
        vs = [vbar + j * np.pi / T for j in range(-8, 9)]
    else:
        v = as_array(velocities, "velocities", min_ndim=1)
        vs = list(v)
    found = []
    for v in vs:
        try:
            run = variational_integrate(scene_or_lagrangian, (t0, t0 + T), qa, v, T / n)
            guess = run.q[..., :n + 1]
            if not np.all(np.isfinite(guess)):
                continue
            path = stationary_path(scene_or_lagrangian, qa, qb, T, n, t0=t0, guess=guess,
                                   tol=tol, max_iter=max_iter)
        except (ConvergenceError, SingularityError):
            continue
        if not all(np.max(np.abs(path.q - other.q)) > atol for other in found):
            continue
        found.append(path)
    return sorted(found, key=lambda p: p.action)


class VariationalTrajectory(NamedTuple):
    """Result of :func:`variational_integrate`.

    Attributes
    ----------
    t : ndarray, shape (n + 1,)
        Times (s).
    q, p, qdot : ndarray, shape (n + 1,) or (d, n + 1)
        Positions, momenta and velocities (from p), one row per coordinate
        (1-D for a scalar q0).
    energy : ndarray, shape (n + 1,)
        For Pendulum, Duffing and HeavyTop the scene's own ``energy``;
        otherwise the energy function
        :math:`h = \\dot q\\cdot\\partial L/\\partial\\dot q - L`.

    Examples
    --------
    >>> tr = mp.variational.variational_integrate(mp.scenes.Pendulum(g=9.81, length=1.0),
    ...                                          (0.0, 1.0), 0.5, 0.0, 0.01)
    >>> tr.t.shape, tr.q.shape, tr.energy.shape
    ((101,), (101,), (101,))
    >>> round(float(tr.energy[0]), 6), round(9.81 * (1 - float(np.cos(0.5))), 6)   # g L (1 - cos)
    (1.200915, 1.200915)
    """
    t: np.ndarray
    q: np.ndarray
    p: np.ndarray
    qdot: np.ndarray
    energy: np.ndarray


def variational_integrate(system, t_span, q0, qdot0, h: float, *,
                          max_steps: int = MAX_STEPS) -> VariationalTrajectory:
    r"""Integrate with the variational integrator of the midpoint discrete Lagrangian.

    .. math:: L_d(q_0, q_1) = h\,L\big(\tfrac{q_0 + q_1}2, \tfrac{q_1 - q_0}h\big),\quad
              p_k = -D_1L_d(q_k, q_{k+1}),\quad p_{k+1} = D_2L_d(q_k, q_{k+1})

    (the same discrete action as :func:`stationary_path`; a d x d Newton
    iteration per step).  The map :math:`(q_k, p_k) \mapsto (q_{k+1}, p_{k+1})`
    is symplectic and second order; for a conservative system the energy
    error stays bounded (O(h^2)) over exponentially long times instead of
    drifting, and the momentum of a cyclic coordinate is conserved exactly.

    Parameters
    ----------
    system : scene or callable ``L(q, qdot[, t])``
        As for :func:`stationary_path`.
    t_span : (t0, t1)
        Time interval (s).
    q0, qdot0 : float or array (d,)
        Initial position and velocity.
    h : float
        Step (s); the last step ends at or after t1 (n = ceil((t1 - t0)/h)).
    max_steps : int
        Step budget (default :data:`MAX_STEPS` = 10**7): more steps are
        refused before any memory is allocated.

    Returns
    -------
    VariationalTrajectory
        Arrays of shape (n + 1,) for a scalar q0, (d, n + 1) otherwise.

    Raises
    ------
    ValueError
        The run would need more than max_steps steps.
    SingularityError
        :math:`\partial^2L/\partial\dot q^2` is singular (the Lagrangian does
        not determine the motion, e.g. it is linear in the velocities).
    ConvergenceError
        A step's Newton iteration failed (the step is too large).

    Examples
    --------
    The harmonic oscillator from q = 1 at rest: q = cos t to O(h^2), and the energy
    error stays bounded:

    >>> tr = mp.variational.variational_integrate(lambda q, v: 0.5 * v**2 - 0.5 * q**2,
    ...                                          (0.0, 10.0), 1.0, 0.0, 0.01)
    >>> round(float(tr.q[-1]), 4), round(float(np.cos(10.0)), 4)
    (-0.8391, -0.8391)
    >>> bool(np.abs(tr.energy - 0.5).max() < 1e-4)
    True
    """
    q0a, v0a = _coords(q0, "q0"), _coords(qdot0, "qdot0")
    spec, d, energy, sing_tol = _system(system, q0a)
    scalar = q0a.ndim == 0 and v0a.ndim == 0
    q0a, v0a = _check_dim(q0a, "q0", d), _check_dim(v0a, "qdot0", d)
    t0, t1 = (as_scalar(v, "t_span") for v in _pair(t_span, "t_span"))
    if not t1 > t0:
        raise ValueError("t_span must be increasing")
    h = as_scalar(h, "h", positive=True)
    max_steps = as_int(max_steps, "max_steps", minimum=1)
    steps = np.ceil((t1 - t0) / h - 1e-9)
    if not steps <= max_steps:
        raise ValueError(f"t_span and h need {steps:.3g} steps, more than max_steps = "
                         f"{max_steps}; raise h or max_steps (each step stores "
                         f"{8 * (3 * d + 2)} bytes)")
    n = int(steps)
    ev = _core.variational_eval(spec, np.array([t0]), q0a[None], v0a[None])
    p0 = ev[0, 1 + d:1 + 2 * d]
    q, p = _core.variational_integrate(spec, t0, h, n, q0a[None], p0[None], v0a[None],
                                       sing_tol)
    t = t0 + h * np.arange(n + 1)      # after the interruptible run
    vguess = np.empty_like(q)
    vguess[0] = v0a
    vguess[1:] = np.diff(q, axis=0) / h
    v, E = _core.variational_velocities(spec, t, q, p, vguess, sing_tol)
    if energy is not None:
        E = energy(np.concatenate([q.T, v.T]))
    return VariationalTrajectory(t, _shape_out(q, scalar), _shape_out(p, scalar),
                                 _shape_out(v, scalar), np.asarray(E, dtype=np.float64))
