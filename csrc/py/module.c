/* mechpy._core: module init.  Merges the per-topic method tables, turns
 * GSL's abort-by-default error handler off, creates the exception classes. */
#define MP_PY_MODULE_C
#include "mp_py.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_version.h>

static struct PyModuleDef mp_core_module = {
    PyModuleDef_HEAD_INIT, "mechpy._core",
    "mechpy's C core (integrators, scenes, inertia, rotations, normal modes).", -1, NULL,
};

/* _core.STATUS: every status code by its C name, the one source from which
 * generated C (mechpy.symbolic) prints its #defines. */
static int add_status_table(PyObject *m)
{
    static const struct { const char *name; int value; } codes[] = {
        {"MP_OK", MP_OK}, {"MP_EDOM", MP_EDOM}, {"MP_ENOMEM", MP_ENOMEM},
        {"MP_EMAXSTEPS", MP_EMAXSTEPS}, {"MP_ESTEP", MP_ESTEP}, {"MP_ENOTSPD", MP_ENOTSPD},
        {"MP_ECALLBACK", MP_ECALLBACK}, {"MP_EINTR", MP_EINTR}, {"MP_ENONFINITE", MP_ENONFINITE},
        {"MP_ENOCONV", MP_ENOCONV}, {"MP_ESINGULAR", MP_ESINGULAR}, {"MP_EMESH", MP_EMESH},
        {"MP_EGSL", MP_EGSL}, {"MP_EUNSTABLE", MP_EUNSTABLE},
    };
    PyObject *d = PyDict_New();
    if (!d) return -1;
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        PyObject *v = PyLong_FromLong(codes[i].value);
        if (!v || PyDict_SetItemString(d, codes[i].name, v) < 0) {
            Py_XDECREF(v);
            Py_DECREF(d);
            return -1;
        }
        Py_DECREF(v);
    }
    return PyModule_AddObject(m, "STATUS", d) < 0 ? (Py_DECREF(d), -1) : 0;
}

PyMODINIT_FUNC PyInit__core(void)
{
    PyMethodDef *tables[] = {
        mp_py_ode_methods, mp_py_scene_methods, mp_py_inertia_methods,
        mp_py_rotation_methods, mp_py_modes_methods, mp_py_variational_methods,
        mp_py_rigid_methods, mp_py_compiled_methods,
    };
    import_array();
    /* GSL must never abort the interpreter: every GSL status is checked. */
    gsl_set_error_handler_off();

    PyObject *m = PyModule_Create(&mp_core_module);
    if (!m) return NULL;
    for (size_t i = 0; i < sizeof tables / sizeof tables[0]; i++) {
        if (PyModule_AddFunctions(m, tables[i]) < 0) goto fail;
    }
    if (mp_py_errors_init(m) < 0) goto fail;
    if (PyModule_AddStringConstant(m, "gsl_version", GSL_VERSION) < 0) goto fail;
    if (PyModule_AddIntConstant(m, "STATUS_EMAXSTEPS", MP_EMAXSTEPS) < 0 ||
        PyModule_AddIntConstant(m, "STATUS_ESTEP", MP_ESTEP) < 0 ||
        PyModule_AddIntConstant(m, "STATUS_ENONFINITE", MP_ENONFINITE) < 0)
        goto fail;
    if (add_status_table(m) < 0) goto fail;
    return m;
fail:
    Py_DECREF(m);
    return NULL;
}
