/* The one status table (see mp_status.h). */
#include "mp_status.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

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

/* Contract: the detail texts of solve messages (see mp_status.h), row d for
 * enum mp_status_detail d; the only place they are written. */
const char *const mp_status_details[MP_NDETAIL] = {
    [MP_DETAIL_NONE] = NULL,
    [MP_DETAIL_AT_T] = "at t = {t}",
    [MP_DETAIL_MAX_STEPS] = "max_steps={max_steps}, at t = {t}",
    [MP_DETAIL_EVENT_LOOP] = "events[{i}] at t = {t}; an action must move the state off the "
                             "event surface (reverse the velocity towards it)",
    [MP_DETAIL_MAX_EVENTS] = "events[{i}] reached max_events={count} at t = {t}",
    [MP_DETAIL_ZENO] = "events[{i}] accumulate (Zeno): {count} crossings, the last two {gap} "
                       "apart in t; the solve ends at their accumulation point t = {t}",
    [MP_DETAIL_ZENO_UNRESOLVED] = "events[{i}] accumulate (Zeno): {count} crossings, the last "
                                  "two closer than t resolves; the solve ends at their "
                                  "accumulation point t = {t}",
    [MP_DETAIL_RHS] = "the right-hand side gave dydt[{i}] = NaN or inf near t = {t}",
    [MP_DETAIL_EVENT] = "events[{i}] returned NaN or inf at t = {t}",
    [MP_DETAIL_JAC] = "jac[{i}, {j}] is NaN or inf near t = {t}",
    [MP_DETAIL_ACTION] = "events[{i}].action returned NaN or inf at t = {t}",
    [MP_DETAIL_STATE] = "the solution's y[{i}] overflowed to NaN or inf in the step from "
                        "t = {t}, the right-hand side being finite",
    [MP_DETAIL_ERR] = "a step's error estimate (or Newton increment), scaled by atol and rtol, "
                      "overflowed near t = {t}, the state and the right-hand side being "
                      "finite: rescale the system",
    [MP_DETAIL_CFUNC] = "the C callback left dydt[{i}] unwritten or NaN (or returned inf) "
                        "near t = {t}",
    [MP_DETAIL_CFUNC2] = "the C callback left acc[{i}] unwritten or NaN (or returned inf) "
                         "near t = {t}",
    [MP_DETAIL_TORQUE] = "the torque callback left tau[{i}] unwritten or NaN (or the "
                         "right-hand side overflowed) near t = {t}",
};

/* What a failure's message ends with when Hairer's stiffness test fired. */
static const char mp_status_stiff_hint[] =
    "; the problem appears stiff: try method='radau', 'auto' or 'gsl:msbdf'";

/* Contract: the field `name` (len chars) of f printed at buf (room: len
 * bytes); snprintf's count, or -1 for a name the templates do not use. */
static int field_print(char *buf, size_t room, const char *name, size_t len,
                       const mp_status_fields *f)
{
#define MP_FIELD_IS(s) (len == sizeof(s) - 1 && memcmp(name, s, len) == 0)
    if (MP_FIELD_IS("t")) return snprintf(buf, room, "%.17g", f->t);
    if (MP_FIELD_IS("gap")) return snprintf(buf, room, "%.3g", f->gap);
    if (MP_FIELD_IS("i")) return snprintf(buf, room, "%zu", f->i);
    if (MP_FIELD_IS("j")) return snprintf(buf, room, "%zu", f->j);
    if (MP_FIELD_IS("count")) return snprintf(buf, room, "%ld", f->count);
    if (MP_FIELD_IS("max_steps")) return snprintf(buf, room, "%ld", f->max_steps);
#undef MP_FIELD_IS
    return -1;
}

/* Contract: src appended at buf[*used] (truncated to len), the template's
 * fields filled from f when f is not NULL. */
static void append(char *buf, size_t len, size_t *used, const char *src,
                   const mp_status_fields *f)
{
    for (const char *p = src; *p && *used + 1 < len; p++) {
        const char *end = f && *p == '{' ? strchr(p, '}') : NULL;
        int w = end ? field_print(buf + *used, len - *used, p + 1, (size_t)(end - p - 1), f) : -1;
        if (w < 0) {
            buf[(*used)++] = *p;
            continue;
        }
        *used += (size_t)w < len - *used ? (size_t)w : len - *used - 1;
        p = end;
    }
    buf[*used] = '\0';
}

/* Contract: see mp_status.h. */
void mp_status_format(char *buf, size_t len, int status, int detail, const mp_status_fields *f)
{
    size_t used = 0;
    if (!len) return;
    buf[0] = '\0';
    append(buf, len, &used, mp_status_message(status), NULL);
    if (detail > MP_DETAIL_NONE && detail < MP_NDETAIL && mp_status_details[detail]) {
        append(buf, len, &used, " (", NULL);
        append(buf, len, &used, mp_status_details[detail], f);
        append(buf, len, &used, ")", NULL);
    }
    if (f && f->stiff && status != MP_OK && status != MP_TERMINATED)
        append(buf, len, &used, mp_status_stiff_hint, NULL);
}
