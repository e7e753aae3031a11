/* Binding for the scene models: their table, and vectorised evaluation of
 * right-hand side, Jacobian and energy over many states. */
#include "mp_py.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_sf_ellint.h>

#include "models/models.h"

static const mp_model *find_model(const char *name)
{
    const mp_model *m = mp_model_find(name);
    if (!m) PyErr_Format(PyExc_ValueError, "unknown scene %s", name);
    return m;
}

/* One parameter of a row as a dict: name, default (None: required), lo, hi,
 * lo_open, hi_open. */
static PyObject *scene_param(const mp_model_param *p)
{
    if (isnan(p->def)) Py_INCREF(Py_None);
    PyObject *def = isnan(p->def) ? Py_None : PyFloat_FromDouble(p->def);
    if (!def) return NULL;
    return Py_BuildValue("{s:s,s:N,s:d,s:d,s:O,s:O}", "name", p->name, "default", def, "lo",
                         p->lo, "hi", p->hi, "lo_open", p->lo_open ? Py_True : Py_False,
                         "hi_open", p->hi_open ? Py_True : Py_False);
}

/* A NULL-terminated list of names (the row's states, coordinates, speeds)
 * as a tuple of str; NULL with an exception set. */
static PyObject *names_tuple(const char *const *names)
{
    Py_ssize_t n = 0;
    while (names && names[n]) n++;
    PyObject *out = PyTuple_New(n);
    for (Py_ssize_t i = 0; out && i < n; i++) {
        PyObject *s = PyUnicode_FromString(names[i]);
        if (!s) {
            Py_CLEAR(out);
            break;
        }
        PyTuple_SET_ITEM(out, i, s);
    }
    return out;
}

/* scene_info(name) -> the row: {"dim" (0: variable), "params" (names),
 * "param_info" (one dict each, see scene_param), "separable" (None: never,
 * "always" or a condition), "lagrangian" (bool), "field" (the right-hand
 * side as dim expression strings, or None), "states", "coordinates",
 * "speeds" (tuples of names; "#" in a variable-size scene's patterns, see
 * models.h), "drawing" (a drawing's name, or None)}. */
static PyObject *py_scene_info(PyObject *self, PyObject *args)
{
    (void)self;
    const char *name;
    if (!PyArg_ParseTuple(args, "s", &name)) return NULL;
    const mp_model *m = find_model(name);
    if (!m) return NULL;
    PyObject *names = PyTuple_New((Py_ssize_t)m->nparams);
    PyObject *info = PyTuple_New((Py_ssize_t)m->nparams);
    if (!names || !info) goto fail;
    for (size_t i = 0; i < m->nparams; i++) {
        PyObject *s = PyUnicode_FromString(m->params[i].name);
        PyObject *d = s ? scene_param(&m->params[i]) : NULL;
        if (!d) {
            Py_XDECREF(s);
            goto fail;
        }
        PyTuple_SET_ITEM(names, (Py_ssize_t)i, s);
        PyTuple_SET_ITEM(info, (Py_ssize_t)i, d);
    }
    PyObject *field = Py_None;
    Py_INCREF(field);
    if (m->field) {
        Py_DECREF(field);
        field = PyTuple_New((Py_ssize_t)m->dim);
        if (!field) goto fail;
        for (size_t i = 0; i < m->dim; i++) {
            PyObject *e = PyUnicode_FromString(m->field[i]);
            if (!e) {
                Py_DECREF(field);
                goto fail;
            }
            PyTuple_SET_ITEM(field, (Py_ssize_t)i, e);
        }
    }
    PyObject *states = names_tuple(m->states), *coords = names_tuple(m->coordinates),
             *speeds = names_tuple(m->speeds);
    if (!states || !coords || !speeds) {
        Py_XDECREF(states);
        Py_XDECREF(coords);
        Py_XDECREF(speeds);
        Py_DECREF(field);
        goto fail;
    }
    return Py_BuildValue("{s:n,s:N,s:N,s:z,s:O,s:N,s:N,s:N,s:N,s:z}", "dim", (Py_ssize_t)m->dim,
                         "params", names, "param_info", info, "separable", m->separable,
                         "lagrangian", m->lagrangian ? Py_True : Py_False, "field", field,
                         "states", states, "coordinates", coords, "speeds", speeds, "drawing",
                         m->drawing);
fail:
    Py_XDECREF(names);
    Py_XDECREF(info);
    return NULL;
}

/* scene_rows() -> the rows' names, in the table's order (models/list.h). */
static PyObject *py_scene_rows(PyObject *self, PyObject *args)
{
    (void)self, (void)args;
    size_t n = 0;
    while (mp_models[n]) n++;
    PyObject *out = PyTuple_New((Py_ssize_t)n);
    for (size_t i = 0; out && i < n; i++) {
        PyObject *s = PyUnicode_FromString(mp_models[i]->name);
        if (!s) {
            Py_CLEAR(out);
            break;
        }
        PyTuple_SET_ITEM(out, (Py_ssize_t)i, s);
    }
    return out;
}

/* scene_check(name, params) -> dim: the row's check of a parameter vector
 * (p,) or of rows (k, p) (each must describe the same dim); ValueError
 * "name: <why>" (params[i]: for row i of k) otherwise. */
static PyObject *py_scene_check(PyObject *self, PyObject *args)
{
    (void)self;
    const char *name;
    PyObject *po;
    if (!PyArg_ParseTuple(args, "sO", &name, &po)) return NULL;
    const mp_model *m = find_model(name);
    if (!m) return NULL;
    PyArrayObject *p = mp_py_array(po, "params", -1);
    if (!p) return NULL;
    int nd = PyArray_NDIM(p);
    if (nd != 1 && nd != 2) {
        PyErr_Format(PyExc_ValueError, "%s: params must have shape (p,) or (k, p)", m->name);
        Py_DECREF(p);
        return NULL;
    }
    npy_intp rows = nd == 2 ? PyArray_DIM(p, 0) : 1, np = PyArray_DIM(p, nd - 1);
    const double *pp = PyArray_DATA(p);
    size_t dim = 0, first = 0;
    char why[200] = "";
    npy_intp bad = -1;
    for (npy_intp r = 0; r < rows && bad < 0; r++) {
        if (mp_model_check(m, pp + r * np, (size_t)np, &dim, why, sizeof why) != MP_OK ||
            (r > 0 && dim != first)) {
            if (r > 0 && dim != first) snprintf(why, sizeof why, "every row must describe "
                                                "the same state dimension");
            bad = r;
        }
        if (r == 0) first = dim;
    }
    Py_DECREF(p);
    if (bad >= 0) {
        if (nd == 2) PyErr_Format(PyExc_ValueError, "%s: params[%zd]: %s", m->name,
                                  (Py_ssize_t)bad, why);
        else PyErr_Format(PyExc_ValueError, "%s: %s", m->name, why);
        return NULL;
    }
    return PyLong_FromSize_t(first);
}

/* scene_eval(name, params, what, t, Y) with Y of shape (m, dim):
 * what = "rhs" -> (m, dim), "jac" -> (m, dim, dim), "energy" -> (m,) */
static PyObject *py_scene_eval(PyObject *self, PyObject *args)
{
    (void)self;
    const char *name, *what;
    PyObject *po, *yo;
    double t;
    if (!PyArg_ParseTuple(args, "sOsdO", &name, &po, &what, &t, &yo)) return NULL;
    const mp_model *m = find_model(name);
    if (!m) return NULL;
    PyArrayObject *p = mp_py_array(po, "params", 1), *y = NULL, *out = NULL;
    if (!p) return NULL;
    size_t dim;
    if (mp_model_prepare(m, PyArray_DATA(p), (size_t)PyArray_SIZE(p), &dim) != MP_OK) {
        mp_py_raise(MP_EDOM, "scene parameters");
        goto done;
    }
    if (!(y = mp_py_array(yo, "y", 2))) goto done;
    npy_intp cnt = PyArray_DIM(y, 0), d = (npy_intp)dim;
    if (PyArray_DIM(y, 1) != d) {
        PyErr_Format(PyExc_ValueError, "y must have %zd components for %s, got %zd", (Py_ssize_t)d,
                     m->name, (Py_ssize_t)PyArray_DIM(y, 1));
        goto done;
    }
    int kind = strcmp(what, "rhs") == 0 ? 0 : strcmp(what, "jac") == 0 ? 1
             : strcmp(what, "energy") == 0 ? 2 : -1;
    if (kind < 0) {
        PyErr_Format(PyExc_ValueError, "unknown evaluation %s", what);
        goto done;
    }
    npy_intp shape[3] = {cnt, d, d};
    out = mp_py_empty(kind == 2 ? 1 : kind + 2, shape);
    if (!out) goto done;
    const double *pp = PyArray_DATA(p), *yy = PyArray_DATA(y);
    double *oo = PyArray_DATA(out);
    mp_ode_problem prob;
    m->bind(pp, &prob);
    npy_intp per = kind == 2 ? 1 : kind == 1 ? d * d : d, bad = -1;
    int rc = MP_OK;
    Py_BEGIN_ALLOW_THREADS
    for (npy_intp i = 0; i < cnt && bad < 0; i++) {
        const double *yi = yy + i * d;
        double *oi = oo + i * per;
        mp_ode_problem at = prob; /* the branch of this state (past a switch or not) */
        mp_ode_problem_at(&at, t, yi);
        if (kind == 0) rc = at.rhs(t, yi, oi, at.data);
        else if (kind == 1) rc = at.jac(t, yi, oi, at.data);
        else oi[0] = m->energy(pp, yi);
        if (rc != MP_OK) {
            bad = i;
            break;
        }
        for (npy_intp j = 0; j < per; j++)
            if (!isfinite(oi[j])) {
                rc = MP_ENONFINITE;
                bad = i;
                break;
            }
    }
    Py_END_ALLOW_THREADS
    if (bad >= 0) { /* a singular state (Kepler at r = 0, the top at theta = 0) or overflow */
        char ctx[112];
        snprintf(ctx, sizeof ctx, "%s %s at state %zd (a singular point or overflow)", m->name,
                 kind == 1 ? "jacobian" : what, (Py_ssize_t)bad);
        mp_py_raise(rc, ctx);
        Py_CLEAR(out);
    }
done:
    Py_XDECREF(p);
    Py_XDECREF(y);
    return (PyObject *)out;
}

/* ellipk_complement(kc): the complete elliptic integral of the first kind
 * K(k) for the complementary modulus kc = sqrt(1 - k^2), 0 < kc <= 1, as
 * Carlson's R_F(0, kc^2, 1) from GSL.  Taking kc (not k) keeps full precision
 * near k = 1, where 1 - k^2 would cancel.  ValueError outside (0, 1]. */
static PyObject *py_ellipk_complement(PyObject *self, PyObject *args)
{
    (void)self;
    double kc;
    if (!PyArg_ParseTuple(args, "d", &kc)) return NULL;
    if (!(kc > 0.0 && kc <= 1.0)) {
        PyErr_Format(PyExc_ValueError, "kc must be in (0, 1], got %g", kc);
        return NULL;
    }
    gsl_sf_result r;
    if (gsl_sf_ellint_RF_e(0.0, kc * kc, 1.0, GSL_PREC_DOUBLE, &r) != GSL_SUCCESS) {
        mp_py_raise(MP_EGSL, "ellipk_complement");
        return NULL;
    }
    return PyFloat_FromDouble(r.val);
}

PyMethodDef mp_py_scene_methods[] = {
    {"scene_info", py_scene_info, METH_VARARGS,
     "A scene's row: dimension, parameters (names, defaults, bounds), separability, "
     "field, the names of its states, coordinates and speeds, its drawing."},
    {"scene_rows", py_scene_rows, METH_NOARGS, "The scene rows' names, in the table's order."},
    {"scene_check", py_scene_check, METH_VARARGS,
     "Check a scene's parameter vector (or rows of them) against its row; -> dim."},
    {"scene_eval", py_scene_eval, METH_VARARGS, "Evaluate a scene over many states (internal)."},
    {"ellipk_complement", py_ellipk_complement, METH_VARARGS,
     "Complete elliptic integral K for the complementary modulus kc (GSL)."},
    {NULL, NULL, 0, NULL},
};
