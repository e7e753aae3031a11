/* Binding for the modes functions of the C core: parse, convert, call with
 * the GIL released, map the status.  No physics here. */
#include "mp_py.h"

#include <limits.h>
#include <stdio.h>

#include "modes.h"

/* A square float64 matrix argument (new reference) with its order in *n. */
static PyArrayObject *mp_py_modes_square(PyObject *obj, const char *name, int *n)
{
    PyArrayObject *a = mp_py_array_finite(obj, name, 2, -1);
    if (!a) return NULL;
    npy_intp r = PyArray_DIM(a, 0), c = PyArray_DIM(a, 1);
    if (r != c || r < 1 || r > INT_MAX / 2) {
        PyErr_Format(PyExc_ValueError, "%s must be a non-empty square matrix, got shape (%zd, %zd)",
                     name, (Py_ssize_t)r, (Py_ssize_t)c);
        Py_DECREF(a);
        return NULL;
    }
    *n = (int)r;
    return a;
}

static PyObject *mp_py_modes_result(int status, PyArrayObject *w, PyArrayObject *z,
                                    double w_bad, const char *context)
{
    if (status != MP_OK) {
        Py_DECREF(w);
        Py_DECREF(z);
        if (status == MP_EUNSTABLE) {
            char detail[96];
            snprintf(detail, sizeof detail, "eigenvalue omega^2 = %.6g < 0", w_bad);
            return mp_py_raise_detail(status, context, detail);
        }
        return mp_py_raise(status, context);
    }
    return Py_BuildValue("(NN)", (PyObject *)w, (PyObject *)z);
}

PyDoc_STRVAR(modes_dense_doc,
"modes_dense(K, M, zero_rtol) -> (w, Z)\n\n"
"Dense K v = w M v by LAPACK dsygvd: w ascending, Z[k] is mode k\n"
"(M-normalised, sign rule applied).  K and M must be symmetric.");

static PyObject *modes_dense(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *ko, *mo;
    int n = 0, nm = 0;
    double zero_rtol = -1.0;
    if (!PyArg_ParseTuple(args, "OO|d:modes_dense", &ko, &mo, &zero_rtol)) return NULL;
    PyArrayObject *k = mp_py_modes_square(ko, "K", &n);
    if (!k) return NULL;
    PyArrayObject *m = mp_py_modes_square(mo, "M", &nm);
    if (!m) {
        Py_DECREF(k);
        return NULL;
    }
    if (nm != n) {
        PyErr_Format(PyExc_ValueError, "M must have the shape of K (%d x %d), got %d x %d",
                     n, n, nm, nm);
        Py_DECREF(k);
        Py_DECREF(m);
        return NULL;
    }
    /* LAPACK overwrites both: work on copies. */
    PyArrayObject *z = (PyArrayObject *)PyArray_NewCopy(k, NPY_CORDER);
    PyArrayObject *mc = (PyArrayObject *)PyArray_NewCopy(m, NPY_CORDER);
    Py_DECREF(k);
    Py_DECREF(m);
    npy_intp shape[1] = {n};
    PyArrayObject *w = mp_py_empty(1, shape);
    if (!z || !mc || !w) {
        Py_XDECREF(z);
        Py_XDECREF(mc);
        Py_XDECREF(w);
        return NULL;
    }
    int status;
    double w_bad = 0.0;
    Py_BEGIN_ALLOW_THREADS
    status = mp_modes_dense(n, (double *)PyArray_DATA(z), (double *)PyArray_DATA(mc),
                            zero_rtol, (double *)PyArray_DATA(w), &w_bad);
    Py_END_ALLOW_THREADS
    Py_DECREF(mc);
    return mp_py_modes_result(status, w, z, w_bad, "normal_modes(K, M)");
}

PyDoc_STRVAR(modes_tridiag_doc,
"modes_tridiag(kd, ke, md, zero_rtol) -> (w, Z)\n\n"
"Chain K v = w M v with K tridiagonal (diagonal kd, off-diagonal ke) and\n"
"M = diag(md), by LAPACK dstemr on M^-1/2 K M^-1/2: O(n^2).");

static PyObject *modes_tridiag(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *kdo, *keo, *mdo;
    double zero_rtol = -1.0;
    if (!PyArg_ParseTuple(args, "OOO|d:modes_tridiag", &kdo, &keo, &mdo, &zero_rtol))
        return NULL;
    PyArrayObject *kd = mp_py_array(kdo, "kd", 1);
    PyArrayObject *ke = mp_py_array(keo, "ke", 1);
    PyArrayObject *md = mp_py_array(mdo, "md", 1);
    PyArrayObject *w = NULL, *z = NULL;
    PyObject *res = NULL;
    if (!kd || !ke || !md) goto done;
    npy_intp n = PyArray_DIM(kd, 0);
    if (n < 1 || n > 100000 || PyArray_DIM(md, 0) != n || PyArray_DIM(ke, 0) != n - 1) {
        PyErr_Format(PyExc_ValueError,
                     "kd, ke, md must have lengths n, n-1, n with 1 <= n <= 100000");
        goto done;
    }
    if (mp_py_require_finite(kd, "K") < 0 || mp_py_require_finite(ke, "K") < 0 ||
        mp_py_require_finite(md, "M") < 0)
        goto done;
    npy_intp s1[1] = {n}, s2[2] = {n, n};
    w = mp_py_empty(1, s1);
    z = mp_py_empty(2, s2);
    if (!w || !z) {
        Py_XDECREF(w);
        Py_XDECREF(z);
        goto done;
    }
    int status;
    double w_bad = 0.0;
    Py_BEGIN_ALLOW_THREADS
    status = mp_modes_tridiag((int)n, (const double *)PyArray_DATA(kd),
                              (const double *)PyArray_DATA(ke),
                              (const double *)PyArray_DATA(md), zero_rtol,
                              (double *)PyArray_DATA(w),
                              (double *)PyArray_DATA(z), &w_bad);
    Py_END_ALLOW_THREADS
    res = mp_py_modes_result(status, w, z, w_bad, "normal_modes(K, M) (chain)");
done:
    Py_XDECREF(kd);
    Py_XDECREF(ke);
    Py_XDECREF(md);
    return res;
}

PyDoc_STRVAR(modes_is_chain_doc,
"modes_is_chain(K, M) -> (kd, ke, md) or None\n\n"
"The bands of K (tridiagonal) and M (diagonal) when the pair is a chain.");

static PyObject *modes_is_chain(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *ko, *mo;
    int n = 0, nm = 0;
    if (!PyArg_ParseTuple(args, "OO:modes_is_chain", &ko, &mo)) return NULL;
    PyArrayObject *k = mp_py_modes_square(ko, "K", &n);
    if (!k) return NULL;
    PyArrayObject *m = mp_py_modes_square(mo, "M", &nm);
    if (!m || nm != n) {
        if (m) PyErr_Format(PyExc_ValueError, "M must have the shape of K");
        Py_DECREF(k);
        Py_XDECREF(m);
        return NULL;
    }
    npy_intp s1[1] = {n}, s0[1] = {n - 1};
    PyArrayObject *kd = mp_py_empty(1, s1), *ke = mp_py_empty(1, s0), *md = mp_py_empty(1, s1);
    PyObject *res = NULL;
    if (kd && ke && md) {
        int yes;
        Py_BEGIN_ALLOW_THREADS
        yes = mp_modes_is_chain(n, (const double *)PyArray_DATA(k),
                                (const double *)PyArray_DATA(m), (double *)PyArray_DATA(kd),
                                (double *)PyArray_DATA(ke), (double *)PyArray_DATA(md));
        Py_END_ALLOW_THREADS
        if (yes) {
            res = Py_BuildValue("(OOO)", kd, ke, md);
        } else {
            Py_INCREF(Py_None);
            res = Py_None;
        }
    }
    Py_DECREF(k);
    Py_DECREF(m);
    Py_XDECREF(kd);
    Py_XDECREF(ke);
    Py_XDECREF(md);
    return res;
}

PyMethodDef mp_py_modes_methods[] = {
    {"modes_dense", modes_dense, METH_VARARGS, modes_dense_doc},
    {"modes_tridiag", modes_tridiag, METH_VARARGS, modes_tridiag_doc},
    {"modes_is_chain", modes_is_chain, METH_VARARGS, modes_is_chain_doc},
    {NULL, NULL, 0, NULL},
};
