/* Binding for the modes functions of the C core: parse, convert, call with
 * the GIL released, map the status.  No physics here. */
#include "mp_py.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "modes.h"

/* ---------------------------------------------------------------- solve jobs
 *
 * A job owns its buffers and runs in the calling thread with the GIL
 * released.  The chain solve (dstemr in chunks of indices) asks for Ctrl-C
 * between chunks and stops with MP_EINTR; the dense solve (one dsygvd call)
 * cannot be stopped part-way and answers Ctrl-C when it returns.  No thread
 * outlives the call. */
struct mp_modes_job {
    int dense, n;
    double zero_rtol, w_bad;
    double *k, *m;          /* dense: K (becomes the vectors) and M, n*n each */
    double *kd, *ke, *md;   /* chain: bands, n, n-1 (at least 1), n */
    double *w, *z;          /* results: n, n*n (chain) */
    int status;
};

/* Free a job and every buffer it still owns (NULL-safe). */
static void mp_modes_job_free(struct mp_modes_job *j)
{
    if (!j) return;
    free(j->k); free(j->m); free(j->kd); free(j->ke); free(j->md); free(j->w); free(j->z);
    free(j);
}

/* A job with zeroed buffer pointers, or NULL. */
static struct mp_modes_job *mp_modes_job_new(int dense, int n, double zero_rtol)
{
    struct mp_modes_job *j = calloc(1, sizeof *j);
    if (!j) return NULL;
    j->dense = dense;
    j->n = n;
    j->zero_rtol = zero_rtol;
    return j;
}

/* Run the job in the calling thread with the GIL released; its status lands
 * in j->status (MP_EINTR with KeyboardInterrupt set after Ctrl-C). */
static void mp_modes_run(struct mp_modes_job *j)
{
    Py_BEGIN_ALLOW_THREADS
    if (j->dense)
        j->status = mp_modes_dense(j->n, j->k, j->m, j->zero_rtol, j->w, &j->w_bad);
    else
        j->status = mp_modes_tridiag(j->n, j->kd, j->ke, j->md, j->zero_rtol, j->w, j->z,
                                     &j->w_bad, mp_py_check_interrupt, NULL);
    Py_END_ALLOW_THREADS
}

/* Free a malloc'd buffer that a NumPy array took over (capsule destructor). */
static void mp_modes_capsule_free(PyObject *cap)
{
    free(PyCapsule_GetPointer(cap, NULL));
}

/* A float64 array over the malloc'd buffer *buf, which it then owns (*buf is
 * set to NULL); NULL with an exception on failure (the buffer stays). */
static PyObject *mp_modes_array_of(double **buf, int nd, npy_intp *dims)
{
    PyObject *a = PyArray_SimpleNewFromData(nd, dims, NPY_DOUBLE, *buf);
    if (!a) return NULL;
    PyObject *cap = PyCapsule_New(*buf, NULL, mp_modes_capsule_free);
    if (!cap) {
        Py_DECREF(a);
        return NULL;
    }
    if (PyArray_SetBaseObject((PyArrayObject *)a, cap) < 0) {   /* steals cap */
        Py_DECREF(a);
        return NULL;
    }
    *buf = NULL;
    return a;
}

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

/* The square pair (K, M) of one order *n, held in refs. */
static int mp_py_modes_pair(mp_py_refs *refs, PyObject *ko, PyObject *mo, PyArrayObject **k,
                            PyArrayObject **m, int *n)
{
    int nm = 0;
    if (!(*k = mp_py_hold(refs, mp_py_modes_square(ko, "K", n))) ||
        !(*m = mp_py_hold(refs, mp_py_modes_square(mo, "M", &nm))))
        return -1;
    if (nm != *n) {
        PyErr_Format(PyExc_ValueError, "M must have the shape of K (%d x %d), got %d x %d",
                     *n, *n, nm, nm);
        return -1;
    }
    return 0;
}

/* The (w, Z) result of a finished job, or the exception of its status; the
 * job is freed either way. */
static PyObject *mp_py_modes_result(struct mp_modes_job *j, double **zbuf, const char *context)
{
    PyObject *res = NULL;
    if (j->status != MP_OK) {
        if (j->status == MP_EUNSTABLE) {
            char detail[96];
            snprintf(detail, sizeof detail, "eigenvalue omega^2 = %.6g < 0", j->w_bad);
            mp_py_raise_detail(j->status, context, detail);
        } else {
            mp_py_raise(j->status, context);
        }
        mp_modes_job_free(j);
        return NULL;
    }
    npy_intp s1[1] = {j->n}, s2[2] = {j->n, j->n};
    PyObject *w = mp_modes_array_of(&j->w, 1, s1);
    PyObject *z = w ? mp_modes_array_of(zbuf, 2, s2) : NULL;
    if (w && z) res = Py_BuildValue("(NN)", w, z);
    else Py_XDECREF(w);
    mp_modes_job_free(j);
    return res;
}

/* A malloc'd copy of a float64 array's data (n doubles, at least 1), or NULL. */
static double *mp_modes_copy(PyArrayObject *a, size_t n)
{
    double *p = malloc((n ? n : 1) * sizeof *p);
    if (p && n) memcpy(p, PyArray_DATA(a), n * sizeof *p);
    return p;
}

PyDoc_STRVAR(modes_dense_doc,
"modes_dense(K, M, zero_rtol) -> (w, Z)\n\n"
"Dense K v = w M v by LAPACK dsygvd: w ascending, Z[k] is mode k\n"
"(M-normalised, sign rule applied).  K and M must be symmetric.\n"
"Ctrl-C is answered when dsygvd returns.");

static PyObject *modes_dense(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *ko, *mo;
    int n = 0;
    double zero_rtol = -1.0;
    if (!PyArg_ParseTuple(args, "OO|d:modes_dense", &ko, &mo, &zero_rtol)) return NULL;
    mp_py_refs refs = {0};
    PyArrayObject *k, *m;
    if (mp_py_modes_pair(&refs, ko, mo, &k, &m, &n) < 0) return mp_py_release(&refs, NULL);
    /* LAPACK overwrites both: the job works on its own copies. */
    size_t nn = (size_t)n * (size_t)n;
    struct mp_modes_job *j = mp_modes_job_new(1, n, zero_rtol);
    if (j) {
        j->k = mp_modes_copy(k, nn);
        j->m = mp_modes_copy(m, nn);
        j->w = malloc((size_t)n * sizeof *j->w);
    }
    mp_py_release(&refs, NULL);
    if (!j || !j->k || !j->m || !j->w) {
        mp_modes_job_free(j);
        return PyErr_NoMemory();
    }
    mp_modes_run(j);
    return mp_py_modes_result(j, &j->k, "normal_modes(K, M)");
}

PyDoc_STRVAR(modes_tridiag_doc,
"modes_tridiag(kd, ke, md, zero_rtol) -> (w, Z)\n\n"
"Chain K v = w M v with K tridiagonal (diagonal kd, off-diagonal ke) and\n"
"M = diag(md), by LAPACK dstemr on M^-1/2 K M^-1/2: O(n^2).\n"
"Ctrl-C is answered between chunks of eigenpairs.");

static PyObject *modes_tridiag(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *kdo, *keo, *mdo;
    double zero_rtol = -1.0;
    if (!PyArg_ParseTuple(args, "OOO|d:modes_tridiag", &kdo, &keo, &mdo, &zero_rtol))
        return NULL;
    mp_py_refs refs = {0};
    PyArrayObject *kd, *ke, *md;
    if (!(kd = mp_py_hold(&refs, mp_py_array(kdo, "kd", 1))) ||
        !(ke = mp_py_hold(&refs, mp_py_array(keo, "ke", 1))) ||
        !(md = mp_py_hold(&refs, mp_py_array(mdo, "md", 1))))
        return mp_py_release(&refs, NULL);
    npy_intp n = PyArray_DIM(kd, 0);
    if (n < 1 || n > 100000 || PyArray_DIM(md, 0) != n || PyArray_DIM(ke, 0) != n - 1) {
        PyErr_Format(PyExc_ValueError,
                     "kd, ke, md must have lengths n, n-1, n with 1 <= n <= 100000");
        return mp_py_release(&refs, NULL);
    }
    if (mp_py_require_finite(kd, "K") < 0 || mp_py_require_finite(ke, "K") < 0 ||
        mp_py_require_finite(md, "M") < 0)
        return mp_py_release(&refs, NULL);
    struct mp_modes_job *j = mp_modes_job_new(0, (int)n, zero_rtol);
    if (j) {
        j->kd = mp_modes_copy(kd, (size_t)n);
        j->ke = mp_modes_copy(ke, (size_t)n - 1);
        j->md = mp_modes_copy(md, (size_t)n);
        j->w = malloc((size_t)n * sizeof *j->w);
        j->z = malloc((size_t)n * (size_t)n * sizeof *j->z);
    }
    mp_py_release(&refs, NULL);
    if (!j || !j->kd || !j->ke || !j->md || !j->w || !j->z) {
        mp_modes_job_free(j);
        return PyErr_NoMemory();
    }
    mp_modes_run(j);
    /* the user called normal_modes (the chain path is its choice, not theirs) */
    return mp_py_modes_result(j, &j->z, "normal_modes(K, M)");
}

PyDoc_STRVAR(modes_is_chain_doc,
"modes_is_chain(K, M) -> (kd, ke, md) or None\n\n"
"The bands of K (tridiagonal) and M (diagonal) when the pair is a chain.");

static PyObject *modes_is_chain(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *ko, *mo;
    int n = 0;
    if (!PyArg_ParseTuple(args, "OO:modes_is_chain", &ko, &mo)) return NULL;
    mp_py_refs refs = {0};
    PyArrayObject *k, *m, *kd, *ke, *md;
    if (mp_py_modes_pair(&refs, ko, mo, &k, &m, &n) < 0) return mp_py_release(&refs, NULL);
    npy_intp s1[1] = {n}, s0[1] = {n - 1};
    if (!(kd = mp_py_hold(&refs, mp_py_empty(1, s1))) ||
        !(ke = mp_py_hold(&refs, mp_py_empty(1, s0))) ||
        !(md = mp_py_hold(&refs, mp_py_empty(1, s1))))
        return mp_py_release(&refs, NULL);
    int yes;
    Py_BEGIN_ALLOW_THREADS
    yes = mp_modes_is_chain(n, (const double *)PyArray_DATA(k), (const double *)PyArray_DATA(m),
                            (double *)PyArray_DATA(kd), (double *)PyArray_DATA(ke),
                            (double *)PyArray_DATA(md));
    Py_END_ALLOW_THREADS
    return mp_py_release(&refs, yes ? Py_BuildValue("(OOO)", kd, ke, md)
                                    : mp_py_result(MP_OK, NULL, Py_None));
}

PyMethodDef mp_py_modes_methods[] = {
    {"modes_dense", modes_dense, METH_VARARGS, modes_dense_doc},
    {"modes_tridiag", modes_tridiag, METH_VARARGS, modes_tridiag_doc},
    {"modes_is_chain", modes_is_chain, METH_VARARGS, modes_is_chain_doc},
    {NULL, NULL, 0, NULL},
};
