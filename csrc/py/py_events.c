/* The integrator binding's events: the event list integrate.py hands over
 * (Python functions g(t, y, *args), pairs (g, action), C impacts), the
 * adapters through which the driver calls them, and the impacts as the
 * ensemble's lanes run them. */
#include "py_ode.h"

#include <stdint.h>
#include <string.h>

static int py_events_eval(double t, const double *y, double *g, void *data)
{
    const py_events *e = data;
    for (size_t k = 0; k < e->count; k++) {
        if (!e->fns[k].fun) {
            double w[3];
            mp_impact_wall(&e->imp[k], t, e->params, 1, w);
            g[k] = mp_impact_g(&e->imp[k], y[e->imp[k].iq], w[0]);
            continue;
        }
        int rc = py_call(&e->fns[k], t, y, &g[k]);
        if (rc != MP_OK) return rc;
    }
    return MP_OK;
}

/* mp_ode_action of the events: the impact's reflection in C, or the Python
 * action's new state (checked: n values; its finiteness is the driver's). */
static int py_events_action(double t, double *y, size_t k, void *data)
{
    const py_events *e = data;
    if (!e->fns[k].fun) {
        const mp_impact *im = &e->imp[k];
        double w[3];
        mp_impact_wall(im, t, e->params, 1, w);
        mp_impact_apply(im, mp_impact_e(im, 0, im->e_param >= 0 ? e->params[im->e_param] : 0.0),
                        w, y, 1);
        return MP_OK;
    }
    return py_call(&e->acts[k], t, y, y);
}

/* mp_ode_options' impact_of: event k's impact (NULL: a Python event) and the
 * trajectory's parameters its moving wall reads. */
static const mp_impact *py_events_impact(size_t k, const double **params, void *data)
{
    const py_events *e = data;
    *params = e->params;
    return e->fns[k].fun ? NULL : &e->imp[k];
}
void event_list_clear(py_event_list *el)
{
    Py_CLEAR(el->term);
    Py_CLEAR(el->dir);
    PyMem_Free(el->has_action);
    el->has_action = NULL;
}

/* Whether entry is a C impact: ("impact", iq, iv, wall, e, side, e_param,
 * wall_fn, rest). */
static int is_impact(PyObject *entry)
{
    if (!PyTuple_Check(entry) || PyTuple_GET_SIZE(entry) != 9) return 0;
    PyObject *tag = PyTuple_GET_ITEM(entry, 0);
    return PyUnicode_Check(tag) && PyUnicode_CompareWithASCIIString(tag, "impact") == 0;
}

/* Contract: events[k], an impact tuple ("impact", iq, iv, wall, e, side,
 * e_param, wall_fn, rest) for states of n and parameter vectors of nparams,
 * into *im (its max_events 0, its e the float e or 0: *eo is e as given,
 * borrowed: a float, or one value per trajectory when e_param < 0; wall_fn
 * the address of a compiled mp_wall_fn, 0 for a wall standing at `wall`;
 * rest 1 when the coordinate may rest on the wall).  0, or -1 with an
 * exception set (a coordinate, velocity or parameter out of range). */
static int parse_impact(PyObject *entry, Py_ssize_t k, size_t n, size_t nparams,
                        mp_impact *im, PyObject **eo)
{
    Py_ssize_t iq, iv;
    long ep;
    int rest;
    unsigned long long wf;
    double wall, side;
    const char *tag;
    if (!PyArg_ParseTuple(entry, "snndOdlKp", &tag, &iq, &iv, &wall, eo, &side, &ep, &wf, &rest))
        return -1;
    if (iq < 0 || iv < 0 || (size_t)iq >= n || (size_t)iv >= n ||
        (ep >= 0 && (size_t)ep >= nparams)) {
        PyErr_Format(PyExc_ValueError, "events[%zd]: an impact's coordinate, velocity "
                     "or restitution parameter is out of range", k);
        return -1;
    }
    *im = (mp_impact){(size_t)iq, (size_t)iv, wall, side, 0.0, NULL, ep, 0, NULL, rest};
    if (wf) *(void **)&im->wall_fn = (void *)(uintptr_t)wf; /* an address handed over */
    if (ep < 0 && PyFloat_Check(*eo)) im->e = PyFloat_AS_DOUBLE(*eo);
    return 0;
}

/* Contract: the event list evo (None or a list of entries: a callable g, a
 * pair (g, action) or a C impact tuple) with terminal and direction (one int
 * each) into el and o's event fields; o->events_data and o->action_data are
 * left to the caller (event_fns).  0, or -1 with an exception set. */
int event_list_parse(PyObject *evo, PyObject *termo, PyObject *diro, py_event_list *el,
                     mp_ode_options *o)
{
    memset(el, 0, sizeof *el);
    if (evo == Py_None) return 0;
    if ((el->count = PyList_Size(evo)) < 0) return -1;
    if (el->count == 0) return 0;
    el->term = (PyArrayObject *)PyArray_FROMANY(termo, NPY_INT, 1, 1, NPY_ARRAY_IN_ARRAY);
    el->dir = (PyArrayObject *)PyArray_FROMANY(diro, NPY_INT, 1, 1, NPY_ARRAY_IN_ARRAY);
    if (!el->term || !el->dir) return -1;
    if (PyArray_SIZE(el->term) != el->count || PyArray_SIZE(el->dir) != el->count) {
        PyErr_SetString(PyExc_ValueError, "terminal and direction need one value per event");
        return -1;
    }
    if (!(el->has_action = PyMem_Calloc((size_t)el->count, 1))) {
        PyErr_NoMemory();
        return -1;
    }
    el->all_c = 1;
    for (Py_ssize_t k = 0; k < el->count; k++) {
        PyObject *entry = PyList_GET_ITEM(evo, k);
        int imp = is_impact(entry), pair = !imp && PyTuple_Check(entry);
        if (pair && (PyTuple_GET_SIZE(entry) != 2 ||
                     !PyCallable_Check(PyTuple_GET_ITEM(entry, 0)) ||
                     !PyCallable_Check(PyTuple_GET_ITEM(entry, 1)))) {
            PyErr_Format(PyExc_TypeError, "events[%zd] must be callable", k);
            return -1;
        }
        el->has_action[k] = (unsigned char)(imp || pair);
        el->all_c &= imp;
        if (imp) o->impact_of = py_events_impact;
    }
    o->n_events = (size_t)el->count;
    o->events = py_events_eval;
    o->terminal = PyArray_DATA(el->term);
    o->direction = PyArray_DATA(el->dir);
    o->has_action = el->has_action;
    o->action = py_events_action;
    return 0;
}

/* Contract: pe's adapters of the entries in evo for states of n: each Python
 * event and action called with (t, y, *args), each impact's parameters (with
 * e_rows (the trajectory's restitution per event, or NULL) and params, the
 * trajectory's parameter vector).  pe->fns, acts, imp are PyMem (the caller
 * frees them with event_fns_free).  0, or -1 with an exception set. */
int event_fns(PyObject *evo, Py_ssize_t count, PyObject *args, size_t n, const double *params,
              size_t nparams, size_t row, py_events *pe)
{
    memset(pe, 0, sizeof *pe);
    pe->count = (size_t)count;
    pe->n = n;
    pe->params = params;
    pe->fns = PyMem_Calloc((size_t)count, sizeof(py_fn));
    pe->acts = PyMem_Calloc((size_t)count, sizeof(py_fn));
    pe->imp = PyMem_Calloc((size_t)count, sizeof(mp_impact));
    pe->names = PyMem_Calloc(2 * (size_t)count, sizeof *pe->names);
    if (!pe->fns || !pe->acts || !pe->imp || !pe->names) {
        PyErr_NoMemory();
        return -1;
    }
    for (Py_ssize_t k = 0; k < count; k++) {
        PyObject *entry = PyList_GET_ITEM(evo, k);
        if (is_impact(entry)) {
            PyObject *eo;
            if (parse_impact(entry, k, n, nparams, &pe->imp[k], &eo) < 0) return -1;
            if (pe->imp[k].e_param >= 0 || PyFloat_Check(eo)) continue;
            /* one restitution per trajectory: this one's row */
            PyArrayObject *ea = mp_py_array(eo, "restitution", 1);
            if (!ea) return -1;
            if ((size_t)PyArray_SIZE(ea) <= row) {
                Py_DECREF(ea);
                PyErr_Format(PyExc_ValueError, "events[%zd]: restitution needs one value "
                             "per trajectory", k);
                return -1;
            }
            pe->imp[k].e = ((const double *)PyArray_DATA(ea))[row];
            Py_DECREF(ea);
            continue;
        }
        PyObject *g = PyTuple_Check(entry) ? PyTuple_GET_ITEM(entry, 0) : entry;
        snprintf(pe->names[2 * k], sizeof pe->names[0], "events[%zd]", k);
        snprintf(pe->names[2 * k + 1], sizeof pe->names[0], "events[%zd].action", k);
        pe->fns[k] = (py_fn){g, args, n, 1, pe->names[2 * k]};
        if (PyTuple_Check(entry))
            pe->acts[k] = (py_fn){PyTuple_GET_ITEM(entry, 1), args, n, n, pe->names[2 * k + 1]};
    }
    return 0;
}

void event_fns_free(py_events *pe)
{
    PyMem_Free(pe->fns);
    PyMem_Free(pe->acts);
    PyMem_Free(pe->imp);
    PyMem_Free(pe->names);
    memset(pe, 0, sizeof *pe);
}

void lane_impacts_clear(py_lane_impacts *li)
{
    if (li->imp_e)
        for (size_t q = 0; li->imps && q < li->n; q++) Py_XDECREF(li->imp_e[q]);
    PyMem_Free(li->imp_e);
    PyMem_Free(li->imps);
    memset(li, 0, sizeof *li);
}

int lane_impacts_parse(py_lane_impacts *li, PyObject *evo, const py_event_list *el, size_t k,
                       size_t n, size_t nparams)
{
    size_t ne = (size_t)el->count;
    const int *dir = PyArray_DATA(el->dir), *term = PyArray_DATA(el->term);
    for (size_t q = 0; q < ne; q++)
        if (dir[q] != -1) return 0;
    li->imps = PyMem_Calloc(ne, sizeof *li->imps);
    li->imp_e = PyMem_Calloc(ne, sizeof *li->imp_e);
    li->n = ne;
    if (!li->imps || !li->imp_e) {
        PyErr_NoMemory();
        return -1;
    }
    for (size_t q = 0; q < ne; q++) {
        mp_impact *im = &li->imps[q];
        PyObject *eo;
        if (parse_impact(PyList_GET_ITEM(evo, (Py_ssize_t)q), (Py_ssize_t)q, n, nparams, im,
                         &eo) < 0)
            return -1;
        im->max_events = term[q];
        if (im->e_param >= 0 || PyFloat_Check(eo)) continue;
        if (!(li->imp_e[q] = mp_py_array(eo, "restitution", 1))) return -1;
        if ((size_t)PyArray_SIZE(li->imp_e[q]) != k) {
            PyErr_SetString(PyExc_ValueError, "restitution needs one value per trajectory");
            return -1;
        }
        im->e_rows = PyArray_DATA(li->imp_e[q]);
    }
    return 1;
}
