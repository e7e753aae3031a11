/* mechpy C core: status codes shared by every fallible function.
 *
 * Every fallible function returns one of these; results go through
 * out-parameters.  The binding (csrc/py/errors.c) maps each code to one
 * Python exception class in a single table. */
#ifndef MP_STATUS_H
#define MP_STATUS_H

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
    MP_NSTATUS
};

/* A short English description of a status code (static storage). */
const char *mp_status_message(int status);

#endif
