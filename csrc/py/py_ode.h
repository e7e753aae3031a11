/* The integrator binding's private header: what its three files share.
 *
 *   py_system.c  system kinds (one table row each) and the adapters through
 *                which the engine calls a system: Python callables, C
 *                callbacks, watched ctypes callbacks, Jacobians, the band;
 *   py_events.c  event lists and impacts;
 *   py_ode.c     the options object, the solve calls and their results.
 *
 * The one callback adapter through which C calls Python is py_call. */
#ifndef MP_PY_ODE_H
#define MP_PY_ODE_H

#include "mp_py.h"

#include "models/models.h"
#include "models/rigid.h"
#include "ode/ensemble.h"
#include "ode/ode.h"

/* ---- Python callables (called with the GIL held) ------------------------- */

typedef struct {
    PyObject *fun;    /* borrowed: alive for the whole call */
    PyObject *args;   /* tuple of extra arguments (borrowed) */
    size_t n;         /* length of y */
    size_t nout;      /* expected number of outputs */
    const char *name; /* for messages: "fun", "jac", "events[0]" */
} py_fn;

/* Call fun(t, y, *args) and copy its float64 result (nout values) to out:
 * MP_OK, or MP_ECALLBACK with the Python exception set. */
int py_call(const py_fn *c, double t, const double *y, double *out);

/* ---- C callbacks: void f(double t, const double *y, double *dydt, void *ud) */

typedef void (*mp_c_rhs_fn)(double, const double *, double *, void *);
typedef struct {
    mp_c_rhs_fn f;
    void *user_data;
    size_t n;        /* outputs the callback must write (set by the caller) */
} c_fn;

/* a C acceleration a(t, q, acc, user_data) as a first-order system */
typedef struct {
    c_fn fn;
    size_t nq;
} c_fn2;

/* ---- wrappers of a problem ------------------------------------------------ */

/* a Python Jacobian jac(t, y, *args) beside the system's own rhs */
typedef struct {
    mp_ode_problem inner;
    py_fn jac;
} py_with_jac;

/* a Jacobian given as a constant matrix (SciPy accepts an array for jac) */
typedef struct {
    mp_ode_problem inner;
    const double *J;   /* n x n, row-major */
} const_jac;

/* a ctypes callback that runs Python: its swallowed exceptions land in the
 * list `caught` (the Python layer's sys.unraisablehook), checked after
 * every call */
typedef struct {
    mp_ode_problem inner;
    PyObject *caught;  /* a list (borrowed: alive for the whole call) */
} py_watched;

/* Contract: p becomes the watched version of itself (wd holds the original). */
void watch_problem(mp_ode_problem *p, py_watched *wd, PyObject *caught);

/* Contract: jaco as a Jacobian for n states: None (*jm NULL), a callable
 * (*jm NULL) or a constant (n, n) finite matrix (*jm a new reference).  0, or
 * -1 with an exception set. */
int jac_parse(PyObject *jaco, size_t n, PyArrayObject **jm);

/* Contract: prob with the user's Jacobian (jac_parse's jaco, jm): the
 * constant matrix through cj, or the callable jac(t, y, *args) through wj;
 * returns 1 when it calls Python.  Nothing for None. */
int jac_wrap(mp_ode_problem *prob, PyObject *jaco, PyArrayObject *jm, PyObject *args,
             const_jac *cj, py_with_jac *wj);

/* Contract: the Jacobian's band (integrate.py's _jac_band) set on p (of n
 * states): None (dense), (ml, mu) with 0 <= ml, mu < n, or (ml, mu, perm)
 * with perm a permutation of 0..n-1, copied into *perm_out (PyMem_Free it).
 * 0, or -1 with an exception set. */
int band_parse(PyObject *band, size_t n, mp_ode_problem *p, size_t **perm_out);

/* ---- systems -------------------------------------------------------------- */

typedef struct py_system py_system;

/* One kind of system the Python layer describes (see py_system.c's table). */
typedef struct py_system_kind {
    const char *name;   /* the spec's tag: "scene", "python", ... */
    /* Contract: s filled from the spec's (a, b) for a state of n, cb the C
     * torque (address, user_data) or NULL; 0, or -1 with an exception set. */
    int (*parse)(const struct py_system_kind *k, PyObject *a, PyObject *b, PyObject *cb,
                 size_t n, py_system *s);
    int second_order;   /* y = (q, v), the callback gives the acceleration */
    int takes_torque;   /* may carry a C torque callback */
    /* the detail (enum mp_status_detail) of a non-finite right-hand side: a
     * C callback's own names its output (MP_DETAIL_CFUNC2: the acceleration
     * part, the rest being y's copy of v) */
    int nonfinite;
} py_system_kind;

struct py_system {
    const py_system_kind *kind;
    mp_ode_problem prob;
    int holds_python;         /* calls Python: keep the GIL */
    PyArrayObject *params;    /* scene parameters (owned) */
    const mp_model *model;    /* a scene's row (NULL: not a scene) */
    py_fn fn;
    c_fn2 cfn;
    mp_rigid_torque torque;   /* a scene's C torque callback (fn NULL: none) */
    mp_lane_rhs lanes;        /* a compiled system's lane rhs (NULL: none) */
    mp_ode_blocks blocks;     /* ... and its fixed-step blocks (prob.blocks) */
};

/* Contract: s from spec, a tuple (kind, a, b[, (address, user_data)]) naming
 * a row of the kinds' table, for a state of n.  0, or -1 with an exception
 * set (clear s either way). */
int py_system_parse(PyObject *spec, size_t n, py_system *s);

void py_system_clear(py_system *s);

/* ---- events --------------------------------------------------------------- */

/* The event functions of one solve (one trajectory): per event a Python
 * function g(t, y, *args) (fns[k].fun) or a C impact (fns[k].fun NULL:
 * imp[k]), and per event its action: a Python callable action(t, y, *args)
 * -> y_new (acts[k].fun), an impact's own, or none. */
typedef struct {
    py_fn *fns;
    py_fn *acts;
    mp_impact *imp;       /* ode.h's: an impact's g and action, as the lanes run them */
    const double *params; /* the trajectory's parameter vector (an impact's e_param) */
    size_t count, n;
    char (*names)[40];    /* "events[k]", "events[k].action": for messages */
} py_events;

/* The event list of a solve as integrate.py hands it over: terminal and
 * direction (owned), which events have an action, and whether every event
 * runs in C (impacts alone: no GIL needed). */
typedef struct {
    PyArrayObject *term, *dir;
    unsigned char *has_action; /* PyMem */
    Py_ssize_t count;
    int all_c;
} py_event_list;

/* Contract: the event list evo (None or a list of entries: a callable g, a
 * pair (g, action) or a C impact tuple) with terminal and direction (one int
 * each) into el and o's event fields; o->events_data and o->action_data are
 * left to the caller (event_fns).  0, or -1 with an exception set. */
int event_list_parse(PyObject *evo, PyObject *termo, PyObject *diro, py_event_list *el,
                     mp_ode_options *o);

void event_list_clear(py_event_list *el);

/* Contract: pe's adapters of the entries in evo for states of n: each Python
 * event and action called with (t, y, *args), each impact's parameters (its
 * restitution the trajectory `row`'s when given per trajectory; params, the
 * trajectory's parameter vector of nparams).  0, or -1 with an exception set
 * (event_fns_free frees pe either way). */
int event_fns(PyObject *evo, Py_ssize_t count, PyObject *args, size_t n, const double *params,
              size_t nparams, size_t row, py_events *pe);

void event_fns_free(py_events *pe);

/* The events of an ensemble as the lanes run them (impacts alone). */
typedef struct {
    size_t n;               /* events (0: the lanes do not run them) */
    mp_impact *imps;
    PyArrayObject **imp_e;  /* their per-trajectory restitutions (owned), or NULL */
} py_lane_impacts;

/* Contract: the entries of evo (all C impacts: el->all_c) into li when each
 * is an impact reached downwards (its direction -1), for k trajectories of
 * states of n and parameter rows of nparams: 1, or 0 when the lanes cannot
 * run them, or -1 with an exception set (lane_impacts_clear either way). */
int lane_impacts_parse(py_lane_impacts *li, PyObject *evo, const py_event_list *el, size_t k,
                       size_t n, size_t nparams);

void lane_impacts_clear(py_lane_impacts *li);

#endif
