/* mechpy._core: module init.  Merges the per-topic method tables, turns
 * GSL's abort-by-default error handler off, creates the exception classes. */
#define MP_PY_MODULE_C
#include "mp_py.h"

#include "ode/lanes.h"
#include "ode/lu.h"

extern const char mp_fixed_steps_text[]; /* fixed_text.c, made from ode/fixed.h */

#include <gsl/gsl_errno.h>
#include <gsl/gsl_version.h>

static struct PyModuleDef mp_core_module = {
    PyModuleDef_HEAD_INIT, "mechpy._core",
    "mechpy's C core (integrators, scenes, inertia, rotations, normal modes).", -1, NULL,
};

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
    if (mp_py_errors_init(m) < 0) goto fail; /* classes, STATUS, STATUS_TABLE */
    if (PyModule_AddStringConstant(m, "gsl_version", GSL_VERSION) < 0) goto fail;
    /* the ensembles' lane count: generated lane right-hand sides are built for it */
    if (PyModule_AddIntConstant(m, "LANES", MP_LANES) < 0) goto fail;
    /* where radau's band form pays (ode/lu.h's mp_ode_band_pays): _validate's too */
    if (PyModule_AddIntConstant(m, "BAND_WIDE", MP_ODE_BAND_WIDE) < 0 ||
        PyModule_AddIntConstant(m, "BAND_MIN_N", MP_ODE_LU_SMALL) < 0)
        goto fail;
    /* ode/fixed.h's text: generated systems build their fixed-step blocks from it */
    if (PyModule_AddStringConstant(m, "FIXED_STEPS_C", mp_fixed_steps_text) < 0) goto fail;
    return m;
fail:
    Py_DECREF(m);
    return NULL;
}
