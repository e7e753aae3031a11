/* The one status table (see mp_status.h). */
#include "mp_status.h"

#include <stddef.h>

/* Contract: row s describes status s; each failure's exception and message
 * live here and nowhere else.  Solution.status: -1 for what SciPy's solve_ivp
 * reports as a failed integration (budget, step size), a distinct negative
 * number for every other kind. */
const mp_status_info mp_status_table[MP_NSTATUS] = {
    {MP_OK, "MP_OK", NULL, NULL,
     "The solver successfully reached the end of the integration interval.", 0, 0},
    {MP_EDOM, "MP_EDOM", "DomainError", "ValueError", "argument out of domain", -4, 1},
    {MP_ENOMEM, "MP_ENOMEM", "MemoryError", NULL, "out of memory", -10, 2},
    {MP_EMAXSTEPS, "MP_EMAXSTEPS", "StepBudgetError", "RuntimeError",
     "the step budget (max_steps) was exhausted", -1, 0},
    {MP_ESTEP, "MP_ESTEP", "StepSizeError", "RuntimeError", "the step size fell below round-off",
     -1, 0},
    {MP_ENOTSPD, "MP_ENOTSPD", "NotPositiveDefiniteError", "LinAlgError",
     "matrix is not symmetric positive definite", -7, 1},
    {MP_ECALLBACK, "MP_ECALLBACK", "RuntimeError", NULL, "a callback failed", -11, 2},
    {MP_EINTR, "MP_EINTR", "KeyboardInterrupt", NULL, "interrupted", -12, 2},
    {MP_ENONFINITE, "MP_ENONFINITE", "NonFiniteError", "ValueError",
     "a non-finite value (NaN or inf) was produced", -2, 1},
    {MP_ENOCONV, "MP_ENOCONV", "ConvergenceError", "RuntimeError",
     "the iteration did not converge", -5, 1},
    {MP_ESINGULAR, "MP_ESINGULAR", "SingularityError", "ValueError",
     "singular configuration (gimbal lock, singular matrix)", -3, 1},
    {MP_EMESH, "MP_EMESH", "MeshError", "ValueError",
     "invalid mesh (open, non-manifold, inside out or degenerate)", -8, 1},
    {MP_EGSL, "MP_EGSL", "GSLError", "RuntimeError", "GSL reported an error", -6, 1},
    {MP_EUNSTABLE, "MP_EUNSTABLE", "UnstableSystemError", "ValueError",
     "the system is unstable (a negative stiffness eigenvalue)", -9, 1},
    {MP_EEVENT, "MP_EEVENT", "EventError", "RuntimeError",
     "an event's action left the state where the event fires again at once", -14, 1},
    {MP_TERMINATED, "MP_TERMINATED", NULL, NULL, "A termination event occurred.", 1, 0},
};

static const mp_status_info mp_status_unknown = {
    -1, "MP_UNKNOWN", "RuntimeError", NULL, "unknown status", -13, 2};

/* Contract: the row of `status`, or a generic row for a code outside the enum. */
const mp_status_info *mp_status_lookup(int status)
{
    if (status < 0 || status >= MP_NSTATUS) return &mp_status_unknown;
    return &mp_status_table[status];
}

/* Contract: the row's message (static storage). */
const char *mp_status_message(int status) { return mp_status_lookup(status)->message; }
