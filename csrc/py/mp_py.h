/* The thin CPython/NumPy binding: shared helpers.  No physics here.
 *
 * Every binding file includes this header.  module.c defines
 * MP_PY_MODULE_C before including it, so that NumPy's C-API table is
 * defined exactly once. */
#ifndef MP_PY_H
#define MP_PY_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define PY_ARRAY_UNIQUE_SYMBOL mechpy_ARRAY_API
#ifndef MP_PY_MODULE_C
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include "mp_status.h"

/* Raise the exception that the one status table (errors.c) maps `status`
 * to, with a message "context: description".  Keeps an exception that a
 * callback already set (MP_ECALLBACK, MP_EINTR).  Always returns NULL. */
PyObject *mp_py_raise(int status, const char *context);

/* Same, with a caller-formatted detail appended to the message. */
PyObject *mp_py_raise_detail(int status, const char *context, const char *detail);

/* Create the exception classes and add them to the module (at init). */
int mp_py_errors_init(PyObject *module);

/* Exception class for a status (borrowed reference). */
PyObject *mp_py_exception_for(int status);

/* Convert obj to an aligned, C-contiguous float64 array (new reference).
 * ndim >= 0 requires that many dimensions; -1 accepts any.  Non-numeric
 * input raises TypeError naming `name`; NULL on error. */
PyArrayObject *mp_py_array(PyObject *obj, const char *name, int ndim);

/* mp_py_array, then: the last axis must have length `last` (-1: any) and every
 * element must be finite; errors name the argument. */
PyArrayObject *mp_py_array_finite(PyObject *obj, const char *name, int ndim, npy_intp last);

/* ValueError naming `name` unless every element is finite. */
int mp_py_require_finite(PyArrayObject *a, const char *name);

/* mp_py_array with exactly the given shape (shape[k] = -1: any length);
 * the error names the argument and the axis. */
PyArrayObject *mp_py_array_shape(PyObject *obj, const char *name, int ndim,
                                 const npy_intp *shape);

/* A new float64 array of the given shape (C order), or NULL. */
PyArrayObject *mp_py_empty(int ndim, const npy_intp *shape);

/* The new references one binding call holds (the arrays it converted or
 * created), dropped together on every way out.  A call declares
 * `mp_py_refs k = {0};`, passes each new reference through mp_py_hold and
 * leaves through `return mp_py_release(&k, result);`, so no exit path can
 * leak or drop one twice.  At most MP_PY_MAXREFS per call. */
#define MP_PY_MAXREFS 32
typedef struct mp_py_refs {
    PyObject *o[MP_PY_MAXREFS];
    int n;
} mp_py_refs;

/* Hold the new reference `obj` (NULL passes through: the error it stands for
 * is already set) until mp_py_release; returns obj. */
void *mp_py_hold(mp_py_refs *k, void *obj);

/* Drop every held reference and return `result` (a new reference of the
 * caller's, or NULL with an exception set). */
PyObject *mp_py_release(mp_py_refs *k, PyObject *result);

/* How a C call ends a binding call: MP_OK gives a new reference to `out`,
 * another status raises its exception ("context: description") and gives
 * NULL. */
PyObject *mp_py_result(int status, const char *context, PyObject *out);

/* Interrupt check usable from C loops with the GIL released: takes the GIL,
 * runs PyErr_CheckSignals, returns MP_EINTR if an exception is pending. */
int mp_py_check_interrupt(void *unused);

/* The per-topic method tables, merged by module.c. */
extern PyMethodDef mp_py_ode_methods[];
extern PyMethodDef mp_py_scene_methods[];
extern PyMethodDef mp_py_inertia_methods[];
extern PyMethodDef mp_py_rotation_methods[];
extern PyMethodDef mp_py_modes_methods[];
extern PyMethodDef mp_py_variational_methods[];
extern PyMethodDef mp_py_rigid_methods[];
extern PyMethodDef mp_py_compiled_methods[];

#endif
