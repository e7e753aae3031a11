/* Binding for the rigid-body functions (mechpy/rigid.py validates first). */
#include "mp_py.h"

#include "models/rigid.h"

/* rigid_free_rotation(moments (3,), omega0 (3,), t (n,)) -> (n, 3) */
static PyObject *py_rigid_free_rotation(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *oi, *ow, *ot, *res = NULL;
    PyArrayObject *Im = NULL, *w = NULL, *t = NULL, *out = NULL;
    if (!PyArg_ParseTuple(args, "OOO", &oi, &ow, &ot)) return NULL;
    if (!(Im = mp_py_array(oi, "moments", 1)) || !(w = mp_py_array(ow, "omega0", 1)) ||
        !(t = mp_py_array(ot, "t", 1)))
        goto done;
    if (PyArray_SIZE(Im) != 3 || PyArray_SIZE(w) != 3) {
        PyErr_SetString(PyExc_ValueError, "moments and omega0 must have 3 components");
        goto done;
    }
    npy_intp shape[2] = {PyArray_SIZE(t), 3};
    if (!(out = mp_py_empty(2, shape))) goto done;
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_rigid_free_rotation(PyArray_DATA(Im), PyArray_DATA(w), PyArray_DATA(t),
                                (size_t)shape[0], PyArray_DATA(out));
    Py_END_ALLOW_THREADS
    if (rc != MP_OK) {
        mp_py_raise(rc, "free_rotation: moments must be positive and satisfy the triangle "
                        "inequality; omega0 and t finite");
        goto done;
    }
    res = (PyObject *)out;
    out = NULL;
done:
    Py_XDECREF(Im); Py_XDECREF(w); Py_XDECREF(t); Py_XDECREF(out);
    return res;
}

static PyObject *py_rigid_flip_period(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *oi, *ow, *res = NULL;
    PyArrayObject *Im = NULL, *w = NULL;
    if (!PyArg_ParseTuple(args, "OO", &oi, &ow)) return NULL;
    if (!(Im = mp_py_array(oi, "moments", 1)) || !(w = mp_py_array(ow, "omega0", 1))) goto done;
    if (PyArray_SIZE(Im) != 3 || PyArray_SIZE(w) != 3) {
        PyErr_SetString(PyExc_ValueError, "moments and omega0 must have 3 components");
        goto done;
    }
    double T = 0.0;
    int rc = mp_rigid_flip_period(PyArray_DATA(Im), PyArray_DATA(w), &T);
    if (rc != MP_OK) {
        mp_py_raise(rc, "flip_period: moments must be distinct, positive and satisfy the "
                        "triangle inequality");
        goto done;
    }
    res = PyFloat_FromDouble(T);
done:
    Py_XDECREF(Im); Py_XDECREF(w);
    return res;
}

PyMethodDef mp_py_rigid_methods[] = {
    {"rigid_free_rotation", py_rigid_free_rotation, METH_VARARGS,
     "Exact torque-free body angular velocity at times t."},
    {"rigid_flip_period", py_rigid_flip_period, METH_VARARGS,
     "Period of the torque-free body angular velocity."},
    {NULL, NULL, 0, NULL},
};
