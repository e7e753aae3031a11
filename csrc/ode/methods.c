/* The method table: one row per method (see ode.h). */
#include "ode/ode.h"

#include <string.h>

extern const mp_ode_method mp_ode_rk4, mp_ode_dopri5, mp_ode_dop853, mp_ode_radau, mp_ode_auto,
    mp_ode_verlet, mp_ode_yoshida4, mp_ode_yoshida6, mp_ode_gauss4;
extern const mp_ode_method mp_ode_gsl_rk2, mp_ode_gsl_rk4, mp_ode_gsl_rkf45, mp_ode_gsl_rkck,
    mp_ode_gsl_rk8pd, mp_ode_gsl_msadams, mp_ode_gsl_rk1imp, mp_ode_gsl_rk2imp,
    mp_ode_gsl_rk4imp, mp_ode_gsl_bsimp, mp_ode_gsl_msbdf, mp_ode_rigid_split, mp_ode_rigid_split4;

const mp_ode_method *const mp_ode_methods[] = {
    &mp_ode_rk4, &mp_ode_dopri5, &mp_ode_dop853, &mp_ode_radau, &mp_ode_auto,
    &mp_ode_verlet, &mp_ode_yoshida4, &mp_ode_yoshida6, &mp_ode_gauss4,
    &mp_ode_gsl_rk2, &mp_ode_gsl_rk4, &mp_ode_gsl_rkf45, &mp_ode_gsl_rkck, &mp_ode_gsl_rk8pd,
    &mp_ode_gsl_msadams, &mp_ode_gsl_rk1imp, &mp_ode_gsl_rk2imp, &mp_ode_gsl_rk4imp,
    &mp_ode_gsl_bsimp, &mp_ode_gsl_msbdf,
    &mp_ode_rigid_split, &mp_ode_rigid_split4, /* rigid_split.c */ NULL,
};

const mp_ode_method *mp_ode_method_find(const char *name)
{
    for (size_t i = 0; mp_ode_methods[i]; i++)
        if (strcmp(mp_ode_methods[i]->name, name) == 0) return mp_ode_methods[i];
    return NULL;
}
