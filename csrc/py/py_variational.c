/* Binding for the variational solvers of the C core.  An integrand spec is
 *   (name, params)              a built-in functional (its dimension d from the table),
 *   ("scene", name, params)     the Lagrangian of a scene's row (models/models.h),
 *                               d = dim / 2, params checked by the row,
 *   ("python", f, d)            a Python callable f(x (m,), y (m, d), p (m, d))
 *                               returning the (m, K) values, K = 1 + 2d + 3d^2,
 *   ("c", capsule, params, d)   a compiled mp_gen_lagrangian (the capsule from
 *                               _variational_capsule), called with params' data.
 * Entry points: the Newton solver, the variational integrator, the discrete
 * momenta, the Legendre transform back to velocities, one evaluation. */
#include "mp_py.h"

#include <stdint.h>
#include <string.h>

#include "models/models.h"
#include "variational.h"

#define MP_VAR_MAXCON 16
#define MP_VAR_MAXDIM 64
#define MP_VAR_CAPSULE "mechpy.variational.lagrangian"

typedef struct {
    mp_var_eval_fn fn;
} py_var_cfun;

typedef struct {
    mp_var_builtin b;
    PyObject *fn;            /* borrowed: the Python callable, or NULL */
    mp_var_integrand F;
} py_var_spec;

/* The Python integrand adapter: called from C with the GIL released. */
static int py_var_eval(size_t m, const double *x, const double *y, const double *p, double *out,
                       void *ctx)
{
    py_var_spec *s = ctx;
    size_t d = s->F.d, K = mp_var_nvalues(d);
    int st = MP_ECALLBACK;
    PyGILState_STATE gs = PyGILState_Ensure();
    npy_intp d1 = (npy_intp)m, d2[2] = {(npy_intp)m, (npy_intp)d};
    mp_py_refs k = {0};
    PyArrayObject *ax, *ay, *ap, *ra;
    if (!(ax = mp_py_hold(&k, mp_py_empty(1, &d1))) || !(ay = mp_py_hold(&k, mp_py_empty(2, d2)))
        || !(ap = mp_py_hold(&k, mp_py_empty(2, d2))))
        goto done;
    memcpy(PyArray_DATA(ax), x, m * sizeof(double));
    memcpy(PyArray_DATA(ay), y, m * d * sizeof(double));
    memcpy(PyArray_DATA(ap), p, m * d * sizeof(double));
    PyObject *r = mp_py_hold(&k, PyObject_CallFunctionObjArgs(s->fn, (PyObject *)ax,
                                                             (PyObject *)ay, (PyObject *)ap,
                                                             NULL));
    if (!r || !(ra = mp_py_hold(&k, mp_py_array(r, "integrand derivatives", 2)))) goto done;
    if (PyArray_DIM(ra, 0) != d1 || PyArray_DIM(ra, 1) != (npy_intp)K) {
        PyErr_Format(PyExc_ValueError,
                     "the integrand must return an array of shape (%zd, %zd), got (%zd, %zd)",
                     (Py_ssize_t)d1, (Py_ssize_t)K, (Py_ssize_t)PyArray_DIM(ra, 0),
                     (Py_ssize_t)PyArray_DIM(ra, 1));
        goto done;
    }
    memcpy(out, PyArray_DATA(ra), m * K * sizeof(double));
    st = MP_OK;
done:
    mp_py_release(&k, NULL);
    PyGILState_Release(gs);
    return st;
}

/* A dimension d from a Python int: 1 <= d <= MP_VAR_MAXDIM. */
static int py_var_dim(PyObject *o, size_t *d, const char *what)
{
    Py_ssize_t v = PyLong_Check(o) ? PyLong_AsSsize_t(o) : -1;
    if (v == -1 && PyErr_Occurred()) PyErr_Clear();
    if (v < 1 || v > MP_VAR_MAXDIM) {
        PyErr_Format(PyExc_ValueError, "%s: the dimension must be an int in 1..%d", what,
                     MP_VAR_MAXDIM);
        return -1;
    }
    *d = (size_t)v;
    return 0;
}

/* Parse ("scene", name, params) into s: the row's Lagrangian on the row's
 * checked parameters (held in k); -1 with an exception set. */
static int py_var_parse_scene(PyObject *obj, py_var_spec *s, const char *what, mp_py_refs *k)
{
    const char *scene = PyTuple_GET_SIZE(obj) == 3 && PyUnicode_Check(PyTuple_GET_ITEM(obj, 1))
                            ? PyUnicode_AsUTF8(PyTuple_GET_ITEM(obj, 1)) : NULL;
    const mp_model *m = scene ? mp_model_find(scene) : NULL;
    if (!m || !m->lagrangian) {
        if (!PyErr_Occurred())
            PyErr_Format(PyExc_TypeError, "%s: (\"scene\", name, params) needs a scene with a "
                         "Lagrangian", what);
        return -1;
    }
    PyArrayObject *params = mp_py_hold(k, mp_py_array(PyTuple_GET_ITEM(obj, 2), "params", 1));
    if (!params) return -1;
    size_t dim;
    char why[200];
    if (mp_model_check(m, PyArray_DATA(params), (size_t)PyArray_SIZE(params), &dim, why,
                       sizeof why) != MP_OK) {
        PyErr_Format(PyExc_ValueError, "%s: %s: %s", what, m->name, why);
        return -1;
    }
    s->F.eval = m->lagrangian;
    s->F.ctx = PyArray_DATA(params);
    s->F.d = dim / 2;
    return 0;
}

/* Parse ("python", f, d) into s: f called from C with the GIL held. */
static int py_var_parse_python(PyObject *obj, py_var_spec *s, const char *what, mp_py_refs *k)
{
    (void)k;
    if (PyTuple_GET_SIZE(obj) != 3 || !PyCallable_Check(PyTuple_GET_ITEM(obj, 1))) {
        PyErr_Format(PyExc_TypeError, "%s: (\"python\", f, d) needs a callable f", what);
        return -1;
    }
    if (py_var_dim(PyTuple_GET_ITEM(obj, 2), &s->F.d, what) < 0) return -1;
    s->fn = PyTuple_GET_ITEM(obj, 1);
    s->F.eval = py_var_eval;
    s->F.ctx = s;
    return 0;
}

/* Parse ("c", capsule, params, d) into s: the compiled Lagrangian on params
 * (held in k). */
static int py_var_parse_c(PyObject *obj, py_var_spec *s, const char *what, mp_py_refs *k)
{
    PyObject *cap = PyTuple_GET_SIZE(obj) == 4 ? PyTuple_GET_ITEM(obj, 1) : NULL;
    if (!cap || !PyCapsule_IsValid(cap, MP_VAR_CAPSULE)) {
        PyErr_Format(PyExc_TypeError, "%s: (\"c\", capsule, params, d) needs a capsule "
                     "from _variational_capsule", what);
        return -1;
    }
    if (py_var_dim(PyTuple_GET_ITEM(obj, 3), &s->F.d, what) < 0) return -1;
    py_var_cfun *cf = PyCapsule_GetPointer(cap, MP_VAR_CAPSULE);
    if (!cf) return -1;
    PyArrayObject *params = mp_py_hold(k, mp_py_array(PyTuple_GET_ITEM(obj, 2), "params", 1));
    if (!params) return -1;
    s->F.eval = cf->fn;
    s->F.ctx = PyArray_DATA(params);
    return 0;
}

/* The tagged integrand kinds, one row each (an untagged spec is a built-in). */
static const struct {
    const char *tag;
    int (*parse)(PyObject *obj, py_var_spec *s, const char *what, mp_py_refs *k);
} py_var_kinds[] = {
    {"python", py_var_parse_python},
    {"c", py_var_parse_c},
    {"scene", py_var_parse_scene},
};

/* Parse a spec (see the file comment) into s; the arrays it keeps (the
 * parameters) are held in k.  -1 with an exception set. */
static int py_var_parse(PyObject *obj, py_var_spec *s, const char *what, mp_py_refs *k)
{
    memset(s, 0, sizeof *s);
    Py_ssize_t len = PyTuple_Check(obj) ? PyTuple_GET_SIZE(obj) : -1;
    PyObject *tag = len >= 2 ? PyTuple_GET_ITEM(obj, 0) : NULL;
    if (!tag || !PyUnicode_Check(tag)) {
        PyErr_Format(PyExc_TypeError,
                     "%s must be a tuple (name, params), (\"scene\", name, params), "
                     "(\"python\", f, d) or (\"c\", capsule, params, d)", what);
        return -1;
    }
    const char *name = PyUnicode_AsUTF8(tag);
    if (!name) return -1;
    for (size_t i = 0; i < sizeof py_var_kinds / sizeof py_var_kinds[0]; i++)
        if (PyUnicode_CompareWithASCIIString(tag, py_var_kinds[i].tag) == 0)
            return py_var_kinds[i].parse(obj, s, what, k);
    if (len != 2) {
        PyErr_Format(PyExc_TypeError, "%s: a built-in is a pair (name, params)", what);
        return -1;
    }
    size_t np, d;
    if (mp_variational_builtin_find(name, &s->b.kind, &np, &d) != MP_OK) {
        PyErr_Format(PyExc_ValueError, "%s: unknown built-in integrand %s", what, name);
        return -1;
    }
    PyArrayObject *p = mp_py_hold(k, mp_py_array(PyTuple_GET_ITEM(obj, 1), "params", 1));
    if (!p) return -1;
    if ((size_t)PyArray_SIZE(p) != np) {
        PyErr_Format(PyExc_ValueError, "%s: %s takes %zd parameters, got %zd", what, name,
                     (Py_ssize_t)np, (Py_ssize_t)PyArray_SIZE(p));
        return -1;
    }
    if (mp_py_require_finite(p, "params") < 0) return -1;
    memcpy(s->b.params, PyArray_DATA(p), np * sizeof(double));
    mp_variational_builtin_bind(&s->b, &s->F);
    return 0;
}

/* Points of d coordinates: an array (m, d), or (m,) when d = 1; finite.  *m
 * receives the count (checked against want when want >= 0). */
static PyArrayObject *py_var_points(PyObject *o, const char *name, size_t d, npy_intp want,
                                    npy_intp *m)
{
    PyArrayObject *a = mp_py_array_finite(o, name, -1, -1);
    if (!a) return NULL;
    int nd = PyArray_NDIM(a);
    int ok = (nd == 2 && PyArray_DIM(a, 1) == (npy_intp)d) || (nd == 1 && d == 1);
    if (ok) *m = PyArray_DIM(a, 0);
    if (ok && (want < 0 || *m == want)) return a;
    PyErr_Format(PyExc_ValueError, "%s must have shape (%zd, %zd)%s", name,
                 (Py_ssize_t)(want >= 0 ? want : (ok ? *m : 0)), (Py_ssize_t)d,
                 d == 1 ? " or (m,)" : "");
    Py_DECREF(a);
    return NULL;
}

/* A copy of a (C order) as a new array; steals nothing. */
static PyArrayObject *py_var_copy(PyArrayObject *a)
{
    return (PyArrayObject *)PyArray_NewCopy(a, NPY_CORDER);
}

/* Free the capsule's record (the capsule's destructor). */
static void py_var_capsule_free(PyObject *cap)
{
    PyMem_Free(PyCapsule_GetPointer(cap, MP_VAR_CAPSULE));
}

/* _variational_capsule(address) -> a capsule of the compiled function at address. */
static PyObject *py_variational_capsule(PyObject *self, PyObject *arg)
{
    (void)self;
    if (!PyLong_Check(arg)) {
        PyErr_SetString(PyExc_TypeError, "address must be an int");
        return NULL;
    }
    void *addr = PyLong_AsVoidPtr(arg);
    if (!addr) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "address must be a non-null function address");
        return NULL;
    }
    py_var_cfun *cf = PyMem_Malloc(sizeof *cf);
    if (!cf) return PyErr_NoMemory();
    cf->fn = (mp_var_eval_fn)(uintptr_t)addr;
    PyObject *cap = PyCapsule_New(cf, MP_VAR_CAPSULE, py_var_capsule_free);
    if (!cap) {
        PyMem_Free(cf);
        return NULL;
    }
    return cap;
}

/* variational_solve(F, x, y0, constraints, values, lambda0, stationary, tol, max_iter)
 * -> (y, lambda, {"iterations", "J", "residual", "constraint_error"}); y0 of
 * shape (n + 1, d) or (n + 1,) for d = 1, y of the same shape. */
static PyObject *py_variational_solve(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo, *xo, *yo, *co, *vo, *lo, *seq;
    int stationary;
    double tol;
    Py_ssize_t max_iter;
    if (!PyArg_ParseTuple(args, "OOOOOOpdn", &fo, &xo, &yo, &co, &vo, &lo, &stationary, &tol,
                          &max_iter))
        return NULL;
    mp_py_refs k = {0};
    py_var_spec F, G[MP_VAR_MAXCON]; /* a Python integrand's context is its spec */
    mp_var_integrand GI[MP_VAR_MAXCON];
    PyArrayObject *x, *y, *v, *lam, *y0, *l0;
    if (py_var_parse(fo, &F, "F", &k) < 0 ||
        !(seq = mp_py_hold(&k, PySequence_Fast(co, "constraints must be a sequence"))))
        return mp_py_release(&k, NULL);
    Py_ssize_t nc = PySequence_Fast_GET_SIZE(seq);
    if (nc > MP_VAR_MAXCON) {
        PyErr_Format(PyExc_ValueError, "at most %d constraints", MP_VAR_MAXCON);
        return mp_py_release(&k, NULL);
    }
    for (Py_ssize_t c = 0; c < nc; c++) {
        if (py_var_parse(PySequence_Fast_GET_ITEM(seq, c), &G[c], "constraint", &k) < 0)
            return mp_py_release(&k, NULL);
        if (G[c].F.d != F.F.d) {
            PyErr_SetString(PyExc_ValueError, "a constraint must have the functional's "
                            "dimension");
            return mp_py_release(&k, NULL);
        }
        GI[c] = G[c].F;
    }
    npy_intp npts = 0;
    if (!(x = mp_py_hold(&k, mp_py_array_finite(xo, "x", 1, -1))) ||
        !(v = mp_py_hold(&k, mp_py_array(vo, "values", 1))) ||
        !(l0 = mp_py_hold(&k, mp_py_array(lo, "lambda0", 1))) ||
        !(y0 = mp_py_hold(&k, py_var_points(yo, "y0", F.F.d, PyArray_SIZE(x), &npts))) ||
        !(y = mp_py_hold(&k, py_var_copy(y0))) || !(lam = mp_py_hold(&k, py_var_copy(l0))))
        return mp_py_release(&k, NULL);
    if (npts < 3 || PyArray_SIZE(v) != nc || PyArray_SIZE(lam) != nc || max_iter < 1) {
        PyErr_SetString(PyExc_ValueError,
                        "variational_solve: need len(x) == len(y0) >= 3, one value and one "
                        "multiplier per constraint, max_iter >= 1");
        return mp_py_release(&k, NULL);
    }
    mp_var_problem pb = {.n = (size_t)npts - 1, .x = PyArray_DATA(x), .F = F.F,
                         .ncon = (size_t)nc, .G = GI, .value = PyArray_DATA(v),
                         .stationary = stationary, .tol = tol, .max_iter = (size_t)max_iter,
                         .interrupt = mp_py_check_interrupt};
    mp_var_info info = {0};
    int st;
    double *yy = PyArray_DATA(y), *ll = PyArray_DATA(lam);
    Py_BEGIN_ALLOW_THREADS
    st = mp_variational_solve(&pb, yy, ll, &info);
    Py_END_ALLOW_THREADS
    if (st != MP_OK) {
        char detail[320];
        if (st == MP_ENOTSPD)
            snprintf(detail, sizeof detail,
                     "the second variation at the stationary path found after %zu Newton "
                     "iterations (residual %.3g) has %zu negative eigenvalue(s) among %zu: it is "
                     "a saddle or a maximum of the discrete functional, not a minimum",
                     info.iterations, info.residual, info.negative,
                     (size_t)(npts - 2) * F.F.d);
        else
            snprintf(detail, sizeof detail,
                     "after %zu Newton iterations (residual %.3g, constraint error %.3g)",
                     info.iterations, info.residual, info.constraint_error);
        return mp_py_release(&k, mp_py_raise_detail(st, "variational_solve", detail));
    }
    return mp_py_release(&k, Py_BuildValue("(OO{s:n,s:d,s:d,s:d})", (PyObject *)y,
                                           (PyObject *)lam, "iterations",
                                           (Py_ssize_t)info.iterations, "J", info.J,
                                           "residual", info.residual, "constraint_error",
                                           info.constraint_error));
}

/* The message of a singular d2L/dqdot2 in `what`, or "" for other statuses. */
static const char *py_var_singular(int st, const char *what)
{
    return st == MP_ESINGULAR ? what : "";
}

/* variational_integrate(L, t0, h, nsteps, q0, p0, v0, sing_tol) -> (q, p), each of
 * shape (nsteps + 1, d). */
static PyObject *py_variational_integrate(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo, *qo, *po, *vo;
    double t0, h, sing_tol;
    Py_ssize_t nsteps;
    if (!PyArg_ParseTuple(args, "OddnOOOd", &fo, &t0, &h, &nsteps, &qo, &po, &vo, &sing_tol))
        return NULL;
    mp_py_refs k = {0};
    py_var_spec L;
    PyArrayObject *q0, *p0, *v0, *q, *p;
    npy_intp one;
    if (py_var_parse(fo, &L, "L", &k) < 0) return mp_py_release(&k, NULL);
    size_t d = L.F.d;
    if (!(q0 = mp_py_hold(&k, py_var_points(qo, "q0", d, 1, &one))) ||
        !(p0 = mp_py_hold(&k, py_var_points(po, "p0", d, 1, &one))) ||
        !(v0 = mp_py_hold(&k, py_var_points(vo, "v0", d, 1, &one))))
        return mp_py_release(&k, NULL);
    if (nsteps < 0 || (size_t)nsteps >= (size_t)PY_SSIZE_T_MAX / (8 * d) - 1) {
        PyErr_SetString(PyExc_ValueError, "nsteps must be >= 0 and fit in memory");
        return mp_py_release(&k, NULL);
    }
    npy_intp dims[2] = {nsteps + 1, (npy_intp)d};
    if (!(q = mp_py_hold(&k, mp_py_empty(2, dims))) || !(p = mp_py_hold(&k, mp_py_empty(2, dims))))
        return mp_py_release(&k, NULL);
    int st;
    double *qq = PyArray_DATA(q), *pp = PyArray_DATA(p);
    const double *a = PyArray_DATA(q0), *b = PyArray_DATA(p0), *c = PyArray_DATA(v0);
    Py_BEGIN_ALLOW_THREADS
    st = mp_variational_integrate(&L.F, t0, h, (size_t)nsteps, a, b, c, sing_tol, qq, pp,
                                  mp_py_check_interrupt, NULL);
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, st == MP_OK ? Py_BuildValue("(OO)", (PyObject *)q, (PyObject *)p)
                                         : mp_py_raise_detail(st, "variational_integrate",
                                                              py_var_singular(st,
                                           "d2L/dqdot2 is singular: the Lagrangian does not "
                                           "determine the velocities")));
}

/* Parse (L, x, y[, p]) of the pointwise entry points: the spec, x (m,), y
 * (m, d) and, when po is given, p (m, d); all held in k.  -1 with an
 * exception set. */
static int py_var_path(mp_py_refs *k, PyObject *fo, PyObject *xo, PyObject *yo, PyObject *po,
                       py_var_spec *L, PyArrayObject **x, PyArrayObject **y, PyArrayObject **p,
                       npy_intp *m)
{
    npy_intp m2;
    if (py_var_parse(fo, L, "L", k) < 0 ||
        !(*x = mp_py_hold(k, mp_py_array_finite(xo, "x", 1, -1))) ||
        !(*y = mp_py_hold(k, py_var_points(yo, "y", L->F.d, PyArray_SIZE(*x), m))))
        return -1;
    if (po && !(*p = mp_py_hold(k, py_var_points(po, "p", L->F.d, *m, &m2)))) return -1;
    return 0;
}

/* variational_momenta(L, x, y) -> p, the discrete momenta along the path (x, y). */
static PyObject *py_variational_momenta(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo, *xo, *yo;
    if (!PyArg_ParseTuple(args, "OOO", &fo, &xo, &yo)) return NULL;
    mp_py_refs k = {0};
    py_var_spec L;
    PyArrayObject *x, *y, *p;
    npy_intp m;
    if (py_var_path(&k, fo, xo, yo, NULL, &L, &x, &y, NULL, &m) < 0)
        return mp_py_release(&k, NULL);
    if (m < 2) {
        PyErr_SetString(PyExc_ValueError, "variational_momenta: need at least 2 points");
        return mp_py_release(&k, NULL);
    }
    if (!(p = mp_py_hold(&k, PyArray_NewLikeArray(y, NPY_CORDER, NULL, 0))))
        return mp_py_release(&k, NULL);
    int st;
    const double *xx = PyArray_DATA(x), *yy = PyArray_DATA(y);
    double *pp = PyArray_DATA(p);
    Py_BEGIN_ALLOW_THREADS
    st = mp_variational_momenta(&L.F, (size_t)m - 1, xx, yy, pp);
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, mp_py_result(st, "variational_momenta", (PyObject *)p));
}

/* variational_velocities(L, x, y, p, v0, sing_tol) -> (v, energy): dL/dv = p solved for v. */
static PyObject *py_variational_velocities(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo, *xo, *yo, *po, *vo;
    double sing_tol;
    if (!PyArg_ParseTuple(args, "OOOOOd", &fo, &xo, &yo, &po, &vo, &sing_tol)) return NULL;
    mp_py_refs k = {0};
    py_var_spec L;
    PyArrayObject *x, *y, *p, *v0, *v, *E;
    npy_intp m, m2;
    if (py_var_path(&k, fo, xo, yo, po, &L, &x, &y, &p, &m) < 0 ||
        !(v0 = mp_py_hold(&k, py_var_points(vo, "v0", L.F.d, m, &m2))) ||
        !(v = mp_py_hold(&k, py_var_copy(v0))) || !(E = mp_py_hold(&k, mp_py_empty(1, &m))))
        return mp_py_release(&k, NULL);
    int st;
    const double *xx = PyArray_DATA(x), *yy = PyArray_DATA(y), *pp = PyArray_DATA(p);
    double *vv = PyArray_DATA(v), *ee = PyArray_DATA(E);
    Py_BEGIN_ALLOW_THREADS
    st = mp_variational_velocities(&L.F, (size_t)m, xx, yy, pp, vv, ee, sing_tol);
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, st == MP_OK ? Py_BuildValue("(OO)", (PyObject *)v, (PyObject *)E)
                                         : mp_py_raise_detail(st, "variational_velocities",
                                                              py_var_singular(st,
                                           "d2L/dqdot2 is singular: the velocities do not "
                                           "follow from the momenta")));
}

/* variational_eval(L, x, y, p) -> (m, K): the values and derivatives at m points. */
static PyObject *py_variational_eval(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo, *xo, *yo, *po;
    if (!PyArg_ParseTuple(args, "OOOO", &fo, &xo, &yo, &po)) return NULL;
    mp_py_refs k = {0};
    py_var_spec L;
    PyArrayObject *x, *y, *p, *out;
    npy_intp m;
    if (py_var_path(&k, fo, xo, yo, po, &L, &x, &y, &p, &m) < 0) return mp_py_release(&k, NULL);
    npy_intp dims[2] = {m, (npy_intp)mp_var_nvalues(L.F.d)};
    if (!(out = mp_py_hold(&k, mp_py_empty(2, dims)))) return mp_py_release(&k, NULL);
    int st;
    const double *xx = PyArray_DATA(x), *yy = PyArray_DATA(y), *pp = PyArray_DATA(p);
    double *oo = PyArray_DATA(out);
    Py_BEGIN_ALLOW_THREADS
    st = m ? L.F.eval((size_t)m, xx, yy, pp, oo, L.F.ctx) : MP_OK;
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, mp_py_result(st, "variational_eval", (PyObject *)out));
}

PyMethodDef mp_py_variational_methods[] = {
    {"variational_solve", py_variational_solve, METH_VARARGS,
     "Newton solver of the discrete Euler-Lagrange equations (internal)."},
    {"variational_integrate", py_variational_integrate, METH_VARARGS,
     "Variational integrator of the midpoint discrete Lagrangian (internal)."},
    {"variational_momenta", py_variational_momenta, METH_VARARGS,
     "Discrete momenta along a path (internal)."},
    {"variational_velocities", py_variational_velocities, METH_VARARGS,
     "Velocities from momenta, the Legendre transform back (internal)."},
    {"variational_eval", py_variational_eval, METH_VARARGS,
     "A Lagrangian and its derivatives at points (internal)."},
    {"_variational_capsule", py_variational_capsule, METH_O,
     "Wrap the address of a compiled mp_gen_lagrangian (internal; the address must be "
     "that of such a function)."},
    {NULL, NULL, 0, NULL},
};
