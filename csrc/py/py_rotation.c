/* Binding for the rotation functions of the C core. */
#include "mp_py.h"

PyMethodDef mp_py_rotation_methods[] = {
    {NULL, NULL, 0, NULL},
};
