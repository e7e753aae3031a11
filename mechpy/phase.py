r"""Phase space and chaos (Marion & Thornton chapter 4; course notes sections 2-3).

The state of a system :math:`\dot{\mathbf y} = \mathbf f(t, \mathbf y)` is a
point moving in the vector field :math:`\mathbf f`.  This module evaluates the
field on grids, finds and classifies fixed points from the Jacobian, measures
limit cycles, takes Poincaré sections and bifurcation diagrams of driven
systems and estimates the largest Lyapunov exponent.

``system`` is a scene from :mod:`mechpy.scenes` (evaluated in C) or a Python
callable ``f(t, y)``.  Units are those of the system.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
section points (n, dim), a bifurcation diagram (len(values), n, dim).
"""
from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from ._validate import as_array, as_int, as_scalar
from ._system import _is_scene as _is_mechpy_scene
from .errors import ConvergenceError, NonFiniteError, StepBudgetError
from .integrate import solve, solve_many
from .tangent import _floquet
from .tangent import _lyapunov_spectrum as _spectrum

__all__ = ["FixedPoint", "vector_field", "fixed_points", "FIXED_POINT_STARTS",
           "MAX_SECTION_POINTS", "SECTION_MAX_STEPS", "limit_cycle", "poincare",
           "bifurcation", "lyapunov", "LyapunovFloorWarning", "logistic",
           "logistic_bifurcation"]


class LyapunovFloorWarning(UserWarning):
    """The neighbour method's separation fell to the integration error: the
    exponent it reports is a floor set by the tolerances, not a measurement.

    Examples
    --------
    Following a neighbour on a contracting system, the separation falls to the
    integration error, and the exponent is only a floor:

    >>> import warnings
    >>> osc = mp.scenes.Duffing(1.0, 0.0, delta=2.0)
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     lam = mp.phase.lyapunov(osc, [1.0, 0.0], 100.0, dt=10.0, method="neighbours")
    >>> w[0].category.__name__
    'LyapunovFloorWarning'
    """


def _is_scene(system) -> bool:
    return _is_mechpy_scene(system)


def _callable(system):
    if not (_is_scene(system) or callable(system)):
        raise TypeError(f"system must be a scene or a callable f(t, y), got "
                        f"{type(system).__name__}")
    return system.rhs if _is_scene(system) else system


def _ensemble(system, y0s, t_span, t_eval, **kw):
    """Integrate one system from several starts; returns a list of Solutions.

    The one place where many trajectories are run: a loop over :func:`solve`
    today, to be replaced by the C ensemble integrator."""
    return [solve(system, t_span, y0, t_eval=t_eval, **kw) for y0 in y0s]


# ---- vector field ---------------------------------------------------------------
def vector_field(system, X, Y, t: float = 0.0, *, vectorized: bool = False):
    """The field (U, V) = f(t, (X, Y)) of a two-dimensional system on a grid.

    Parameters
    ----------
    system : Scene or callable f(t, y)
        A system with a 2-component state.  A scene is evaluated in C in one
        call.  A callable is called once per grid point with ``y`` of shape
        (2,), unless ``vectorized`` is True.
    X, Y : array_like, same shape
        Grid coordinates (e.g. from ``np.meshgrid``).
    t : float
        Time at which the field is taken (driven systems).
    vectorized : bool
        As in :func:`scipy.integrate.solve_ivp`: the callable accepts ``y``
        of shape (2, ...) (the grid stacked on a leading axis) and returns
        the field in the same shape, acting on each point independently.
        Whether a callable does so cannot be told from its output (``A @ y``
        returns the right shape and mixes grid points), so it is never
        guessed.  Ignored for scenes.

    Returns
    -------
    U, V : ndarray, shape of X
        dx/dt and dy/dt (units of the state per unit time).

    Examples
    --------
    The pendulum's field (theta_dot, -(g/L) sin theta):

    >>> X, Y = np.meshgrid([0.0, np.pi / 2], [1.0])
    >>> U, V = mp.phase.vector_field(mp.scenes.Pendulum(g=1.0, length=1.0), X, Y)
    >>> U, np.round(V, 12)
    (array([[1., 1.]]), array([[-0., -1.]]))
    >>> U, V = mp.phase.vector_field(lambda t, y: [y[1], -y[0]], X, Y)   # a Python callable
    >>> U, np.round(V, 12) + 0.0
    (array([[1., 1.]]), array([[ 0.        , -1.57079633]]))
    """
    f = _callable(system)
    X = as_array(X, "X").reshape(np.shape(X))
    Y = as_array(Y, "Y").reshape(np.shape(Y))
    if X.shape != Y.shape:
        raise ValueError(f"X and Y must have the same shape, got {X.shape} and {Y.shape}")
    t = as_scalar(t, "t")
    if not isinstance(vectorized, (bool, np.bool_)):
        raise TypeError(f"vectorized must be True or False, got {vectorized!r}")
    if _is_scene(system) and system.dim != 2:
        raise ValueError(f"vector_field needs a 2-D system; this scene has dim {system.dim}")
    Z = np.stack([X, Y])
    if _is_scene(system) or vectorized:
        F = np.asarray(f(t, Z), dtype=np.float64)
        if F.shape != Z.shape:
            raise ValueError(f"a vectorized system must return shape {Z.shape} for y of "
                             f"shape {Z.shape}, got {F.shape}")
        return F[0], F[1]
    F = np.empty_like(Z)
    for idx in np.ndindex(X.shape):
        val = np.asarray(f(t, Z[(slice(None),) + idx]), dtype=np.float64)
        if val.shape != (2,):
            raise ValueError(f"the system must return 2 components, got shape {val.shape}")
        F[(slice(None),) + idx] = val
    return F[0], F[1]


# ---- fixed points -----------------------------------------------------------------
class FixedPoint(NamedTuple):
    """A fixed point f(x) = 0 and its linear classification.

    ``kind`` is ``"saddle"``, ``"node"``, ``"focus"``, ``"centre"`` (2-D), or
    ``"hyperbolic"``/``"non-hyperbolic"`` in higher dimension; ``stable`` is
    True when no eigenvalue of the Jacobian has a positive real part (a centre
    counts as stable: neutrally, in the linear approximation);
    ``eigenvalues`` are the Jacobian's.

    Examples
    --------
    >>> (p,) = mp.phase.fixed_points(mp.scenes.VanDerPol(1.0), [(-1, 1), (-1, 1)])
    >>> p.kind, p.stable                         # eigenvalues (mu -+ sqrt(mu^2 - 4)) / 2
    ('focus', False)
    >>> np.round(p.eigenvalues, 9)
    array([0.5+0.8660254j, 0.5-0.8660254j])
    """
    x: np.ndarray
    kind: str
    stable: bool
    eigenvalues: np.ndarray


def _jacobian(system, t, y):
    if _is_scene(system):
        return system.jacobian(t, y)
    f = system
    n = y.size
    J = np.empty((n, n))
    for j in range(n):
        h = 1e-7 * max(1.0, abs(y[j]))
        e = np.zeros(n)
        e[j] = h
        J[:, j] = (np.asarray(f(t, y + e)) - np.asarray(f(t, y - e))) / (2 * h)
    return J


def _classify(ev, scale):
    re, im = ev.real, ev.imag
    tol = 1e-9 * max(scale, 1e-300)
    stable = bool(np.all(re <= tol))
    if ev.size == 2:
        if np.any(re > tol) and np.any(re < -tol) and np.all(np.abs(im) <= tol):
            return "saddle", False
        if np.all(np.abs(im) > tol):
            return ("centre", True) if np.all(np.abs(re) <= tol) else ("focus", stable)
        return "node", stable
    return ("hyperbolic" if np.all(np.abs(re) > tol) else "non-hyperbolic"), stable


#: Budget of fixed_points: starting points for a scene (Newton runs batched in C)
#: and for a Python callable (one point at a time, about 1 ms each).
FIXED_POINT_STARTS = {"scene": 1_000_000, "callable": 10_000}


def fixed_points(system, bounds, *, t: float = 0.0, seeds: int = 15, tol: float = 1e-12,
                 max_starts: int | None = None):
    r"""Fixed points of an autonomous system in a box, classified from the Jacobian.

    Newton's method :math:`\mathbf y \leftarrow \mathbf y - J^{-1}\mathbf f`
    is started from a grid of ``seeds`` points per axis; converged points
    inside ``bounds`` are kept once each.  In 2-D the eigenvalues of J give a
    saddle (real, opposite signs), a node (real, same sign), a focus
    (complex) or a centre (purely imaginary).  For a scene every start runs
    at once (the field and Jacobian of the whole batch in one C call each);
    a Python callable is iterated one start at a time.

    Parameters
    ----------
    system : Scene or callable f(t, y)
    bounds : array_like, shape (dim, 2)
        ``[(lo, hi), ...]`` per state component.
    t : float
        Time at which the field is frozen.
    seeds : int
        Starting points per axis (``seeds ** dim`` in all).
    tol : float
        Convergence tolerance on the step (state units).
    max_starts : int, optional
        Budget on ``seeds ** dim``; default :data:`FIXED_POINT_STARTS`:
        10^6 for a scene (about 1 s per 10^5 starts), 10^4 for a Python
        callable (about 1 ms per start).  A larger grid is a ``ValueError``
        before any work; Ctrl-C stops the search between Newton steps.

    Returns
    -------
    list of FixedPoint
        Sorted by their coordinates.

    Examples
    --------
    The pendulum: centres at 2 pi n (eigenvalues +-i sqrt(g/L)), saddles at
    pi + 2 pi n (+-sqrt(g/L)):

    >>> fps = mp.phase.fixed_points(mp.scenes.Pendulum(g=4.0, length=1.0), [(-4, 4), (-2, 2)])
    >>> [(round(float(p.x[0]), 9), p.kind) for p in fps]
    [(-3.141592654, 'saddle'), (0.0, 'centre'), (3.141592654, 'saddle')]
    >>> np.round(fps[1].eigenvalues.imag, 12), np.round(fps[0].eigenvalues.real, 12)
    (array([ 2., -2.]), array([ 2., -2.]))
    """
    f = _callable(system)
    b = as_array(bounds, "bounds", ndim=2)
    if b.shape[1] != 2 or np.any(b[:, 1] <= b[:, 0]):
        raise ValueError(f"bounds must have shape (dim, 2) with lo < hi, got {b.shape}")
    dim = b.shape[0]
    scene = _is_scene(system)
    if scene and system.dim != dim:
        raise ValueError(f"bounds gives {dim} components; the scene has dim {system.dim}")
    seeds = as_int(seeds, "seeds", minimum=1)
    kind = "scene" if scene else "callable"
    budget = (FIXED_POINT_STARTS[kind] if max_starts is None
              else as_int(max_starts, "max_starts", minimum=1))
    if seeds ** dim > budget:
        raise ValueError(
            f"fixed_points: seeds ** dim = {seeds}^{dim} = {seeds ** dim:.3g} starting points "
            f"exceed the budget max_starts = {budget} for a {kind}; lower seeds or raise "
            "max_starts")
    t = as_scalar(t, "t")
    tol = as_scalar(tol, "tol", positive=True)
    axes = [np.linspace(lo, hi, seeds + 2)[1:-1] for lo, hi in b]
    starts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    span = np.max(b[:, 1] - b[:, 0])
    cand = _newton_batch(system, t, starts, tol) if scene else _newton_each(f, system, t,
                                                                              starts, tol)
    inside = np.all(np.isfinite(cand), axis=1) & np.all((cand >= b[:, 0]) & (cand <= b[:, 1]),
                                                       axis=1)
    cand = cand[inside]
    found = []
    # near-duplicates first collapse on a grid of 1e-7 span, then one by one
    if cand.shape[0]:
        _, first = np.unique(np.round(cand / (1e-7 * span)), axis=0, return_index=True)
        cand = cand[np.sort(first)]
    for y in cand:
        if np.linalg.norm(f(t, y)) > 1e-8 * max(1.0, np.abs(_jacobian(system, t, y)).max()):
            continue
        if any(np.linalg.norm(y - p) < 1e-7 * span for p in found):
            continue
        found.append(np.array(y))
    found.sort(key=tuple)
    out = []
    for y in found:
        J = _jacobian(system, t, y)
        ev = np.linalg.eigvals(J)
        kind_, stable = _classify(ev, np.abs(J).max())
        out.append(FixedPoint(y, kind_, stable, ev))
    return out


def _newton_each(f, system, t, starts, tol):
    """Newton from each start in turn; a start that fails gives a row of NaN."""
    out = np.full(starts.shape, np.nan)
    for i, y in enumerate(starts):
        y = y.copy()
        for _ in range(60):
            J = _jacobian(system, t, y)
            try:
                step = np.linalg.solve(J, np.asarray(f(t, y), dtype=np.float64))
            except np.linalg.LinAlgError:
                break
            y -= step
            if not np.all(np.isfinite(y)):
                break
            if np.linalg.norm(step) <= tol * max(1.0, np.linalg.norm(y)):
                out[i] = y
                break
    return out


def _newton_batch(scene, t, starts, tol):
    """Newton from every start at once (a scene's rhs and Jacobian take (dim, N)
    states); rows that do not converge in 60 steps, meet a singular Jacobian or
    leave the finite numbers are NaN."""
    y = starts.T.copy()                                # (dim, N)
    n = y.shape[1]
    active = np.ones(n, dtype=bool)
    done = np.zeros(n, dtype=bool)
    with np.errstate(all="ignore"):
        for _ in range(60):
            idx = np.flatnonzero(active)
            if idx.size == 0:
                break
            ya = y[:, idx]
            F = np.asarray(scene.rhs(t, ya), dtype=np.float64).T          # (k, dim)
            J = np.moveaxis(np.asarray(scene.jacobian(t, ya), dtype=np.float64), -1, 0)
            ok = np.all(np.isfinite(J), axis=(1, 2)) & np.all(np.isfinite(F), axis=1)
            # an exactly singular J (a zero pivot) would stop the batched solve
            ok &= np.linalg.det(np.where(ok[:, None, None], J, np.eye(J.shape[-1]))) != 0.0
            Js = np.where(ok[:, None, None], J, np.eye(J.shape[-1]))
            step = np.linalg.solve(Js, np.where(ok[:, None], F, 0.0)[..., None])[..., 0]
            ynew = ya - step.T
            ok &= np.all(np.isfinite(ynew), axis=0)
            y[:, idx] = np.where(ok, ynew, y[:, idx])
            conv = ok & (np.linalg.norm(step, axis=1)
                         <= tol * np.maximum(1.0, np.linalg.norm(ynew, axis=0)))
            done[idx[conv]] = True
            active[idx[conv | ~ok]] = False
    out = np.full(starts.shape, np.nan)
    out[done] = y[:, done].T
    return out


# ---- limit cycles ------------------------------------------------------------------
def limit_cycle(system, y0, *, component: int = 0, tol: float = 1e-9, t_max: float = 1e5,
                method: str = "dop853", rtol: float = 1e-12, max_periods: int = 2000,
                stall: int = 100):
    r"""Period and amplitude of the limit cycle reached from ``y0``.

    The trajectory is integrated until the times between successive maxima of
    ``y[component]`` (zeros of its rate, located on the interpolant) agree to
    ``tol`` (relative); the amplitude is the value at the maximum.

    Parameters
    ----------
    system : Scene or callable f(t, y)
        An autonomous system with an attracting cycle.
    y0 : array_like
        Start in the cycle's basin.
    component : int
        Which coordinate's maxima mark the section.
    tol : float
        Relative tolerance on the period and the amplitude.  What can be
        reached is limited by ``rtol`` (the spread of successive periods
        settles a little below ``rtol``; e.g. 2e-15 for the Van der Pol cycle at
        ``rtol=1e-12``).
    t_max : float
        Give up after this time.
    max_periods : int
        Budget: give up after this many cycles (about 15 ms each for a scene).
    stall : int
        Give up early when the spread of the periods and amplitudes has not
        halved over this many cycles (``tol`` below the integration's
        resolution: without this the search ran to ``t_max``, 116 s).
    method, rtol : str, float
        Passed to :func:`mechpy.solve`.  Keep ``"dop853"`` unless the cycle is
        strongly stiff: on Van der Pol from (2, 0) (``tol=1e-6``; ``rtol=1e-12``
        for mu = 1, 10, ``1e-8`` for mu = 100, 1000) dop853 took 0.12 s, 0.78 s,
        5.1 s and more than 60 s for mu = 1, 10, 100, 1000, ``"radau"`` 5.3 s,
        14 s, 2.2 s and 3.9 s: radau is 18-45x slower for a mildly stiff cycle
        (mu <= 10) and pays off from mu of about 100 on, where the slow
        branches make explicit steps stability-limited.  ``"auto"`` switches
        between them by Hairer's stiffness test.

    Returns
    -------
    period, amplitude : float
        Period (time units) and max of ``y[component]`` on the cycle.

    Raises
    ------
    mechpy.ConvergenceError
        When a budget (``t_max``, ``max_periods``, ``stall``) runs out; the
        message gives the spread reached and why no cycle was found (the
        amplitude keeps decaying or growing, the motion does not repeat, no
        oscillation at all, or ``tol`` below what ``rtol`` resolves).  Also
        when the closed orbit reached is not isolated: the integral of
        :math:`\nabla\cdot\mathbf f` over its period (the log of its
        nontrivial Floquet multipliers' product) is zero to 1e-6 of the
        Jacobian's size, so its neighbours are closed as well -- a centre's
        family of closed orbits, as the undamped pendulum's, not a limit
        cycle (before, one of them was returned).  Ctrl-C raises
        ``KeyboardInterrupt``.

    Examples
    --------
    The Van der Pol cycle at mu = 1: period 6.6632868593 and amplitude 2.00861986
    (published values):

    >>> T, A = mp.phase.limit_cycle(mp.scenes.VanDerPol(1.0), [0.5, 0.0], tol=1e-10)
    >>> round(T, 10), round(A, 8)
    (6.6632868593, 2.00861986)
    """
    f = _callable(system)
    y = as_array(y0, "y0", ndim=1).copy()
    k = as_int(component, "component", minimum=0, maximum=y.size - 1)
    tol = as_scalar(tol, "tol", positive=True)
    t_max = as_scalar(t_max, "t_max", positive=True)
    max_periods = as_int(max_periods, "max_periods", minimum=4)
    stall = as_int(stall, "stall", minimum=1)

    def rate(t, z):
        return np.asarray(f(t, z))[k]
    rate.direction = -1

    times, amps = [], []
    spreads = []          # relative spread of the last three periods / amplitudes, per cycle
    t0, chunk = 0.0, 20.0
    while t0 < t_max:
        s = solve(system, (t0, min(t0 + chunk, t_max)), y, method=method, rtol=rtol,
                  atol=rtol * 1e-2, events=rate)
        if s.status < 0:
            raise ConvergenceError(f"limit_cycle: integration failed ({s.message})")
        times.extend(s.t_events[0])
        amps.extend(s.y_events[0][:, k])
        y, t0 = s.y[:, -1], s.t[-1]
        for j in range(max(4, len(times) - len(s.t_events[0])), len(times) + 1):
            P = np.diff(times[j - 4:j])
            A = np.array(amps[j - 3:j])
            spreads.append(max(np.ptp(P) / P[-1], np.ptp(A) / max(abs(A[-1]), 1e-300)))
            if spreads[-1] <= tol:
                _refuse_centre(system, s.y_events[0][-1], float(s.t_events[0][-1]),
                               float(P[-1]), method, rtol)
                return float(P[-1]), float(A[-1])
            if j > max_periods:
                raise ConvergenceError(
                    f"limit_cycle: no cycle converged to tol = {tol:g} within max_periods = "
                    f"{max_periods} cycles (relative spread {spreads[-1]:.2g})")
        if len(times) >= 4:
            chunk = max(chunk, 10.0 * (times[-1] - times[-2]))
        else:
            chunk *= 2.0
        if len(spreads) > stall and min(spreads[-stall:]) > 0.5 * min(spreads[:-stall]):
            raise ConvergenceError(_stall_message(amps, spreads, stall, tol, rtol, k))
    if len(times) < 4:
        raise ConvergenceError(
            f"limit_cycle: no cycle found: y[{k}] reached only {len(times)} maxima up to "
            f"t_max = {t_max:g} (a cycle needs 4 to be measured): the trajectory from y0 "
            "settles or runs off without oscillating")
    raise ConvergenceError(f"limit_cycle: no cycle converged to tol = {tol:g} before t_max = "
                           f"{t_max:g} (relative spread {spreads[-1]:.2g} after "
                           f"{len(times)} maxima)")


def _stall_message(amps, spreads, stall, tol, rtol, k) -> str:
    """Why the spread of periods and amplitudes stopped shrinking: the amplitude
    keeps decaying or growing (no cycle there), the motion does not repeat (the
    spread stays far above the integration's resolution), or tol is below what
    rtol resolves (a cycle is there)."""
    A = np.asarray(amps[-stall:], dtype=float)
    lo = min(spreads)
    spread = (f"the relative spread of periods and amplitudes stopped shrinking at {lo:.2g} "
              f"over the last {stall} cycles")
    head = f"limit_cycle: no cycle found: {spread}"
    if A.size >= 3 and np.all(np.diff(A) < 0):
        return (f"{head}; the amplitude (max of y[{k}]) kept decreasing, from {A[0]:.6g} to "
                f"{A[-1]:.6g}: the orbit decays (towards a fixed point or a cycle not yet "
                "reached), it is not a limit cycle")
    if A.size >= 3 and np.all(np.diff(A) > 0):
        return (f"{head}; the amplitude (max of y[{k}]) kept growing, from {A[0]:.6g} to "
                f"{A[-1]:.6g}: the orbit runs away, it is not a limit cycle")
    if lo > 1e3 * rtol:
        return (f"{head}, far above what rtol = {rtol:g} resolves: the motion does not repeat "
                "(quasi-periodic or chaotic), so there is no cycle to converge to")
    return (f"limit_cycle: {spread}, above tol = {tol:g}: the orbit repeats to within what "
            f"rtol = {rtol:g} resolves (a cycle is there, tol asks for more); raise tol or "
            "lower rtol")


def _refuse_centre(system, y, t, period, method, rtol):
    """Raise ConvergenceError when the closed orbit through y is one of a
    centre's family, not a limit cycle.

    A limit cycle attracts (or repels) its neighbours: the product of its
    nontrivial Floquet multipliers, exp(integral of div f over one period)
    (Liouville), is not 1.  A centre's orbits (the undamped pendulum's, any
    conservative system's) keep phase-space volume, div f = 0: every nearby
    orbit is closed too, none is isolated.  The integral is taken by the
    trapezoid rule on 256 points of the orbit (spectrally accurate for a
    periodic integrand) and compared with the Jacobian's size along it."""
    te = np.linspace(t, t + period, 257)
    s = solve(system, (t, t + period), y, method=method, rtol=rtol, atol=rtol * 1e-2,
              t_eval=te)
    if s.status < 0:
        return
    tr, size = np.empty(te.size), np.empty(te.size)
    for i in range(te.size):
        J = np.asarray(_jacobian(system, te[i], s.y[:, i]), dtype=float)
        tr[i], size[i] = np.trace(J), np.max(np.abs(J))
    h = period / (te.size - 1)
    div = h * (0.5 * (tr[0] + tr[-1]) + tr[1:-1].sum())
    scale = h * (0.5 * (size[0] + size[-1]) + size[1:-1].sum())
    if abs(div) <= 1e-6 * scale:
        raise ConvergenceError(
            f"limit_cycle: the closed orbit through y0 (period {period:.10g}) is not a limit "
            f"cycle: the flow keeps phase-space volume along it (integral of div f over the "
            f"period {div:.2g}, Floquet multiplier product exp of it = 1), so its neighbours "
            "are closed orbits too: a centre's family of closed orbits (a conservative "
            "system, such as the undamped pendulum), none isolated. Every start gives its "
            "own period; there is no limit cycle to converge to")


# ---- sections ----------------------------------------------------------------------
def _section_times(t0, period, n, skip):
    return t0 + period * (skip + np.arange(n))


#: Budget of poincare and bifurcation: at most this many section points per run
#: (n * dim floats are returned).
MAX_SECTION_POINTS = 10_000_000
#: Default step budget of one poincare / bifurcation integration (about 0.5 s
#: for a C scene).
SECTION_MAX_STEPS = 1_000_000


def poincare(system, y0, period, n, skip: int = 0, *, t0: float = 0.0, rtol: float = 1e-10,
             atol: float = 1e-12, method: str = "dop853", max_steps: int = SECTION_MAX_STEPS):
    r"""Stroboscopic Poincaré section of a driven system.

    The states :math:`\mathbf y(t_0 + kT)` for k = skip, ..., skip + n - 1,
    read from one integration's interpolant.

    Parameters
    ----------
    system : Scene or callable f(t, y)
    y0 : array_like, shape (dim,)
        State at ``t0``.
    period : float
        The drive period T (time units), e.g. ``2 pi / drive_frequency``.
    n : int
        Points to return (at most :data:`MAX_SECTION_POINTS`); ``skip`` first
        periods are discarded (transient).
    max_steps : int
        Step budget of the integration over (skip + n) periods (default
        10^6, about 0.5 s for a scene); an absurd span exhausts it and raises
        :class:`mechpy.StepBudgetError` instead of running for hours.  Ctrl-C
        raises ``KeyboardInterrupt``.

    Returns
    -------
    ndarray, shape (n, dim)
        The section points (angles are not wrapped: use ``np.angle(np.exp(1j*theta))``).

    Examples
    --------
    A damped, driven linear oscillator (Duffing with beta = 0) settles on its
    steady state; sampled once a drive period, it is one point, the closed form
    x = gamma (alpha - w^2) / D, v = gamma delta w^2 / D,
    D = (alpha - w^2)^2 + (delta w)^2:

    >>> a, d, g, w = 1.0, 0.5, 0.3, 2.0
    >>> osc = mp.scenes.Duffing(a, 0.0, delta=d, gamma=g, omega=w)
    >>> pts = mp.phase.poincare(osc, [1.0, 0.0], 2 * np.pi / w, 3, skip=60)
    >>> np.round(pts, 9)
    array([[-0.09,  0.06],
           [-0.09,  0.06],
           [-0.09,  0.06]])
    >>> D = (a - w**2) ** 2 + (d * w) ** 2
    >>> round(g * (a - w**2) / D, 9), round(g * d * w**2 / D, 9)
    (-0.09, 0.06)
    """
    _callable(system)
    y0 = as_array(y0, "y0", ndim=1)
    period = as_scalar(period, "period", positive=True)
    n = as_int(n, "n", minimum=1, maximum=MAX_SECTION_POINTS)
    skip = as_int(skip, "skip", minimum=0)
    t0 = as_scalar(t0, "t0")
    te = _section_times(t0, period, n, skip)
    t_end = _section_end(te, period)
    s = solve(system, (t0, t_end), y0, method=method, rtol=rtol, atol=atol, t_eval=te,
              max_steps=max_steps)
    _check(s, f"over {skip + n} drive periods (t up to {t_end:.6g})")
    return np.ascontiguousarray(s.y.T)


def _section_end(te, period):
    """The end of a section run, half a period after its last point; a span that
    float64 cannot step through is refused."""
    t_end = te[-1] + 0.5 * period
    if not np.isfinite(t_end) or np.any(np.diff(te) <= 0.0):
        raise ValueError(f"the section times t0 + period * (skip + k) are not distinct in "
                         f"float64 (up to {te[-1]:.3g}): lower skip or n, or shift t0")
    return float(t_end)


def _check(s, what=""):
    if s.status < 0:
        if "max_steps" in s.message:
            raise StepBudgetError(f"the integration{' ' + what if what else ''} needs more "
                                  "steps than its budget: "
                                  f"{s.message} Raise max_steps or shorten the span.")
        raise ConvergenceError(f"integration failed: {s.message}")


def bifurcation(scene, param: str, values, y0, period, n: int, skip: int, *, t0: float = 0.0,
                rtol: float = 1e-10, atol: float = 1e-12, max_steps: int = SECTION_MAX_STEPS):
    r"""Bifurcation diagram: Poincaré points of ``scene`` as ``param`` varies.

    For each value v the scene ``scene.replace(param=v)`` is integrated from
    ``y0`` and its stroboscopic section is taken as in :func:`poincare`.

    Parameters
    ----------
    scene : Scene
        E.g. ``Pendulum(damping=0.5, drive_amplitude=1.2, drive_frequency=2/3)``.
    param : str
        Name of the parameter varied (e.g. ``"drive_amplitude"``).
    values : array_like, shape (m,)
    y0 : array_like, shape (dim,)
    period : float or callable
        Drive period T; a callable ``period(v)`` when it depends on the value.
    n, skip : int
        Section points kept per value, and drive periods discarded first
        (``len(values) * n`` at most :data:`MAX_SECTION_POINTS`).
    max_steps : int
        Step budget of each value's integration (default 10^6); exhausting it
        raises :class:`mechpy.StepBudgetError` naming the value.  Ctrl-C
        raises ``KeyboardInterrupt``.

    Returns
    -------
    ndarray, shape (m, n, dim)
        Section points per value.

    Examples
    --------
    For the linear oscillator of :func:`poincare` the section point grows in
    proportion to the drive (no bifurcation):

    >>> osc = mp.scenes.Duffing(1.0, 0.0, delta=0.5, omega=2.0)
    >>> pts = mp.phase.bifurcation(osc, "gamma", [0.3, 0.6], [0.0, 0.0], np.pi, 1, 60)
    >>> pts.shape
    (2, 1, 2)
    >>> np.round(pts[:, 0, :], 9)
    array([[-0.09,  0.06],
           [-0.18,  0.12]])
    """
    if not _is_scene(scene):
        raise TypeError("bifurcation needs a scene (its parameters are varied)")
    if param not in scene.params:
        raise ValueError(f"{param!r} is not a parameter of {type(scene).__name__}: "
                         f"{list(scene.params)}")
    vals = as_array(values, "values", ndim=1)
    y0 = as_array(y0, "y0", shape=(scene.dim,))
    n = as_int(n, "n", minimum=1, maximum=MAX_SECTION_POINTS)
    skip = as_int(skip, "skip", minimum=0)
    if vals.size * n > MAX_SECTION_POINTS:
        raise ValueError(f"bifurcation: {vals.size} values x n = {n} section points exceed "
                         f"the budget MAX_SECTION_POINTS = {MAX_SECTION_POINTS}")
    out = np.empty((vals.size, n, scene.dim))
    if not callable(period):
        # one drive period for every value: the whole diagram is one C ensemble
        T = as_scalar(period, "period", positive=True)
        te = _section_times(t0, T, n, skip)
        t_end = _section_end(te, T)
        e = solve_many(scene, (t0, t_end), np.tile(y0, (vals.size, 1)),
                       params={param: vals}, t_eval=te, rtol=rtol, atol=atol,
                       max_steps=max_steps, errors="status")
        if not np.all(e.success):
            bad = int(np.flatnonzero(~e.success)[0])
            if int(e.status[bad]) == -2:
                raise NonFiniteError(f"bifurcation: the integration for {param} = "
                                     f"{float(vals[bad])!r} produced NaN or inf")
            raise StepBudgetError(
                f"bifurcation: the integration for {param} = {float(vals[bad])!r} over "
                f"{skip + n} drive periods (t up to {t_end:.6g}) ran out of its step budget "
                f"max_steps = {max_steps} (or its step fell below round-off); raise max_steps "
                "or take fewer periods")
        return np.ascontiguousarray(e.y.transpose(0, 2, 1))
    for i, v in enumerate(vals):
        T = as_scalar(period(v) if callable(period) else period, "period", positive=True)
        te = _section_times(t0, T, n, skip)
        sc = scene.replace(**{param: float(v)})
        (s,) = _ensemble(sc, [y0], (t0, _section_end(te, T)), te, rtol=rtol, atol=atol,
                         max_steps=max_steps)
        _check(s, f"for {param} = {float(v)!r}")
        out[i] = s.y.T
    return out


# ---- Lyapunov exponent -------------------------------------------------------------
def lyapunov(system, y0, t, *, dt: float = 1.0, method: str = "variational", d0: float = 1e-8,
             transient: float = 0.0, rtol: float = 1e-10, return_history: bool = False):
    r"""The largest Lyapunov exponent along the trajectory from ``y0``.

    .. math:: \lambda = \lim_{t\to\infty}\frac1t\ln\frac{|\delta\mathbf y(t)|}{|\delta\mathbf y(0)|}

    ``method="variational"`` integrates the tangent equations
    :math:`\dot{\delta} = J(t, \mathbf y)\,\delta` beside the state, as a
    unit direction u and its log-norm,
    :math:`\dot u = Ju - (u\cdot Ju)\,u,\ \dot\rho = u\cdot Ju`, so that
    any exponent, however negative, is resolved to the integration tolerance
    (a decaying tangent vector never reaches ``atol``).
    ``method="neighbours"`` follows a neighbour at distance ``d0``; when that
    separation shrinks to the trajectories' own integration error (about
    ``rtol |y|``) the exponent is not resolved, and a
    :class:`LyapunovFloorWarning` says so with the floor's value.  Either way
    the separation is renormalised every ``dt`` and the logarithms of the
    growth factors are summed (Benettin's method).

    Parameters
    ----------
    system : Scene or callable f(t, y)
    y0 : array_like, shape (dim,)
    t : float
        Averaging time (after ``transient``).
    dt : float
        Renormalisation interval.
    return_history : bool
        Also return the times and the running estimate (its convergence).

    Returns
    -------
    float
        The exponent (1/time units); with ``return_history``,
        ``(lam, times, running)``.

    Examples
    --------
    Along y' = c y neighbouring solutions separate (or approach) as exp(c t): the
    exponent is c.

    >>> round(mp.phase.lyapunov(lambda t, y: 0.3 * y, [1.0], 20.0), 8)
    0.3
    >>> round(mp.phase.lyapunov(lambda t, y: -0.5 * y, [1.0], 20.0), 8)
    -0.5
    """
    f = _callable(system)
    y = as_array(y0, "y0", ndim=1).copy()
    T = as_scalar(t, "t", positive=True)
    dt = as_scalar(dt, "dt", positive=True)
    d0 = as_scalar(d0, "d0", positive=True)
    transient = as_scalar(transient, "transient", nonnegative=True)
    if method not in ("variational", "neighbours"):
        raise ValueError("method must be 'variational' or 'neighbours'")
    t0 = 0.0
    if transient > 0:
        s = solve(system, (0.0, transient), y, rtol=rtol, atol=rtol * 1e-2)
        _check(s)
        y, t0 = s.y[:, -1], transient
    nd = y.size
    rng = np.random.default_rng(12345)
    d = rng.normal(size=nd)
    d /= np.linalg.norm(d)
    m = max(1, int(round(T / dt)))
    logs = np.empty(m)
    times = t0 + dt * np.arange(1, m + 1)
    if method == "variational":
        # The tangent vector is carried as a direction u and a log-norm rho,
        #   u' = J u - (u.J u / u.u) u,   rho' = u.J u / u.u,
        # so |u| stays 1 (exactly, before round-off) and rho integrates the growth
        # rate itself: no separation shrinks to the integrator's atol, whatever the
        # exponent (a plain tangent vector decaying as exp(-50 dt) hits that floor).
        def aug(tt, z):
            yy, uu = z[:nd], z[nd:2 * nd]
            Ju = _jacobian(system, tt, yy) @ uu
            r = float(uu @ Ju) / float(uu @ uu)
            return np.concatenate([np.asarray(f(tt, yy), dtype=np.float64).reshape(nd),
                                   Ju - r * uu, [r]])
        z = np.concatenate([y, d, [0.0]])
        ta = t0
        for i in range(m):
            s = solve(aug, (ta, times[i]), z, rtol=rtol, atol=rtol * 1e-2)
            _check(s)
            z = s.y[:, -1].copy()
            g = np.linalg.norm(z[nd:2 * nd])
            logs[i] = z[-1] + np.log(g)
            z[nd:2 * nd] /= g
            z[-1] = 0.0
            ta = times[i]
    else:
        ref = solve(system, (t0, times[-1]), y, rtol=rtol, atol=rtol * 1e-2, t_eval=times)
        _check(ref)
        ys = np.column_stack([y, ref.y])
        ta = t0
        floor = None
        for i in range(m):
            w = ys[:, i] + d0 * d
            (s,) = _ensemble(system, [w], (ta, times[i]), None, rtol=rtol, atol=rtol * 1e-2)
            _check(s)
            sep = s.y[:, -1] - ys[:, i + 1]
            nsep = np.linalg.norm(sep)
            # what the difference of two trajectories resolves: the absolute
            # tolerance atol = rtol / 100 (errors relative to |y| largely cancel in
            # the difference of two nearby runs) and the spacing of float64 at |y|;
            # a separation within 100x of that is noise, and the exponent read from
            # it a floor, log(100 noise / d0) / dt, not a measurement
            noise = rtol * 1e-2 + np.finfo(float).eps * np.linalg.norm(ys[:, i + 1])
            if nsep <= 100.0 * noise and floor is None:
                floor = (i, nsep)
            if nsep == 0.0:
                raise ConvergenceError(
                    "lyapunov: the neighbour merged with the reference trajectory (separation "
                    "0 in float64); use method='variational'")
            g = nsep / d0
            logs[i] = np.log(g)
            d = sep / nsep
            ta = times[i]
        if floor is not None:
            warnings.warn(LyapunovFloorWarning(
                f"lyapunov: the neighbour's separation fell to {floor[1]:.3g} at t = "
                f"{times[floor[0]]:.6g}, within 100x of what the integration resolves "
                f"(atol = rtol / 100 = {rtol * 1e-2:.1e}): the exponent is not resolved, "
                f"the value returned is set by the tolerances (a floor near "
                f"log(100 atol / d0) / dt = {np.log(100.0 * rtol * 1e-2 / d0) / dt:.3g}); use "
                "method='variational' (no floor) or a shorter dt"),
                stacklevel=2)
    running = np.cumsum(logs) / (times - t0)
    lam = float(running[-1])
    return (lam, times, running) if return_history else lam


def _logistic_args(r, x0, n, skip):
    r = as_array(r, "r")
    if not ((r >= 0) & (r <= 4)).all():
        raise ValueError("r must lie in [0, 4] (beyond 4 orbits leave [0, 1] and diverge), "
                         f"got min {float(r.min())!r}, max {float(r.max())!r}")
    x0 = as_array(x0, "x0")
    if not ((x0 >= 0) & (x0 <= 1)).all():
        raise ValueError("x0 must lie in [0, 1]")
    n = as_int(n, "n", minimum=1)
    skip = as_int(skip, "skip", minimum=0)
    try:
        r, x0 = np.broadcast_arrays(r, x0)
    except ValueError:
        raise ValueError(f"x0 of shape {x0.shape} does not broadcast against r of shape "
                         f"{r.shape}") from None
    if r.size * n > 10 ** 8:
        raise ValueError(f"r.size * n = {r.size * n} values is too many (at most 1e8)")
    return r, x0, n, skip


def logistic(r, x0=0.5, n: int = 1000, skip: int = 0) -> np.ndarray:
    r"""Orbit of the logistic map :math:`x_{k+1} = r\,x_k(1 - x_k)`.

    The course's model of period doubling and chaos (Marion & Thornton,
    section 4.7): a fixed point :math:`1 - 1/r` for 1 < r < 3, cycles of
    period 2, 4, 8, ... accumulating at :math:`r_\infty = 3.5699456...`,
    the spacing of the doublings shrinking by Feigenbaum's
    :math:`\delta = 4.669201609...`; at r = 4,
    :math:`x_k = \sin^2(2^k\theta)` with :math:`x_0 = \sin^2\theta`.

    Parameters
    ----------
    r : float or array_like (...)
        Growth parameter(s), in [0, 4]; the iteration runs on all at once.
    x0 : float or array_like, broadcast against r
        Starting value(s), in [0, 1].
    n : int
        Number of iterates returned.
    skip : int
        Iterations discarded first (the transient).

    Returns
    -------
    ndarray (..., n)
        :math:`x_{skip}, \dots, x_{skip+n-1}` for each r (``x0`` first when
        skip = 0); dimensionless.  The batch axes of r come first (the
        layout rule in :mod:`mechpy`).

    Examples
    --------
    >>> import mechpy as mp
    >>> round(float(mp.phase.logistic(2.5, 0.1, n=1, skip=200)[0]), 12)   # 1 - 1/r
    0.6
    """
    r, x, n, skip = _logistic_args(r, x0, n, skip)
    out = np.empty(r.shape + (n,))
    if r.size == 1:                       # one orbit: Python floats beat 1-element arrays
        rr, xx = float(r.flat[0]), float(x.flat[0])
        for _ in range(skip):
            xx = rr * xx * (1.0 - xx)
        flat = out.reshape(n)
        for k in range(n):
            flat[k] = xx
            xx = rr * xx * (1.0 - xx)
        return out
    x = x.copy()
    for _ in range(skip):
        x = r * x * (1.0 - x)
    for k in range(n):
        out[..., k] = x
        x = r * x * (1.0 - x)
    return out


def logistic_bifurcation(r_values, x0=0.5, n: int = 200, skip: int = 1000) -> np.ndarray:
    r"""Points of the logistic map's bifurcation (period-doubling) diagram.

    For each r the orbit from ``x0`` is iterated ``skip`` times to settle on
    its attractor, then ``n`` points of it are kept (:func:`logistic`).

    Parameters
    ----------
    r_values : array_like (k,)
        Parameters, in [0, 4].
    x0 : float
        Start, in [0, 1] (0.5 is the critical point, attracted to the stable
        cycle whenever one exists).
    n, skip : int
        Points kept per r, iterations discarded first.

    Returns
    -------
    ndarray (k, n)
        Row i is the attractor sampled at ``r_values[i]``; draw it with
        ``plt.plot(np.repeat(r_values, n), x.ravel(), ",")``.

    Examples
    --------
    >>> import numpy as np, mechpy as mp
    >>> x = mp.phase.logistic_bifurcation([3.2, 3.5], n=8)
    >>> [len(np.unique(np.round(row, 9))) for row in x]   # periods 2 and 4
    [2, 4]
    """
    r = as_array(r_values, "r_values", ndim=1)
    return logistic(r, as_scalar(x0, "x0"), n, skip)


# ---- the tangent flow: Lyapunov spectrum, Floquet multipliers ------------------------------
def lyapunov_spectrum(system, y0, t, *, dt: float = 1.0, transient: float = 0.0,
                      method: str = "dop853", rtol: float = 1e-10, atol: float = 1e-12,
                      return_history: bool = False):
    r"""All Lyapunov exponents along the trajectory from ``y0`` (Benettin's method).

    .. math:: \lambda_i = \lim_{t\to\infty}\frac1t \ln |R_{ii}|, \qquad
              \Phi(t_{j+1}, t_j)\,Q_j = Q_{j+1} R_{j+1}

    The tangent flow :math:`\dot\Phi = J(t, \mathbf y)\,\Phi` (the variational
    equations, generated from ``system.symbolic()`` and compiled with it:
    :mod:`mechpy.tangent`) carries an orthonormal frame Q over each interval ``dt``;
    a QR decomposition re-orthonormalises it, and the logarithms of R's diagonal,
    summed and divided by the elapsed time, are the running estimates.  Their sum is
    the mean divergence of f (the trace of J) along the orbit, exactly up to the
    integration error; a flow has one zero exponent (along f), a Hamiltonian system
    pairs them as +-lambda.

    Parameters
    ----------
    system : Scene or compiled system
        With a symbolic form (``system.symbolic()``); a Python callable has none
        (``TypeError``: write it with :func:`mechpy.equations`).
    y0 : array_like, shape (dim,)
    t : float
        Averaging time (after ``transient``), in the system's time units.
    dt : float
        Re-orthonormalisation interval (the frame's columns may grow or shrink by
        exp(lambda dt) in between; keep lambda_max dt well below 709, float64's range:
        beyond it the tangent vectors overflow and the error says to shorten dt, while
        an orbit that itself fails is named as such).
    transient : float
        Time integrated first and discarded.
    method, rtol, atol
        For :func:`mechpy.solve`; the tolerances apply to the state and the frame alike.
    return_history : bool
        Also return the renormalisation times (m,) and the running estimates (m, dim)
        (row j: the exponents after times[j], in the QR order): their convergence.

    Returns
    -------
    ndarray (dim,)
        The exponents, descending (1/time units); -inf for a direction that collapses in
        finite time (a switch of the field that pins a component, as
        :class:`mechpy.scenes.Rocket`'s burn-out pins its mass); with ``return_history``,
        ``(spectrum, times, running)``.

    Examples
    --------
    >>> import numpy as np
    >>> import mechpy as mp
    >>> lam = mp.phase.lyapunov_spectrum(mp.scenes.Duffing(alpha=-1.0, beta=1.0,
    ...                                  delta=0.3), [1.0, 0.0], 50.0)
    >>> bool(np.isclose(lam.sum(), -0.3, atol=1e-8))
    True
    """
    return _spectrum(system, y0, t, dt=dt, transient=transient, method=method, rtol=rtol,
                     atol=atol, return_history=return_history)


def floquet(system, y0, *, period=None, tol: float = 1e-10, max_iter: int = 50,
            method: str = "dop853", rtol: float = 1e-11, atol: float = 1e-12,
            t_max: float = 1e4):
    r"""Period and Floquet multipliers of the periodic orbit through (near) ``y0``.

    The orbit is found by shooting: Newton's method on
    :math:`\varphi_T(\mathbf y_0) - \mathbf y_0 = 0` with the exact monodromy matrix
    :math:`M = \partial\varphi_T/\partial\mathbf y_0` from the tangent flow
    (:mod:`mechpy.tangent`).  For an autonomous system the unknowns are
    (y0, T), closed by the phase condition
    :math:`\mathbf f(\mathbf y_0^{(k)})\cdot(\mathbf y_0 - \mathbf y_0^{(k)}) = 0`
    (the correction is normal to the flow), and the first guess of T is the first
    return of the orbit from y0 to the plane through y0 normal to f(y0) (a given
    ``period`` bounds that search to four of it, and is the guess when there is no
    return).  The period returned is the minimal one: a Newton solution at k periods
    is replaced by the orbit's first return, and one whose first return does not
    divide it is a ConvergenceError.  For a forced system (f depends on t) the period
    must be given and is checked (f(t + T, y) = f(t, y) at a few points; a T that is no
    period of the forcing is a ValueError): the unknowns are y0 at t = 0, T is fixed.  The multipliers are M's eigenvalues; an
    autonomous orbit has one equal to 1 (along f), and their product is
    :math:`\exp\int_0^T \nabla\cdot\mathbf f\,dt` (Liouville).  On a family of orbits
    (a conservative system's) the shooting is underdetermined and Newton's least-squares
    step stays on the family; the two multipliers at 1 then form a Jordan block, which the
    integration error splits by about its square root (1 +- 2e-6 for the pendulum at the
    default tolerances).  Newton ending on a fixed point is a ConvergenceError.

    Parameters
    ----------
    system : Scene or compiled system
        With a symbolic form (``system.symbolic()``).
    y0 : array_like, shape (dim,)
        A state on or near the orbit (after a transient for an attracting cycle).
    period : float, optional
        The period: required for a forced system (the forcing's period or a multiple),
        a guess for an autonomous one (any from about half a period to a few periods
        gives the minimal period).
    tol : float
        Newton stops when ``|phi_T(y0) - y0| <= tol (1 + |y0|)``.
    max_iter : int
        Newton iterations before :class:`mechpy.ConvergenceError`.
    method, rtol, atol
        For :func:`mechpy.solve` of the augmented system.
    t_max : float
        Longest integration when looking for the first return.

    Returns
    -------
    period : float
        In the system's time units.
    multipliers : ndarray (dim,), complex
        The monodromy matrix's eigenvalues, by decreasing modulus.

    Raises
    ------
    ValueError
        A forced system without ``period``, or with one that is not a period of the
        forcing; ``y0`` a fixed point.
    ConvergenceError
        No return to the section, Newton's shooting did not converge (or closed the
        orbit at a time its first return does not divide).

    Examples
    --------
    >>> import mechpy as mp
    >>> T, mu = mp.phase.floquet(mp.scenes.VanDerPol(1.0), [2.0, 0.0])
    >>> round(T, 6)
    6.663287
    """
    return _floquet(system, y0, period=period, tol=tol, max_iter=max_iter, method=method,
                    rtol=rtol, atol=atol, t_max=t_max)


__all__ += ["lyapunov_spectrum", "floquet"]
