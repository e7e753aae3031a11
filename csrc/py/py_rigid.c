/* Binding for the rigid-body functions (mechpy/rigid.py validates first). */
#include "mp_py.h"

#include "models/rigid.h"

/* The (moments (3,), omega0 (3,)) pair both functions take, held in k. */
static int rigid_pair(mp_py_refs *k, PyObject *oi, PyObject *ow, PyArrayObject **Im,
                      PyArrayObject **w)
{
    npy_intp s3[1] = {3};
    if (!(*Im = mp_py_hold(k, mp_py_array_shape(oi, "moments", 1, s3))) ||
        !(*w = mp_py_hold(k, mp_py_array_shape(ow, "omega0", 1, s3))))
        return -1;
    return 0;
}

/* rigid_free_rotation(moments (3,), omega0 (3,), t (n,)) -> (n, 3) */
static PyObject *py_rigid_free_rotation(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *oi, *ow, *ot;
    PyArrayObject *Im, *w, *t, *out;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "OOO", &oi, &ow, &ot)) return NULL;
    if (rigid_pair(&k, oi, ow, &Im, &w) < 0 || !(t = mp_py_hold(&k, mp_py_array(ot, "t", 1))))
        return mp_py_release(&k, NULL);
    npy_intp shape[2] = {PyArray_SIZE(t), 3};
    if (!(out = mp_py_hold(&k, mp_py_empty(2, shape)))) return mp_py_release(&k, NULL);
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_rigid_free_rotation(PyArray_DATA(Im), PyArray_DATA(w), PyArray_DATA(t),
                                (size_t)shape[0], PyArray_DATA(out));
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, mp_py_result(rc, "free_rotation: moments must be positive and "
                                              "satisfy the triangle inequality; omega0 and t "
                                              "finite", (PyObject *)out));
}

/* rigid_flip_period(moments (3,), omega0 (3,)) -> float */
static PyObject *py_rigid_flip_period(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *oi, *ow;
    PyArrayObject *Im, *w;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "OO", &oi, &ow)) return NULL;
    if (rigid_pair(&k, oi, ow, &Im, &w) < 0) return mp_py_release(&k, NULL);
    double T = 0.0;
    int rc = mp_rigid_flip_period(PyArray_DATA(Im), PyArray_DATA(w), &T);
    return mp_py_release(&k, rc == MP_OK ? PyFloat_FromDouble(T)
                                         : mp_py_raise(rc, "flip_period: moments must be "
                                                           "distinct, positive and satisfy the "
                                                           "triangle inequality"));
}

PyMethodDef mp_py_rigid_methods[] = {
    {"rigid_free_rotation", py_rigid_free_rotation, METH_VARARGS,
     "Exact torque-free body angular velocity at times t."},
    {"rigid_flip_period", py_rigid_flip_period, METH_VARARGS,
     "Period of the torque-free body angular velocity."},
    {NULL, NULL, 0, NULL},
};
