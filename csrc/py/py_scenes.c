/* Binding for the scene models (right-hand sides, Jacobians, energies). */
#include "mp_py.h"

PyMethodDef mp_py_scene_methods[] = {
    {NULL, NULL, 0, NULL},
};
