/* Binding for the integrator engine: the calls ode_solve and ode_solve_many
 * (one options object, parsed in one place), their results and messages,
 * dense output and the method table.  Systems and their adapters are
 * py_system.c's, events py_events.c's (see py_ode.h). */
#include "py_ode.h"

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

/* ---- messages ---------------------------------------------------------------- */

/* Contract: the detail (enum mp_status_detail) of a solve's outcome, its
 * fields set in f: where the failure happened and, for MP_ENONFINITE, what
 * produced the value (an event function or action, the state, the error
 * norm, the Jacobian, then by the system's kind: a C callback's unwritten
 * output, the torque callback or the right-hand side). */
static int ode_detail(const py_system *sys, const mp_ode_outcome *out, mp_status_fields *f)
{
    static const int by_what[] = {
        [MP_ODE_BAD_RHS] = MP_DETAIL_RHS,       [MP_ODE_BAD_EVENT] = MP_DETAIL_EVENT,
        [MP_ODE_BAD_JAC] = MP_DETAIL_JAC,       [MP_ODE_BAD_ACTION] = MP_DETAIL_ACTION,
        [MP_ODE_BAD_STATE] = MP_DETAIL_STATE,   [MP_ODE_BAD_ERR] = MP_DETAIL_ERR};
    size_t i = out->bad_index, n = sys->prob.n, nq = sys->prob.nq;
    switch (out->status) {
    case MP_OK: return MP_DETAIL_NONE;
    case MP_TERMINATED:
        f->i = out->stop_event;
        if (out->stop_reason == MP_ODE_STOP_MAX_EVENTS) return MP_DETAIL_MAX_EVENTS;
        if (out->stop_reason != MP_ODE_STOP_ZENO) return MP_DETAIL_NONE;
        return out->zeno_gap > 0.0 ? MP_DETAIL_ZENO : MP_DETAIL_ZENO_UNRESOLVED;
    case MP_EMAXSTEPS: return MP_DETAIL_MAX_STEPS;
    case MP_EEVENT: f->i = out->stop_event; return MP_DETAIL_EVENT_LOOP;
    case MP_ENONFINITE: break;
    default: return MP_DETAIL_AT_T;
    }
    int what = out->bad_what >= 0 && out->bad_what < (int)(sizeof by_what / sizeof *by_what)
                   ? by_what[out->bad_what] : MP_DETAIL_RHS;
    if (what == MP_DETAIL_JAC) f->i = i / n, f->j = i % n;
    if (what != MP_DETAIL_RHS) return what;
    int own = sys->kind ? sys->kind->nonfinite : MP_DETAIL_RHS;
    if (own == MP_DETAIL_CFUNC) return own;
    if (own == MP_DETAIL_CFUNC2 && i >= nq) {
        f->i = i - nq; /* the acceleration's index */
        return own;
    }
    if (sys->torque.fn && i < 3) return MP_DETAIL_TORQUE;
    return MP_DETAIL_RHS;
}

/* Contract: the message of a solve's outcome as a new str, from the status
 * table (mp_status_format): the status's message, the detail in
 * parentheses and, when Hairer's test found the problem stiff, the methods
 * to try. */
static PyObject *ode_message(const py_system *sys, const mp_ode_outcome *out, long max_steps)
{
    mp_status_fields f = {.t = out->t_fail, .gap = out->zeno_gap, .i = out->bad_index,
                          .count = out->stop_count, .max_steps = max_steps,
                          .stiff = out->stiff};
    char buf[640];
    mp_status_format(buf, sizeof buf, out->status, ode_detail(sys, out, &f), &f);
    return PyUnicode_FromString(buf);
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

/* ---- the options object -------------------------------------------------------
 * ode_solve and ode_solve_many take one dict of options, built by
 * integrate.py's _options and parsed here alone: one row per key, saying
 * what it converts to, where it goes and which call takes it. */

typedef struct {
    double t0, tf, h, first_step, max_step;
    long max_steps;
    /* borrowed (the options dict holds them for the whole call) */
    PyObject *rtol, *atol, *t_eval, *events, *terminal, *direction, *args, *jac, *watch, *band;
    int dense;                   /* ode_solve's */
    PyObject *params, *progress; /* ode_solve_many's */
    int threads, lanes;
} ode_opts;

enum { OPT_F64, OPT_LONG, OPT_INT, OPT_BOOL, OPT_OBJ, OPT_TUPLE, OPT_LIST_OR_NONE };
enum { FOR_SOLVE = 1, FOR_MANY = 2, FOR_BOTH = 3 };

typedef struct {
    const char *key;
    size_t len;     /* strlen(key) */
    int type;       /* OPT_*: what the value converts to */
    size_t offset;  /* of the field in ode_opts */
    int calls;      /* FOR_*: the calls that take it (and require it) */
} ode_opt_row;

#define OPT(key, type, calls) {#key, sizeof #key - 1, type, offsetof(ode_opts, key), calls}
/* In _options' order, which the parse tries first. */
static const ode_opt_row ode_opt_rows[] = {
    OPT(t0, OPT_F64, FOR_BOTH),         OPT(tf, OPT_F64, FOR_BOTH),
    OPT(rtol, OPT_OBJ, FOR_BOTH),       OPT(atol, OPT_OBJ, FOR_BOTH),
    OPT(t_eval, OPT_OBJ, FOR_BOTH),     OPT(h, OPT_F64, FOR_BOTH),
    OPT(first_step, OPT_F64, FOR_BOTH), OPT(max_step, OPT_F64, FOR_BOTH),
    OPT(max_steps, OPT_LONG, FOR_BOTH), OPT(events, OPT_OBJ, FOR_BOTH),
    OPT(terminal, OPT_OBJ, FOR_BOTH),   OPT(direction, OPT_OBJ, FOR_BOTH),
    OPT(args, OPT_TUPLE, FOR_BOTH),     OPT(jac, OPT_OBJ, FOR_BOTH),
    OPT(watch, OPT_LIST_OR_NONE, FOR_BOTH), OPT(band, OPT_OBJ, FOR_BOTH),
    OPT(dense, OPT_BOOL, FOR_SOLVE),    OPT(params, OPT_OBJ, FOR_MANY),
    OPT(threads, OPT_INT, FOR_MANY),    OPT(progress, OPT_OBJ, FOR_MANY),
    OPT(lanes, OPT_INT, FOR_MANY),
};
#undef OPT
#define N_OPTS (sizeof ode_opt_rows / sizeof ode_opt_rows[0])

/* Contract: the value v of row r stored in op.  0, or -1 with an exception set. */
static int opt_store(const ode_opt_row *r, PyObject *v, ode_opts *op)
{
    char *at = (char *)op + r->offset;
    switch (r->type) {
    case OPT_F64:
        *(double *)at = PyFloat_CheckExact(v) ? PyFloat_AS_DOUBLE(v) : PyFloat_AsDouble(v);
        return *(double *)at == -1.0 && PyErr_Occurred() ? -1 : 0;
    case OPT_LONG:
        *(long *)at = PyLong_AsLong(v);
        return *(long *)at == -1 && PyErr_Occurred() ? -1 : 0;
    case OPT_INT: {
        long l = PyLong_AsLong(v);
        if (l == -1 && PyErr_Occurred()) return -1;
        if (l < INT_MIN || l > INT_MAX) {
            PyErr_Format(PyExc_OverflowError, "option %s is out of range", r->key);
            return -1;
        }
        *(int *)at = (int)l;
        return 0;
    }
    case OPT_BOOL: return (*(int *)at = PyObject_IsTrue(v)) < 0 ? -1 : 0;
    case OPT_TUPLE:
    case OPT_LIST_OR_NONE:
        if (r->type == OPT_TUPLE ? !PyTuple_Check(v) : v != Py_None && !PyList_Check(v)) {
            PyErr_Format(PyExc_TypeError, "option %s must be a %s", r->key,
                         r->type == OPT_TUPLE ? "tuple" : "list or None");
            return -1;
        }
        break;
    }
    *(PyObject **)at = v;
    return 0;
}

/* Whether key (any object) is row r's name: a length and a memcmp for the
 * ASCII str keys _options writes (the parse's cost is a small solve's). */
static int opt_is(const ode_opt_row *r, PyObject *key)
{
    if (!PyUnicode_Check(key) || !PyUnicode_IS_COMPACT_ASCII(key)) return 0;
    return (size_t)PyUnicode_GET_LENGTH(key) == r->len &&
           memcmp(PyUnicode_DATA(key), r->key, r->len) == 0;
}

/* Contract: the options dict d of a call (FOR_SOLVE or FOR_MANY) into op:
 * every key the call takes, no other.  0, or -1 with an exception set. */
static int ode_opts_parse(PyObject *d, int call, ode_opts *op)
{
    memset(op, 0, sizeof *op);
    if (!PyDict_CheckExact(d)) {
        PyErr_SetString(PyExc_TypeError, "options must be a dict (integrate.py's _options)");
        return -1;
    }
    unsigned char seen[N_OPTS] = {0};
    Py_ssize_t pos = 0;
    PyObject *key, *v;
    size_t r = 0;
    while (PyDict_Next(d, &pos, &key, &v)) {
        size_t tries = 0; /* from the row after the last one: keys come in table order */
        while (tries < N_OPTS && !opt_is(&ode_opt_rows[r], key))
            r = (r + 1) % N_OPTS, tries++;
        if (tries == N_OPTS || !(ode_opt_rows[r].calls & call)) {
            PyErr_Format(PyExc_TypeError, "unknown option %R", key);
            return -1;
        }
        if (opt_store(&ode_opt_rows[r], v, op) < 0) return -1;
        seen[r] = 1;
        r = (r + 1) % N_OPTS;
    }
    for (r = 0; r < N_OPTS; r++)
        if ((ode_opt_rows[r].calls & call) && !seen[r]) {
            PyErr_Format(PyExc_TypeError, "options lack %s", ode_opt_rows[r].key);
            return -1;
        }
    return 0;
}

/* What the options convert to once n is known: the tolerances as n values
 * each, t_eval as an array. */
typedef struct {
    double rtol; /* the least of the n */
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

/* Contract: the arrays of a from op's rtol and atol (each a Python float,
 * taken as n copies, or n values) and t_eval (None or m values), then o from
 * op and a (o points into a: clear a after the solve; o->rtol the least
 * rtol).  0, or -1 with an exception set and a cleared. */
static int ode_args_fill(const ode_opts *op, size_t n, ode_args *a, mp_ode_options *o)
{
    memset(a, 0, sizeof *a);
    const double *rtolv = ode_tolerances(op->rtol, "rtol", 1, n, &a->rtolv, &a->rtol1);
    const double *atol = rtolv ? ode_tolerances(op->atol, "atol", 0, n, &a->atol, &a->atol1)
                               : NULL;
    if (!atol) {
        ode_args_clear(a);
        return -1;
    }
    a->rtol = PyFloat_CheckExact(op->rtol) ? PyFloat_AS_DOUBLE(op->rtol) : INFINITY;
    for (size_t i = 0; i < n; i++) a->rtol = fmin(a->rtol, rtolv[i]);
    if (op->t_eval != Py_None && !(a->tev = mp_py_array(op->t_eval, "t_eval", 1))) {
        ode_args_clear(a);
        return -1;
    }
    memset(o, 0, sizeof *o);
    o->rtol = a->rtol;
    o->rtolv = rtolv;
    o->atol = atol;
    o->first_step = op->first_step;
    o->max_step = op->max_step;
    o->h = op->h;
    o->max_steps = op->max_steps;
    o->t_eval = a->tev ? PyArray_DATA(a->tev) : NULL;
    o->n_eval = a->tev ? (size_t)PyArray_SIZE(a->tev) : 0;
    o->interrupt = mp_py_check_interrupt;
    return 0;
}

/* Contract: the one calling convention of ode_solve and ode_solve_many,
 * (method, system, y0 or y0s, options): *m the row named by method (a str)
 * and op the options for the call (FOR_SOLVE or FOR_MANY).  0, or -1 with an
 * exception set. */
static int ode_call_args(PyObject *const *argv, Py_ssize_t nargs, int call,
                         const mp_ode_method **m, ode_opts *op)
{
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "%s takes 4 arguments (method, system, y0, options), "
                     "got %zd", call == FOR_SOLVE ? "ode_solve" : "ode_solve_many", nargs);
        return -1;
    }
    const char *s = PyUnicode_Check(argv[0]) ? PyUnicode_AsUTF8(argv[0]) : NULL;
    if (!s) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_TypeError, "method must be a str");
        return -1;
    }
    if (!(*m = mp_ode_method_find(s))) {
        PyErr_Format(PyExc_ValueError, "unknown method %s", s);
        return -1;
    }
    return ode_opts_parse(argv[3], call, op);
}

/* ---- ode_solve ------------------------------------------------------------ */

/* What ode_solve and ode_solve_many both convert: the options, the
 * tolerances and samples, the system, its band and Jacobian, the event
 * list; dropped together by ode_call_clear. */
typedef struct {
    ode_opts op;
    ode_args oa;
    mp_ode_options o;
    py_system sys;
    size_t *perm;
    PyArrayObject *jm;
    py_event_list el;
} ode_call;

static void ode_call_clear(ode_call *c)
{
    py_system_clear(&c->sys);
    ode_args_clear(&c->oa);
    event_list_clear(&c->el);
    Py_CLEAR(c->jm);
    PyMem_Free(c->perm);
    c->perm = NULL;
}

/* One ode_solve call: its state and the adapters the problem runs through. */
typedef struct {
    ode_call b;
    PyArrayObject *y0;
    mp_ode_problem prob;
    py_with_jac wj;
    py_watched wd;
    const_jac cj;
    py_events pe;
    int holds_python;
} solve_call;

static void solve_call_clear(solve_call *c)
{
    ode_call_clear(&c->b);
    event_fns_free(&c->pe);
    Py_CLEAR(c->y0);
}

/* Contract: ValueError unless method m can run the system of c (a
 * symplectic explicit row needs q'' = a(t, q); the scene rows say which
 * scenes are).  0, or -1 with an exception set. */
static int separable_check(const mp_ode_method *m, const solve_call *c)
{
    if (!m->symplectic || m->implicit || c->prob.nq != 0) return 0;
    char why[256];
    mp_model_separable_hint(c->b.sys.model ? c->b.sys.model->name : NULL, why, sizeof why);
    PyErr_Format(PyExc_ValueError,
                 "method %s needs a separable system q'' = a(t, q) with y = (q, v): %s",
                 m->name, why);
    return -1;
}

/* Contract: c's problem from the system spec and y0o with c->b.op's options:
 * the system, its band, watch, Jacobian and events.  0, or -1 with an
 * exception set. */
static int solve_prepare(solve_call *c, const mp_ode_method *m, PyObject *spec, PyObject *y0o)
{
    const ode_opts *op = &c->b.op;
    c->y0 = mp_py_array(y0o, "y0", 1);
    if (!c->y0 || mp_py_require_finite(c->y0, "y0") < 0) return -1;
    size_t n = (size_t)PyArray_SIZE(c->y0);
    if (ode_args_fill(op, n, &c->b.oa, &c->b.o) < 0 || py_system_parse(spec, n, &c->b.sys) < 0)
        return -1;
    c->prob = c->b.sys.prob;
    if (band_parse(op->band, n, &c->prob, &c->b.perm) < 0 || separable_check(m, c) < 0) return -1;
    c->holds_python = c->b.sys.holds_python;
    if (op->watch != Py_None) { /* a ctypes callback that runs Python: hold the GIL, check */
        watch_problem(&c->prob, &c->wd, op->watch);
        c->holds_python = 1;
    }
    if (jac_parse(op->jac, n, &c->b.jm) < 0) return -1;
    c->holds_python |= jac_wrap(&c->prob, op->jac, c->b.jm, op->args, &c->cj, &c->wj);
    c->b.o.dense = op->dense;
    if (event_list_parse(op->events, op->terminal, op->direction, &c->b.el, &c->b.o) < 0) return -1;
    if (c->b.el.count) {
        const py_system *s = &c->b.sys;
        if (event_fns(op->events, c->b.el.count, op->args, n,
                      s->params ? PyArray_DATA(s->params) : NULL,
                      s->params ? (size_t)PyArray_SIZE(s->params) : 0, 0, &c->pe) < 0)
            return -1;
        c->b.o.events_data = c->b.o.action_data = &c->pe;
        c->holds_python |= !c->b.el.all_c; /* impacts alone run in C */
    }
    return 0;
}

/* Contract: ode_solve(method, system, y0, options), options the dict of
 * integrate.py's _options (validated there; see ode_opt_rows) -> the tuple
 * of result_to_python.  A failure the status table marks as always raising
 * (a callback's exception, Ctrl-C, memory) raises; every other outcome is
 * returned with its code and message (integrate.py decides, from the same
 * table, what raises).  METH_FASTCALL: its fixed cost is that of a small
 * solve. */
static PyObject *py_ode_solve(PyObject *self, PyObject *const *argv, Py_ssize_t nargs)
{
    (void)self;
    const mp_ode_method *m;
    solve_call c;
    memset(&c, 0, sizeof c);
    PyObject *result = NULL;
    if (ode_call_args(argv, nargs, FOR_SOLVE, &m, &c.b.op) < 0 ||
        solve_prepare(&c, m, argv[1], argv[2]) < 0)
        goto out;
    c.prob.replayable = !c.holds_python; /* plain C all through: a block may be run again */
    mp_ode_result r;
    int rc;
    const double *y0 = PyArray_DATA(c.y0);
    if (c.holds_python) {
        rc = mp_ode_solve(m, &c.prob, c.b.op.t0, c.b.op.tf, y0, &c.b.o, &r);
    } else {
        Py_BEGIN_ALLOW_THREADS
        rc = mp_ode_solve(m, &c.prob, c.b.op.t0, c.b.op.tf, y0, &c.b.o, &r);
        Py_END_ALLOW_THREADS
    }
    if (mp_status_lookup(rc)->raises == 2) mp_py_raise(rc, "solve");
    else result = result_to_python(&c.b.sys, &r, c.b.op.dense, c.b.op.max_steps);
    mp_ode_result_free(&r);
out:
    solve_call_clear(&c);
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
    mp_ode_result *results; /* with events: each trajectory's whole result */
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
    memset(a, 0, sizeof *a);
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


/* Contract: each trajectory's problem with its row (rows: k of np) where
 * the caller passes it: a Python system's as leading arguments (its tuple:
 * the row, then args), a C callback's as user_data.  0, or -1 with an
 * exception set. */
static int many_caller_rows(many_adapters *ad, mp_ode_ensemble *ens, const py_system *sys,
                            const double *rows, size_t np, PyObject *args)
{
    size_t k = ad->k;
    if (sys->holds_python) {
        if (many_row_tuples(ad, rows, np, args) < 0) return -1;
        if (!(ad->fns = PyMem_Calloc(k, sizeof *ad->fns))) goto nomem;
        for (size_t i = 0; i < k; i++) {
            ad->fns[i] = sys->fn;
            ad->fns[i].args = ad->tuples[i];
            ens->probs[i].data = &ad->fns[i];
        }
        return 0;
    }
    if (!(ad->cfns = PyMem_Calloc(k, sizeof *ad->cfns))) goto nomem;
    for (size_t i = 0; i < k; i++) { /* a C callback gets a pointer to its row as user_data */
        ad->cfns[i] = sys->cfn.fn;
        ad->cfns[i].user_data = (double *)rows + i * np;
        ens->probs[i].data = &ad->cfns[i];
    }
    return 0;
nomem:
    PyErr_NoMemory();
    return -1;
}

/* One ode_solve_many call: its state, the ensemble and the adapters of its
 * trajectories, dropped together by many_call_clear. */
typedef struct {
    ode_call b;
    PyArrayObject *y0s, *par, *yout;
    size_t k, n, np, npar; /* trajectories, states, params' columns, an event's params */
    mp_ode_outcome *outc;
    py_lane_impacts li;
    many_adapters ad;
    mp_ode_ensemble ens;
} many_call;

static void many_call_clear(many_call *c)
{
    many_adapters_clear(&c->ad);
    lane_impacts_clear(&c->li);
    mp_ode_ensemble_free(&c->ens);
    PyMem_Free(c->outc);
    ode_call_clear(&c->b);
    Py_CLEAR(c->y0s);
    Py_CLEAR(c->par);
    Py_CLEAR(c->yout);
}

/* Contract: c's inputs from the system spec and y0o with c->b.op's options:
 * the states, tolerances and samples, the parameter rows, the system and its
 * band, the Jacobian and the event list.  0, or -1 with an exception set. */
static int many_inputs(many_call *c, PyObject *spec, PyObject *y0o)
{
    const ode_opts *op = &c->b.op;
    if (!(c->y0s = mp_py_array(y0o, "y0s", 2))) return -1;
    c->k = c->ad.k = (size_t)PyArray_DIM(c->y0s, 0);
    c->n = (size_t)PyArray_DIM(c->y0s, 1);
    if (ode_args_fill(op, c->n, &c->b.oa, &c->b.o) < 0) return -1;
    if (!c->b.oa.tev) {
        PyErr_SetString(PyExc_ValueError, "solve_many needs t_eval");
        return -1;
    }
    if (op->params != Py_None) {
        if (!(c->par = mp_py_array(op->params, "params", 2))) return -1;
        if ((size_t)PyArray_DIM(c->par, 0) != c->k) {
            PyErr_SetString(PyExc_ValueError, "params must have one row per trajectory");
            return -1;
        }
        c->np = (size_t)PyArray_DIM(c->par, 1);
    }
    const py_system *s = &c->b.sys;
    if (py_system_parse(spec, c->n, &c->b.sys) < 0 ||
        band_parse(op->band, c->n, &c->b.sys.prob, &c->b.perm) < 0)
        return -1;
    if (c->par && !s->model && !s->params && !s->holds_python && s->cfn.nq) {
        PyErr_SetString(PyExc_ValueError, "params are not supported for SecondOrder C callbacks");
        return -1;
    }
    if (jac_parse(op->jac, c->n, &c->b.jm) < 0 ||
        event_list_parse(op->events, op->terminal, op->direction, &c->b.el, &c->b.o) < 0)
        return -1;
    /* the parameter vector each trajectory's events see (an impact's e_param) */
    size_t nparams = s->params ? (size_t)PyArray_SIZE(s->params) : 0;
    c->npar = c->par && (s->model || s->params) ? c->np : nparams;
    return 0;
}

/* Contract: c's ensemble (mp_ode_ensemble_build's problems and lanes) from
 * its inputs.  0, or -1 with an exception set. */
static int many_build(many_call *c, const mp_ode_method *m)
{
    const py_system *s = &c->b.sys;
    const ode_opts *op = &c->b.op;
    int lane_imps = 0; /* impacts alone: the lanes run them too */
    if (c->b.el.count && c->b.el.all_c &&
        (lane_imps = lane_impacts_parse(&c->li, op->events, &c->b.el, c->k, c->n, c->npar)) < 0)
        return -1;
    c->ens = (mp_ode_ensemble){
        .m = m, .base = s->prob, .k = c->k, .n = c->n,
        .rows = c->par ? PyArray_DATA(c->par) : NULL, .np = c->np,
        .rows_kind = !c->par ? MP_ENS_ROWS_NONE : s->model ? MP_ENS_ROWS_SCENE
                   : s->params ? MP_ENS_ROWS_DATA : MP_ENS_ROWS_CALLER,
        .model = s->model, .params = s->params ? PyArray_DATA(s->params) : NULL,
        .nparams = s->params ? (size_t)PyArray_SIZE(s->params) : 0,
        .torque = s->torque.fn ? &s->torque : NULL, .lane_rhs = s->lanes,
        .holds_python = s->holds_python || op->watch != Py_None ||
                        (op->jac != Py_None && !c->b.jm) || (c->b.el.count && !c->b.el.all_c),
        .want_lanes = op->lanes, .impacts = lane_imps > 0 ? c->li.imps : NULL,
        .n_impacts = lane_imps > 0 ? c->li.n : 0};
    int rc = mp_ode_ensemble_build(&c->ens, c->b.op.t0, c->b.op.tf, &c->b.o);
    if (rc != MP_OK) {
        ensemble_error(&c->ens, rc, s->kind->name);
        return -1;
    }
    return 0;
}

/* Contract: the caller's part of each trajectory's problem (the ensemble
 * builds the rest): a Python system's rows as leading arguments or a C
 * callback's row as user_data, the watch, the Jacobian, the events.  0, or
 * -1 with an exception set. */
static int many_attach(many_call *c)
{
    many_adapters *ad = &c->ad;
    mp_ode_ensemble *ens = &c->ens;
    const ode_opts *op = &c->b.op;
    size_t k = c->k;
    const double *rows = c->par ? PyArray_DATA(c->par) : NULL;
    if (c->par && ens->rows_kind == MP_ENS_ROWS_CALLER &&
        many_caller_rows(ad, ens, &c->b.sys, rows, c->np, op->args) < 0)
        return -1;
    if (k && op->watch != Py_None) { /* a ctypes callback that runs Python: see py_watched */
        if (!(ad->watched = PyMem_Calloc(k, sizeof *ad->watched))) goto nomem;
        for (size_t i = 0; i < k; i++) watch_problem(&ens->probs[i], &ad->watched[i], op->watch);
    }
    if (k && op->jac != Py_None) {
        if (!(ad->cjs = PyMem_Calloc(k, sizeof *ad->cjs)) ||
            !(ad->wjs = PyMem_Calloc(k, sizeof *ad->wjs)))
            goto nomem;
        for (size_t i = 0; i < k; i++)
            jac_wrap(&ens->probs[i], op->jac, c->b.jm, ad->tuples ? ad->tuples[i] : op->args,
                     &ad->cjs[i], &ad->wjs[i]);
    }
    if (k && c->b.el.count) { /* each trajectory's event adapters (its args) and whole result */
        if (!(ad->evs = PyMem_Calloc(k, sizeof *ad->evs)) ||
            !(ad->evdata = PyMem_Calloc(k, sizeof *ad->evdata)) ||
            !(ad->results = PyMem_Calloc(k, sizeof *ad->results)))
            goto nomem;
        for (size_t i = 0; i < k; i++) {
            const double *pv = rows && ens->rows_kind != MP_ENS_ROWS_CALLER ? rows + i * c->np
                                                                             : ens->params;
            if (event_fns(op->events, c->b.el.count, ad->tuples ? ad->tuples[i] : op->args, c->n,
                          pv, c->npar, i, &ad->evs[i]) < 0)
                return -1;
            ad->evdata[i] = &ad->evs[i];
        }
    }
    return 0;
nomem:
    PyErr_NoMemory();
    return -1;
}

/* Contract: c's ensemble run (with the GIL released unless it calls Python)
 * into its samples and outcomes -> many_result, or NULL with an exception. */
static PyObject *many_run(many_call *c, const mp_ode_method *m)
{
    size_t k = c->k;
    mp_ode_ensemble *ens = &c->ens;
    many_adapters *ad = &c->ad;
    if (!(c->outc = PyMem_Calloc(k ? k : 1, sizeof *c->outc))) return PyErr_NoMemory();
    npy_intp shape[3] = {(npy_intp)k, (npy_intp)c->n, (npy_intp)c->b.o.n_eval};
    if (!(c->yout = mp_py_empty(3, shape))) return NULL;
    PyObject *progress = c->b.op.progress; /* False, True (a stderr line) or report(done, total) */
    many_progress_ctx pctx = {0, PyCallable_Check(progress) ? progress : NULL};
    void (*report)(size_t, size_t, void *) =
        pctx.report || PyObject_IsTrue(progress) == 1 ? many_progress : NULL;
    const double *y0s = PyArray_DATA(c->y0s);
    double *yout = PyArray_DATA(c->yout);
    const ode_opts *op = &c->b.op;
    int rc;
    if (ens->holds_python) {
        rc = mp_ode_solve_many(m, ens->probs, NULL, k, op->t0, op->tf, y0s, &c->b.o, 1, yout,
                               c->outc, ad->results, ad->evdata, report, &pctx);
    } else {
        Py_BEGIN_ALLOW_THREADS
        rc = mp_ode_solve_many(m, ens->probs, ens->lanes, k, op->t0, op->tf, y0s, &c->b.o,
                               op->threads, yout, c->outc, ad->results, ad->evdata, report,
                               &pctx);
        Py_END_ALLOW_THREADS
    }
    if (rc != MP_OK) return mp_py_raise(rc, "solve_many");
    return many_result(&c->b.sys, c->outc, ad->results, k, c->yout, ens->lanes != NULL,
                       c->b.op.max_steps);
}

/* Contract: ode_solve_many(method, system, y0s, options) -> see many_result.
 * options: the dict of integrate.py's _options (see ode_opt_rows; t_eval
 * required), events, terminal, direction and jac as ode_solve takes them
 * (an event function and jac are called as fun is, with a trajectory's row
 * before args); lanes: -1 when possible, 0 never, 1 always (ValueError when
 * not possible).  The binding parses and translates; the ensemble's problems
 * and its lanes are mp_ode_ensemble_build's.  An ensemble stopped by a
 * callback's exception, Ctrl-C or memory raises. */
static PyObject *py_ode_solve_many(PyObject *self, PyObject *const *argv, Py_ssize_t nargs)
{
    (void)self;
    const mp_ode_method *m;
    many_call c;
    memset(&c, 0, sizeof c);
    PyObject *result = NULL;
    if (ode_call_args(argv, nargs, FOR_MANY, &m, &c.b.op) == 0 &&
        many_inputs(&c, argv[1], argv[2]) == 0 && many_build(&c, m) == 0 && many_attach(&c) == 0)
        result = many_run(&c, m);
    many_call_clear(&c);
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
            "{s:s,s:i,s:O,s:O,s:O,s:O,s:i,s:O,s:O,s:O,s:O}", "name", m->name, "order", m->order,
            "adaptive", m->adaptive ? Py_True : Py_False, "implicit",
            m->implicit ? Py_True : Py_False, "symplectic", m->symplectic ? Py_True : Py_False,
            "needs_jacobian", m->needs_jacobian ? Py_True : Py_False, "dense_output",
            m->dense_order, "lanes", m->lanes != MP_LANE_NONE ? Py_True : Py_False, "rigid",
            m->rigid ? Py_True : Py_False, "compensated", m->compensated ? Py_True : Py_False,
            "scalar_rtol", m->scalar_rtol ? Py_True : Py_False);
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
     METH_FASTCALL, "Integrate an ensemble (internal; use mechpy.solve_many)."},
    {"ode_dense_eval", py_ode_dense_eval, METH_VARARGS,
     "Evaluate stored dense output (internal)."},
    {"ode_methods", py_ode_methods, METH_NOARGS, "The method table (internal)."},
    {NULL, NULL, 0, NULL},
};
