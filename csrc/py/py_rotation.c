/* Binding for the rotation functions of the C core: parse arguments, check
 * array shapes, release the GIL around the C loop, map statuses.  Batched
 * arrays arrive flattened to (n, k). */
#include "mp_py.h"

#include <stdio.h>

#include "rotation.h"

/* obj as a C-contiguous, finite float64 (n, k) array (new reference) or NULL. */
static PyArrayObject *batch(PyObject *obj, const char *name, npy_intp k)
{
    return mp_py_array_finite(obj, name, 2, k);
}

static int parse_seq(const char *text, struct mp_rotation_seq *seq)
{
    if (mp_rotation_seq_parse(text, seq) != MP_OK) {
        PyErr_Format(PyExc_ValueError,
                     "seq must be three axis letters from 'xyz' (extrinsic) or 'XYZ' "
                     "(intrinsic), no two consecutive alike, e.g. 'ZXZ'; got '%s'",
                     text);
        return -1;
    }
    return 0;
}

/* A new (n, k) result array. */
static PyArrayObject *result(npy_intp n, npy_intp k)
{
    npy_intp shape[2] = {n, k};
    return mp_py_empty(2, shape);
}

static PyObject *raise_at(int status, const char *context, size_t bad)
{
    char detail[64];
    snprintf(detail, sizeof detail, "item %zu of the batch", bad);
    return mp_py_raise_detail(status, context, detail);
}

/* The parameters a one-array conversion may need. */
struct call {
    struct mp_rotation_seq seq;
    int passive;
    double orth_tol, lock_tol;
};

/* One array of n rows in, one out; *nlock counts gimbal locks. */
typedef int (*kernel)(const struct call *c, size_t n, const double *in, double *out,
                      size_t *nlock, size_t *bad);

static int k_euler_matrix(const struct call *c, size_t n, const double *in, double *out,
                          size_t *nlock, size_t *bad)
{
    (void)nlock;
    (void)bad;
    return mp_rotation_euler_matrix(n, in, &c->seq, c->passive, out);
}

static int k_euler_angles(const struct call *c, size_t n, const double *in, double *out,
                          size_t *nlock, size_t *bad)
{
    return mp_rotation_euler_angles(n, in, &c->seq, c->passive, c->orth_tol, c->lock_tol, out,
                                    nlock, bad);
}

static int k_quat_from_matrix(const struct call *c, size_t n, const double *in, double *out,
                              size_t *nlock, size_t *bad)
{
    (void)nlock;
    return mp_rotation_quat_from_matrix(n, in, c->orth_tol, out, bad);
}

static int k_matrix_from_quat(const struct call *c, size_t n, const double *in, double *out,
                              size_t *nlock, size_t *bad)
{
    (void)c;
    (void)nlock;
    return mp_rotation_matrix_from_quat(n, in, out, bad);
}

static int k_quat_normalize(const struct call *c, size_t n, const double *in, double *out,
                            size_t *nlock, size_t *bad)
{
    (void)c;
    (void)nlock;
    return mp_rotation_quat_normalize(n, in, out, bad);
}

static int k_quat_from_euler(const struct call *c, size_t n, const double *in, double *out,
                             size_t *nlock, size_t *bad)
{
    (void)nlock;
    (void)bad;
    return mp_rotation_quat_from_euler(n, in, &c->seq, c->passive, out);
}

static int k_euler_from_quat(const struct call *c, size_t n, const double *in, double *out,
                             size_t *nlock, size_t *bad)
{
    return mp_rotation_euler_from_quat(n, in, &c->seq, c->passive, c->lock_tol, out, nlock,
                                       bad);
}

#define NOT_ROTATION "R is not a rotation matrix (|R R^T - I| > orth_tol or det <= 0)"
#define ZERO_QUAT "quat must have a non-zero norm"

/* Convert obj (n, k_in), run f with the GIL released, return the (n, k_out)
 * result, or (result, nlock) when with_nlock. */
static PyObject *run(PyObject *obj, const char *name, npy_intp k_in, npy_intp k_out, kernel f,
                     const struct call *c, const char *errctx, int with_nlock)
{
    PyArrayObject *a = batch(obj, name, k_in);
    if (!a) return NULL;
    npy_intp n = PyArray_DIM(a, 0);
    PyArrayObject *out = result(n, k_out);
    if (!out) {
        Py_DECREF(a);
        return NULL;
    }
    size_t nlock = 0, bad = 0;
    int st;
    Py_BEGIN_ALLOW_THREADS
    st = f(c, (size_t)n, PyArray_DATA(a), PyArray_DATA(out), &nlock, &bad);
    Py_END_ALLOW_THREADS
    Py_DECREF(a);
    if (st != MP_OK) {
        Py_DECREF(out);
        return raise_at(st, errctx, bad);
    }
    if (with_nlock) return Py_BuildValue("Nn", out, (Py_ssize_t)nlock);
    return (PyObject *)out;
}

/* (angles, seq, passive) -> (n, k_out) through f. */
static PyObject *from_euler(PyObject *args, npy_intp k_out, kernel f, const char *ctx)
{
    PyObject *obj;
    const char *text;
    struct call c = {0};
    if (!PyArg_ParseTuple(args, "Osp", &obj, &text, &c.passive)) return NULL;
    if (parse_seq(text, &c.seq) < 0) return NULL;
    return run(obj, "angles", 3, k_out, f, &c, ctx, 0);
}

static PyObject *py_euler_matrix(PyObject *self, PyObject *args)
{
    (void)self;
    return from_euler(args, 9, k_euler_matrix, "euler_matrix");
}

static PyObject *py_euler_angles(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *obj;
    const char *text;
    struct call c = {0};
    if (!PyArg_ParseTuple(args, "Ospdd", &obj, &text, &c.passive, &c.orth_tol, &c.lock_tol))
        return NULL;
    if (parse_seq(text, &c.seq) < 0) return NULL;
    return run(obj, "R", 9, 3, k_euler_angles, &c, NOT_ROTATION, 1);
}

static PyObject *py_quat_from_matrix(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *obj;
    struct call c = {0};
    if (!PyArg_ParseTuple(args, "Od", &obj, &c.orth_tol)) return NULL;
    return run(obj, "R", 9, 4, k_quat_from_matrix, &c, NOT_ROTATION, 0);
}

static PyObject *py_matrix_from_quat(PyObject *self, PyObject *obj)
{
    (void)self;
    struct call c = {0};
    return run(obj, "quat", 4, 9, k_matrix_from_quat, &c, ZERO_QUAT, 0);
}

static PyObject *py_quat_normalize(PyObject *self, PyObject *obj)
{
    (void)self;
    struct call c = {0};
    return run(obj, "quat", 4, 4, k_quat_normalize, &c, ZERO_QUAT, 0);
}

static PyObject *py_quat_from_euler(PyObject *self, PyObject *args)
{
    (void)self;
    return from_euler(args, 4, k_quat_from_euler, "quat_from_euler");
}

static PyObject *py_euler_from_quat(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *obj;
    const char *text;
    struct call c = {0};
    if (!PyArg_ParseTuple(args, "Ospd", &obj, &text, &c.passive, &c.lock_tol)) return NULL;
    if (parse_seq(text, &c.seq) < 0) return NULL;
    return run(obj, "quat", 4, 3, k_euler_from_quat, &c, ZERO_QUAT, 1);
}

static PyObject *py_quat_multiply(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *po, *qo;
    if (!PyArg_ParseTuple(args, "OO", &po, &qo)) return NULL;
    PyArrayObject *p = batch(po, "p", 4);
    if (!p) return NULL;
    PyArrayObject *q = batch(qo, "q", 4);
    if (!q) {
        Py_DECREF(p);
        return NULL;
    }
    npy_intp n = PyArray_DIM(p, 0);
    if (PyArray_DIM(q, 0) != n) {
        Py_DECREF(p);
        Py_DECREF(q);
        PyErr_SetString(PyExc_ValueError, "p and q must hold the same number of quaternions");
        return NULL;
    }
    PyArrayObject *out = result(n, 4);
    if (out) {
        Py_BEGIN_ALLOW_THREADS
        mp_rotation_quat_multiply((size_t)n, PyArray_DATA(p), PyArray_DATA(q),
                                  PyArray_DATA(out));
        Py_END_ALLOW_THREADS
    }
    Py_DECREF(p);
    Py_DECREF(q);
    return (PyObject *)out;
}

/* Shared by angular_velocity (inverse = 0) and euler_rates (inverse = 1). */
static PyObject *rate_map(PyObject *args, int inverse)
{
    PyObject *ao, *vo;
    const char *text;
    int space;
    double lock_tol = 0.0;
    struct mp_rotation_seq seq;
    if (inverse) {
        if (!PyArg_ParseTuple(args, "OOspd", &ao, &vo, &text, &space, &lock_tol)) return NULL;
    } else if (!PyArg_ParseTuple(args, "OOsp", &ao, &vo, &text, &space)) {
        return NULL;
    }
    if (parse_seq(text, &seq) < 0) return NULL;
    PyArrayObject *a = batch(ao, "angles", 3);
    if (!a) return NULL;
    PyArrayObject *v = batch(vo, inverse ? "omega" : "rates", 3);
    if (!v) {
        Py_DECREF(a);
        return NULL;
    }
    npy_intp n = PyArray_DIM(a, 0);
    if (PyArray_DIM(v, 0) != n) {
        Py_DECREF(a);
        Py_DECREF(v);
        PyErr_SetString(PyExc_ValueError, "angles and the vectors must have the same length");
        return NULL;
    }
    PyArrayObject *out = result(n, 3);
    if (!out) {
        Py_DECREF(a);
        Py_DECREF(v);
        return NULL;
    }
    size_t bad = 0;
    int st;
    Py_BEGIN_ALLOW_THREADS
    if (inverse)
        st = mp_rotation_euler_rates((size_t)n, PyArray_DATA(a), PyArray_DATA(v), &seq, space,
                                     lock_tol, PyArray_DATA(out), &bad);
    else
        st = mp_rotation_angular_velocity((size_t)n, PyArray_DATA(a), PyArray_DATA(v), &seq,
                                          space, PyArray_DATA(out));
    Py_END_ALLOW_THREADS
    Py_DECREF(a);
    Py_DECREF(v);
    if (st != MP_OK) {
        Py_DECREF(out);
        return raise_at(st,
                        "euler_rates: gimbal lock, the Euler-angle rates are not determined "
                        "by omega (the middle angle makes the rate map singular)",
                        bad);
    }
    return (PyObject *)out;
}

static PyObject *py_angular_velocity(PyObject *self, PyObject *args)
{
    (void)self;
    return rate_map(args, 0);
}

static PyObject *py_euler_rates(PyObject *self, PyObject *args)
{
    (void)self;
    return rate_map(args, 1);
}

PyMethodDef mp_py_rotation_methods[] = {
    {"rotation_euler_matrix", py_euler_matrix, METH_VARARGS,
     "rotation_euler_matrix(angles (n,3), seq, passive) -> (n,9)"},
    {"rotation_euler_angles", py_euler_angles, METH_VARARGS,
     "rotation_euler_angles(R (n,9), seq, passive, orth_tol, lock_tol) -> ((n,3), nlock)"},
    {"rotation_quat_from_matrix", py_quat_from_matrix, METH_VARARGS,
     "rotation_quat_from_matrix(R (n,9), orth_tol) -> (n,4)"},
    {"rotation_matrix_from_quat", py_matrix_from_quat, METH_O,
     "rotation_matrix_from_quat(q (n,4)) -> (n,9)"},
    {"rotation_quat_multiply", py_quat_multiply, METH_VARARGS,
     "rotation_quat_multiply(p (n,4), q (n,4)) -> (n,4)"},
    {"rotation_quat_normalize", py_quat_normalize, METH_O,
     "rotation_quat_normalize(q (n,4)) -> (n,4)"},
    {"rotation_quat_from_euler", py_quat_from_euler, METH_VARARGS,
     "rotation_quat_from_euler(angles (n,3), seq, passive) -> (n,4)"},
    {"rotation_euler_from_quat", py_euler_from_quat, METH_VARARGS,
     "rotation_euler_from_quat(q (n,4), seq, passive, lock_tol) -> ((n,3), nlock)"},
    {"rotation_angular_velocity", py_angular_velocity, METH_VARARGS,
     "rotation_angular_velocity(angles (n,3), rates (n,3), seq, space) -> (n,3)"},
    {"rotation_euler_rates", py_euler_rates, METH_VARARGS,
     "rotation_euler_rates(angles (n,3), omega (n,3), seq, space, lock_tol) -> (n,3)"},
    {NULL, NULL, 0, NULL},
};
