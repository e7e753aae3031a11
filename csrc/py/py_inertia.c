/* Binding for the inertia functions of the C core. */
#include "mp_py.h"

PyMethodDef mp_py_inertia_methods[] = {
    {NULL, NULL, 0, NULL},
};
