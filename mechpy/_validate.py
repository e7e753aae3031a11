"""Argument validation: one helper per concern, shared by every module.

Each helper names the argument in its message and says what was expected.
Non-numeric input is a ``TypeError``; wrong shapes, non-finite values and
out-of-domain numbers are ``ValueError``.  Results are C-contiguous float64
arrays, ready to hand to the C core.
"""
from __future__ import annotations

import math
import numbers
import operator

import numpy as np

from . import _core

__all__ = ["as_array", "as_scalar", "as_int", "as_vector3", "as_symmetric", "as_square",
           "as_finite_result", "as_args"]

_INT64_MAX = 2 ** 63 - 1
#: The smallest positive normal double (sys.float_info.min): the floor of a first_step.
_DBL_MIN = 2.2250738585072014e-308


def as_array(x, name: str, *, ndim=None, shape=None, min_ndim=None, finite=True,
             positive=False, nonnegative=False, allow_empty=False) -> np.ndarray:
    """Convert *x* to a C-contiguous float64 array and check it.

    ``shape`` may contain ``None`` (any length) and ``-1`` entries are not
    used; ``ndim`` fixes the number of dimensions, ``min_ndim`` bounds it.
    """
    if type(x) is np.ndarray and x.dtype == np.float64 and x.flags.c_contiguous:
        a = x  # already what the C core takes
    else:
        if isinstance(x, (str, bytes)) or x is None:
            raise TypeError(f"{name} must be a real numeric array, got {type(x).__name__}")
        try:
            a = np.asarray(x)
        except Exception as exc:  # ragged sequences and the like
            raise ValueError(f"{name} must be a rectangular numeric array ({exc})") from None
        if a.dtype == object:
            raise TypeError(f"{name} must be a real numeric array, got objects "
                            "(a ragged or non-numeric sequence)")
        if a.dtype.kind not in "biuf":
            raise TypeError(f"{name} must be a real numeric array, got dtype {a.dtype}")
        a = np.asarray(a, dtype=np.float64, order="C")  # keeps 0-d input 0-d
    if ndim is not None and a.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} dimension(s), got shape {a.shape}")
    if min_ndim is not None and a.ndim < min_ndim:
        raise ValueError(f"{name} must have at least {min_ndim} dimension(s), got shape {a.shape}")
    if shape is not None:
        ok = a.ndim == len(shape) and all(s is None or s == d for s, d in zip(shape, a.shape))
        if not ok:
            want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
            raise ValueError(f"{name} must have shape {want}, got {a.shape}")
    if not allow_empty and a.size == 0:
        raise ValueError(f"{name} must not be empty")
    if finite and not (all(map(math.isfinite, a.flat)) if a.size <= 16
                       else np.isfinite(a).all()):
        raise ValueError(f"{name} must be finite (it contains NaN or inf)")
    if positive and not (a > 0).all():
        raise ValueError(f"{name} must be positive")
    if nonnegative and not (a >= 0).all():
        raise ValueError(f"{name} must be non-negative")
    return a


def as_scalar(x, name: str, *, positive=False, nonnegative=False, finite=True,
              lo=None, hi=None) -> float:
    """A real number, checked (bools are refused)."""
    if type(x) is not float and type(x) is not int:  # the common cases skip the type checks
        if isinstance(x, (bool, np.bool_)) or not isinstance(x, (numbers.Real, np.ndarray)):
            raise TypeError(f"{name} must be a real number, got {type(x).__name__}")
        if isinstance(x, np.ndarray):
            if x.ndim != 0 or x.dtype.kind not in "iuf":
                raise TypeError(f"{name} must be a real scalar, got an array of shape {x.shape}")
    try:
        v = float(x)
    except OverflowError:  # a Python int beyond float64's range
        raise ValueError(f"{name} must be finite, got an integer too large for float64") from None
    if finite and not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    if positive and not v > 0:
        raise ValueError(f"{name} must be positive, got {v}")
    if name == "first_step" and 0 < v < _DBL_MIN:
        # a step below the smallest normal double: the step-size controls divide
        # by it and scale errors with it (radau's overflowed at 1e-308), as a
        # fixed step h is checked against the spacing of t's floats
        raise ValueError(f"first_step = {v!r} is below the smallest normal double "
                         f"({_DBL_MIN!r}): the step-size control cannot work with it; give "
                         "a larger first_step, or None to let the solver choose")
    if nonnegative and not v >= 0:
        raise ValueError(f"{name} must be non-negative, got {v}")
    if lo is not None and v < lo:
        raise ValueError(f"{name} must be >= {lo}, got {v}")
    if hi is not None and v > hi:
        raise ValueError(f"{name} must be <= {hi}, got {v}")
    return v


def as_int(x, name: str, *, minimum=None, maximum=None) -> int:
    """An integer (numpy integers accepted, floats and bools refused).

    Python integers beyond int64 (what the C core and NumPy index with) are a
    ``ValueError`` naming the argument, never an ``OverflowError`` from deeper
    down."""
    if type(x) is int:  # the common case skips the type checks
        v = x
    elif isinstance(x, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, got bool")
    else:
        try:
            v = operator.index(x)
        except TypeError:
            raise TypeError(f"{name} must be an integer, got {type(x).__name__}") from None
    if not -_INT64_MAX - 1 <= v <= _INT64_MAX:
        digits = len(str(abs(v)))
        raise ValueError(f"{name} is too large ({'a negative ' if v < 0 else 'a '}{digits}-digit "
                         f"integer): "
                         f"it must fit in a 64-bit integer (|{name}| < 2**63)")
    if minimum is not None and v < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {v}")
    if maximum is not None and v > maximum:
        raise ValueError(f"{name} must be <= {maximum}, got {v}")
    return v


def as_vector3(x, name: str, **kw) -> np.ndarray:
    """A 3-vector or a stack of them (..., 3)."""
    a = as_array(x, name, min_ndim=1, **kw)
    if a.shape[-1] != 3:
        raise ValueError(f"{name} must have a last axis of length 3, got shape {a.shape}")
    return a


def as_square(x, name: str, *, n=None, batch=False, **kw) -> np.ndarray:
    """A square matrix (n, n), or a stack (..., n, n) when ``batch``."""
    a = as_array(x, name, min_ndim=2, **kw)
    if (not batch and a.ndim != 2) or a.shape[-1] != a.shape[-2]:
        raise ValueError(f"{name} must be a square matrix{' stack' if batch else ''}, "
                         f"got shape {a.shape}")
    if n is not None and a.shape[-1] != n:
        raise ValueError(f"{name} must be {n}x{n}, got shape {a.shape}")
    return a


def as_symmetric(x, name: str, *, rtol=1e-10, atol=0.0, batch=False, **kw) -> np.ndarray:
    """A symmetric matrix (or stack): asymmetry beyond ``rtol * max|A| + atol``
    is an error; the result is exactly symmetrised."""
    a = as_square(x, name, batch=batch, **kw)
    at = np.swapaxes(a, -1, -2)
    scale = np.max(np.abs(a)) if a.size else 0.0
    if np.any(np.abs(a - at) > rtol * scale + atol):
        raise ValueError(f"{name} must be symmetric (max |A - A^T| = "
                         f"{float(np.max(np.abs(a - at))):.3g})")
    return np.ascontiguousarray(0.5 * (a + at))


def as_finite_result(x, what: str, cause: str) -> np.ndarray:
    """Return *x* (a computed result) if every element is finite; otherwise raise
    :class:`mechpy.NonFiniteError` saying that ``what`` overflowed (or became
    NaN) and ``cause`` (which inputs are too large or too small)."""
    a = np.asarray(x)
    if a.dtype.kind in "fc" and not np.isfinite(a).all():
        from .errors import NonFiniteError
        kind = "NaN" if np.isnan(a).any() else "inf"
        raise NonFiniteError(f"{what} overflowed float64 (the result contains {kind}): {cause}")
    return x


#: csrc/ode/lu.h's numbers for mp_ode_band_pays (band_pays below)
BAND_WIDE, BAND_MIN_N = _core.BAND_WIDE, _core.BAND_MIN_N


def band_pays(n: int, ml: int, mu: int) -> bool:
    """Whether radau factorises an (n, n) matrix of band ml + mu in band form:
    csrc/ode/lu.h's mp_ode_band_pays, BAND_WIDE (ml + mu + 1) <= n and
    n >= BAND_MIN_N."""
    return n >= BAND_MIN_N and BAND_WIDE * (ml + mu + 1) <= n


def band_of_pattern(rows, cols, n: int):
    """The band of an (n, n) Jacobian whose nonzero entries are at (rows[k],
    cols[k]), as the C core takes it (``mp_ode_problem``'s ml, mu, perm):
    (ml, mu) in the states' own order; (ml, mu, perm) in the order perm, the
    reverse Cuthill-McKee order of the symmetrised pattern (SciPy's), when
    that band is narrower and the own one too wide for radau's band form (a
    system written y = (q, v): its Jacobian [[0, I], [K, C]] has band n/2,
    the interleaved order a few); None when the band covers the matrix."""
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)

    def band(r, c):
        d = r - c
        return (int(max(d.max(), 0)), int(max(-d.min(), 0))) if d.size else (0, 0)
    ml, mu = band(rows, cols)
    if n >= BAND_MIN_N and not band_pays(n, ml, mu):
        try:
            from scipy.sparse import coo_matrix
            from scipy.sparse.csgraph import reverse_cuthill_mckee
        except ImportError:      # without SciPy: the states' own order
            pass
        else:
            g = coo_matrix((np.ones(2 * rows.size), (np.r_[rows, cols], np.r_[cols, rows])),
                           shape=(n, n)).tocsr()
            perm = np.asarray(reverse_cuthill_mckee(g, symmetric_mode=True), dtype=np.int64)
            where = np.empty(n, dtype=np.int64)
            where[perm] = np.arange(n)
            pl, pu = band(where[rows], where[cols])
            if pl + pu < ml + mu:
                return (pl, pu, perm.tolist())
    return (ml, mu) if ml + mu + 1 < n else None


def as_args(args, name: str = "args") -> tuple:
    """Extra arguments of a Python right-hand side as a tuple, by SciPy's rule
    (``scipy.integrate.solve_ivp``): None is no arguments, any iterable is
    unpacked (a tuple, a list, an array's rows), anything else is a ``TypeError``
    that shows the tuple meant (SciPy refuses it too; it is not wrapped, since
    ``args=p`` where ``p`` happens to be a sequence would then mean something else)."""
    if args is None:
        return ()
    if isinstance(args, tuple):
        return args
    try:
        return tuple(args)
    except TypeError:
        raise TypeError(f"{name} must be a tuple of extra arguments (or None), got "
                        f"{type(args).__name__} {args!r}, which cannot be unpacked: write "
                        f"{name}=({args!r},) for one argument, as scipy.integrate.solve_ivp "
                        "asks") from None
