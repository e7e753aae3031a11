/* Status codes to Python exceptions: the classes and STATUS_TABLE are made
 * from the one table in mp_status.c; nothing here holds message text. */
#include "mp_py.h"

#include <string.h>
#include <stdio.h>
#include <math.h>

/* Classes are created once at module init and never change afterwards. */
static PyObject *mp_exc[MP_NSTATUS];
static PyObject *mp_base_error;
static PyObject *mp_linalg_error; /* numpy.linalg.LinAlgError (owned) */

/* Contract: the builtin class a table row names ("ValueError", "LinAlgError",
 * "MemoryError", ...), a borrowed reference, or NULL for a name not listed. */
static PyObject *builtin_class(const char *name)
{
    static const struct { const char *name; PyObject **cls; } known[] = {
        {"ValueError", &PyExc_ValueError}, {"RuntimeError", &PyExc_RuntimeError},
        {"MemoryError", &PyExc_MemoryError}, {"KeyboardInterrupt", &PyExc_KeyboardInterrupt},
    };
    if (strcmp(name, "LinAlgError") == 0) return mp_linalg_error;
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        if (strcmp(known[i].name, name) == 0) return *known[i].cls;
    return NULL;
}

/* Contract: add _core.STATUS ({C name: code}, what generated C prints its
 * #defines from) and _core.STATUS_TABLE (one dict per row: code, name,
 * exception (the class), message, solve_status, raises).  0 or -1. */
static int add_status_tables(PyObject *module)
{
    PyObject *names = PyDict_New(), *rows = PyTuple_New(MP_NSTATUS);
    if (!names || !rows) goto fail;
    for (int s = 0; s < MP_NSTATUS; s++) {
        const mp_status_info *r = &mp_status_table[s];
        PyObject *cls = s == MP_OK || s == MP_TERMINATED ? Py_None : mp_py_exception_for(s);
        PyObject *row = Py_BuildValue("{s:i,s:s,s:O,s:s,s:i,s:i}", "code", s, "name", r->name,
                                      "exception", cls, "message", r->message, "solve_status",
                                      r->solve_status, "raises", r->raises);
        if (!row) goto fail;
        PyTuple_SET_ITEM(rows, s, row);
        PyObject *v = PyLong_FromLong(s);
        if (!v || PyDict_SetItemString(names, r->name, v) < 0) {
            Py_XDECREF(v);
            goto fail;
        }
        Py_DECREF(v);
    }
    if (PyModule_AddObject(module, "STATUS", names) < 0) goto fail;
    names = NULL;
    if (PyModule_AddObject(module, "STATUS_TABLE", rows) < 0) goto fail;
    return 0;
fail:
    Py_XDECREF(names);
    Py_XDECREF(rows);
    return -1;
}

/* Contract: create MechpyError and one class per table row that has a builtin
 * base (dual inheritance: MechpyError and that builtin), add them and the
 * status tables to the module.  0 or -1 with an exception set. */
int mp_py_errors_init(PyObject *module)
{
    PyObject *linalg = PyImport_ImportModule("numpy.linalg");
    if (!linalg) return -1;
    mp_linalg_error = PyObject_GetAttrString(linalg, "LinAlgError");
    Py_DECREF(linalg);
    if (!mp_linalg_error) return -1;

    mp_base_error = PyErr_NewExceptionWithDoc(
        "mechpy.MechpyError", "Base class of every error mechpy raises.", PyExc_Exception, NULL);
    if (!mp_base_error) return -1;
    Py_INCREF(mp_base_error);
    if (PyModule_AddObject(module, "MechpyError", mp_base_error) < 0) return -1;

    for (int s = 0; s < MP_NSTATUS; s++) {
        const mp_status_info *d = &mp_status_table[s];
        if (!d->base) continue;
        PyObject *extra = builtin_class(d->base);
        if (!extra) {
            PyErr_Format(PyExc_RuntimeError, "status table: unknown base %s", d->base);
            return -1;
        }
        char qual[96], doc[160];
        snprintf(qual, sizeof qual, "mechpy.%s", d->exception);
        snprintf(doc, sizeof doc, "Raised when %s.", d->message);
        PyObject *bases = PyTuple_Pack(2, mp_base_error, extra);
        if (!bases) return -1;
        PyObject *cls = PyErr_NewExceptionWithDoc(qual, doc, bases, NULL);
        Py_DECREF(bases);
        if (!cls) return -1;
        mp_exc[s] = cls;
        Py_INCREF(cls);
        if (PyModule_AddObject(module, d->exception, cls) < 0) return -1;
    }
    return add_status_tables(module);
}

/* Contract: the class a status raises (borrowed): its mechpy class, or the
 * builtin its row names (MemoryError, RuntimeError, KeyboardInterrupt). */
PyObject *mp_py_exception_for(int status)
{
    if (status > 0 && status < MP_NSTATUS && mp_exc[status]) return mp_exc[status];
    const mp_status_info *r = mp_status_lookup(status);
    PyObject *cls = r->exception && !r->base ? builtin_class(r->exception) : NULL;
    if (cls) return cls;
    return mp_base_error ? mp_base_error : PyExc_RuntimeError;
}

/* Contract: raise the status's class with "context: message (detail)"; an
 * exception a callback already set (MP_ECALLBACK, MP_EINTR) is kept with its
 * traceback.  Returns NULL. */
PyObject *mp_py_raise_detail(int status, const char *context, const char *detail)
{
    if ((status == MP_ECALLBACK || status == MP_EINTR) && PyErr_Occurred())
        return NULL;   /* keep the callback's own exception and traceback */
    if (status == MP_ENOMEM) {
        PyErr_NoMemory();
        return NULL;
    }
    PyObject *cls = mp_py_exception_for(status);
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

PyArrayObject *mp_py_array_shape(PyObject *obj, const char *name, int ndim,
                                 const npy_intp *shape)
{
    PyArrayObject *a = mp_py_array(obj, name, ndim);
    if (!a) return NULL;
    for (int k = 0; k < ndim; k++) {
        if (shape[k] >= 0 && PyArray_DIM(a, k) != shape[k]) {
            PyErr_Format(PyExc_ValueError, "%s has a wrong shape (axis %d has length %zd, "
                         "expected %zd)", name, k, (Py_ssize_t)PyArray_DIM(a, k),
                         (Py_ssize_t)shape[k]);
            Py_DECREF(a);
            return NULL;
        }
    }
    return a;
}

void *mp_py_hold(mp_py_refs *k, void *obj)
{
    if (!obj) return NULL;
    if (k->n == MP_PY_MAXREFS) { /* a binding holding too many: refuse, never leak */
        Py_DECREF((PyObject *)obj);
        PyErr_SetString(PyExc_SystemError, "mechpy binding: too many held references");
        return NULL;
    }
    k->o[k->n++] = obj;
    return obj;
}

PyObject *mp_py_release(mp_py_refs *k, PyObject *result)
{
    while (k->n > 0) Py_DECREF(k->o[--k->n]);
    return result;
}

PyObject *mp_py_result(int status, const char *context, PyObject *out)
{
    if (status != MP_OK) return mp_py_raise(status, context);
    Py_INCREF(out);
    return out;
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
