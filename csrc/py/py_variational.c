/* Binding for the variational solvers of the C core. */
#include "mp_py.h"

PyMethodDef mp_py_variational_methods[] = {
    {NULL, NULL, 0, NULL},
};
