/* Binding for systems compiled from a user's equations (mechpy.symbolic):
 * one evaluation loop over many states for the generated library's
 * functions, run with the GIL released.  No physics here. */
#include "mp_py.h"

#include <string.h>

/* The generated evaluation signature: int f(t, y, out, params). */
typedef int (*mp_gen_fn)(double t, const double *y, double *out, void *params);

/* compiled_eval(address, params, t, Y, nout, context) -> (m, nout) array.
 * Calls the function at `address` on each row of Y (m, n) with the parameter
 * vector; a non-zero status stops the loop and raises the status table's
 * exception, with `context` and the row in its message. */
static PyObject *py_compiled_eval(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *addro, *po, *yo;
    double t;
    Py_ssize_t nout;
    const char *context;
    if (!PyArg_ParseTuple(args, "OOdOns", &addro, &po, &t, &yo, &nout, &context)) return NULL;
    void *addr = PyLong_AsVoidPtr(addro);
    if (!addr) {
        if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "compiled function address is NULL");
        return NULL;
    }
    if (nout < 0) {
        PyErr_SetString(PyExc_ValueError, "nout must be non-negative");
        return NULL;
    }
    mp_gen_fn f;
    *(void **)&f = addr; /* a data pointer handed over as an address */
    PyArrayObject *p, *y, *out;
    mp_py_refs k = {0};
    if (!(p = mp_py_hold(&k, mp_py_array(po, "params", 1))) ||
        !(y = mp_py_hold(&k, mp_py_array(yo, "y", 2))))
        return mp_py_release(&k, NULL);
    npy_intp m = PyArray_DIM(y, 0), n = PyArray_DIM(y, 1);
    npy_intp shape[2] = {m, (npy_intp)nout};
    if (!(out = mp_py_hold(&k, mp_py_empty(2, shape)))) return mp_py_release(&k, NULL);
    const double *yd = PyArray_DATA(y);
    double *od = PyArray_DATA(out);
    void *pd = PyArray_DATA(p);
    int rc = MP_OK;
    npy_intp bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (npy_intp i = 0; i < m; i++) {
        rc = f(t, yd + i * n, od + i * nout, pd);
        if (rc != MP_OK) {
            bad = i;
            break;
        }
    }
    Py_END_ALLOW_THREADS
    if (rc != MP_OK) {
        char detail[64];
        snprintf(detail, sizeof detail, "at state %ld, t = %.17g", (long)bad, t);
        return mp_py_release(&k, mp_py_raise_detail(rc, context, detail));
    }
    return mp_py_release(&k, mp_py_result(MP_OK, context, (PyObject *)out));
}

PyMethodDef mp_py_compiled_methods[] = {
    {"compiled_eval", py_compiled_eval, METH_VARARGS,
     "Evaluate a compiled system's function over many states (internal)."},
    {NULL, NULL, 0, NULL},
};
