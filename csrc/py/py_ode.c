/* Binding for the integrator engine: system adapters (C scene, Python
 * callable, C callback), argument conversion, result building.  The one
 * callback adapter through which C calls Python lives here. */
#include "mp_py.h"

#include <math.h>
#include <string.h>

#include "models/models.h"
#include "models/rigid.h"
#include "ode/ensemble.h"
#include "ode/ode.h"

/* ---- Python callables (called with the GIL held) -------------------------- */

typedef struct {
    PyObject *fun;    /* borrowed: alive for the whole call */
    PyObject *args;   /* tuple of extra arguments (borrowed) */
    size_t n;         /* length of y */
    size_t nout;      /* expected number of outputs */
    const char *name; /* for messages: "fun", "jac", "events[0]" */
} py_fn;

/* Call fun(t, y, *args) and copy its float64 result (nout values) to out. */
static int py_call(const py_fn *c, double t, const double *y, double *out)
{
    npy_intp dim = (npy_intp)c->n;
    Py_ssize_t na = PyTuple_GET_SIZE(c->args);
    PyObject *ya = PyArray_SimpleNew(1, &dim, NPY_DOUBLE);
    if (!ya) return MP_ECALLBACK;
    memcpy(PyArray_DATA((PyArrayObject *)ya), y, c->n * sizeof(double));
    PyObject *targs = PyTuple_New(2 + na);
    if (!targs) {
        Py_DECREF(ya);
        return MP_ECALLBACK;
    }
    PyTuple_SET_ITEM(targs, 0, PyFloat_FromDouble(t));
    PyTuple_SET_ITEM(targs, 1, ya);
    for (Py_ssize_t i = 0; i < na; i++) {
        PyObject *a = PyTuple_GET_ITEM(c->args, i);
        Py_INCREF(a);
        PyTuple_SET_ITEM(targs, 2 + i, a);
    }
    PyObject *res = PyObject_Call(c->fun, targs, NULL);
    Py_DECREF(targs);
    if (!res) return MP_ECALLBACK;
    if (c->nout == 1 && PyFloat_Check(res)) { /* an event function's scalar */
        out[0] = PyFloat_AS_DOUBLE(res);
        Py_DECREF(res);
        return MP_OK;
    }
    PyArrayObject *ra = (PyArrayObject *)PyArray_FROM_OTF(res, NPY_DOUBLE, NPY_ARRAY_IN_ARRAY);
    Py_DECREF(res);
    if (!ra) {
        /* a conversion failure becomes a message naming the callback; anything
         * else (KeyboardInterrupt during the conversion, MemoryError) is kept */
        if (PyErr_ExceptionMatches(PyExc_TypeError) || PyErr_ExceptionMatches(PyExc_ValueError)) {
            PyErr_Clear();
            PyErr_Format(PyExc_TypeError, "%s must return real numbers", c->name);
        }
        return MP_ECALLBACK;
    }
    if ((size_t)PyArray_SIZE(ra) != c->nout) {
        PyObject *shape = PyObject_GetAttrString((PyObject *)ra, "shape");
        PyErr_Format(PyExc_ValueError, "%s returned shape %R; expected %zu value(s)", c->name,
                     shape ? shape : Py_None, c->nout);
        Py_XDECREF(shape);
        Py_DECREF(ra);
        return MP_ECALLBACK;
    }
    memcpy(out, PyArray_DATA(ra), c->nout * sizeof(double));
    Py_DECREF(ra);
    return MP_OK;
}

static int py_rhs(double t, const double *y, double *dydt, void *data)
{
    return py_call((const py_fn *)data, t, y, dydt);
}

/* second-order systems q'' = a(t, q): y = (q, v), f = (v, a(t, q)) */
static int py_rhs2(double t, const double *y, double *dydt, void *data)
{
    const py_fn *c = data; /* c->n = c->nout = nq: a(t, q, *args) */
    memcpy(dydt, y + c->n, c->n * sizeof(double));
    return py_call(c, t, y, dydt + c->n);
}

typedef struct {
    mp_ode_problem inner; /* the system's own rhs (scene, callback or Python) */
    py_fn jac;
} py_with_jac;

static int py_jac_rhs(double t, const double *y, double *dydt, void *data)
{
    const py_with_jac *w = data;
    return w->inner.rhs(t, y, dydt, w->inner.data);
}

static int py_jac(double t, const double *y, double *J, void *data)
{
    return py_call(&((const py_with_jac *)data)->jac, t, y, J);
}

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

static int py_events_eval(double t, const double *y, double *g, void *data)
{
    const py_events *e = data;
    for (size_t k = 0; k < e->count; k++) {
        if (!e->fns[k].fun) {
            double w[3];
            mp_impact_wall(&e->imp[k], t, e->params, 1, w);
            g[k] = mp_impact_g(&e->imp[k], y[e->imp[k].iq], w[0]);
            continue;
        }
        int rc = py_call(&e->fns[k], t, y, &g[k]);
        if (rc != MP_OK) return rc;
    }
    return MP_OK;
}

/* mp_ode_action of the events: the impact's reflection in C, or the Python
 * action's new state (checked: n values; its finiteness is the driver's). */
static int py_events_action(double t, double *y, size_t k, void *data)
{
    const py_events *e = data;
    if (!e->fns[k].fun) {
        const mp_impact *im = &e->imp[k];
        double w[3];
        mp_impact_wall(im, t, e->params, 1, w);
        mp_impact_apply(im, mp_impact_e(im, 0, im->e_param >= 0 ? e->params[im->e_param] : 0.0),
                        w, y, 1);
        return MP_OK;
    }
    return py_call(&e->acts[k], t, y, y);
}

/* mp_ode_options' impact_of: event k's impact (NULL: a Python event) and the
 * trajectory's parameters its moving wall reads. */
static const mp_impact *py_events_impact(size_t k, const double **params, void *data)
{
    const py_events *e = data;
    *params = e->params;
    return e->fns[k].fun ? NULL : &e->imp[k];
}

/* ---- C callbacks: void f(double t, const double *y, double *dydt, void *ud) -- */

typedef void (*mp_c_rhs_fn)(double, const double *, double *, void *);
typedef struct {
    mp_c_rhs_fn f;
    void *user_data;
    size_t n;        /* outputs the callback must write (set by the caller) */
} c_fn;

/* Contract: dydt = f(t, y) by the user's C function.  dydt is filled with NaN
 * first, so that an output the callback leaves unwritten is a NonFiniteError
 * naming it, never uninitialised memory. */
static int c_rhs(double t, const double *y, double *dydt, void *data)
{
    const c_fn *c = data;
    for (size_t i = 0; i < c->n; i++) dydt[i] = NAN;
    c->f(t, y, dydt, c->user_data);
    return MP_OK;
}

/* a C acceleration a(t, q, acc, user_data) as a first-order system */
typedef struct {
    c_fn fn;
    size_t nq;
} c_fn2;

static int c_rhs2(double t, const double *y, double *dydt, void *data)
{
    const c_fn2 *c = data;
    memcpy(dydt, y + c->nq, c->nq * sizeof(double));
    for (size_t i = 0; i < c->nq; i++) dydt[c->nq + i] = NAN; /* unwritten: NonFiniteError */
    c->fn.f(t, y, dydt + c->nq, c->fn.user_data);
    return MP_OK;
}

/* ---- a C callback that is Python underneath (ctypes) --------------------------
 * ctypes prints and swallows an exception raised in a Python callback (Ctrl-C
 * included) and returns with the outputs unwritten.  The Python layer catches
 * those through sys.unraisablehook into the list `caught`; the solve then runs
 * with the GIL held, and after every call of the system the list is checked:
 * the first exception caught stops the solve and is raised again. */

typedef struct {
    mp_ode_problem inner;
    PyObject *caught;  /* a list (borrowed: alive for the whole call) */
} py_watched;

/* Contract: MP_ECALLBACK with the caught exception set when the call left one. */
static int watch_check(const py_watched *w)
{
    if (PyList_GET_SIZE(w->caught) == 0) return MP_OK;
    PyObject *e = PyList_GET_ITEM(w->caught, 0);
    if (PyExceptionInstance_Check(e)) {
        PyErr_SetObject((PyObject *)Py_TYPE(e), e);
        PyObject *tb = PyException_GetTraceback(e);
        if (tb) {
            PyObject *tp, *v, *otb;
            PyErr_Fetch(&tp, &v, &otb);
            Py_XDECREF(otb);
            PyErr_Restore(tp, v, tb);
        }
    } else {
        PyErr_SetString(PyExc_RuntimeError, "a ctypes callback raised an exception");
    }
    return MP_ECALLBACK;
}

static int watched_rhs(double t, const double *y, double *dydt, void *data)
{
    const py_watched *w = data;
    int rc = w->inner.rhs(t, y, dydt, w->inner.data);
    return rc != MP_OK ? rc : watch_check(w);
}

static int watched_jac(double t, const double *y, double *jac, void *data)
{
    const py_watched *w = data;
    int rc = w->inner.jac(t, y, jac, w->inner.data);
    return rc != MP_OK ? rc : watch_check(w);
}

/* Contract: p becomes the watched version of itself (wd holds the original). */
static void watch_problem(mp_ode_problem *p, py_watched *wd, PyObject *caught)
{
    wd->inner = *p;
    wd->caught = caught;
    p->rhs = watched_rhs;
    p->jac = p->jac ? watched_jac : NULL;
    p->data = wd;
}

/* A Jacobian given as a constant matrix (SciPy accepts an array for jac). */
typedef struct {
    mp_ode_problem inner;
    const double *J;   /* n x n, row-major */
} const_jac;

static int const_jac_rhs(double t, const double *y, double *dydt, void *data)
{
    const const_jac *c = data;
    return c->inner.rhs(t, y, dydt, c->inner.data);
}

static int const_jac_jac(double t, const double *y, double *jac, void *data)
{
    (void)t;
    (void)y;
    const const_jac *c = data;
    memcpy(jac, c->J, c->inner.n * c->inner.n * sizeof(double));
    return MP_OK;
}

/* ---- a system described by the Python layer --------------------------------
 * ("scene", name, params) | ("python", fun, args) | ("cfunc", address, user_data)
 * and the second-order ("python2", accel, args) | ("cfunc2", address, user_data),
 * or a generated library ("compiled", (rhs, jac, nq[, lanes, rk4, compose]), params)
 * with lanes its mp_lane_rhs (lanes.h; None: ensembles wrap rhs lane by lane) and
 * rk4/compose its fixed-step blocks (ode.h's mp_ode_blocks; None: the generic ones);
 * a RigidBody scene may carry a C torque: ("scene", name, params, (address, user_data)) */

typedef struct {
    mp_ode_problem prob;
    int holds_python;         /* calls Python: keep the GIL */
    PyArrayObject *params;    /* scene parameters (owned) */
    const mp_model *model;    /* a scene's row (NULL: not a scene) */
    py_fn fn;
    c_fn2 cfn;
    mp_rigid_torque torque;   /* a scene's C torque callback (fn NULL: none) */
    mp_lane_rhs lanes;        /* a compiled system's lane rhs (NULL: none) */
    mp_ode_blocks blocks;     /* ... and its fixed-step blocks (prob.blocks) */
} py_system;

static int c_address(PyObject *a, PyObject *b, c_fn *out)
{
    void *addr = PyLong_AsVoidPtr(a);
    if (!addr && PyErr_Occurred()) return -1;
    void *ud = b == Py_None ? NULL : PyLong_AsVoidPtr(b);
    if (PyErr_Occurred()) return -1;
    if (!addr) {
        PyErr_SetString(PyExc_ValueError, "the C callback is a NULL function pointer");
        return -1;
    }
    /* A data pointer converted to a function pointer: the one place this is
     * done, for callbacks handed over as addresses. */
    *(void **)&out->f = addr;
    out->user_data = ud;
    out->n = 0;
    return 0;
}

static void py_system_clear(py_system *s) { Py_CLEAR(s->params); }

static int py_system_parse(PyObject *spec, size_t n, py_system *s)
{
    const char *kind;
    PyObject *a, *b, *cb = NULL;
    memset(s, 0, sizeof *s);
    if (!PyArg_ParseTuple(spec, "sOO|O!", &kind, &a, &b, &PyTuple_Type, &cb)) return -1;
    if (cb && (strcmp(kind, "scene") != 0 || PyTuple_GET_SIZE(cb) != 2)) {
        PyErr_SetString(PyExc_ValueError, "a callback in a system spec needs a scene and "
                                          "(address, user_data)");
        return -1;
    }
    s->prob.n = n;
    if (strcmp(kind, "scene") == 0) {
        const char *name = PyUnicode_AsUTF8(a);
        if (!name) return -1;
        const mp_model *m = mp_model_find(name);
        if (!m) {
            PyErr_Format(PyExc_ValueError, "unknown scene %s", name);
            return -1;
        }
        s->params = mp_py_array(b, "scene parameters", 1);
        if (!s->params) return -1;
        size_t dim;
        if (mp_model_prepare(m, PyArray_DATA(s->params), (size_t)PyArray_SIZE(s->params), &dim)
            != MP_OK) {
            mp_py_raise(MP_EDOM, "scene parameters");
            return -1;
        }
        if (dim != n) {
            PyErr_Format(PyExc_ValueError, "y0 must have %zu values for %s, got %zu", dim,
                         m->name, n);
            return -1;
        }
        m->bind(PyArray_DATA(s->params), &s->prob);
        s->model = m;
        if (cb) {
            c_fn f;
            if (c_address(PyTuple_GET_ITEM(cb, 0), PyTuple_GET_ITEM(cb, 1), &f) < 0) return -1;
            s->torque = (mp_rigid_torque){PyArray_DATA(s->params), f.f, f.user_data};
            if (mp_rigid_bind_torque(m, &s->torque, &s->prob) != MP_OK) {
                PyErr_Format(PyExc_ValueError, "scene %s takes no C callback", m->name);
                return -1;
            }
        }
    } else if (strcmp(kind, "python") == 0 || strcmp(kind, "python2") == 0) {
        int second = kind[6] == '2';
        if (!PyCallable_Check(a) || !PyTuple_Check(b)) {
            PyErr_SetString(PyExc_TypeError, "system must be callable and args a tuple");
            return -1;
        }
        if (second && n % 2) {
            PyErr_SetString(PyExc_ValueError, "y0 of a second-order system is (q, v): even length");
            return -1;
        }
        size_t nf = second ? n / 2 : n;
        s->fn = (py_fn){a, b, nf, nf, second ? "accel" : "fun"};
        s->prob.rhs = second ? py_rhs2 : py_rhs;
        s->prob.data = &s->fn;
        s->prob.nq = second ? n / 2 : 0;
        s->holds_python = 1;
    } else if (strcmp(kind, "cfunc") == 0 || strcmp(kind, "cfunc2") == 0) {
        int second = kind[5] == '2';
        if (c_address(a, b, &s->cfn.fn) < 0) return -1;
        if (second && n % 2) {
            PyErr_SetString(PyExc_ValueError, "y0 of a second-order system is (q, v): even length");
            return -1;
        }
        s->cfn.nq = second ? n / 2 : 0;
        s->prob.rhs = second ? c_rhs2 : c_rhs;
        s->prob.data = second ? (void *)&s->cfn : (void *)&s->cfn.fn;
        s->prob.nq = s->cfn.nq;
    } else if (strcmp(kind, "compiled") == 0) {
        /* a generated library (mechpy.symbolic): ((rhs, jac, nq[, lanes, rk4,
         * compose]), params), each function an address or None (rhs: never);
         * its functions take the parameter vector as data */
        enum { RHS, JAC, LANES, RK4, COMPOSE, NFN };
        PyObject *fa[NFN] = {NULL, NULL, Py_None, Py_None, Py_None};
        c_fn fn[NFN] = {{0}};
        Py_ssize_t nq;
        if (!PyArg_ParseTuple(a, "OOn|OOO", &fa[RHS], &fa[JAC], &nq, &fa[LANES], &fa[RK4],
                              &fa[COMPOSE]))
            return -1;
        for (int i = 0; i < NFN; i++) /* each handed over as an address (see c_address) */
            if ((i == RHS || fa[i] != Py_None) && c_address(fa[i], Py_None, &fn[i]) < 0) return -1;
        if (nq < 0 || (size_t)nq * 2 > n) {
            PyErr_SetString(PyExc_ValueError, "compiled system: bad second-order split nq");
            return -1;
        }
        s->params = mp_py_array(b, "scene parameters", 1);
        if (!s->params) return -1;
        *(void **)&s->prob.rhs = *(void **)&fn[RHS].f;
        *(void **)&s->prob.jac = *(void **)&fn[JAC].f;
        *(void **)&s->lanes = *(void **)&fn[LANES].f;
        s->prob.data = PyArray_DATA(s->params);
        s->prob.nq = (size_t)nq;
        if (fn[RK4].f) { /* its fixed-step blocks, with its rhs inlined */
            s->blocks.rhs = s->prob.rhs;
            *(void **)&s->blocks.rk4 = *(void **)&fn[RK4].f;
            *(void **)&s->blocks.compose = *(void **)&fn[COMPOSE].f;
            s->prob.blocks = &s->blocks;
        }
    } else {
        PyErr_Format(PyExc_ValueError, "unknown system kind %s", kind);
        return -1;
    }
    s->cfn.fn.n = n; /* the outputs a first-order C callback must write */
    return 0;
}

/* Contract: the message of a solve's outcome as a new str: the status table's
 * message, then in parentheses where the failure happened (t, the step budget,
 * for MP_ENONFINITE what produced the value: a C callback's unwritten output,
 * the torque callback, an event function, the Jacobian or the right-hand
 * side) and, when Hairer's test found the problem stiff, the methods to try. */
static PyObject *ode_message(const py_system *sys, const mp_ode_outcome *out, long max_steps)
{
    char detail[256];
    size_t i = out->bad_index;
    double t = out->t_fail;
    int st = out->status;
    if (st == MP_TERMINATED && out->stop_reason == MP_ODE_STOP_MAX_EVENTS) {
        snprintf(detail, sizeof detail, "events[%zu] reached max_events=%ld at t = %.17g",
                 out->stop_event, out->stop_count, t);
        return PyUnicode_FromFormat("%s (%s)", mp_status_message(st), detail);
    }
    if (st == MP_TERMINATED && out->stop_reason == MP_ODE_STOP_ZENO) {
        char gap[64] = "closer than t resolves";
        if (out->zeno_gap > 0.0) snprintf(gap, sizeof gap, "%.3g apart in t", out->zeno_gap);
        snprintf(detail, sizeof detail, "events[%zu] accumulate (Zeno): %ld crossings, the "
                 "last two %s; the solve ends at their accumulation point t = %.17g",
                 out->stop_event, out->stop_count, gap, t);
        return PyUnicode_FromFormat("%s (%s)", mp_status_message(st), detail);
    }
    if (st == MP_OK || st == MP_TERMINATED) return PyUnicode_FromString(mp_status_message(st));
    if (st == MP_EMAXSTEPS) {
        snprintf(detail, sizeof detail, "max_steps=%ld, at t = %.17g", max_steps, t);
    } else if (st == MP_EEVENT) {
        snprintf(detail, sizeof detail, "events[%zu] at t = %.17g; an action must move the "
                 "state off the event surface (reverse the velocity towards it)",
                 out->stop_event, t);
    } else if (st != MP_ENONFINITE) {
        snprintf(detail, sizeof detail, "at t = %.17g", t);
    } else if (out->bad_what == MP_ODE_BAD_ACTION) {
        snprintf(detail, sizeof detail, "events[%zu].action returned NaN or inf at t = %.17g",
                 i, t);
    } else if (out->bad_what == MP_ODE_BAD_EVENT) {
        snprintf(detail, sizeof detail, "events[%zu] returned NaN or inf at t = %.17g", i, t);
    } else if (out->bad_what == MP_ODE_BAD_STATE) {
        snprintf(detail, sizeof detail, "the solution's y[%zu] overflowed to NaN or inf in the "
                 "step from t = %.17g, the right-hand side being finite", i, t);
    } else if (out->bad_what == MP_ODE_BAD_ERR) {
        snprintf(detail, sizeof detail, "a step's error estimate (or Newton increment), scaled "
                 "by atol and rtol, overflowed near t = %.17g, the state and the right-hand side "
                 "being finite: rescale the system", t);
    } else if (out->bad_what == MP_ODE_BAD_JAC) {
        snprintf(detail, sizeof detail, "jac[%zu, %zu] is NaN or inf near t = %.17g",
                 i / sys->prob.n, i % sys->prob.n, t);
    } else if (sys->prob.rhs == c_rhs) {
        snprintf(detail, sizeof detail, "the C callback left dydt[%zu] unwritten or NaN "
                 "(or returned inf) near t = %.17g", i, t);
    } else if (sys->prob.rhs == c_rhs2 && i >= sys->prob.nq) {
        snprintf(detail, sizeof detail, "the C callback left acc[%zu] unwritten or NaN "
                 "(or returned inf) near t = %.17g", i - sys->prob.nq, t);
    } else if (sys->torque.fn && i < 3) {
        snprintf(detail, sizeof detail, "the torque callback left tau[%zu] unwritten or NaN "
                 "(or the right-hand side overflowed) near t = %.17g", i, t);
    } else {
        snprintf(detail, sizeof detail, "the right-hand side gave dydt[%zu] = NaN or inf "
                 "near t = %.17g", i, t);
    }
    return PyUnicode_FromFormat("%s (%s)%s", mp_status_message(st), detail,
                                out->stiff ? "; the problem appears stiff: try method='radau', "
                                             "'auto' or 'gsl:msbdf'" : "");
}

/* ---- results ---------------------------------------------------------------- */

static PyObject *array_from(const double *src, int nd, const npy_intp *shape)
{
    PyArrayObject *a = mp_py_empty(nd, shape);
    if (!a) return NULL;
    npy_intp sz = PyArray_SIZE(a);
    if (sz) memcpy(PyArray_DATA(a), src, (size_t)sz * sizeof(double));
    return (PyObject *)a;
}

/* Contract: r's event lists as Python: one triple (t (c,), y (c, n), rests)
 * per event function, rests the times its body came to rest on a wall and
 * lifted off, alternating (None for an event that never rested: no array
 * for each of an ensemble's many trajectories).  NULL with an exception set. */
static PyObject *event_lists(const mp_ode_result *r)
{
    PyObject *lst = PyList_New((Py_ssize_t)r->n_events);
    if (!lst) return NULL;
    for (size_t q = 0; q < r->n_events; q++) {
        npy_intp c = r->ev_count ? (npy_intp)r->ev_count[q] : 0;
        npy_intp cr = r->rs_count ? (npy_intp)r->rs_count[q] : 0;
        npy_intp e1[1] = {c}, e2[2] = {c, (npy_intp)r->n}, e3[1] = {cr};
        PyObject *et = array_from(c ? r->ev_t[q] : NULL, 1, e1);
        PyObject *ey = array_from(c ? r->ev_y[q] : NULL, 2, e2);
        PyObject *er = cr ? array_from(r->rs_t[q], 1, e3) : Py_NewRef(Py_None);
        PyObject *trip = (et && ey && er) ? Py_BuildValue("(NNN)", et, ey, er) : NULL;
        if (!trip) {
            Py_XDECREF(et);
            Py_XDECREF(ey);
            Py_XDECREF(er);
            Py_DECREF(lst);
            return NULL;
        }
        PyList_SET_ITEM(lst, (Py_ssize_t)q, trip);
    }
    return lst;
}

/* Contract: the tuple ode_solve returns for a finished solve (any status the
 * table lets be a status): (code, message, t (m,), y (m, n), nfev, njev, nlu,
 * nsteps, nreject, dense (seg_t, seg_h, seg_c) or None, events [(t, y) per
 * event function] or None when there are none, backward), code being the C
 * status (MP_TERMINATED for a terminal event). */
static PyObject *result_to_python(const py_system *sys, const mp_ode_result *r, int dense,
                                  long max_steps)
{
    npy_intp n = (npy_intp)r->n, m = (npy_intp)r->m;
    npy_intp s1[1] = {m}, s2[2] = {m, n};
    PyObject *t = array_from(r->t, 1, s1), *y = array_from(r->y, 2, s2);
    PyObject *den = NULL, *ev = NULL, *out = NULL;
    if (!t || !y) goto fail;
    if (dense && r->nseg) {
        npy_intp ns[1] = {(npy_intp)r->nseg}, cs[3] = {(npy_intp)r->nseg, (npy_intp)r->ncoef, n};
        PyObject *st = array_from(r->seg_t, 1, ns), *sh = array_from(r->seg_h, 1, ns),
                 *sc = array_from(r->seg_c, 3, cs);
        den = (st && sh && sc) ? Py_BuildValue("(NNN)", st, sh, sc) : NULL;
        if (!den) {
            Py_XDECREF(st);
            Py_XDECREF(sh);
            Py_XDECREF(sc);
            goto fail;
        }
    } else {
        den = Py_NewRef(Py_None);
    }
    ev = r->n_events ? event_lists(r) : Py_NewRef(Py_None);
    if (!ev) goto fail;
    mp_ode_outcome oc;
    mp_ode_result_outcome(r, &oc);
    PyObject *msg = ode_message(sys, &oc, max_steps);
    if (!msg) goto fail;
    out = Py_BuildValue("(iNNNlllllNNi)", oc.status, msg, t, y, r->nfev, r->njev, r->nlu,
                        r->nsteps, r->nreject, den, ev, r->backward);
    return out;
fail:
    Py_XDECREF(t);
    Py_XDECREF(y);
    Py_XDECREF(den);
    Py_XDECREF(ev);
    return NULL;
}

/* The options ode_solve and ode_solve_many share, as integrate.py hands them
 * over (its _options: nine values in one order), parsed here and nowhere
 * else: ode_solve's as positional arguments (its call is the one whose fixed
 * cost counts), ode_solve_many's as one tuple of the same nine. */
typedef struct {
    double t0, tf, rtol, h, first_step, max_step; /* rtol: the least of the n */
    long max_steps;
    /* owned; atol/rtolv NULL: a scalar in atol1/rtol1; tev NULL: no t_eval */
    PyArrayObject *atol, *rtolv, *tev;
    double *atol1, *rtol1;     /* PyMem: n copies of a scalar atol, rtol */
} ode_args;

static void ode_args_clear(ode_args *a)
{
    Py_CLEAR(a->atol);
    Py_CLEAR(a->rtolv);
    Py_CLEAR(a->tev);
    PyMem_Free(a->atol1);
    PyMem_Free(a->rtol1);
    a->atol1 = a->rtol1 = NULL;
}

/* Contract: n tolerances from obj, a Python float (finite, > 0 when positive,
 * else >= 0; n copies in *copies, PyMem) or n values (*arr, a new reference;
 * their values are the solve's to check): their address, or NULL with an
 * exception set (what was allocated is in *arr / *copies). */
static const double *ode_tolerances(PyObject *obj, const char *name, int positive, size_t n,
                                    PyArrayObject **arr, double **copies)
{
    if (PyFloat_CheckExact(obj)) {
        double v = PyFloat_AS_DOUBLE(obj);
        if (!(positive ? v > 0 : v >= 0) || !isfinite(v)) {
            PyErr_Format(PyExc_ValueError, "%s must be finite and %s, got %R", name,
                         positive ? "positive" : "non-negative", obj);
            return NULL;
        }
        if (!(*copies = PyMem_Malloc((n ? n : 1) * sizeof(double)))) {
            PyErr_NoMemory();
            return NULL;
        }
        for (size_t i = 0; i < n; i++) (*copies)[i] = v;
        return *copies;
    }
    if (!(*arr = mp_py_array(obj, name, 1))) return NULL;
    if ((size_t)PyArray_SIZE(*arr) != n) {
        PyErr_Format(PyExc_ValueError, "%s must be a scalar or have one value per state", name);
        return NULL;
    }
    return PyArray_DATA(*arr);
}

/* Contract: the arrays of a from rtol and atol (each a Python float, taken as
 * n copies, or n values) and t_eval (None or m values), then o from a (o
 * points into a: clear a after the solve; o->rtol the least rtol).  0, or -1
 * with an exception set and a cleared. */
static int ode_args_fill(PyObject *rtolo, PyObject *atolo, PyObject *tevo, size_t n,
                         ode_args *a, mp_ode_options *o)
{
    const double *rtolv = ode_tolerances(rtolo, "rtol", 1, n, &a->rtolv, &a->rtol1);
    const double *atol = rtolv ? ode_tolerances(atolo, "atol", 0, n, &a->atol, &a->atol1)
                               : NULL;
    if (!atol) {
        ode_args_clear(a);
        return -1;
    }
    a->rtol = PyFloat_CheckExact(rtolo) ? PyFloat_AS_DOUBLE(rtolo) : INFINITY;
    for (size_t i = 0; i < n; i++) a->rtol = fmin(a->rtol, rtolv[i]);
    if (tevo != Py_None && !(a->tev = mp_py_array(tevo, "t_eval", 1))) {
        ode_args_clear(a);
        return -1;
    }
    memset(o, 0, sizeof *o);
    o->rtol = a->rtol;
    o->rtolv = rtolv;
    o->atol = atol;
    o->first_step = a->first_step;
    o->max_step = a->max_step;
    o->h = a->h;
    o->max_steps = a->max_steps;
    o->t_eval = a->tev ? PyArray_DATA(a->tev) : NULL;
    o->n_eval = a->tev ? (size_t)PyArray_SIZE(a->tev) : 0;
    o->interrupt = mp_py_check_interrupt;
    return 0;
}

/* Contract: the options from argv[0..8] (t0, tf, rtol, atol, t_eval, h,
 * first_step, max_step, max_steps) into a, and o filled from them (o points
 * into a's arrays: clear a after the solve).  0, or -1 with an exception set. */
static int ode_args_from_argv(PyObject *const *argv, size_t n, ode_args *a, mp_ode_options *o)
{
    double *dst[8] = {&a->t0, &a->tf, NULL, NULL, NULL, &a->h, &a->first_step, &a->max_step};
    memset(a, 0, sizeof *a);
    for (int i = 0; i < 8; i++) {
        if (!dst[i]) continue;
        *dst[i] = PyFloat_AsDouble(argv[i]);
        if (*dst[i] == -1.0 && PyErr_Occurred()) return -1;
    }
    a->max_steps = PyLong_AsLong(argv[8]);
    if (a->max_steps == -1 && PyErr_Occurred()) return -1;
    return ode_args_fill(argv[2], argv[3], argv[4], n, a, o);
}

/* ---- options solve and solve_many share ------------------------------------- */

/* Contract: jaco as a Jacobian for n states: None (*jm NULL), a callable
 * (*jm NULL) or a constant (n, n) finite matrix (*jm a new reference).  0, or
 * -1 with an exception set. */
static int jac_parse(PyObject *jaco, size_t n, PyArrayObject **jm)
{
    *jm = NULL;
    if (jaco == Py_None || PyCallable_Check(jaco)) return 0;
    if (!(*jm = mp_py_array(jaco, "jac", 2))) return -1;
    if ((size_t)PyArray_DIM(*jm, 0) != n || (size_t)PyArray_DIM(*jm, 1) != n) {
        PyErr_Format(PyExc_ValueError, "jac must have shape (%zu, %zu)", n, n);
        return -1;
    }
    return mp_py_require_finite(*jm, "jac");
}

/* Contract: prob with the user's Jacobian (jac_parse's jaco, jm): the
 * constant matrix through cj, or the callable jac(t, y, *args) through wj;
 * returns 1 when it calls Python.  Nothing for None. */
static int jac_wrap(mp_ode_problem *prob, PyObject *jaco, PyArrayObject *jm, PyObject *args,
                    const_jac *cj, py_with_jac *wj)
{
    size_t n = prob->n;
    if (jm) {
        cj->inner = *prob;
        cj->J = PyArray_DATA(jm);
        prob->rhs = const_jac_rhs;
        prob->jac = const_jac_jac;
        prob->jac_const = 1;
        prob->data = cj;
        return 0;
    }
    if (jaco == Py_None) return 0;
    wj->inner = *prob;
    wj->jac = (py_fn){jaco, args, n, n * n, "jac"};
    prob->rhs = py_jac_rhs;
    prob->jac = py_jac;
    prob->data = wj;
    return 1;
}

/* The event list of a solve as integrate.py hands it over: terminal and
 * direction (owned), which events have an action, and whether every event
 * runs in C (impacts alone: no GIL needed). */
typedef struct {
    PyArrayObject *term, *dir;
    unsigned char *has_action; /* PyMem */
    Py_ssize_t count;
    int all_c;
} py_event_list;

static void event_list_clear(py_event_list *el)
{
    Py_CLEAR(el->term);
    Py_CLEAR(el->dir);
    PyMem_Free(el->has_action);
    el->has_action = NULL;
}

/* Whether entry is a C impact: ("impact", iq, iv, wall, e, side, e_param,
 * wall_fn, rest). */
static int is_impact(PyObject *entry)
{
    if (!PyTuple_Check(entry) || PyTuple_GET_SIZE(entry) != 9) return 0;
    PyObject *tag = PyTuple_GET_ITEM(entry, 0);
    return PyUnicode_Check(tag) && PyUnicode_CompareWithASCIIString(tag, "impact") == 0;
}

/* Contract: events[k], an impact tuple ("impact", iq, iv, wall, e, side,
 * e_param, wall_fn, rest) for states of n and parameter vectors of nparams,
 * into *im (its max_events 0, its e the float e or 0: *eo is e as given,
 * borrowed: a float, or one value per trajectory when e_param < 0; wall_fn
 * the address of a compiled mp_wall_fn, 0 for a wall standing at `wall`;
 * rest 1 when the coordinate may rest on the wall).  0, or -1 with an
 * exception set (a coordinate, velocity or parameter out of range). */
static int parse_impact(PyObject *entry, Py_ssize_t k, size_t n, size_t nparams,
                        mp_impact *im, PyObject **eo)
{
    Py_ssize_t iq, iv;
    long ep;
    int rest;
    unsigned long long wf;
    double wall, side;
    const char *tag;
    if (!PyArg_ParseTuple(entry, "snndOdlKp", &tag, &iq, &iv, &wall, eo, &side, &ep, &wf, &rest))
        return -1;
    if (iq < 0 || iv < 0 || (size_t)iq >= n || (size_t)iv >= n ||
        (ep >= 0 && (size_t)ep >= nparams)) {
        PyErr_Format(PyExc_ValueError, "events[%zd]: an impact's coordinate, velocity "
                     "or restitution parameter is out of range", k);
        return -1;
    }
    *im = (mp_impact){(size_t)iq, (size_t)iv, wall, side, 0.0, NULL, ep, 0, NULL, rest};
    if (wf) *(void **)&im->wall_fn = (void *)(uintptr_t)wf; /* an address handed over */
    if (ep < 0 && PyFloat_Check(*eo)) im->e = PyFloat_AS_DOUBLE(*eo);
    return 0;
}

/* Contract: the event list evo (None or a list of entries: a callable g, a
 * pair (g, action) or a C impact tuple) with terminal and direction (one int
 * each) into el and o's event fields; o->events_data and o->action_data are
 * left to the caller (event_fns).  0, or -1 with an exception set. */
static int event_list_parse(PyObject *evo, PyObject *termo, PyObject *diro, py_event_list *el,
                            mp_ode_options *o)
{
    memset(el, 0, sizeof *el);
    if (evo == Py_None) return 0;
    if ((el->count = PyList_Size(evo)) < 0) return -1;
    if (el->count == 0) return 0;
    el->term = (PyArrayObject *)PyArray_FROMANY(termo, NPY_INT, 1, 1, NPY_ARRAY_IN_ARRAY);
    el->dir = (PyArrayObject *)PyArray_FROMANY(diro, NPY_INT, 1, 1, NPY_ARRAY_IN_ARRAY);
    if (!el->term || !el->dir) return -1;
    if (PyArray_SIZE(el->term) != el->count || PyArray_SIZE(el->dir) != el->count) {
        PyErr_SetString(PyExc_ValueError, "terminal and direction need one value per event");
        return -1;
    }
    if (!(el->has_action = PyMem_Calloc((size_t)el->count, 1))) {
        PyErr_NoMemory();
        return -1;
    }
    el->all_c = 1;
    for (Py_ssize_t k = 0; k < el->count; k++) {
        PyObject *entry = PyList_GET_ITEM(evo, k);
        int imp = is_impact(entry), pair = !imp && PyTuple_Check(entry);
        if (pair && (PyTuple_GET_SIZE(entry) != 2 ||
                     !PyCallable_Check(PyTuple_GET_ITEM(entry, 0)) ||
                     !PyCallable_Check(PyTuple_GET_ITEM(entry, 1)))) {
            PyErr_Format(PyExc_TypeError, "events[%zd] must be callable", k);
            return -1;
        }
        el->has_action[k] = (unsigned char)(imp || pair);
        el->all_c &= imp;
        if (imp) o->impact_of = py_events_impact;
    }
    o->n_events = (size_t)el->count;
    o->events = py_events_eval;
    o->terminal = PyArray_DATA(el->term);
    o->direction = PyArray_DATA(el->dir);
    o->has_action = el->has_action;
    o->action = py_events_action;
    return 0;
}

/* Contract: pe's adapters of the entries in evo for states of n: each Python
 * event and action called with (t, y, *args), each impact's parameters (with
 * e_rows (the trajectory's restitution per event, or NULL) and params, the
 * trajectory's parameter vector).  pe->fns, acts, imp are PyMem (the caller
 * frees them with event_fns_free).  0, or -1 with an exception set. */
static int event_fns(PyObject *evo, Py_ssize_t count, PyObject *args, size_t n,
                     const double *params, size_t nparams, size_t row, py_events *pe)
{
    memset(pe, 0, sizeof *pe);
    pe->count = (size_t)count;
    pe->n = n;
    pe->params = params;
    pe->fns = PyMem_Calloc((size_t)count, sizeof(py_fn));
    pe->acts = PyMem_Calloc((size_t)count, sizeof(py_fn));
    pe->imp = PyMem_Calloc((size_t)count, sizeof(mp_impact));
    pe->names = PyMem_Calloc(2 * (size_t)count, sizeof *pe->names);
    if (!pe->fns || !pe->acts || !pe->imp || !pe->names) {
        PyErr_NoMemory();
        return -1;
    }
    for (Py_ssize_t k = 0; k < count; k++) {
        PyObject *entry = PyList_GET_ITEM(evo, k);
        if (is_impact(entry)) {
            PyObject *eo;
            if (parse_impact(entry, k, n, nparams, &pe->imp[k], &eo) < 0) return -1;
            if (pe->imp[k].e_param >= 0 || PyFloat_Check(eo)) continue;
            /* one restitution per trajectory: this one's row */
            PyArrayObject *ea = mp_py_array(eo, "restitution", 1);
            if (!ea) return -1;
            if ((size_t)PyArray_SIZE(ea) <= row) {
                Py_DECREF(ea);
                PyErr_Format(PyExc_ValueError, "events[%zd]: restitution needs one value "
                             "per trajectory", k);
                return -1;
            }
            pe->imp[k].e = ((const double *)PyArray_DATA(ea))[row];
            Py_DECREF(ea);
            continue;
        }
        PyObject *g = PyTuple_Check(entry) ? PyTuple_GET_ITEM(entry, 0) : entry;
        snprintf(pe->names[2 * k], sizeof pe->names[0], "events[%zd]", k);
        snprintf(pe->names[2 * k + 1], sizeof pe->names[0], "events[%zd].action", k);
        pe->fns[k] = (py_fn){g, args, n, 1, pe->names[2 * k]};
        if (PyTuple_Check(entry))
            pe->acts[k] = (py_fn){PyTuple_GET_ITEM(entry, 1), args, n, n, pe->names[2 * k + 1]};
    }
    return 0;
}

static void event_fns_free(py_events *pe)
{
    PyMem_Free(pe->fns);
    PyMem_Free(pe->acts);
    PyMem_Free(pe->imp);
    PyMem_Free(pe->names);
    memset(pe, 0, sizeof *pe);
}

/* Contract: the Jacobian's band of integrate.py's _jac_band set on p (of n
 * states): None (dense), 0 <= ml, mu < n, or (ml, mu, perm) with perm a
 * permutation of 0..n-1 (a sequence of ints), copied into *perm_out, which
 * the caller frees with PyMem_Free; -1 with an exception for anything else. */
static int band_parse(PyObject *band, size_t n, mp_ode_problem *p, size_t **perm_out)
{
    *perm_out = NULL;
    if (band == Py_None) return 0;
    Py_ssize_t ml = -1, mu = -1;
    PyObject *permo = Py_None;
    if (!PyTuple_Check(band) ||
        !PyArg_ParseTuple(band, "nn|O;band must be a tuple (ml, mu[, perm])", &ml, &mu, &permo)) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_TypeError, "band must be a tuple (ml, mu)");
        return -1;
    }
    if (ml < 0 || mu < 0 || (size_t)ml >= n || (size_t)mu >= n) {
        PyErr_Format(PyExc_ValueError, "band (ml, mu) must be >= 0 and < n = %zu", n);
        return -1;
    }
    if (permo != Py_None) {
        PyObject *seq = PySequence_Fast(permo, "band's perm must be a sequence");
        if (!seq) return -1;
        size_t *perm = PyMem_Calloc(n ? n : 1, sizeof *perm);
        unsigned char *seen = PyMem_Calloc(n ? n : 1, 1);
        int ok = perm && seen && (size_t)PySequence_Fast_GET_SIZE(seq) == n;
        for (size_t i = 0; ok && i < n; i++) {
            Py_ssize_t v = PyLong_AsSsize_t(PySequence_Fast_GET_ITEM(seq, (Py_ssize_t)i));
            ok = v >= 0 && (size_t)v < n && !seen[v];
            if (ok) seen[v] = 1, perm[i] = (size_t)v;
        }
        Py_DECREF(seq);
        PyMem_Free(seen);
        if (!ok) {
            PyMem_Free(perm);
            if (!PyErr_Occurred())
                PyErr_Format(PyExc_ValueError, "band's perm must be a permutation of 0..%zu",
                             n ? n - 1 : 0);
            return -1;
        }
        p->perm = *perm_out = perm;
    }
    p->banded = 1;
    p->ml = (size_t)ml;
    p->mu = (size_t)mu;
    return 0;
}

/* ---- ode_solve ------------------------------------------------------------ */

/* Contract: ode_solve(method, system, y0, t0, tf, rtol, atol, t_eval, h,
 * first_step, max_step, max_steps, dense, events, terminal, direction, args,
 * jac, watch, band), all positional (its fixed cost is the cost of a small
 * solve; integrate.py has validated them; band: None or the Jacobian's
 * (ml, mu), mp_ode_problem's) -> the tuple of result_to_python.  A
 * failure the status table marks as always raising (a callback's exception,
 * Ctrl-C, memory) raises; every other outcome is returned with its code and
 * message (integrate.py decides, from the same table, what raises). */
static PyObject *py_ode_solve(PyObject *self, PyObject *const *argv, Py_ssize_t nargs)
{
    (void)self;
    if (nargs != 20) {
        PyErr_Format(PyExc_TypeError, "ode_solve takes 20 arguments, got %zd", nargs);
        return NULL;
    }
    const char *mname = PyUnicode_Check(argv[0]) ? PyUnicode_AsUTF8(argv[0]) : NULL;
    if (!mname) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_TypeError, "method must be a str");
        return NULL;
    }
    PyObject *spec = argv[1], *y0o = argv[2], *evo = argv[13], *termo = argv[14],
             *diro = argv[15], *eargs = argv[16], *jaco = argv[17], *watch = argv[18];
    int dense = PyObject_IsTrue(argv[12]);
    if (dense < 0) return NULL;
    if (!PyTuple_Check(spec) || !PyTuple_Check(eargs)) {
        PyErr_SetString(PyExc_TypeError, "system spec and args must be tuples");
        return NULL;
    }
    if (watch != Py_None && !PyList_Check(watch)) {
        PyErr_SetString(PyExc_TypeError, "watch must be a list");
        return NULL;
    }
    const mp_ode_method *m = mp_ode_method_find(mname);
    if (!m) {
        PyErr_Format(PyExc_ValueError, "unknown method %s", mname);
        return NULL;
    }
    PyArrayObject *y0 = NULL, *jm = NULL;
    PyObject *result = NULL;
    size_t *perm = NULL;
    py_event_list el = {0};
    ode_args oa = {0};
    mp_ode_options o;
    py_system sys;
    py_with_jac wj;
    py_watched wd;
    const_jac cj;
    py_events pe;
    memset(&pe, 0, sizeof pe);
    memset(&sys, 0, sizeof sys);

    y0 = mp_py_array(y0o, "y0", 1);
    if (!y0 || mp_py_require_finite(y0, "y0") < 0) goto out;
    size_t n = (size_t)PyArray_SIZE(y0);
    if (ode_args_from_argv(argv + 3, n, &oa, &o) < 0) goto out;
    if (py_system_parse(spec, n, &sys) < 0) goto out;
    mp_ode_problem prob = sys.prob;
    if (band_parse(argv[19], n, &prob, &perm) < 0) goto out;
    int holds_python = sys.holds_python;
    if (m->symplectic && !m->implicit && prob.nq == 0) { /* the scene rows say which are */
        char why[256];
        const char *kind = PyUnicode_AsUTF8(PyTuple_GET_ITEM(spec, 0));
        mp_model_separable_hint(kind && strcmp(kind, "scene") == 0
                                    ? PyUnicode_AsUTF8(PyTuple_GET_ITEM(spec, 1)) : NULL,
                                why, sizeof why);
        PyErr_Format(PyExc_ValueError,
                     "method %s needs a separable system q'' = a(t, q) with y = (q, v): %s",
                     m->name, why);
        goto out;
    }
    if (watch != Py_None) { /* a ctypes callback that runs Python: hold the GIL, check */
        watch_problem(&prob, &wd, watch);
        holds_python = 1;
    }
    if (jac_parse(jaco, n, &jm) < 0) goto out;
    holds_python |= jac_wrap(&prob, jaco, jm, eargs, &cj, &wj);
    o.dense = dense;
    if (event_list_parse(evo, termo, diro, &el, &o) < 0) goto out;
    if (el.count) {
        if (event_fns(evo, el.count, eargs, n, sys.params ? PyArray_DATA(sys.params) : NULL,
                      sys.params ? (size_t)PyArray_SIZE(sys.params) : 0, 0, &pe) < 0)
            goto out;
        o.events_data = o.action_data = &pe;
        holds_python |= !el.all_c; /* impacts alone run in C */
    }

    prob.replayable = !holds_python; /* plain C all through: a block may be run again */
    mp_ode_result r;
    int rc;
    if (holds_python) {
        rc = mp_ode_solve(m, &prob, oa.t0, oa.tf, PyArray_DATA(y0), &o, &r);
    } else {
        Py_BEGIN_ALLOW_THREADS
        rc = mp_ode_solve(m, &prob, oa.t0, oa.tf, PyArray_DATA(y0), &o, &r);
        Py_END_ALLOW_THREADS
    }
    if (mp_status_lookup(rc)->raises == 2) mp_py_raise(rc, "solve");
    else result = result_to_python(&sys, &r, dense, oa.max_steps);
    mp_ode_result_free(&r);
out:
    py_system_clear(&sys);
    ode_args_clear(&oa);
    event_fns_free(&pe);
    event_list_clear(&el);
    Py_XDECREF(y0);
    Py_XDECREF(jm);
    PyMem_Free(perm);
    return result;
}

/* ---- ode_solve_many ----------------------------------------------------- */

/* Progress of an ensemble: what the callback below is handed as ctx. */
typedef struct {
    size_t last;       /* trajectories done at the last report */
    PyObject *report;  /* Python callable report(done, total), or NULL for a stderr line */
} many_progress_ctx;

/* Called by mp_ode_solve_many (from any worker thread, GIL not held) as
 * trajectories finish; reports at most once per percent and at the end, to
 * ctx->report(done, total) or as a line on stderr.  An exception raised by
 * the callable is printed as unraisable and ignored: progress never stops a
 * solve. */
static void many_progress(size_t done, size_t total, void *ctx)
{
    many_progress_ctx *c = ctx;
    if (done != total && done * 100 / total == c->last * 100 / total) return;
    c->last = done;
    PyGILState_STATE g = PyGILState_Ensure();
    if (c->report) {
        PyObject *r = PyObject_CallFunction(c->report, "nn", (Py_ssize_t)done, (Py_ssize_t)total);
        if (r) Py_DECREF(r);
        else PyErr_WriteUnraisable(c->report);
    } else {
        PySys_WriteStderr("\rsolve_many: %zu/%zu trajectories%s", done, total,
                          done == total ? "\n" : "");
    }
    PyGILState_Release(g);
}

/* Contract: the names of the methods whose rows run in lanes, for a message. */
static void lane_method_names(char *buf, size_t len)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t i = 0; mp_ode_methods[i] && used < len; i++)
        if (mp_ode_methods[i]->lanes != MP_LANE_NONE)
            used += (size_t)snprintf(buf + used, len - used, "%s%s", used ? ", " : "",
                                     mp_ode_methods[i]->name);
}

/* Contract: the Python exception for mp_ode_ensemble_build's refusal. */
static void ensemble_error(const mp_ode_ensemble *e, int rc, const char *kind)
{
    if (rc != MP_EDOM) {
        mp_py_raise(rc, "solve_many");
        return;
    }
    const char *scene = e->model ? e->model->name : "the system";
    char names[128], ctx[128];
    switch (e->why) {
    case MP_ENS_SEPARABLE:
        PyErr_Format(PyExc_ValueError, "method %s needs a separable system q'' = a(t, q)",
                     e->m->name);
        break;
    case MP_ENS_COLUMNS:
        PyErr_Format(PyExc_ValueError, "params must have %zu columns (%s's parameters)",
                     e->np_need, scene);
        break;
    case MP_ENS_ROW:
        snprintf(ctx, sizeof ctx, "params[%zu] (%s's parameters for a state of %zu)",
                 e->bad_row, scene, e->n);
        mp_py_raise(MP_EDOM, ctx);
        break;
    case MP_ENS_NO_LANES:
        if (e->base.sw) {
            PyErr_Format(PyExc_ValueError, "lanes=True: %s has a switch of its right-hand side "
                         "(a discontinuity the engine crosses as an event), which the lanes do "
                         "not take; use lanes=None or False", scene);
            break;
        }
        lane_method_names(names, sizeof names);
        PyErr_Format(PyExc_ValueError, "lanes=True needs a scene or compiled system, a method "
                     "that runs in lanes (%s), no dense output and no events but impacts (got %s "
                     "with a %s system)", names, e->m->name, kind);
        break;
    default:
        mp_py_raise(rc, "solve_many");
    }
}

/* The per-trajectory adapters of an ensemble whose rows or callbacks are
 * Python's: each trajectory's argument tuple (its row, then args), its
 * Python or C callback, events, Jacobian and watch wrappers. */
typedef struct {
    size_t k;
    PyObject **tuples;      /* k new references, or NULL */
    py_fn *fns;
    c_fn *cfns;
    py_events *evs;
    void **evdata;          /* k pointers: &evs[i] (each trajectory's events_data) */
    const_jac *cjs;
    py_with_jac *wjs;
    py_watched *watched;
    size_t nimp;
    mp_ode_result *results; /* with events: each trajectory's whole result */
    mp_impact *imps;        /* the events as the lanes run them (all impacts), or NULL */
    PyArrayObject **imp_e;  /* ... their per-trajectory restitutions (owned) */
} many_adapters;

static void many_adapters_clear(many_adapters *a)
{
    if (a->tuples)
        for (size_t i = 0; i < a->k; i++) Py_XDECREF(a->tuples[i]);
    if (a->results)
        for (size_t i = 0; i < a->k; i++) mp_ode_result_free(&a->results[i]);
    PyMem_Free(a->tuples);
    PyMem_Free(a->fns);
    PyMem_Free(a->cfns);
    if (a->evs)
        for (size_t i = 0; i < a->k; i++) event_fns_free(&a->evs[i]);
    PyMem_Free(a->evs);
    PyMem_Free(a->evdata);
    PyMem_Free(a->cjs);
    PyMem_Free(a->wjs);
    PyMem_Free(a->watched);
    PyMem_Free(a->results);
    if (a->imp_e)
        for (size_t q = 0; a->imps && q < a->nimp; q++) Py_XDECREF(a->imp_e[q]);
    PyMem_Free(a->imp_e);
    PyMem_Free(a->imps);
    memset(a, 0, sizeof *a);
}

/* Contract: the event entries evo (all C impacts: el->all_c) as the lanes run
 * them, into a->imps (n_events of them; states of n, parameter rows of
 * nparams), when each is an impact reached downwards (its direction -1): 1,
 * or 0 when the lanes cannot run them, or -1 with an exception set. */
static int many_lane_impacts(many_adapters *a, PyObject *evo, const py_event_list *el, size_t k,
                             size_t n, size_t nparams)
{
    size_t ne = (size_t)el->count;
    const int *dir = PyArray_DATA(el->dir), *term = PyArray_DATA(el->term);
    for (size_t q = 0; q < ne; q++)
        if (dir[q] != -1) return 0;
    a->imps = PyMem_Calloc(ne, sizeof *a->imps);
    a->imp_e = PyMem_Calloc(ne, sizeof *a->imp_e);
    a->nimp = ne;
    if (!a->imps || !a->imp_e) {
        PyErr_NoMemory();
        return -1;
    }
    for (size_t q = 0; q < ne; q++) {
        mp_impact *im = &a->imps[q];
        PyObject *eo;
        if (parse_impact(PyList_GET_ITEM(evo, (Py_ssize_t)q), (Py_ssize_t)q, n, nparams, im,
                         &eo) < 0)
            return -1;
        im->max_events = term[q];
        if (im->e_param >= 0 || PyFloat_Check(eo)) continue;
        if (!(a->imp_e[q] = mp_py_array(eo, "restitution", 1))) return -1;
        if ((size_t)PyArray_SIZE(a->imp_e[q]) != k) {
            PyErr_SetString(PyExc_ValueError, "restitution needs one value per trajectory");
            return -1;
        }
        im->e_rows = PyArray_DATA(a->imp_e[q]);
    }
    return 1;
}

/* Contract: trajectory i's rows of a Python system as leading extra
 * arguments: tuples[i] = (*row, *eargs).  0, or -1 with an exception set. */
static int many_row_tuples(many_adapters *a, const double *rows, size_t np, PyObject *eargs)
{
    if (!(a->tuples = PyMem_Calloc(a->k, sizeof *a->tuples))) {
        PyErr_NoMemory();
        return -1;
    }
    Py_ssize_t na = PyTuple_GET_SIZE(eargs);
    for (size_t i = 0; i < a->k; i++) {
        PyObject *tup = PyTuple_New((Py_ssize_t)np + na);
        if (!tup) return -1;
        a->tuples[i] = tup;
        for (size_t j = 0; j < np; j++) {
            PyObject *v = PyFloat_FromDouble(rows[i * np + j]);
            if (!v) return -1;
            PyTuple_SET_ITEM(tup, (Py_ssize_t)j, v);
        }
        for (Py_ssize_t j = 0; j < na; j++)
            PyTuple_SET_ITEM(tup, (Py_ssize_t)np + j, Py_NewRef(PyTuple_GET_ITEM(eargs, j)));
    }
    return 0;
}

/* Contract: an ensemble's trajectory table, events and samples as Python
 * objects: {"y": (k, n, m), "code": (k,) C statuses, "message": k str,
 * "nfev": (k,), "lanes": bool, "events": k lists [(t, y) per event function]
 * or None}. */
static PyObject *many_result(const py_system *sys, const mp_ode_outcome *outc,
                             const mp_ode_result *results, size_t k, PyArrayObject *yout,
                             int lanes, long max_steps)
{
    npy_intp ks[1] = {(npy_intp)k};
    PyArrayObject *st = (PyArrayObject *)PyArray_SimpleNew(1, ks, NPY_INT);
    PyArrayObject *nf = (PyArrayObject *)PyArray_SimpleNew(1, ks, NPY_LONG);
    PyObject *msgs = PyList_New((Py_ssize_t)k), *evs = NULL, *result = NULL;
    if (!st || !nf || !msgs) goto out;
    for (size_t i = 0; i < k; i++) {
        ((int *)PyArray_DATA(st))[i] = outc[i].status;
        ((long *)PyArray_DATA(nf))[i] = outc[i].nfev;
        PyObject *msg = ode_message(sys, &outc[i], max_steps);
        if (!msg) goto out;
        PyList_SET_ITEM(msgs, (Py_ssize_t)i, msg);
    }
    if (results) {
        if (!(evs = PyList_New((Py_ssize_t)k))) goto out;
        for (size_t i = 0; i < k; i++) {
            PyObject *lst = event_lists(&results[i]);
            if (!lst) goto out;
            PyList_SET_ITEM(evs, (Py_ssize_t)i, lst);
        }
    } else {
        evs = Py_NewRef(Py_None);
    }
    result = Py_BuildValue("{s:O,s:O,s:O,s:O,s:O,s:O}", "y", yout, "code", st, "message", msgs,
                           "nfev", nf, "lanes", lanes ? Py_True : Py_False, "events", evs);
out:
    Py_XDECREF(st);
    Py_XDECREF(nf);
    Py_XDECREF(msgs);
    Py_XDECREF(evs);
    return result;
}

/* Contract: ode_solve_many(method, system, y0s, options, *, params, args,
 * threads, progress, watch, lanes, events, terminal, direction, jac) -> see
 * many_result.  options: the nine values of ode_solve's options (integrate.py's
 * _options; t_eval required); events, terminal, direction and jac as
 * ode_solve takes them (an event function and jac are called as fun is, with
 * a trajectory's row before args).  lanes: -1 when possible, 0 never, 1
 * always (ValueError when not possible).  The binding parses and translates;
 * the ensemble's problems and its lanes are mp_ode_ensemble_build's.  An
 * ensemble stopped by a callback's exception, Ctrl-C or memory raises. */
static PyObject *py_ode_solve_many(PyObject *self, PyObject *args, PyObject *kw)
{
    (void)self;
    static char *kwlist[] = {"method", "system", "y0s", "options", "params", "args", "threads",
                             "progress", "watch", "lanes", "events", "terminal", "direction",
                             "jac", "band", NULL};
    const char *mname;
    PyObject *spec, *y0o, *opts, *paro = Py_None, *eargs = NULL, *watch = Py_None;
    PyObject *evo = Py_None, *termo = Py_None, *diro = Py_None, *jaco = Py_None;
    PyObject *bando = Py_None;
    int threads = 1, want_lanes = -1;
    PyObject *progress = Py_False; /* False, True (a stderr line) or a callable report(done, total) */
    if (!PyArg_ParseTupleAndKeywords(args, kw, "sOOO!|$OO!iOOiOOOOO", kwlist, &mname, &spec,
                                     &y0o, &PyTuple_Type, &opts, &paro, &PyTuple_Type, &eargs,
                                     &threads, &progress, &watch, &want_lanes, &evo, &termo,
                                     &diro, &jaco, &bando))
        return NULL;
    if (PyTuple_GET_SIZE(opts) != 9) {
        PyErr_SetString(PyExc_TypeError, "options: t0, tf, rtol, atol, t_eval, h, first_step, "
                                         "max_step and max_steps");
        return NULL;
    }
    if (watch != Py_None && !PyList_Check(watch)) {
        PyErr_SetString(PyExc_TypeError, "watch must be a list");
        return NULL;
    }
    const mp_ode_method *m = mp_ode_method_find(mname);
    if (!m) return PyErr_Format(PyExc_ValueError, "unknown method %s", mname);
    if (!eargs) eargs = PyTuple_New(0);
    else Py_INCREF(eargs);
    if (!eargs) return NULL;
    PyArrayObject *y0s = NULL, *par = NULL, *yout = NULL, *jm = NULL;
    PyObject *result = NULL;
    ode_args oa = {0};
    mp_ode_options o;
    mp_ode_outcome *outc = NULL;
    py_event_list el = {0};
    many_adapters ad = {0};
    mp_ode_ensemble ens = {0};
    py_system sys;
    memset(&sys, 0, sizeof sys);
    size_t k = 0, np = 0;
    size_t *perm = NULL;

    if (!(y0s = mp_py_array(y0o, "y0s", 2))) goto out;
    k = ad.k = (size_t)PyArray_DIM(y0s, 0);
    size_t n = (size_t)PyArray_DIM(y0s, 1);
    if (ode_args_from_argv(&PyTuple_GET_ITEM(opts, 0), n, &oa, &o) < 0) goto out;
    if (!oa.tev) {
        PyErr_SetString(PyExc_ValueError, "solve_many needs t_eval");
        goto out;
    }
    if (paro != Py_None) {
        if (!(par = mp_py_array(paro, "params", 2))) goto out;
        if ((size_t)PyArray_DIM(par, 0) != k) {
            PyErr_SetString(PyExc_ValueError, "params must have one row per trajectory");
            goto out;
        }
        np = (size_t)PyArray_DIM(par, 1);
    }
    if (py_system_parse(spec, n, &sys) < 0) goto out;
    if (band_parse(bando, n, &sys.prob, &perm) < 0) goto out;
    const char *kind = PyUnicode_AsUTF8(PyTuple_GET_ITEM(spec, 0));
    if (par && !sys.model && !sys.params && !sys.holds_python && sys.cfn.nq) {
        PyErr_SetString(PyExc_ValueError, "params are not supported for SecondOrder C callbacks");
        goto out;
    }
    if (jac_parse(jaco, n, &jm) < 0 || event_list_parse(evo, termo, diro, &el, &o) < 0)
        goto out;
    const double *rows = par ? PyArray_DATA(par) : NULL;
    /* the parameter vector each trajectory's events see (an impact's e_param) */
    size_t nparams = sys.params ? (size_t)PyArray_SIZE(sys.params) : 0;
    size_t npar = par && (sys.model || sys.params) ? np : nparams;
    int lane_imps = 0; /* impacts alone: the lanes run them too */
    if (el.count && el.all_c &&
        (lane_imps = many_lane_impacts(&ad, evo, &el, k, n, npar)) < 0)
        goto out;
    ens = (mp_ode_ensemble){
        .m = m, .base = sys.prob, .k = k, .n = n, .rows = rows, .np = np,
        .rows_kind = !par ? MP_ENS_ROWS_NONE : sys.model ? MP_ENS_ROWS_SCENE
                   : sys.params ? MP_ENS_ROWS_DATA : MP_ENS_ROWS_CALLER,
        .model = sys.model, .params = sys.params ? PyArray_DATA(sys.params) : NULL,
        .nparams = nparams,
        .torque = sys.torque.fn ? &sys.torque : NULL, .lane_rhs = sys.lanes,
        .holds_python = sys.holds_python || watch != Py_None || (jaco != Py_None && !jm) ||
                        (el.count && !el.all_c),
        .want_lanes = want_lanes, .impacts = lane_imps > 0 ? ad.imps : NULL,
        .n_impacts = lane_imps > 0 ? ad.nimp : 0};
    int rc = mp_ode_ensemble_build(&ens, oa.t0, oa.tf, &o);
    if (rc != MP_OK) {
        ensemble_error(&ens, rc, kind);
        goto out;
    }
    /* the caller's part: Python rows and callbacks, events, Jacobians, watches */
    if (par && ens.rows_kind == MP_ENS_ROWS_CALLER) {
        if (sys.holds_python) {
            if (many_row_tuples(&ad, rows, np, eargs) < 0) goto out;
            if (!(ad.fns = PyMem_Calloc(k, sizeof *ad.fns))) goto nomem;
            for (size_t i = 0; i < k; i++) {
                ad.fns[i] = sys.fn;
                ad.fns[i].args = ad.tuples[i];
                ens.probs[i].data = &ad.fns[i];
            }
        } else { /* a C callback gets a pointer to its row as user_data */
            if (!(ad.cfns = PyMem_Calloc(k, sizeof *ad.cfns))) goto nomem;
            for (size_t i = 0; i < k; i++) {
                ad.cfns[i] = sys.cfn.fn;
                ad.cfns[i].user_data = (double *)rows + i * np;
                ens.probs[i].data = &ad.cfns[i];
            }
        }
    }
    if (k && watch != Py_None) { /* a ctypes callback that runs Python: see py_watched */
        if (!(ad.watched = PyMem_Calloc(k, sizeof *ad.watched))) goto nomem;
        for (size_t i = 0; i < k; i++) watch_problem(&ens.probs[i], &ad.watched[i], watch);
    }
    if (k && jaco != Py_None) {
        if (!(ad.cjs = PyMem_Calloc(k, sizeof *ad.cjs)) ||
            !(ad.wjs = PyMem_Calloc(k, sizeof *ad.wjs)))
            goto nomem;
        for (size_t i = 0; i < k; i++)
            jac_wrap(&ens.probs[i], jaco, jm, ad.tuples ? ad.tuples[i] : eargs, &ad.cjs[i],
                     &ad.wjs[i]);
    }
    if (k && el.count) { /* each trajectory's event adapters (its args) and whole result */
        if (!(ad.evs = PyMem_Calloc(k, sizeof *ad.evs)) ||
            !(ad.evdata = PyMem_Calloc(k, sizeof *ad.evdata)) ||
            !(ad.results = PyMem_Calloc(k, sizeof *ad.results)))
            goto nomem;
        for (size_t i = 0; i < k; i++) {
            const double *pv = rows && ens.rows_kind != MP_ENS_ROWS_CALLER ? rows + i * np
                                                                            : ens.params;
            if (event_fns(evo, el.count, ad.tuples ? ad.tuples[i] : eargs, n, pv, npar, i,
                          &ad.evs[i]) < 0)
                goto out;
            ad.evdata[i] = &ad.evs[i];
        }
    }
    if (!(outc = PyMem_Calloc(k ? k : 1, sizeof *outc))) goto nomem;
    npy_intp shape[3] = {(npy_intp)k, (npy_intp)n, (npy_intp)o.n_eval};
    if (!(yout = mp_py_empty(3, shape))) goto out;
    many_progress_ctx pctx = {0, PyCallable_Check(progress) ? progress : NULL};
    void (*report)(size_t, size_t, void *) =
        pctx.report || PyObject_IsTrue(progress) == 1 ? many_progress : NULL;
    if (ens.holds_python) {
        rc = mp_ode_solve_many(m, ens.probs, NULL, k, oa.t0, oa.tf, PyArray_DATA(y0s), &o, 1,
                               PyArray_DATA(yout), outc, ad.results, ad.evdata, report, &pctx);
    } else {
        Py_BEGIN_ALLOW_THREADS
        rc = mp_ode_solve_many(m, ens.probs, ens.lanes, k, oa.t0, oa.tf, PyArray_DATA(y0s), &o,
                               threads, PyArray_DATA(yout), outc, ad.results, ad.evdata, report,
                               &pctx);
        Py_END_ALLOW_THREADS
    }
    if (rc != MP_OK) {
        mp_py_raise(rc, "solve_many");
        goto out;
    }
    result = many_result(&sys, outc, ad.results, k, yout, ens.lanes != NULL, oa.max_steps);
    goto out;
nomem:
    PyErr_NoMemory();
out:
    many_adapters_clear(&ad);
    mp_ode_ensemble_free(&ens);
    PyMem_Free(outc);
    py_system_clear(&sys);
    ode_args_clear(&oa);
    event_list_clear(&el);
    Py_XDECREF(eargs);
    Py_XDECREF(y0s);
    Py_XDECREF(par);
    Py_XDECREF(yout);
    Py_XDECREF(jm);
    PyMem_Free(perm);
    return result;
}

static PyObject *py_ode_dense_eval(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *sto, *sho, *sco, *tqo;
    if (!PyArg_ParseTuple(args, "OOOO", &sto, &sho, &sco, &tqo)) return NULL;
    PyArrayObject *st = mp_py_array(sto, "seg_t", 1), *sh = mp_py_array(sho, "seg_h", 1),
                  *sc = mp_py_array(sco, "seg_c", 3), *tq = mp_py_array(tqo, "t", 1);
    PyArrayObject *out = NULL;
    if (!st || !sh || !sc || !tq) goto done;
    npy_intp nseg = PyArray_DIM(sc, 0), ncoef = PyArray_DIM(sc, 1), n = PyArray_DIM(sc, 2);
    if (PyArray_SIZE(st) != nseg || PyArray_SIZE(sh) != nseg || nseg == 0) {
        PyErr_SetString(PyExc_ValueError, "inconsistent dense output segments");
        goto done;
    }
    npy_intp shape[2] = {PyArray_SIZE(tq), n};
    out = mp_py_empty(2, shape);
    if (!out) goto done;
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_ode_result_dense_eval((size_t)n, (size_t)ncoef, (size_t)nseg, PyArray_DATA(st),
                                  PyArray_DATA(sh), PyArray_DATA(sc), PyArray_DATA(tq),
                                  (size_t)shape[0], PyArray_DATA(out));
    Py_END_ALLOW_THREADS
    if (rc != MP_OK) {
        Py_CLEAR(out);
        mp_py_raise(rc, "dense output: t must be finite");
    }
done:
    Py_XDECREF(st);
    Py_XDECREF(sh);
    Py_XDECREF(sc);
    Py_XDECREF(tq);
    return (PyObject *)out;
}

static PyObject *py_ode_methods(PyObject *self, PyObject *unused)
{
    (void)self;
    (void)unused;
    PyObject *lst = PyList_New(0);
    if (!lst) return NULL;
    for (size_t i = 0; mp_ode_methods[i]; i++) {
        const mp_ode_method *m = mp_ode_methods[i];
        PyObject *d = Py_BuildValue(
            "{s:s,s:i,s:O,s:O,s:O,s:O,s:i,s:O,s:O,s:O}", "name", m->name, "order", m->order,
            "adaptive", m->adaptive ? Py_True : Py_False, "implicit",
            m->implicit ? Py_True : Py_False, "symplectic", m->symplectic ? Py_True : Py_False,
            "needs_jacobian", m->needs_jacobian ? Py_True : Py_False, "dense_output",
            m->dense_order, "lanes", m->lanes != MP_LANE_NONE ? Py_True : Py_False, "rigid",
            m->rigid ? Py_True : Py_False, "compensated", m->compensated ? Py_True : Py_False);
        if (!d || PyList_Append(lst, d) < 0) {
            Py_XDECREF(d);
            Py_DECREF(lst);
            return NULL;
        }
        Py_DECREF(d);
    }
    return lst;
}

PyMethodDef mp_py_ode_methods[] = {
    {"ode_solve", (PyCFunction)(void (*)(void))py_ode_solve, METH_FASTCALL,
     "Integrate an ODE system (internal; use mechpy.solve)."},
    {"ode_solve_many", (PyCFunction)(void (*)(void))py_ode_solve_many,
     METH_VARARGS | METH_KEYWORDS, "Integrate an ensemble (internal; use mechpy.solve_many)."},
    {"ode_dense_eval", py_ode_dense_eval, METH_VARARGS,
     "Evaluate stored dense output (internal)."},
    {"ode_methods", py_ode_methods, METH_NOARGS, "The method table (internal)."},
    {NULL, NULL, 0, NULL},
};
