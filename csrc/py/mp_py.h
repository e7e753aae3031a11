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

/* A new float64 array of the given shape (C order), or NULL. */
PyArrayObject *mp_py_empty(int ndim, const npy_intp *shape);

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
