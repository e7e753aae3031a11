"""Initial value problems: ``mp.solve`` and the method table ``mp.methods()``.

The integrators run in C (``csrc/ode``).  A system is a scene (its right-hand
side runs in C), a Python callable with SciPy's signature ``f(t, y, *args)``,
or a low-level C callback ``void f(double t, const double *y, double *dydt,
void *user_data)`` given as a ctypes function pointer, a
``scipy.LowLevelCallable`` or a numba ``cfunc``.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
states first, as SciPy's: ``Solution.y`` (n, m), ``EnsembleSolution.y`` (k, n, m).
"""
from __future__ import annotations

import contextlib
import math
import os
import warnings
from typing import Callable, Sequence

import numpy as np

from . import _core
from . import cluster as _cluster
from ._solution import (_STATUS, DenseOutput, EnsembleSolution, Solution,  # noqa: F401
                        _ConstantDense, _errors_mode, _MappedDense, _raise_first, _raises,
                        _status_error)
from ._system import (SCIPY_METHODS, SecondOrder, _as_args, _catch_unraisable,  # noqa: F401
                      _ensemble_params, _events_spec, _method_names, _python_fun,
                      _rigid_split_check, _system_spec, _watch_list, methods)
from ._validate import as_args, as_array, as_int, as_scalar, band_of_pattern

__all__ = ["solve", "solve_many", "methods", "Solution", "EnsembleSolution", "DenseOutput",
           "SecondOrder"]


def _common(method, t_span, rtol, atol, n, h, first_step, max_step, max_steps,
            scalar_atol=False, zero_span=False, infinite_tf=False):
    """Validate the arguments solve and solve_many share.

    atol comes back as n values, or with ``scalar_atol`` a scalar as a float
    (the C core of ``solve`` spreads it over the n states).  ``zero_span``:
    t0 == tf is allowed (solve returns y0, as SciPy); ``infinite_tf``: tf may
    be infinite for an adaptive method (solve, as SciPy)."""
    if not isinstance(method, str):
        raise TypeError(f"method must be a string, got {type(method).__name__}")
    names = _method_names()
    method = SCIPY_METHODS.get(method, method)
    if method not in names:
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(names)} "
                         f"or SciPy's {sorted(SCIPY_METHODS)}")
    info = names[method]
    if type(t_span) is not tuple and (isinstance(t_span, (str, bytes)) or
                                      not hasattr(t_span, "__len__")) or len(t_span) != 2:
        raise ValueError("t_span must be a pair (t0, tf)")
    t0 = as_scalar(t_span[0], "t_span[0]")
    tf = as_scalar(t_span[1], "t_span[1]", finite=not infinite_tf)
    if math.isnan(tf):
        raise ValueError("t_span[1] must not be NaN")
    if math.isinf(tf) and not info["adaptive"]:
        raise ValueError(f"t_span[1] = {tf}: method {method!r} has a fixed step and needs a "
                         "finite t_span")
    if t0 == tf and not zero_span:
        raise ValueError(f"t_span must have t0 != tf, got ({t0}, {tf})")
    if tf < t0 and ((info["symplectic"] and not info["implicit"]) or info["rigid"]):
        raise ValueError(f"method {method!r} integrates forwards in time only (t0 < tf); "
                         "for a backward solve use dop853, radau, gauss4, ...")
    if type(rtol) is float or np.ndim(rtol) == 0:
        rtol = as_scalar(rtol, "rtol")
        if not rtol > 0:
            raise ValueError(f"rtol must be positive, got {rtol}")
    else:   # one per component, as SciPy's
        rtol = as_array(rtol, "rtol", shape=(n,), positive=True)
        if info["scalar_rtol"] and np.any(rtol != rtol[0]):
            raise ValueError(f"method {method!r} takes one rtol (GSL's control): give a "
                             "scalar, or use dop853, dopri5, radau, ...")
    if type(atol) is float and math.isfinite(atol) and atol >= 0:  # the common case
        atol_a = atol if scalar_atol else np.full(n, atol)
    else:
        atol_a = as_array(atol, "atol", nonnegative=True)
        if atol_a.ndim == 0 or atol_a.size == 1:
            a1 = float(atol_a.reshape(-1)[0])
            atol_a = a1 if scalar_atol else np.full(n, a1)
        elif atol_a.shape != (n,):
            raise ValueError(f"atol must be a scalar or have shape ({n},), got {atol_a.shape}")
    hh = 0.0
    if not info["adaptive"]:
        if h is None:
            raise ValueError(f"method {method!r} has a fixed step: give h")
        hh = as_scalar(h, "h", positive=True)
        tm = max(abs(t0), abs(tf))
        if tm + hh == tm:
            raise ValueError(f"h = {hh!r} is below the spacing of floats near t = {tm!r}: "
                             "t would never advance")
    elif h is not None:
        raise ValueError(f"method {method!r} is adaptive: use first_step/max_step, not h")
    fs = 0.0 if first_step is None else as_scalar(first_step, "first_step", positive=True)
    if fs > abs(tf - t0):
        raise ValueError("`first_step` exceeds bounds.")  # SciPy's message
    ms = as_scalar(max_step, "max_step", finite=False)
    if not ms > 0 or math.isnan(ms):
        raise ValueError(f"max_step must be positive, got {ms}")
    budget = as_int(max_steps, "max_steps", minimum=1)
    return method, t0, tf, rtol, atol_a, hh, fs, ms, budget


def _options(t0, tf, rtol, atol, t_eval, h, first_step, max_step, max_steps, events,
             terminal, direction, args, jac, watch, band, own: dict) -> dict:
    """The one options object of ``_core.ode_solve`` and ``ode_solve_many``,
    built here alone and parsed in one place in C (py_ode.c's ode_opt_rows,
    whose order the keys follow: it is the parse's fast path).  ``own``: the
    options one of the two calls alone takes (solve: ``dense``; solve_many:
    ``params``, ``threads``, ``progress``, ``lanes``).  Positional, as the
    call is part of a small solve's fixed cost."""
    return {"t0": t0, "tf": tf, "rtol": rtol, "atol": atol, "t_eval": t_eval, "h": h,
            "first_step": first_step, "max_step": max_step, "max_steps": max_steps,
            "events": events, "terminal": terminal, "direction": direction, "args": args,
            "jac": jac, "watch": watch, "band": band, **own}


def _t_eval(t_eval, t0, tf):
    lo, hi = min(t0, tf), max(t0, tf)
    if type(t_eval) in (list, tuple) and len(t_eval) <= 8 and \
            all(type(v) is float and v - v == 0.0 for v in t_eval):
        # a few plain finite floats (t_eval=[tf], the common case): checked
        # without NumPy's reductions, which cost more than a short solve (a NaN
        # or an inf takes the array path, whose message names it)
        for a, b in zip(t_eval, t_eval[1:]):
            if not (b > a if tf > t0 else b < a):
                raise ValueError("t_eval must be strictly increasing" if tf > t0 else
                                 "t_eval must be strictly decreasing (t_span is decreasing)")
        if not all(lo <= v <= hi for v in t_eval):
            raise ValueError("t_eval must lie within t_span")
        return np.array(t_eval)
    tev = as_array(t_eval, "t_eval", ndim=1, allow_empty=True)
    if tev.size and (tev.min() < lo or tev.max() > hi):
        raise ValueError("t_eval must lie within t_span")
    d = np.diff(tev)
    if tf > t0 and np.any(d <= 0):
        raise ValueError("t_eval must be strictly increasing")
    if tf < t0 and np.any(d >= 0):
        raise ValueError("t_eval must be strictly decreasing (t_span is decreasing)")
    return tev


def solve(system, t_span: Sequence[float], y0, method: str = "dop853", *,
          rtol: float = 1e-8, atol=1e-10, t_eval=None, dense_output: bool = False,
          events=None, args: tuple = (), h: float | None = None,
          first_step: float | None = None, max_step: float = np.inf,
          max_steps: int = 10_000_000, jac: Callable | None = None,
          jac_sparsity=None, errors: str = "auto", vectorized: bool = False) -> Solution:
    """Solve an initial value problem dy/dt = f(t, y), y(t0) = y0.

    Parameters
    ----------
    system : Scene, callable or C callback
        A scene from :mod:`mechpy.scenes` (its right-hand side runs in C), a
        Python callable ``f(t, y, *args)`` returning dy/dt (SciPy's signature),
        or a C function ``void f(double t, const double *y, double *dydt,
        void *user_data)`` as a ctypes function pointer, a
        ``scipy.LowLevelCallable`` or a numba ``cfunc``.
    t_span : (t0, tf)
        Interval of integration; ``tf < t0`` integrates backwards (as in
        SciPy: ``t``, ``t_eval`` and ``t_events`` then decrease).  The
        right-hand side is never evaluated outside the interval, except by
        ``yoshida4``/``yoshida6``, whose negative sub-steps sample it up to
        0.35 h (0.16 h) beyond a step's ends.
    y0 : array_like, shape (n,)
        Initial state; complex for a Python callable (integrated as the real
        system (Re y, Im y) of size 2n, ``y`` returned complex, as SciPy
        integrates complex states); empty gives y0's empty rows.
    method : str
        See :func:`methods`: ``"dop853"`` (default), ``"dopri5"``; stiff
        ``"radau"`` (Radau IIA, order 5, keeping its Jacobian and LU factors
        across steps as Hairer's RADAU5 does) and ``"auto"`` (dop853, switching to
        radau and back as Hairer's stiffness test decides); fixed-step ``"rk4"``
        and the geometric ``"verlet"``, ``"yoshida4"``, ``"yoshida6"``
        (symplectic, for q'' = a(t, q): an undamped scene or
        :class:`SecondOrder`) and ``"gauss4"`` (implicit, symplectic), which
        need ``h`` (``"yoshida4"`` and ``"yoshida6"`` update the state with
        compensated sums, carrying it to about twice the working precision:
        on Kepler e = 0.6 over 1000 orbits, ``yoshida6`` at h = T/400 keeps
        the energy to 9.8e-15 at the orbits' ends, 2.6e-13 with plain
        updates); GSL's steppers ``"gsl:rkf45"``, ``"gsl:rk8pd"``,
        ``"gsl:msadams"``, ``"gsl:msbdf"``, ``"gsl:bsimp"``, ...  SciPy's
        names run their nearest counterparts: ``"RK45"`` dopri5, ``"DOP853"``
        dop853, ``"Radau"`` radau, ``"BDF"`` gsl:msbdf (GSL's variable-order
        BDF), ``"LSODA"`` auto (see :data:`SCIPY_METHODS`).
    rtol, atol : float or array_like
        Relative and absolute tolerances, each a scalar or one per component
        (as SciPy's; GSL's steppers take one rtol): the local error estimate
        e of each step satisfies ``rms(e / (atol + rtol |y|)) <= 1`` (radau's
        order-3 estimate against RADAU5's transformed tolerances, rtol' =
        min(0.1 rtol^(2/3), 2 rtol) and atol' = atol rtol' / rtol).
    t_eval : array_like, optional
        Times in ``t_span``, ordered along the integration, at which to store the solution, filled
        from each step's interpolant (the steps are never forced onto them).
    dense_output : bool
        Return a continuous solution in ``sol``.
    events : callable or list of callables
        ``g(t, y, *args)``; a zero crossing is located to round-off on the
        interpolant.  Attributes ``terminal`` (bool, or the number of
        crossings after which to stop) and ``direction`` as in SciPy.  As in
        SciPy, a g exactly zero at t0 is an event at t0 when the solution
        leaves zero in its direction; a crossing landing exactly on zero at a
        step's end is reported once (SciPy: twice).  ``[]``: no event.
    args : tuple, optional
        Extra arguments for a Python ``system``, ``jac`` and events.  As in
        SciPy: None is none, any iterable is unpacked, anything else is a
        ``TypeError`` (write ``args=(p,)`` for one argument).
    h : float
        Step of fixed-step methods.
    first_step, max_step : float
        Initial step (default: Hairer's estimate; at most ``|tf - t0|``; one
        below the step floor, ``16 eps |t0|``, is raised to it, as SciPy raises
        it) and largest step.
    max_steps : int
        Budget of attempted steps; when it runs out the solve ends with
        ``status = -1``.
    jac : callable or array_like (n, n), optional
        ``jac(t, y, *args)`` -> (n, n) Jacobian, or a constant matrix, for
        methods that use one (scenes bring their own analytic Jacobian).
    jac_sparsity : array_like (n, n) or scipy.sparse matrix, optional
        SciPy's: the Jacobian's nonzero pattern (a zero entry: df_i/dy_j is
        zero everywhere).  mechpy uses its band, ml = max(i - j) and
        mu = max(j - i) over the nonzero entries: finite-difference Jacobians
        take ml + mu + 1 evaluations of f instead of n, and ``radau`` (and
        ``auto``'s stiff part) factorise their Newton matrices in band form
        where 3 (ml + mu + 1) <= n and n >= 16 (LAPACK's ``dgbtrf``).
        Entries of an analytic ``jac`` outside the band are not read then.
        Where the states' own order has too wide a band (a system written
        y = (q, v)) and SciPy is installed, the band is that of the reverse
        Cuthill-McKee order (``scipy.sparse.csgraph``), in which the Newton
        matrices are factorised.  Systems from :func:`mechpy.symbolic.equations`
        bring their own pattern, from the symbolic Jacobian.
    errors : {"auto", "raise", "status"}
        What a failure does.  ``"auto"``: the integration giving up (step
        budget, step size) ends with ``status = -1`` and a message, as
        SciPy's ``solve_ivp``; a NaN or inf, a singular state or a domain
        error raises (:class:`mechpy.NonFiniteError`, ...).  ``"raise"``:
        every failure raises (:class:`mechpy.StepBudgetError`,
        :class:`mechpy.StepSizeError` too).  ``"status"``: every failure is a
        negative ``status`` with its message.  An exception of a Python
        callback, Ctrl-C and memory exhaustion always raise.
    vectorized : bool
        SciPy's: a Python ``system`` takes y of shape (n, k) (it is called
        with one column, k = 1).

    Returns
    -------
    Solution
        ``t`` (m,), ``y`` (n, m), ``sol``, ``t_events``, ``y_events``,
        ``nfev``, ``njev``, ``nlu``, ``nsteps``, ``nreject``, ``status``,
        ``message``, ``success``.

    Notes
    -----
    Units are those of the system: t in the unit its rates are given in.
    An exception raised by a Python callable (or a ctypes callback written in
    Python) propagates with its traceback; Ctrl-C raises
    ``KeyboardInterrupt``.  A NaN or inf in a trial stage rejects the step
    (h shrinks tenfold); at an accepted state, or when no step avoids it, it
    raises ``NonFiniteError`` naming the component; a C callback's outputs
    are NaN until it writes them.  Each step's new state is checked too (it
    can overflow where f stays finite): an adaptive step is retried smaller,
    a fixed step raises, naming ``y[i]`` and the step; an error estimate that
    overflows from finite values is named as such.  Integration failures
    (budget exhausted, step below round-off) are reported in
    ``status``/``message`` as SciPy does (see ``errors``);
    ``Solution.raise_for_status()`` raises them.

    As SciPy's ``solve_ivp``: ``t0 == tf`` (or an empty y0) takes no step and
    returns y0 at ``t = [t0, tf]``; ``tf = +-inf`` runs an adaptive method
    until a terminal event (one is required); ``method="RK23"`` runs
    ``"dopri5"``.

    Examples
    --------
    A pendulum of length 1 m released from 0.01 rad: its period is the small-angle
    2 pi sqrt(L/g) to 6e-6 relative (the amplitude's correction theta0^2/16), and the
    exact one of :meth:`mechpy.scenes.Pendulum.period`.  A terminal event, theta_dot
    crossing 0 upwards, stops the solve at the opposite turning point, half a period:

    >>> pend = mp.scenes.Pendulum(g=9.81, length=1.0)
    >>> def back(t, y):
    ...     return y[1]
    >>> back.terminal, back.direction = True, 1.0
    >>> s = mp.solve(pend, (0, 10), [0.01, 0.0], rtol=1e-10, atol=1e-12, events=back)
    >>> s.status, s.message
    (1, 'A termination event occurred.')
    >>> round(2 * float(s.t_events[0][0]), 6), round(float(pend.period(0.01)), 6)
    (2.006079, 2.006079)
    >>> round(2 * np.pi * (1.0 / 9.81) ** 0.5, 6)
    2.006067

    A Python right-hand side, SciPy's signature: y' = -y gives exp(-t).

    >>> s = mp.solve(lambda t, y: -y, (0, 2), [1.0], t_eval=[0.0, 1.0, 2.0])
    >>> np.round(s.y[0], 8), np.round(np.exp(-s.t), 8)
    (array([1.        , 0.36787944, 0.13533528]), array([1.        , 0.36787944, 0.13533528]))
    """
    if not isinstance(vectorized, (bool, np.bool_)):
        raise TypeError(f"vectorized must be a bool, got {vectorized!r}")
    if vectorized and _python_fun(system):
        system = _one_column(system)
    args = as_args(args)
    y0 = _named_state(system, y0)
    if _is_complex(y0):
        return _solve_complex(system, t_span, y0, dict(
            method=method, rtol=rtol, atol=atol, t_eval=t_eval, dense_output=dense_output,
            events=events, args=args, h=h, first_step=first_step, max_step=max_step,
            max_steps=max_steps, jac=jac, jac_sparsity=jac_sparsity, errors=errors))
    # y0's values are checked finite by the C core, which reads them anyway
    y0a = as_array(y0, "y0", ndim=1, finite=False, allow_empty=True)
    n = y0a.size
    method, t0, tf, rtol, atol_a, hh, fs, ms, budget = _common(
        method, t_span, rtol, atol, n, h, first_step, max_step, max_steps, scalar_atol=True,
        zero_span=True, infinite_tf=True)
    tev = None if t_eval is None else _t_eval(t_eval, t0, tf)
    if not isinstance(dense_output, (bool, np.bool_)):
        raise TypeError("dense_output must be a bool")
    if jac is not None and not callable(jac):
        if isinstance(jac, (str, bytes)):
            raise TypeError("jac must be callable or a constant (n, n) array")
        jac = as_array(jac, "jac", shape=(n, n))
    band = _jac_band(jac_sparsity, system, n)
    _rigid_split_check(method, system)
    spec, dim = _system_spec(system, args, method)
    if dim is not None and dim != n:
        raise ValueError(f"y0 must have {dim} values for {type(system).__name__}, got {n}")
    evs, term, dirs = _events_spec(events, system, n)
    if math.isinf(tf) and n and not (term is not None and term.any()):
        raise ValueError(f"t_span = ({t0}, {tf}): an infinite t_span needs a terminal event "
                         "to end the solve (events with terminal = True)")
    errors = _errors_mode(errors)
    check = getattr(system, "_check_initial", None)   # e.g. constraints a scene imposes
    if check is not None and n:
        # a singular mass matrix at y0 is for the solve's first evaluation to
        # find (the error is then raised below by the check, naming the matrix;
        # errors="status" reports it); a solve without a step (t0 == tf)
        # evaluates nothing, so the check looks itself
        check(t0, y0a, singular=t0 == tf and errors != "status")
    if t0 == tf or n == 0:
        return _no_step(t0, tf, y0a, tev, dense_output, evs)

    watch = _watch_list(system)
    opts = _options(t0, tf, rtol, atol_a, tev, hh, fs, ms, budget, evs or None, term, dirs,
                    args, jac, watch, band, {"dense": bool(dense_output)})
    if watch is None:
        r = _core.ode_solve(method, spec, y0a, opts)
    else:
        with _catch_unraisable(watch):
            r = _core.ode_solve(method, spec, y0a, opts)
    code, message, t, y, nfev, njev, nlu, nsteps, nreject, dense, events_out, backward = r
    if code and _raises(code, errors):
        if check is not None and code == _core.STATUS["MP_ESINGULAR"]:
            check(t0, y0a)   # singular at y0 itself: the check's error, naming the matrix
        raise _status_error(code, "solve", message)
    status = _STATUS[code]["solve_status"]
    sol = None
    if dense_output and dense is not None:
        sol = DenseOutput(*dense, backward=bool(backward))
    fields = {"t_events": None, "y_events": None}
    if evs is not None:
        fields = _event_fields(events_out or ())
    out = Solution(t=t, y=y.T, sol=sol, nfev=nfev, njev=njev, nlu=nlu, nsteps=nsteps,
                   nreject=nreject, status=status, message=message, success=status >= 0,
                   **fields)
    object.__setattr__(out, "_code", code)
    return out


#: The rests of an event that never rested (shared, read-only: an ensemble has
#: one per trajectory and event).
_NO_RESTS = np.empty((0, 2))
_NO_RESTS.flags.writeable = False


def _rests(rs):
    """Alternating rest and lift-off times as (r, 2) [came to rest, lifted off],
    inf when it still rested at the end."""
    if rs is None:
        return _NO_RESTS
    if rs.size % 2:
        rs = np.append(rs, np.inf)
    return rs.reshape(-1, 2)


def _named_state(system, y0):
    """y0 as given, or a dict of values keyed by the system's state names (or the
    SymPy objects they name) as its state vector: a compiled system's
    ``initial_state`` (PyDy's habit)."""
    if not isinstance(y0, dict):
        return y0
    make = getattr(system, "initial_state", None)
    if getattr(system, "states", None) is None or make is None:
        raise TypeError("y0 as a dict needs a system with named states (mp.lagrangian, "
                        "mp.equations, mp.mechanics); give a sequence of numbers")
    return make(y0)


def _event_fields(lists) -> dict:
    """A solve's event lists (per event function: its times, its states, and
    the times its body came to rest on a wall and lifted off, alternating, or
    None) as the Solution's ``t_events``, ``y_events`` and ``rests``."""
    te, ye, rs = zip(*lists) if lists else ((), (), ())
    return {"t_events": list(te), "y_events": list(ye), "rests": [_rests(r) for r in rs]}


def _no_step(t0, tf, y0, tev, dense_output, evs) -> Solution:
    """SciPy's result of a solve that takes no step (t0 == tf) or integrates
    no state (an empty y0): y0 at t = [t0, tf] (at t_eval: none for t0 == tf,
    where no step passes them, as in SciPy), no event."""
    if not np.all(np.isfinite(y0)):
        raise ValueError("y0 must be finite")
    n = y0.size
    if n == 0 and evs:
        raise ValueError("events need a state: y0 is empty")
    t = np.array([t0, tf]) if tev is None else (tev[:0] if t0 == tf else tev)
    out = Solution(t=t, y=np.tile(y0[:, None], (1, t.size)),
                   sol=_ConstantDense(y0, t0, tf) if dense_output else None,
                   t_events=None if evs is None else [np.empty(0) for _ in evs],
                   y_events=None if evs is None else [np.empty((0, n)) for _ in evs],
                   **({} if evs is None else {"rests": [_NO_RESTS for _ in evs]}),
                   nfev=0, njev=0, nlu=0, nsteps=0, nreject=0, status=0,
                   message=_STATUS[0]["message"], success=True)
    object.__setattr__(out, "_code", 0)
    return out


def _one_column(fun):
    """SciPy's ``vectorized=True`` fun (y of shape (n, k)) called with one column."""
    def f(t, y, *args):
        return np.asarray(fun(t, y[:, None], *args)).reshape(-1)
    return f


def _is_complex(y0) -> bool:
    if type(y0) is np.ndarray:
        return y0.dtype.kind == "c"
    if isinstance(y0, (str, bytes)) or y0 is None:
        return False
    try:
        return np.iscomplexobj(y0)
    except Exception:   # as_array names what is wrong with it
        return False


def _jac_band(jac_sparsity, system, n: int):
    """The Jacobian's band for the core (``_validate.band_of_pattern``), from
    jac_sparsity (an (n, n) pattern: array_like or scipy.sparse) or, without
    one, the system's own (``_jac_band``: a compiled system's, from the zeros
    of its symbolic Jacobian); None: dense."""
    if jac_sparsity is None:
        return getattr(system, "_jac_band", None)
    if hasattr(jac_sparsity, "tocoo"):
        # scipy.sparse: its stored entries, explicit zeros too (as SciPy's
        # group_columns reads a pattern: stored means possibly nonzero)
        if tuple(jac_sparsity.shape) != (n, n):
            raise ValueError(f"jac_sparsity must have shape ({n}, {n}), "
                             f"got {tuple(jac_sparsity.shape)}")
        c = jac_sparsity.tocoo()
        rows, cols = c.row, c.col
    else:
        rows, cols = np.nonzero(as_array(jac_sparsity, "jac_sparsity", shape=(n, n)))
    return band_of_pattern(rows, cols, n)


def _solve_complex(system, t_span, y0, kw) -> Solution:
    """solve for a complex y0, as SciPy integrates complex states: the real
    system z = (Re y, Im y) of size 2n (f, jac and events see complex y), the
    results mapped back to complex y.  The error norm is over the 2n real
    components (SciPy's over |y_i|)."""
    if not _python_fun(system):
        raise TypeError("a complex y0 needs a Python callable f(t, y): scenes, SecondOrder "
                        "and C callbacks integrate real states (split y0 into its real and "
                        "imaginary parts)")
    y0c = np.asarray(y0, dtype=np.complex128)
    if y0c.ndim != 1:
        raise ValueError(f"y0 must have 1 dimension(s), got shape {y0c.shape}")
    n = y0c.size

    def cplx(z):   # states first
        return z[:n] + 1j * z[n:]

    def f(t, z, *args):
        d = np.asarray(system(t, cplx(z), *args), dtype=np.complex128).reshape(-1)
        return np.concatenate([d.real, d.imag])

    def real_jac(J):
        J = np.asarray(J, dtype=np.complex128)
        if J.shape != (n, n):
            raise ValueError(f"jac must be of shape ({n}, {n}), got {J.shape}")
        return np.block([[J.real, -J.imag], [J.imag, J.real]])

    if kw["jac_sparsity"] is not None:   # the real system's: the pattern in each block
        S = kw["jac_sparsity"]
        S = (S.toarray() if hasattr(S, "toarray") else
             as_array(S, "jac_sparsity", shape=(n, n))) != 0
        kw["jac_sparsity"] = np.block([[S, S], [S, S]])
    jac = kw["jac"]
    if callable(jac):
        user_jac = jac
        kw["jac"] = lambda t, z, *args: real_jac(user_jac(t, cplx(z), *args))
    elif jac is not None and not isinstance(jac, (str, bytes)):
        kw["jac"] = real_jac(jac)
    events = kw["events"]
    if events is not None:
        wrapped = []
        for e in ([events] if callable(events) else list(events)):
            if callable(e):
                def g(t, z, *args, e=e):
                    return e(t, cplx(z), *args)
                for attr in ("terminal", "direction"):
                    if hasattr(e, attr):
                        setattr(g, attr, getattr(e, attr))
                e = g
            wrapped.append(e)
        kw["events"] = wrapped
    atol = kw["atol"]
    if not isinstance(atol, (str, bytes)) and np.ndim(atol) == 1 and np.size(atol) == n:
        kw["atol"] = np.concatenate([np.asarray(atol), np.asarray(atol)])
    r = solve(f, t_span, np.concatenate([y0c.real, y0c.imag]), **kw)
    r["y"] = cplx(r["y"])
    if r["y_events"] is not None:
        r["y_events"] = [cplx(ye.T).T for ye in r["y_events"]]
    if r["sol"] is not None:
        r["sol"] = _MappedDense(r["sol"], cplx)
    return r


def _lanes_mode(lanes) -> int:
    """solve_many's ``lanes`` as the core takes it: -1 when possible, 0, 1."""
    if lanes is None:
        return 0 if os.environ.get("MECHPY_LANES", "").strip() == "0" else -1
    if not isinstance(lanes, (bool, np.bool_)):
        raise TypeError(f"lanes must be None, True or False, got {lanes!r}")
    return int(bool(lanes))


class _TqdmProgress:
    """A ``tqdm.auto`` bar fed by the C ensemble's (done, total) reports."""

    def __init__(self, tqdm, total: int):
        self.bar = tqdm(total=total, desc="solve_many", unit="traj")

    def report(self, done: int, total: int) -> None:
        # a broken display never costs the results: warn once, stop drawing
        if self.bar is None:
            return
        try:
            self.bar.update(done - self.bar.n)
        except Exception as exc:
            warnings.warn(f"solve_many: progress bar failed ({exc!r}); continuing without it",
                          RuntimeWarning, stacklevel=2)
            self.bar = None

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _progress_bar(k: int):
    """A tqdm progress bar for k trajectories, or None when tqdm is not installed."""
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    return _TqdmProgress(tqdm, k)


def solve_many(system, t_span: Sequence[float], y0s, *, params=None, t_eval=None,
               method: str = "dop853", rtol: float = 1e-8, atol=1e-10,
               threads: int | None = None, progress: bool = False, args: tuple = (),
               h: float | None = None, first_step: float | None = None,
               max_step: float = np.inf, max_steps: int = 10_000_000,
               errors: str = "auto", client=None, chunk_size: int | None = None,
               lazy: bool = False, lanes: bool | None = None, events=None,
               jac=None, jac_sparsity=None) -> EnsembleSolution:
    """Integrate k initial states (an ensemble) in C, on several threads.

    Parameters
    ----------
    system : Scene, callable or C callback
        As for :func:`solve`.  Scenes and C callbacks run with the GIL released
        on ``threads`` threads; a Python callable (or a ctypes callback
        written in Python) runs on one thread.
    t_span : (t0, tf)
        ``tf < t0`` integrates backwards, as in :func:`solve`.
    y0s : array_like, shape (k, n)
        Initial states.
    params : array_like (k, p) or dict, optional
        Per-trajectory parameters: for a scene, rows of its parameters in the
        order of ``scene.params`` (or a dict ``{name: (k,) array}`` overriding
        some of them); for a Python callable, extra leading arguments
        ``f(t, y, *params[i], *args)``; for a C callback, ``user_data`` points
        to row i (p doubles).
    t_eval : array_like (m,), optional
        Sample times; only these are stored.  Default: the final time only.
    threads : int, optional
        Threads to use (default: all cores).
    progress : bool
        Show progress as trajectories finish: a ``tqdm.auto`` bar when tqdm
        is installed (a widget in notebooks), else a line on stderr; with a
        ``client``, ``dask.distributed.progress`` over the chunks.
    client : dask.distributed.Client, optional
        Run the ensemble on a Dask cluster (:mod:`mechpy.cluster`): it is
        cut into chunks of ``chunk_size`` consecutive trajectories (default:
        4 chunks per worker thread), each solved in C on a worker with
        ``threads`` threads (default 1), and joined in order; the result
        equals a local run bit for bit.  A worker lost mid-run costs only its
        chunks, which Dask runs again elsewhere.  A C callback cannot travel
        (``TypeError``); a Python callable travels if cloudpickle serialises
        it.
    chunk_size : int, optional
        Trajectories per chunk (with ``client``).
    lazy : bool
        With ``client``: return at once, the per-trajectory fields (``y``
        (k, n, m), ``status``, ...) as ``dask.array`` arrays built from
        delayed chunk solves, to reduce or store (``.to_zarr``) on the
        cluster without gathering them.
    lanes : bool, optional
        Run the trajectories in SIMD lanes: four at a time in lock-step
        through one vectorised step (AVX2+FMA where the processor has them),
        each lane with its own step size, error control, step budget, output
        and status.  ``None`` (default): in lanes whenever possible (a scene
        or compiled scene, method ``"dopri5"``, ``"dop853"`` or ``"rk4"``),
        unless the environment variable ``MECHPY_LANES`` is ``0``; ``True``:
        in lanes or ``ValueError``; ``False``: one scalar solve per trajectory.
        ``EnsembleSolution.lanes`` says which ran.
    events : callable or list of callables, optional
        As for :func:`solve` (SciPy's ``terminal`` and ``direction``), each
        called as ``g(t, y, *args)`` (with a Python system's row of
        ``params`` before ``args``, as the system is); per trajectory, the
        crossings come back in ``t_events[i]`` and ``y_events[i]``.  Event
        functions written in Python run on one thread, on the scalar path.
    jac : callable or array_like (n, n), optional
        As for :func:`solve`: the Jacobian for the implicit methods, called as
        the system is (a constant matrix runs in C on every thread).
    jac_sparsity : array_like (n, n) or scipy.sparse matrix, optional
        As for :func:`solve`: the Jacobian's pattern, whose band serves the
        finite differences and ``radau``'s band LU of every trajectory.
    errors : {"auto", "raise", "status"}
        As for :func:`solve`, per trajectory: ``"auto"`` reports the step
        budget and step size in ``status`` and raises the first trajectory
        (by index) whose failure raises in :func:`solve` (a NaN or inf, a
        singular state), naming it; ``"raise"`` raises the first failed
        trajectory's exception; ``"status"`` reports every failure (a sweep
        across singular states keeps its other trajectories).

    Returns
    -------
    EnsembleSolution
        ``t`` (m,), ``y`` (k, n, m), ``success`` (k,), ``status`` (k,),
        ``message`` (k str), ``nfev`` (k,), ``lanes`` (bool); with
        ``events``, ``t_events`` and ``y_events``: per trajectory, a list of
        one array per event function (as :func:`solve` gives them).

    Notes
    -----
    Each trajectory is an ordinary solve with the same method and tolerances
    as :func:`solve`.  On the scalar path (``lanes=False``) its samples equal
    ``solve(...).y`` exactly; in lanes each lane runs the scalar driver's
    logic, but its right-hand side (fused multiply-adds, vector
    ``sin``/``cos``) rounds differently: each evaluation agrees with the
    scalar one to round-off (7e-16 of its largest component measured; about
    40% of the double pendulum's components differ in their last bits), and
    that difference is amplified by the flow.  On a regular trajectory the samples agree to
    about 1e-12 relative and ``status``, ``message`` and ``nfev`` agree; on a
    chaotic one the two are different round-off realisations of the same
    solve, equally accurate (the same energy error) but separating at the
    flow's Lyapunov rate: a double pendulum from large angles agrees to 4e-12
    at t = 1 and is O(1) apart at t = 20, and an accept/reject decision
    taken differently changes ``nfev`` (within 7% on 333 such rows; measured
    in tests/test_lanes.py).  ``lanes=False`` gives ``solve``'s bits.  A
    trajectory's result does
    not depend on its neighbours, the thread count or chunking.  The inputs
    pickle (scenes, arrays), so a sweep can be split across processes or a
    dask cluster, each worker calling ``solve_many`` on its share: pass
    ``client=`` for that.

    Examples
    --------
    Four harmonic oscillators (a linear pendulum stands in: the Duffing scene with
    beta = 0) started at x0 = 1, 2, 3, 4: after a quarter period x = 0 and
    v = -omega x0.

    >>> osc = mp.scenes.Duffing(alpha=4.0, beta=0.0)          # omega = 2
    >>> y0s = [[x0, 0.0] for x0 in (1.0, 2.0, 3.0, 4.0)]
    >>> e = mp.solve_many(osc, (0, np.pi / 4), y0s, rtol=1e-10, atol=1e-12)
    >>> e.y.shape                                              # (k, n, m): the final time only
    (4, 2, 1)
    >>> np.round(e.y[:, :, -1], 8) + 0.0
    array([[ 0., -2.],
           [ 0., -4.],
           [ 0., -6.],
           [ 0., -8.]])

    Per-trajectory parameters: pendulums of lengths 1 and 4 m over a small-angle
    period of the first, 2 pi sqrt(L/g); the second is then half-way.

    >>> T = 2 * np.pi * (1.0 / 9.81) ** 0.5
    >>> e = mp.solve_many(mp.scenes.Pendulum(), (0, T), [[1e-4, 0.0]] * 2,
    ...                   params={"length": [1.0, 4.0]}, rtol=1e-10, atol=1e-14)
    >>> np.round(e.y[:, 0, -1] / 1e-4, 6)
    array([ 1., -1.])
    """
    if client is not None or chunk_size is not None or lazy:
        given = dict(locals())              # every argument, new ones too
        return _cluster._solve_many(local=solve_many, **given)   # dask is imported there
    if isinstance(y0s, (list, tuple)) and any(isinstance(r, dict) for r in y0s):
        y0s = [_named_state(system, r) for r in y0s]
    Y0 = as_array(y0s, "y0s", ndim=2, allow_empty=True)
    k, n = Y0.shape
    if n == 0:
        raise ValueError("y0s must have at least one state component")
    method, t0, tf, rtol, atol_a, hh, fs, ms, budget = _common(
        method, t_span, rtol, atol, n, h, first_step, max_step, max_steps)
    tev = np.array([tf]) if t_eval is None else _t_eval(t_eval, t0, tf)
    args = as_args(args)
    _rigid_split_check(method, system)
    spec, dim = _system_spec(system, args, method)
    if dim is not None and dim != n:
        raise ValueError(f"y0s must have {dim} columns for {type(system).__name__}, got {n}")
    par = _ensemble_params(system, params, k)
    evs, term, dirs = _events_spec(events, system, n, k)
    if jac is not None and not callable(jac):
        if isinstance(jac, (str, bytes)):
            raise TypeError("jac must be callable or a constant (n, n) array")
        jac = as_array(jac, "jac", shape=(n, n))
    band = _jac_band(jac_sparsity, system, n)
    errors = _errors_mode(errors)
    check = getattr(system, "_check_initial", None)   # e.g. constraints a scene imposes
    if check is not None and k:   # singular rows: statuses under errors="status"
        check(t0, Y0, params=par, singular=errors != "status")
    if threads is None:
        nthreads = os.cpu_count() or 1
    else:
        nthreads = as_int(threads, "threads", minimum=1)
    if not isinstance(progress, (bool, np.bool_)):
        raise TypeError("progress must be a bool")
    want_lanes = _lanes_mode(lanes)
    watch = _watch_list(system)
    bar = _progress_bar(k) if progress else None
    opts = _options(t0, tf, rtol, atol_a, tev, hh, fs, ms, budget, evs or None, term, dirs,
                    args, jac, watch, band,
                    {"params": par, "threads": int(nthreads),
                     "progress": bool(progress) if bar is None else bar.report,
                     "lanes": want_lanes})
    try:
        with _catch_unraisable(watch) if watch is not None else contextlib.nullcontext():
            r = _core.ode_solve_many(method, spec, Y0, opts)
        if bar is not None:
            bar.report(k, k)    # the C side reports from one thread: it may miss the last
    finally:
        if bar is not None:
            bar.close()
    _raise_first(r["code"], r["message"], errors)
    status = np.array([_STATUS[c]["solve_status"] for c in r["code"].tolist()], dtype=int)
    fields = {}
    if evs is not None:
        found = [_event_fields(row) for row in (r["events"] or [[] for _ in range(k)])]
        fields = {key: [f[key] for f in found] for key in ("t_events", "y_events", "rests")}
    out = EnsembleSolution(t=tev, y=r["y"], success=status >= 0, status=status,
                           message=r["message"], nfev=r["nfev"], lanes=r["lanes"], **fields)
    object.__setattr__(out, "_code", r["code"])
    return out
