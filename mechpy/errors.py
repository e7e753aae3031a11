"""The exceptions mechpy raises, and when a failure raises at all.

A status code of the C core travels unchanged to Python and meets one table
(``csrc/mp_status.c``, read here as ``mechpy._core.STATUS_TABLE``) that gives
it its exception class, its message and the ``status`` number a
:class:`~mechpy.integrate.Solution` reports.  Each class derives from
:class:`MechpyError` and from the builtin a SciPy user would catch.

**Which failures raise.** ``solve`` and ``solve_many`` follow one rule, chosen by their ``errors``
argument:

* ``errors="auto"`` (the default): the integration giving up -- the step
  budget ``max_steps`` ran out, or the step fell below round-off -- is a
  status, ``status = -1`` with a message and ``success = False``, as SciPy's
  ``solve_ivp`` reports a failed step; a failure of the model or its state
  (a NaN or inf, a singular configuration, an argument out of its domain)
  raises.  ``solve_many`` raises the first such trajectory (by index), naming
  it; the others' budget and step-size failures are per-trajectory statuses.
* ``errors="raise"``: every failure raises, :class:`StepBudgetError` and
  :class:`StepSizeError` included.
* ``errors="status"``: every failure is a negative ``status`` with its message
  (``solve_many``: per trajectory, so a sweep across singular states keeps
  the rest).

``Solution.raise_for_status()`` (and ``EnsembleSolution.raise_for_status()``)
raises a reported failure afterwards.  Plain ``TypeError``/``ValueError`` are
raised by argument validation before any C code runs; an exception raised
inside a user callback propagates unchanged, with its traceback; Ctrl-C raises
``KeyboardInterrupt``; these three never become a status.

**The table** (C status, class, its builtin base, ``Solution.status``, what
``errors="auto"`` does, message):
"""
from ._core import (  # noqa: F401
    STATUS_TABLE as _TABLE,
    ConvergenceError,
    DomainError,
    EventError,
    GSLError,
    MechpyError,
    MeshError,
    NonFiniteError,
    NotPositiveDefiniteError,
    SingularityError,
    StepBudgetError,
    StepSizeError,
    UnstableSystemError,
)

__all__ = [
    "MechpyError", "DomainError", "NonFiniteError", "SingularityError", "MeshError",
    "UnstableSystemError", "NotPositiveDefiniteError", "StepBudgetError", "StepSizeError",
    "ConvergenceError", "GSLError", "EventError",
]


def _table_rst() -> str:
    """The status table as reStructuredText, from the C table itself."""
    rows = [("C status", "class", "also an instance of", "status", "errors='auto'", "message")]
    for r in _TABLE:
        cls = r["exception"]
        if cls is None:
            continue
        bases = [b for b in cls.__mro__[1:] if b not in (MechpyError, Exception, BaseException,
                                                          object)]
        mine = issubclass(cls, MechpyError)
        rows.append((r["name"], cls.__name__, bases[0].__name__ if mine and bases else "",
                     str(r["solve_status"]) if r["raises"] < 2 else "",
                     ("status", "raises", "always raises")[r["raises"]], r["message"]))
    w = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    rule = "  ".join("=" * x for x in w)
    lines = [rule, "  ".join(c.ljust(x) for c, x in zip(rows[0], w)).rstrip(), rule]
    lines += ["  ".join(c.ljust(x) for c, x in zip(row, w)).rstrip() for row in rows[1:]]
    return "\n".join(lines + [rule])


__doc__ = (__doc__ or "") + "\n" + _table_rst() + "\n"
