/* Binding for the integrator engine. */
#include "mp_py.h"

PyMethodDef mp_py_ode_methods[] = {
    {NULL, NULL, 0, NULL},
};
