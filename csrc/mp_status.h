/* mechpy C core: status codes shared by every fallible function, and the one
 * table that describes them.
 *
 * Every fallible function returns one of these; results go through
 * out-parameters.  The status travels unchanged to Python, where the table
 * below (exposed as mechpy._core.STATUS_TABLE) gives it its exception class,
 * its message and the status number a Solution reports: csrc/py/errors.c,
 * mechpy/errors.py and mechpy/integrate.py read it and hold no text of their
 * own. */
#ifndef MP_STATUS_H
#define MP_STATUS_H

#include <stddef.h>

enum mp_status {
    MP_OK = 0,
    MP_EDOM,        /* an argument is outside its domain (NaN, negative mass, ...) */
    MP_ENOMEM,      /* allocation failed */
    MP_EMAXSTEPS,   /* the step budget ran out */
    MP_ESTEP,       /* the step size fell below round-off */
    MP_ENOTSPD,     /* a matrix that must be symmetric positive definite is not */
    MP_ECALLBACK,   /* a user callback raised or failed (Python error already set) */
    MP_EINTR,       /* interrupted (Ctrl-C); Python error already set */
    MP_ENONFINITE,  /* a right-hand side or result produced NaN or inf */
    MP_ENOCONV,     /* an iteration did not converge */
    MP_ESINGULAR,   /* a singular configuration (gimbal lock, singular matrix) */
    MP_EMESH,       /* a mesh is open, non-manifold, inside out or degenerate */
    MP_EGSL,        /* GSL returned an unexpected error */
    MP_EUNSTABLE,   /* a physical system is unstable (negative stiffness eigenvalue) */
    MP_EEVENT,      /* an event's action left the state where the event fires again at once */
    /* Not a failure and returned by no function: the table's row for a solve
     * that a terminal event ended (mp_ode_result.terminated). */
    MP_TERMINATED,
    MP_NSTATUS
};

/* What a status means, to the binding and to the user. */
typedef struct mp_status_info {
    int status;
    const char *name;      /* the C name, "MP_EMAXSTEPS" */
    /* the Python class: a mechpy.errors class, or a builtin the binding keeps
     * ("MemoryError", "RuntimeError", "KeyboardInterrupt"); NULL: no failure */
    const char *exception;
    const char *base;      /* a mechpy class's builtin base: "ValueError", ... */
    const char *message;   /* the message (a class's docstring is the same text) */
    int solve_status;      /* Solution.status: 0, 1, or negative (-1 as SciPy's) */
    /* solve/solve_many with errors="auto": 1 raises, 0 is a status; 2 always
     * raises (the failure cannot be a status: a callback's own exception,
     * Ctrl-C, memory) */
    int raises;
} mp_status_info;

/* The table, one row per status in enum order (mp_status_table[s].status == s). */
extern const mp_status_info mp_status_table[MP_NSTATUS];

/* The row of a status; unknown codes get a generic row (static storage). */
const mp_status_info *mp_status_lookup(int status);

/* The row's message (static storage). */
const char *mp_status_message(int status);

/* What a solve's message says after its status's own text, in parentheses:
 * where it happened and, for a non-finite value, what produced it.  One row
 * per kind (mp_status_details), its text a template whose named fields are
 * filled from mp_status_fields: {t} (%.17g), {gap} (%.3g), {i}, {j}
 * (%zu), {count}, {max_steps} (%ld). */
enum mp_status_detail {
    MP_DETAIL_NONE = 0,        /* the status's message alone */
    MP_DETAIL_AT_T,            /* any failure: where */
    MP_DETAIL_MAX_STEPS,       /* MP_EMAXSTEPS */
    MP_DETAIL_EVENT_LOOP,      /* MP_EEVENT */
    MP_DETAIL_MAX_EVENTS,      /* MP_TERMINATED: an event reached its max_events */
    MP_DETAIL_ZENO,            /* MP_TERMINATED: events accumulate, gap > 0 */
    MP_DETAIL_ZENO_UNRESOLVED, /* ... closer than t resolves */
    /* MP_ENONFINITE, by what produced the value ({i}: its index) */
    MP_DETAIL_RHS,             /* the right-hand side */
    MP_DETAIL_EVENT,           /* event function i */
    MP_DETAIL_JAC,             /* jac[i, j] */
    MP_DETAIL_ACTION,          /* event i's action */
    MP_DETAIL_STATE,           /* the state overflowed, f finite */
    MP_DETAIL_ERR,             /* the scaled error norm overflowed */
    MP_DETAIL_CFUNC,           /* a C callback's dydt[i] */
    MP_DETAIL_CFUNC2,          /* a second-order C callback's acc[i] */
    MP_DETAIL_TORQUE,          /* a RigidBody's C torque callback's tau[i] */
    MP_NDETAIL
};

/* The values a detail's template names (unused ones are ignored). */
typedef struct mp_status_fields {
    double t, gap;
    size_t i, j;
    long count, max_steps;
    int stiff;                 /* Hairer's stiffness test fired: a failure's message
                                  ends with the methods to try */
} mp_status_fields;

/* The templates, one per enum mp_status_detail in enum order (NULL: none). */
extern const char *const mp_status_details[MP_NDETAIL];

/* Contract: the message of a solve's outcome into buf (len bytes, truncated,
 * always terminated): the status's message, then " (detail)" filled from f
 * unless detail is MP_DETAIL_NONE, then for a failure (not MP_OK nor
 * MP_TERMINATED) with f->stiff the stiffness hint. */
void mp_status_format(char *buf, size_t len, int status, int detail, const mp_status_fields *f);

#endif
