"""What a solve returns: ``Solution``, ``EnsembleSolution``, dense output, and
the status table's rules for what raises.

This module sits below everything that solves (``mechpy.integrate``, the
scenes' own solves, ``mechpy.cluster``, ``mechpy.tangent``): it imports no
other mechpy module but the extension, so that each of those imports it at
load time, one way.
"""
from __future__ import annotations

import numpy as np

from . import _core

#: The status table of the C core (``mechpy._core.STATUS_TABLE``): per C status
#: code its exception class, message, Solution status and whether it raises.
_STATUS = {row["code"]: row for row in _core.STATUS_TABLE}


_ERRORS = ("auto", "raise", "status")


def _errors_mode(errors) -> str:
    if not isinstance(errors, str) or errors not in _ERRORS:
        raise ValueError(f"errors must be one of {_ERRORS}, got {errors!r}")
    return errors


def _raises(code: int, errors: str) -> bool:
    """Whether the outcome ``code`` raises under ``errors`` (the table decides
    for "auto"; a failure that cannot be a status always raises)."""
    row = _STATUS[code]
    if row["solve_status"] >= 0:
        return False
    return errors == "raise" or row["raises"] == 2 or (errors == "auto" and row["raises"] == 1)


def _status_error(code: int, where: str, message: str) -> Exception:
    """The exception of the outcome ``code``: its class from the table."""
    return _STATUS[code]["exception"](f"{where}: {message}")


class Solution(dict):
    """Result of :func:`solve`, shaped like SciPy's ``OdeResult``.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Time points.
    y : ndarray, shape (n, m)
        Values of the solution at ``t``.
    sol : DenseOutput or None
        Continuous solution when ``dense_output=True``.
    t_events, y_events : list of ndarray or None
        For each event function, the times and states at which it crossed zero
        (for an :func:`mechpy.events.impact`: its impacts, the point where
        they accumulate and the body comes to rest on the wall, and each
        lift-off from it).
    rests : list of ndarray, shape (r, 2)
        With events: for each event function, the intervals [t_on, t_off] in
        which its body rested on the wall (an impact's); t_off is inf when it
        still rested at the end; (0, 2) for an event that never rested.
    nfev, njev, nlu, nsteps, nreject : int
        Right-hand side evaluations, Jacobian evaluations, LU decompositions,
        accepted and rejected steps.
    status : int
        0 end reached, 1 terminal event, negative a failure: -1 the step
        budget ran out or the step fell below round-off (SciPy's -1), and with
        ``errors="status"`` the other kinds (-2 a NaN or inf, -3 a singular
        state, ...; the table in :mod:`mechpy.errors`).
    message : str
        What happened, and for a failure where (t, the component).
    success : bool
        ``status >= 0``.

    Methods
    -------
    raise_for_status()
        Raise the failure's exception (:class:`mechpy.StepBudgetError`,
        :class:`mechpy.StepSizeError`, ...); nothing when ``success``.

    Examples
    --------
    >>> s = mp.solve(lambda t, y: -2.0 * y, (0, 1), [3.0], t_eval=[0.5, 1.0])
    >>> s.success, s.status, s.y.shape
    (True, 0, (1, 2))
    >>> np.round(s.y[0], 7), np.round(3.0 * np.exp(-2.0 * s.t), 7)    # y = 3 exp(-2t)
    (array([1.1036383, 0.4060059]), array([1.1036383, 0.4060058]))
    >>> s.raise_for_status() is None
    True

    A step budget too small is a status, not an exception (``errors="auto"``), until
    asked for:

    >>> s = mp.solve(mp.scenes.VanDerPol(1.0), (0, 1000), [2.0, 0.0], max_steps=10)
    >>> s.status, s.success
    (-1, False)
    >>> try:
    ...     s.raise_for_status()
    ... except mp.StepBudgetError:
    ...     print("StepBudgetError")
    StepBudgetError
    """

    def raise_for_status(self) -> None:
        """Raise the exception of a failed solve; return None when it succeeded.

        Raises
        ------
        mechpy.MechpyError
            The class the status table gives the failure (for ``status = -1``
            :class:`mechpy.StepBudgetError` or :class:`mechpy.StepSizeError`),
            with the solve's message.
        """
        code = self.__dict__.get("_code", 0)
        if _STATUS[code]["solve_status"] < 0:
            raise _status_error(code, "solve", self["message"])

    def __getattr__(self, name):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(name) from None

    __setattr__ = dict.__setitem__

    def __repr__(self):
        keys = ["message", "success", "status", "t", "y", "sol", "t_events", "y_events", "nfev",
                "njev", "nlu", "nsteps", "nreject"]
        w = max(map(len, keys))
        lines = []
        for k in keys:
            v = self.get(k)
            s = repr(v) if not isinstance(v, np.ndarray) or v.size < 8 else \
                f"array of shape {v.shape}"
            lines.append(f"{k.rjust(w)}: {s}")
        return "\n".join(lines)

    def __dir__(self):
        return list(self.keys())


class DenseOutput:
    """Continuous solution: ``sol(t)`` gives y at any t in ``[t_min, t_max]``.

    Like SciPy's ``OdeSolution``: a scalar t gives shape (n,), an array of
    times shape (n, len(t)), times of any shape (...) shape (n, ...).  Each
    step's interpolant is the method's own (4th order for dopri5, 7th for
    dop853, cubic Hermite otherwise); it is evaluated in C.

    Examples
    --------
    >>> s = mp.solve(lambda t, y: [y[1], -y[0]], (0, 2 * np.pi), [0.0, 1.0], dense_output=True,
    ...              rtol=1e-10, atol=1e-12)
    >>> t = np.array([0.3, 1.7, 4.0])
    >>> np.round(s.sol(t)[0], 8), np.round(np.sin(t), 8)            # y = (sin t, cos t)
    (array([ 0.29552021,  0.99166481, -0.7568025 ]), array([ 0.29552021,  0.99166481, -0.7568025 ]))
    >>> s.sol(1.0).shape, s.sol(np.ones((2, 5))).shape
    ((2,), (2, 2, 5))
    """

    def __init__(self, seg_t, seg_h, seg_c, backward=False):
        # a backward solve keeps its segments in s = -t
        self._seg = (np.ascontiguousarray(seg_t), np.ascontiguousarray(seg_h),
                     np.ascontiguousarray(seg_c))
        self._sign = -1.0 if backward else 1.0
        ends = (self._sign * float(seg_t[0]), self._sign * float(seg_t[-1] + seg_h[-1]))
        self.t_min, self.t_max = min(ends), max(ends)
        self.n_segments = len(seg_t)

    def __call__(self, t):
        t = np.asarray(t, dtype=np.float64)
        scalar = t.ndim == 0
        tq = np.ascontiguousarray(t.reshape(-1) * self._sign)
        if not np.all(np.isfinite(tq)):
            raise ValueError("t must be finite")
        out = _core.ode_dense_eval(*self._seg, tq)
        return out[0] if scalar else out.T.reshape(out.shape[1:] + t.shape)

    def __repr__(self):
        return f"DenseOutput(t_min={self.t_min}, t_max={self.t_max}, segments={self.n_segments})"


class _ConstantDense(DenseOutput):
    """The continuous solution of a solve that takes no step (t0 == tf, or an
    empty y0): y0 at every t, shaped as :class:`DenseOutput`'s values."""

    def __init__(self, y0, t0, tf):
        self._y = np.array(y0)
        self.t_min, self.t_max = min(t0, tf), max(t0, tf)
        self.n_segments = 1

    def __call__(self, t):
        t = np.asarray(t, dtype=np.float64)
        if not np.all(np.isfinite(t)):
            raise ValueError("t must be finite")
        y = self._y.reshape(self._y.shape + (1,) * t.ndim)
        return np.array(np.broadcast_to(y, self._y.shape + t.shape))


class _MappedDense(DenseOutput):
    """A DenseOutput whose values (states first) go through ``fn``: a complex
    solve's (Re y, Im y) back to y."""

    def __init__(self, inner, fn):
        self._inner, self._fn = inner, fn
        self.t_min, self.t_max = inner.t_min, inner.t_max
        self.n_segments = inner.n_segments

    def __call__(self, t):
        return self._fn(self._inner(t))


class _JoinedDense(DenseOutput):
    """Dense outputs of consecutive pieces of one solve (a switch or a restart
    between them), joined in time: t in a piece's span is that piece's, a
    time shared by two pieces the one's that starts there (forwards: the
    state after the switch)."""

    def __init__(self, parts):
        self._parts = list(parts)
        self.t_min = min(q.t_min for q in self._parts)
        self.t_max = max(q.t_max for q in self._parts)
        self.n_segments = sum(q.n_segments for q in self._parts)
        # the pieces' starts in the order of time; a backward solve's last
        # piece starts earliest
        mins = np.array([q.t_min for q in self._parts])
        self._order = np.argsort(mins, kind="stable")
        self._starts = mins[self._order]

    def __call__(self, t):
        t = np.asarray(t, dtype=np.float64)
        if not np.all(np.isfinite(t)):
            raise ValueError("t must be finite")
        flat = t.reshape(-1)
        k = np.clip(np.searchsorted(self._starts, flat, side="right") - 1, 0,
                    len(self._parts) - 1)
        out = None
        for j in np.unique(k):
            sel = k == j
            v = self._parts[self._order[j]](flat[sel])
            if out is None:
                out = np.empty((v.shape[0], flat.size))
            out[:, sel] = v
        if out is None:     # no time asked
            out = np.empty((np.asarray(self._parts[0](self._parts[0].t_min)).shape[0], 0))
        return out[:, 0] if t.ndim == 0 else out.reshape(out.shape[:1] + t.shape)


class EnsembleSolution(Solution):
    """Result of :func:`solve_many`: ``t`` (m,), ``y`` (k, n, m), ``success``
    (k,), ``status`` (k,), ``message`` (a list of k str), ``nfev`` (k,),
    ``lanes`` (bool: the trajectories ran in SIMD lanes).

    ``status[i]`` is what :func:`solve` reports for trajectory i: 0 end
    reached, -1 step budget or step size, and with ``errors="status"`` the
    other failures' numbers (-2 a NaN or inf, -3 a singular state, ...; the
    table in :mod:`mechpy.errors`); ``message[i]`` says what happened where.
    ``raise_for_status()`` raises the first failed trajectory's exception,
    naming its index.

    Examples
    --------
    Exponential decays y' = -c y with c = 1, 2, 3 (Python callable: c is the
    per-trajectory parameter, the leading argument):

    >>> e = mp.solve_many(lambda t, y, c: -c * y, (0, 1), [[1.0]] * 3, params=[[1.0], [2.0], [3.0]])
    >>> e.success, e.status
    (array([ True,  True,  True]), array([0, 0, 0]))
    >>> np.round(e.y[:, 0, -1], 8), np.round(np.exp(-np.array([1.0, 2.0, 3.0])), 8)
    (array([0.36787944, 0.13533528, 0.04978707]), array([0.36787944, 0.13533528, 0.04978707]))
    """

    def raise_for_status(self) -> None:
        """Raise the exception of the first failed trajectory (by index), naming
        it; return None when every trajectory succeeded.

        Raises
        ------
        mechpy.MechpyError
            The class the status table gives that trajectory's failure.
        """
        _raise_first(self.__dict__.get("_code", np.zeros(0, int)), self["message"], "raise")

    def __repr__(self):
        return (f"EnsembleSolution(k={self['y'].shape[0]}, n={self['y'].shape[1]}, "
                f"m={self['t'].size}, all success={bool(np.all(self['success']))})")


def _raise_first(codes, messages, errors: str) -> None:
    """Raise the first trajectory's failure that raises under ``errors``."""
    for i, c in enumerate(np.asarray(codes).tolist()):
        if _raises(c, errors):
            raise _status_error(c, f"solve_many: trajectory {i}", messages[i])
