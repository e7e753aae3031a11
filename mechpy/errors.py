"""The exceptions mechpy raises.

Every status code of the C core maps to exactly one of these classes (the
table lives in ``csrc/py/errors.c``).  Each derives from :class:`MechpyError`
and from the builtin a SciPy user would catch:

=========================  =====================================  =========================
class                      raised when                            also an instance of
=========================  =====================================  =========================
DomainError                an argument is outside its domain      ValueError
NonFiniteError             a NaN or inf was produced              ValueError
SingularityError           gimbal lock, a singular matrix         ValueError
MeshError                  an open, inverted or degenerate mesh   ValueError
UnstableSystemError        a negative stiffness eigenvalue        ValueError
NotPositiveDefiniteError   a matrix is not SPD                    numpy.linalg.LinAlgError
StepBudgetError            max_steps ran out                      RuntimeError
StepSizeError              the step fell below round-off          RuntimeError
ConvergenceError           an iteration did not converge          RuntimeError
GSLError                   GSL failed unexpectedly                RuntimeError
=========================  =====================================  =========================

Plain ``TypeError``/``ValueError`` are raised by argument validation before
any C code runs; an exception raised inside a user callback propagates
unchanged, with its traceback; Ctrl-C raises ``KeyboardInterrupt``.
"""
from ._core import (  # noqa: F401
    ConvergenceError,
    DomainError,
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
    "ConvergenceError", "GSLError",
]
