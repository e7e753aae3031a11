/* Binding for the variational solvers of the C core: integrand specs
 * (a built-in by name, or a Python callable returning the six derivative
 * arrays), the Newton solver and the variational integrator. */
#include "mp_py.h"

#include <string.h>

#include "variational.h"

#define MP_VAR_MAXCON 16

typedef struct {
    mp_var_builtin b;
    PyObject *fn; /* borrowed: a Python callable f(x, y, p) -> (6, m), or NULL */
    mp_var_integrand F;
} py_var_spec;

/* The Python integrand adapter: called from C with the GIL released. */
static int py_var_eval(size_t m, const double *x, const double *y, const double *p, double *out,
                       void *ctx)
{
    py_var_spec *s = ctx;
    int st = MP_ECALLBACK;
    PyGILState_STATE gs = PyGILState_Ensure();
    npy_intp dim = (npy_intp)m;
    PyArrayObject *ax = mp_py_empty(1, &dim), *ay = mp_py_empty(1, &dim), *ap = mp_py_empty(1, &dim);
    PyObject *r = NULL;
    PyArrayObject *ra = NULL;
    if (!ax || !ay || !ap) goto done;
    memcpy(PyArray_DATA(ax), x, m * sizeof(double));
    memcpy(PyArray_DATA(ay), y, m * sizeof(double));
    memcpy(PyArray_DATA(ap), p, m * sizeof(double));
    r = PyObject_CallFunctionObjArgs(s->fn, (PyObject *)ax, (PyObject *)ay, (PyObject *)ap, NULL);
    if (!r) goto done;
    ra = mp_py_array(r, "integrand derivatives", 2);
    if (!ra) goto done;
    if (PyArray_DIM(ra, 0) != 6 || PyArray_DIM(ra, 1) != dim) {
        PyErr_Format(PyExc_ValueError,
                     "the integrand must return an array of shape (6, %zd), got (%zd, %zd)",
                     (Py_ssize_t)dim, (Py_ssize_t)PyArray_DIM(ra, 0),
                     (Py_ssize_t)PyArray_DIM(ra, 1));
        goto done;
    }
    memcpy(out, PyArray_DATA(ra), 6 * m * sizeof(double));
    st = MP_OK;
done:
    Py_XDECREF(ax);
    Py_XDECREF(ay);
    Py_XDECREF(ap);
    Py_XDECREF(r);
    Py_XDECREF(ra);
    PyGILState_Release(gs);
    return st;
}

/* spec: a callable, or a tuple (name, params) naming a built-in. */
static int py_var_parse(PyObject *obj, py_var_spec *s, const char *what)
{
    memset(s, 0, sizeof *s);
    if (PyCallable_Check(obj)) {
        s->fn = obj;
        s->F.eval = py_var_eval;
        s->F.ctx = s;
        return 0;
    }
    const char *name;
    PyObject *po;
    if (!PyTuple_Check(obj) || !PyArg_ParseTuple(obj, "sO", &name, &po)) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s must be a callable or a tuple (name, params)", what);
        return -1;
    }
    size_t np;
    if (mp_variational_builtin_find(name, &s->b.kind, &np) != MP_OK) {
        PyErr_Format(PyExc_ValueError, "%s: unknown built-in integrand %s", what, name);
        return -1;
    }
    PyArrayObject *p = mp_py_array(po, "params", 1);
    if (!p) return -1;
    if ((size_t)PyArray_SIZE(p) != np) {
        PyErr_Format(PyExc_ValueError, "%s: %s takes %zd parameters, got %zd", what, name,
                     (Py_ssize_t)np, (Py_ssize_t)PyArray_SIZE(p));
        Py_DECREF(p);
        return -1;
    }
    if (mp_py_require_finite(p, "params") < 0) {
        Py_DECREF(p);
        return -1;
    }
    memcpy(s->b.params, PyArray_DATA(p), np * sizeof(double));
    Py_DECREF(p);
    mp_variational_builtin_bind(&s->b, &s->F);
    return 0;
}

/* variational_solve(F, x, y0, constraints, values, lambda0, stationary, tol, max_iter)
 * -> (y, lambda, {"iterations", "J", "residual", "constraint_error"}) */
static PyObject *py_variational_solve(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo, *xo, *yo, *co, *vo, *lo;
    int stationary;
    double tol;
    Py_ssize_t max_iter;
    if (!PyArg_ParseTuple(args, "OOOOOOpdn", &fo, &xo, &yo, &co, &vo, &lo, &stationary, &tol,
                          &max_iter))
        return NULL;
    py_var_spec F, G[MP_VAR_MAXCON];
    mp_var_integrand GI[MP_VAR_MAXCON];
    PyArrayObject *x = NULL, *y = NULL, *v = NULL, *lam = NULL;
    PyObject *seq = NULL, *res = NULL;
    if (py_var_parse(fo, &F, "F") < 0) return NULL;
    seq = PySequence_Fast(co, "constraints must be a sequence");
    if (!seq) return NULL;
    Py_ssize_t nc = PySequence_Fast_GET_SIZE(seq);
    if (nc > MP_VAR_MAXCON) {
        PyErr_Format(PyExc_ValueError, "at most %d constraints", MP_VAR_MAXCON);
        goto done;
    }
    for (Py_ssize_t k = 0; k < nc; k++) {
        if (py_var_parse(PySequence_Fast_GET_ITEM(seq, k), &G[k], "constraint") < 0) goto done;
        GI[k] = G[k].F;
    }
    if (!(x = mp_py_array(xo, "x", 1)) || !(v = mp_py_array(vo, "values", 1)) ||
        !(lam = mp_py_array(lo, "lambda0", 1)))
        goto done;
    PyArrayObject *y0 = mp_py_array(yo, "y0", 1);
    if (!y0) goto done;
    y = (PyArrayObject *)PyArray_NewCopy(y0, NPY_CORDER);
    Py_DECREF(y0);
    if (!y) goto done;
    PyArrayObject *l2 = (PyArrayObject *)PyArray_NewCopy(lam, NPY_CORDER);
    Py_DECREF(lam);
    lam = l2;
    if (!lam) goto done;
    npy_intp npts = PyArray_SIZE(x);
    if (npts < 3 || PyArray_SIZE(y) != npts || PyArray_SIZE(v) != nc || PyArray_SIZE(lam) != nc ||
        max_iter < 1) {
        PyErr_SetString(PyExc_ValueError,
                        "variational_solve: need len(x) == len(y0) >= 3, one value and one "
                        "multiplier per constraint, max_iter >= 1");
        goto done;
    }
    mp_var_problem pb = {.n = (size_t)npts - 1, .x = PyArray_DATA(x), .F = F.F,
                         .ncon = (size_t)nc, .G = GI, .value = PyArray_DATA(v),
                         .stationary = stationary, .tol = tol, .max_iter = (size_t)max_iter};
    mp_var_info info = {0};
    int st;
    double *yy = PyArray_DATA(y), *ll = PyArray_DATA(lam);
    Py_BEGIN_ALLOW_THREADS
    st = mp_variational_solve(&pb, yy, ll, &info);
    Py_END_ALLOW_THREADS
    if (st != MP_OK) {
        char detail[160];
        snprintf(detail, sizeof detail,
                 "after %zu Newton iterations (residual %.3g, constraint error %.3g)",
                 info.iterations, info.residual, info.constraint_error);
        mp_py_raise_detail(st, "variational_solve", detail);
        goto done;
    }
    res = Py_BuildValue("(OO{s:n,s:d,s:d,s:d})", (PyObject *)y, (PyObject *)lam, "iterations",
                        (Py_ssize_t)info.iterations, "J", info.J, "residual", info.residual,
                        "constraint_error", info.constraint_error);
done:
    Py_XDECREF(seq);
    Py_XDECREF(x);
    Py_XDECREF(y);
    Py_XDECREF(v);
    Py_XDECREF(lam);
    return res;
}

/* variational_integrate(L, t0, h, nsteps, q0, p0) -> (q, p), each nsteps + 1 */
static PyObject *py_variational_integrate(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *fo;
    double t0, h, q0, p0;
    Py_ssize_t nsteps;
    if (!PyArg_ParseTuple(args, "Oddndd", &fo, &t0, &h, &nsteps, &q0, &p0)) return NULL;
    py_var_spec L;
    if (py_var_parse(fo, &L, "L") < 0) return NULL;
    if (nsteps < 0) {
        PyErr_SetString(PyExc_ValueError, "nsteps must be >= 0");
        return NULL;
    }
    npy_intp dim = nsteps + 1;
    PyArrayObject *q = mp_py_empty(1, &dim), *p = mp_py_empty(1, &dim);
    if (!q || !p) {
        Py_XDECREF(q);
        Py_XDECREF(p);
        return NULL;
    }
    int st;
    double *qq = PyArray_DATA(q), *pp = PyArray_DATA(p);
    Py_BEGIN_ALLOW_THREADS
    st = mp_variational_integrate(&L.F, t0, h, (size_t)nsteps, q0, p0, qq, pp,
                                  mp_py_check_interrupt, NULL);
    Py_END_ALLOW_THREADS
    if (st != MP_OK) {
        Py_DECREF(q);
        Py_DECREF(p);
        return mp_py_raise(st, "variational_integrate");
    }
    return Py_BuildValue("(NN)", (PyObject *)q, (PyObject *)p);
}

PyMethodDef mp_py_variational_methods[] = {
    {"variational_solve", py_variational_solve, METH_VARARGS,
     "Newton solver of the discrete Euler-Lagrange equations (internal)."},
    {"variational_integrate", py_variational_integrate, METH_VARARGS,
     "Variational integrator of the midpoint discrete Lagrangian (internal)."},
    {NULL, NULL, 0, NULL},
};
