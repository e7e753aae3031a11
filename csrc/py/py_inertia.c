/* Binding for the inertia functions of the C core (mechpy/inertia.py and
 * mechpy/stress.py validate first; shapes are re-checked here so that no
 * call can read out of bounds). */
#include "mp_py.h"

#include <stdio.h>

#include "inertia.h"

static PyObject *py_inertia_point_masses(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *om, *ox, *oo;
    PyArrayObject *m, *x, *o, *out;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "OOO", &om, &ox, &oo)) return NULL;
    npy_intp sm[2] = {-1, -1};
    if (!(m = mp_py_hold(&k, mp_py_array_shape(om, "masses", 2, sm))))
        return mp_py_release(&k, NULL);
    npy_intp B = PyArray_DIM(m, 0), n = PyArray_DIM(m, 1);
    npy_intp sx[3] = {B, n, 3}, so[2] = {B, 3}, sI[3] = {B, 3, 3};
    if (!(x = mp_py_hold(&k, mp_py_array_shape(ox, "positions", 3, sx))) ||
        !(o = mp_py_hold(&k, mp_py_array_shape(oo, "origin", 2, so))) ||
        !(out = mp_py_hold(&k, mp_py_empty(3, sI))))
        return mp_py_release(&k, NULL);
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_inertia_point_masses((size_t)B, (size_t)n, PyArray_DATA(m), PyArray_DATA(x),
                                 PyArray_DATA(o), PyArray_DATA(out));
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, mp_py_result(rc, "point_masses: masses must be positive",
                                          (PyObject *)out));
}

static PyObject *py_inertia_shift(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *oi, *om, *oa;
    int sign;
    PyArrayObject *J, *m, *a, *out;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "OOOi", &oi, &om, &oa, &sign)) return NULL;
    npy_intp si[3] = {-1, 3, 3};
    if (!(J = mp_py_hold(&k, mp_py_array_shape(oi, "I", 3, si)))) return mp_py_release(&k, NULL);
    npy_intp B = PyArray_DIM(J, 0), sm[1] = {B}, sa[2] = {B, 3}, sI[3] = {B, 3, 3};
    if (!(m = mp_py_hold(&k, mp_py_array_shape(om, "mass", 1, sm))) ||
        !(a = mp_py_hold(&k, mp_py_array_shape(oa, "a", 2, sa))) ||
        !(out = mp_py_hold(&k, mp_py_empty(3, sI))))
        return mp_py_release(&k, NULL);
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_inertia_shift((size_t)B, PyArray_DATA(J), PyArray_DATA(m), PyArray_DATA(a),
                          sign < 0 ? -1 : 1, PyArray_DATA(out));
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, mp_py_result(rc, "shift: mass must be non-negative",
                                          (PyObject *)out));
}

static PyObject *py_inertia_eigh(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *oa;
    PyArrayObject *A, *w, *V;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "O", &oa)) return NULL;
    npy_intp sa[3] = {-1, 3, 3};
    if (!(A = mp_py_hold(&k, mp_py_array_shape(oa, "matrix", 3, sa))))
        return mp_py_release(&k, NULL);
    npy_intp B = PyArray_DIM(A, 0), sw[2] = {B, 3};
    if (!(w = mp_py_hold(&k, mp_py_empty(2, sw))) ||
        !(V = mp_py_hold(&k, mp_py_empty(3, PyArray_DIMS(A)))))
        return mp_py_release(&k, NULL);
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_inertia_eigh((size_t)B, PyArray_DATA(A), PyArray_DATA(w), PyArray_DATA(V));
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, rc == MP_OK ? Py_BuildValue("OO", w, V)
                                         : mp_py_raise(rc, "symmetric 3x3 eigen-decomposition"));
}

static void mp_py_mesh_detail(const struct mp_mesh_report *r, char *buf, size_t size)
{
    switch (r->defect) {
    case MP_MESH_INDEX:
        snprintf(buf, size, "face %lld refers to vertex %lld, which does not exist",
                 (long long)r->face, (long long)r->v0);
        break;
    case MP_MESH_REPEATED:
        snprintf(buf, size, "degenerate: face %lld repeats a vertex", (long long)r->face);
        break;
    case MP_MESH_ZERO_AREA:
        snprintf(buf, size, "degenerate: face %lld has zero area", (long long)r->face);
        break;
    case MP_MESH_OPEN:
        if (r->face < 0)
            snprintf(buf, size, "open: a closed surface needs at least 4 faces and 4 vertices");
        else
            snprintf(buf, size, "open: edge (%lld, %lld) of face %lld belongs to no other face",
                     (long long)r->v0, (long long)r->v1, (long long)r->face);
        break;
    case MP_MESH_NONMANIFOLD:
        snprintf(buf, size, "non-manifold: edge (%lld, %lld) of face %lld is shared by more "
                 "than two faces", (long long)r->v0, (long long)r->v1, (long long)r->face);
        break;
    case MP_MESH_ORIENTATION:
        snprintf(buf, size, "inconsistently oriented: edge (%lld, %lld) is traversed in the "
                 "same direction by face %lld and another face", (long long)r->v0,
                 (long long)r->v1, (long long)r->face);
        break;
    case MP_MESH_INSIDE_OUT:
        snprintf(buf, size, "inside out: the faces are ordered clockwise seen from outside "
                 "(signed volume %.6g < 0); reverse the vertex order of every face",
                 r->volume);
        break;
    case MP_MESH_FLAT:
        snprintf(buf, size, "degenerate: the enclosed volume is zero (%.3g)", r->volume);
        break;
    case MP_MESH_RANGE:
        snprintf(buf, size, "out of range: with an extent of %.3g the coordinate differences, "
                 "the volume (extent^3) or the inertia (extent^5) %s float64; rescale the "
                 "vertices (other units)", r->extent,
                 !(r->extent <= 1.0) ? "overflow" : "underflow");
        break;
    default:
        buf[0] = 0;
    }
}

static PyObject *py_inertia_mesh(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *ov, *of;
    PyArrayObject *V, *F, *com, *J;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "OO", &ov, &of)) return NULL;
    npy_intp sv[2] = {-1, 3}, s3[1] = {3}, s33[2] = {3, 3};
    if (!(V = mp_py_hold(&k, mp_py_array_shape(ov, "vertices", 2, sv))) ||
        !(F = mp_py_hold(&k, PyArray_FROM_OTF(of, NPY_INT64, NPY_ARRAY_IN_ARRAY))))
        return mp_py_release(&k, NULL);
    if (PyArray_NDIM(F) != 2 || PyArray_DIM(F, 1) != 3) {
        PyErr_SetString(PyExc_ValueError, "faces must have shape (n, 3)");
        return mp_py_release(&k, NULL);
    }
    if (!(com = mp_py_hold(&k, mp_py_empty(1, s3))) || !(J = mp_py_hold(&k, mp_py_empty(2, s33))))
        return mp_py_release(&k, NULL);
    double vol = 0;
    struct mp_mesh_report rep;
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_inertia_mesh((size_t)PyArray_DIM(V, 0), PyArray_DATA(V), (size_t)PyArray_DIM(F, 0),
                         PyArray_DATA(F), &vol, PyArray_DATA(com), PyArray_DATA(J), &rep,
                         mp_py_check_interrupt, NULL);
    Py_END_ALLOW_THREADS
    if (rc != MP_OK) {
        char detail[256];
        mp_py_mesh_detail(&rep, detail, sizeof detail);
        return mp_py_release(&k, mp_py_raise_detail(rc, rep.defect == MP_MESH_OK
                                                          ? "mesh: vertices must be finite"
                                                          : "mesh", detail));
    }
    return mp_py_release(&k, Py_BuildValue("dOO", vol, com, J));
}

static PyObject *py_inertia_grid(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *orho, *oh, *oo;
    PyArrayObject *R, *h, *o, *com, *J;
    mp_py_refs k = {0};
    if (!PyArg_ParseTuple(args, "OOO", &orho, &oh, &oo)) return NULL;
    npy_intp sr[3] = {-1, -1, -1}, s3[1] = {3}, s33[2] = {3, 3};
    if (!(R = mp_py_hold(&k, mp_py_array_shape(orho, "rho", 3, sr))) ||
        !(h = mp_py_hold(&k, mp_py_array_shape(oh, "spacing", 1, s3))) ||
        !(o = mp_py_hold(&k, mp_py_array_shape(oo, "origin", 1, s3))))
        return mp_py_release(&k, NULL);
    if (PyArray_SIZE(R) == 0) {
        PyErr_SetString(PyExc_ValueError, "rho must not be empty");
        return mp_py_release(&k, NULL);
    }
    if (!(com = mp_py_hold(&k, mp_py_empty(1, s3))) || !(J = mp_py_hold(&k, mp_py_empty(2, s33))))
        return mp_py_release(&k, NULL);
    double mass = 0;
    int rc;
    Py_BEGIN_ALLOW_THREADS
    rc = mp_inertia_grid((size_t)PyArray_DIM(R, 0), (size_t)PyArray_DIM(R, 1),
                         (size_t)PyArray_DIM(R, 2), PyArray_DATA(R), PyArray_DATA(h),
                         PyArray_DATA(o), &mass, PyArray_DATA(com), PyArray_DATA(J));
    Py_END_ALLOW_THREADS
    return mp_py_release(&k, rc == MP_OK ? Py_BuildValue("dOO", mass, com, J)
                                         : mp_py_raise(rc, "density_grid: rho must be finite "
                                                           "and >= 0 with a positive total"));
}

PyMethodDef mp_py_inertia_methods[] = {
    {"inertia_point_masses", py_inertia_point_masses, METH_VARARGS,
     "inertia_point_masses(masses (B, n), positions (B, n, 3), origin (B, 3)) -> (B, 3, 3)"},
    {"inertia_shift", py_inertia_shift, METH_VARARGS,
     "inertia_shift(I (B, 3, 3), mass (B,), a (B, 3), sign) -> (B, 3, 3): Steiner's theorem"},
    {"inertia_eigh", py_inertia_eigh, METH_VARARGS,
     "inertia_eigh(A (B, 3, 3)) -> (w (B, 3) ascending, V (B, 3, 3) right-handed columns)"},
    {"inertia_mesh", py_inertia_mesh, METH_VARARGS,
     "inertia_mesh(vertices (nv, 3), faces (nf, 3)) -> (volume, com, I about com), unit density"},
    {"inertia_grid", py_inertia_grid, METH_VARARGS,
     "inertia_grid(rho (nx, ny, nz), spacing (3,), origin (3,)) -> (mass, com, I about com)"},
    {NULL, NULL, 0, NULL},
};
