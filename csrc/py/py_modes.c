/* Binding for the modes functions of the C core. */
#include "mp_py.h"

PyMethodDef mp_py_modes_methods[] = {
    {NULL, NULL, 0, NULL},
};
