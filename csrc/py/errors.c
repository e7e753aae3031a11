/* The one table that maps C status codes to Python exceptions. */
#include "mp_py.h"

#include <stdio.h>
#include <math.h>

/* Classes are created once at module init and never change afterwards. */
static PyObject *mp_exc[MP_NSTATUS];
static PyObject *mp_base_error;

struct mp_exc_def {
    int status;
    const char *name;      /* attribute name on mechpy._core */
    const char *doc;
    PyObject **extra_base; /* a builtin base besides MechpyError, or NULL */
};

/* Builtin bases are looked up at init (they are stable singletons). */
static PyObject *mp_py_ValueError, *mp_py_RuntimeError, *mp_py_LinAlgError;

static const struct mp_exc_def mp_exc_table[] = {
    {MP_EDOM, "DomainError", "An argument is outside its domain.", &mp_py_ValueError},
    {MP_EMAXSTEPS, "StepBudgetError", "The step budget (max_steps) ran out.", &mp_py_RuntimeError},
    {MP_ESTEP, "StepSizeError", "The step size fell below round-off.", &mp_py_RuntimeError},
    {MP_ENOTSPD, "NotPositiveDefiniteError",
     "A matrix that must be symmetric positive definite is not.", &mp_py_LinAlgError},
    {MP_ENONFINITE, "NonFiniteError", "A NaN or inf was produced.", &mp_py_ValueError},
    {MP_ENOCONV, "ConvergenceError", "An iteration did not converge.", &mp_py_RuntimeError},
    {MP_ESINGULAR, "SingularityError",
     "A singular configuration (gimbal lock, singular matrix).", &mp_py_ValueError},
    {MP_EMESH, "MeshError", "A mesh is open, non-manifold, inside out or degenerate.",
     &mp_py_ValueError},
    {MP_EGSL, "GSLError", "GSL reported an unexpected error.", &mp_py_RuntimeError},
    {MP_EUNSTABLE, "UnstableSystemError",
     "A physical system is unstable (a negative stiffness eigenvalue).", &mp_py_ValueError},
};

int mp_py_errors_init(PyObject *module)
{
    PyObject *linalg = PyImport_ImportModule("numpy.linalg");
    if (!linalg) return -1;
    mp_py_LinAlgError = PyObject_GetAttrString(linalg, "LinAlgError");
    Py_DECREF(linalg);
    if (!mp_py_LinAlgError) return -1;
    mp_py_ValueError = PyExc_ValueError;
    mp_py_RuntimeError = PyExc_RuntimeError;

    mp_base_error = PyErr_NewExceptionWithDoc(
        "mechpy.MechpyError", "Base class of every error mechpy raises.", PyExc_Exception, NULL);
    if (!mp_base_error) return -1;
    Py_INCREF(mp_base_error);
    if (PyModule_AddObject(module, "MechpyError", mp_base_error) < 0) return -1;

    for (size_t i = 0; i < sizeof mp_exc_table / sizeof mp_exc_table[0]; i++) {
        const struct mp_exc_def *d = &mp_exc_table[i];
        char qual[96];
        snprintf(qual, sizeof qual, "mechpy.%s", d->name);
        PyObject *bases = PyTuple_Pack(2, mp_base_error, *d->extra_base);
        if (!bases) return -1;
        PyObject *cls = PyErr_NewExceptionWithDoc(qual, d->doc, bases, NULL);
        Py_DECREF(bases);
        if (!cls) return -1;
        mp_exc[d->status] = cls;
        Py_INCREF(cls);
        if (PyModule_AddObject(module, d->name, cls) < 0) return -1;
    }
    return 0;
}

PyObject *mp_py_exception_for(int status)
{
    if (status == MP_ENOMEM) return PyExc_MemoryError;
    if (status > 0 && status < MP_NSTATUS && mp_exc[status]) return mp_exc[status];
    return mp_base_error ? mp_base_error : PyExc_RuntimeError;
}

PyObject *mp_py_raise_detail(int status, const char *context, const char *detail)
{
    if ((status == MP_ECALLBACK || status == MP_EINTR) && PyErr_Occurred())
        return NULL;   /* keep the callback's own exception and traceback */
    if (status == MP_ENOMEM) {
        PyErr_NoMemory();
        return NULL;
    }
    PyObject *cls = (status == MP_ECALLBACK || status == MP_EINTR)
                        ? PyExc_RuntimeError : mp_py_exception_for(status);
    if (detail && detail[0])
        PyErr_Format(cls, "%s: %s (%s)", context ? context : "mechpy",
                     mp_status_message(status), detail);
    else
        PyErr_Format(cls, "%s: %s", context ? context : "mechpy", mp_status_message(status));
    return NULL;
}

PyObject *mp_py_raise(int status, const char *context)
{
    return mp_py_raise_detail(status, context, NULL);
}

PyArrayObject *mp_py_array(PyObject *obj, const char *name, int ndim)
{
    PyArrayObject *a;
    if (PyArray_Check(obj)) {
        int t = PyArray_TYPE((PyArrayObject *)obj);
        if (!(PyTypeNum_ISINTEGER(t) || PyTypeNum_ISFLOAT(t) || PyTypeNum_ISBOOL(t))) {
            PyErr_Format(PyExc_TypeError, "%s must be a real numeric array, got dtype %R",
                         name, (PyObject *)PyArray_DESCR((PyArrayObject *)obj));
            return NULL;
        }
    }
    a = (PyArrayObject *)PyArray_FROM_OTF(obj, NPY_DOUBLE,
                                          NPY_ARRAY_IN_ARRAY | NPY_ARRAY_FORCECAST);
    if (!a) {
        if (PyErr_ExceptionMatches(PyExc_TypeError) || PyErr_ExceptionMatches(PyExc_ValueError)) {
            PyErr_Clear();
            PyErr_Format(PyExc_TypeError, "%s must be a real numeric array", name);
        }
        return NULL;
    }
    if (ndim >= 0 && PyArray_NDIM(a) != ndim) {
        PyErr_Format(PyExc_ValueError, "%s must have %d dimension(s), got %d", name, ndim,
                     PyArray_NDIM(a));
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

PyArrayObject *mp_py_array_finite(PyObject *obj, const char *name, int ndim, npy_intp last)
{
    PyArrayObject *a = mp_py_array(obj, name, ndim);
    if (!a) return NULL;
    int nd = PyArray_NDIM(a);
    if (last >= 0 && (nd == 0 || PyArray_DIM(a, nd - 1) != last)) {
        PyErr_Format(PyExc_ValueError, "%s must have a last axis of length %zd", name,
                     (Py_ssize_t)last);
        Py_DECREF(a);
        return NULL;
    }
    if (mp_py_require_finite(a, name) < 0) {
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

int mp_py_require_finite(PyArrayObject *a, const char *name)
{
    const double *p = (const double *)PyArray_DATA(a);
    npy_intp n = PyArray_SIZE(a);
    for (npy_intp i = 0; i < n; i++) {
        if (!isfinite(p[i])) {
            PyErr_Format(PyExc_ValueError, "%s must be finite (element %zd is %s)", name,
                         (Py_ssize_t)i, isnan(p[i]) ? "nan" : (p[i] > 0 ? "inf" : "-inf"));
            return -1;
        }
    }
    return 0;
}

PyArrayObject *mp_py_empty(int ndim, const npy_intp *shape)
{
    return (PyArrayObject *)PyArray_SimpleNew(ndim, (npy_intp *)shape, NPY_DOUBLE);
}

int mp_py_check_interrupt(void *unused)
{
    (void)unused;
    PyGILState_STATE g = PyGILState_Ensure();
    int rc = PyErr_CheckSignals() < 0 ? MP_EINTR : MP_OK;
    PyGILState_Release(g);
    return rc;
}
