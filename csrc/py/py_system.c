/* The integrator binding's systems: the table of system kinds the Python
 * layer describes (scene, Python callable, C callback, compiled library),
 * and the adapters through which the engine calls them, their Jacobians and
 * their band.  The one callback adapter through which C calls Python,
 * py_call, lives here. */
#include "py_ode.h"

#include <math.h>
#include <string.h>

/* ---- Python callables (called with the GIL held) -------------------------- */

/* Call fun(t, y, *args) and copy its float64 result (nout values) to out. */
int py_call(const py_fn *c, double t, const double *y, double *out)
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


static int py_jac_rhs(double t, const double *y, double *dydt, void *data)
{
    const py_with_jac *w = data;
    return w->inner.rhs(t, y, dydt, w->inner.data);
}

static int py_jac(double t, const double *y, double *J, void *data)
{
    return py_call(&((const py_with_jac *)data)->jac, t, y, J);
}


/* ---- C callbacks ------------------------------------------------------------ */

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
void watch_problem(mp_ode_problem *p, py_watched *wd, PyObject *caught)
{
    wd->inner = *p;
    wd->caught = caught;
    p->rhs = watched_rhs;
    p->jac = p->jac ? watched_jac : NULL;
    p->data = wd;
}

/* A Jacobian given as a constant matrix (SciPy accepts an array for jac). */
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

/* ---- options solve and solve_many share ------------------------------------- */

/* Contract: jaco as a Jacobian for n states: None (*jm NULL), a callable
 * (*jm NULL) or a constant (n, n) finite matrix (*jm a new reference).  0, or
 * -1 with an exception set. */
int jac_parse(PyObject *jaco, size_t n, PyArrayObject **jm)
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
int jac_wrap(mp_ode_problem *prob, PyObject *jaco, PyArrayObject *jm, PyObject *args,
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

/* Contract: the Jacobian's band of integrate.py's _jac_band set on p (of n
 * states): None (dense), 0 <= ml, mu < n, or (ml, mu, perm) with perm a
 * permutation of 0..n-1 (a sequence of ints), copied into *perm_out, which
 * the caller frees with PyMem_Free; -1 with an exception for anything else. */
int band_parse(PyObject *band, size_t n, mp_ode_problem *p, size_t **perm_out)
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

/* ---- a system described by the Python layer --------------------------------
 * ("scene", name, params) | ("python", fun, args) | ("cfunc", address, user_data)
 * and the second-order ("python2", accel, args) | ("cfunc2", address, user_data),
 * or a generated library ("compiled", (rhs, jac, nq[, lanes, rk4, compose]), params)
 * with lanes its mp_lane_rhs (lanes.h; None: ensembles wrap rhs lane by lane) and
 * rk4/compose its fixed-step blocks (ode.h's mp_ode_blocks; None: the generic ones);
 * a RigidBody scene may carry a C torque: ("scene", name, params, (address, user_data)) */

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

/* Contract: a scene's row by name a, its parameters b (checked by the row:
 * MP_EDOM names them), its dimension n; cb a C torque (address, user_data)
 * for a row that takes one. */
static int parse_scene(const py_system_kind *k, PyObject *a, PyObject *b, PyObject *cb, size_t n,
                       py_system *s)
{
    (void)k;
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
        PyErr_Format(PyExc_ValueError, "y0 must have %zu values for %s, got %zu", dim, m->name,
                     n);
        return -1;
    }
    m->bind(PyArray_DATA(s->params), &s->prob);
    s->model = m;
    if (!cb) return 0;
    c_fn f;
    if (c_address(PyTuple_GET_ITEM(cb, 0), PyTuple_GET_ITEM(cb, 1), &f) < 0) return -1;
    s->torque = (mp_rigid_torque){PyArray_DATA(s->params), f.f, f.user_data};
    if (mp_rigid_bind_torque(m, &s->torque, &s->prob) != MP_OK) {
        PyErr_Format(PyExc_ValueError, "scene %s takes no C callback", m->name);
        return -1;
    }
    return 0;
}

/* Contract: y0 of a second-order system is (q, v): n even. */
static int second_order_split(const py_system_kind *k, size_t n)
{
    if (k->second_order && n % 2) {
        PyErr_SetString(PyExc_ValueError, "y0 of a second-order system is (q, v): even length");
        return -1;
    }
    return 0;
}

/* Contract: a Python callable a (fun(t, y, *b), or accel(t, q, *b) for a
 * second-order kind) with its extra arguments b. */
static int parse_python(const py_system_kind *k, PyObject *a, PyObject *b, PyObject *cb, size_t n,
                        py_system *s)
{
    (void)cb;
    if (!PyCallable_Check(a) || !PyTuple_Check(b)) {
        PyErr_SetString(PyExc_TypeError, "system must be callable and args a tuple");
        return -1;
    }
    if (second_order_split(k, n) < 0) return -1;
    int second = k->second_order;
    size_t nf = second ? n / 2 : n;
    s->fn = (py_fn){a, b, nf, nf, second ? "accel" : "fun"};
    s->prob.rhs = second ? py_rhs2 : py_rhs;
    s->prob.data = &s->fn;
    s->prob.nq = second ? n / 2 : 0;
    s->holds_python = 1;
    return 0;
}

/* Contract: a C callback at address a with user_data b (an address or None). */
static int parse_cfunc(const py_system_kind *k, PyObject *a, PyObject *b, PyObject *cb, size_t n,
                       py_system *s)
{
    (void)cb;
    int second = k->second_order;
    if (c_address(a, b, &s->cfn.fn) < 0 || second_order_split(k, n) < 0) return -1;
    s->cfn.nq = second ? n / 2 : 0;
    s->prob.rhs = second ? c_rhs2 : c_rhs;
    s->prob.data = second ? (void *)&s->cfn : (void *)&s->cfn.fn;
    s->prob.nq = s->cfn.nq;
    return 0;
}

/* Contract: a generated library (mechpy.symbolic): a = (rhs, jac, nq[, lanes,
 * rk4, compose]), each function an address or None (rhs: never), b its
 * parameter vector, which its functions take as data; lanes its
 * mp_lane_rhs (lanes.h; None: ensembles wrap rhs lane by lane), rk4/compose
 * its fixed-step blocks (ode.h's mp_ode_blocks; None: the generic ones). */
static int parse_compiled(const py_system_kind *k, PyObject *a, PyObject *b, PyObject *cb,
                          size_t n, py_system *s)
{
    (void)k;
    (void)cb;
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
    return 0;
}

/* The system kinds, one row each: the spec's tag (_system.py's _system_spec
 * writes them), its parser and what differs between kinds. */
static const py_system_kind py_system_kinds[] = {
    /* name        parser          second takes_torque nonfinite */
    {"scene", parse_scene, 0, 1, MP_DETAIL_RHS},
    {"python", parse_python, 0, 0, MP_DETAIL_RHS},
    {"python2", parse_python, 1, 0, MP_DETAIL_RHS},
    {"cfunc", parse_cfunc, 0, 0, MP_DETAIL_CFUNC},
    {"cfunc2", parse_cfunc, 1, 0, MP_DETAIL_CFUNC2},
    {"compiled", parse_compiled, 0, 0, MP_DETAIL_RHS},
};

void py_system_clear(py_system *s) { Py_CLEAR(s->params); }

int py_system_parse(PyObject *spec, size_t n, py_system *s)
{
    PyObject *tag, *a, *b, *cb = NULL;
    memset(s, 0, sizeof *s);
    if (!PyTuple_Check(spec)) {
        PyErr_SetString(PyExc_TypeError, "a system spec must be a tuple (kind, a, b)");
        return -1;
    }
    if (!PyArg_ParseTuple(spec, "UOO|O!", &tag, &a, &b, &PyTuple_Type, &cb)) return -1;
    size_t nk = sizeof py_system_kinds / sizeof py_system_kinds[0];
    for (size_t i = 0; i < nk && !s->kind; i++)
        if (PyUnicode_CompareWithASCIIString(tag, py_system_kinds[i].name) == 0)
            s->kind = &py_system_kinds[i];
    if (cb && (!s->kind || !s->kind->takes_torque || PyTuple_GET_SIZE(cb) != 2)) {
        PyErr_SetString(PyExc_ValueError, "a callback in a system spec needs a scene and "
                                          "(address, user_data)");
        return -1;
    }
    if (!s->kind) {
        PyErr_Format(PyExc_ValueError, "unknown system kind %U", tag);
        return -1;
    }
    s->prob.n = n;
    if (s->kind->parse(s->kind, a, b, cb, n, s) < 0) return -1;
    s->cfn.fn.n = n; /* the outputs a first-order C callback must write */
    return 0;
}
