/* The scene table. */
#include "models/models.h"

#include <string.h>

#include "mp_status.h"

extern const mp_model mp_model_pendulum, mp_model_vanderpol, mp_model_duffing, mp_model_kepler,
    mp_model_r3b, mp_model_foucault, mp_model_rigid, mp_model_rigid_q, mp_model_heavy_top;
extern const mp_model mp_model_chain;
extern const mp_model mp_model_rocket;

const mp_model *const mp_models[] = {
    &mp_model_pendulum, &mp_model_vanderpol, &mp_model_duffing, &mp_model_kepler, &mp_model_r3b,
    &mp_model_foucault, &mp_model_rigid, &mp_model_rigid_q, &mp_model_heavy_top,
    &mp_model_chain,
    &mp_model_rocket,
    NULL,
};

const mp_model *mp_model_find(const char *name)
{
    for (size_t i = 0; mp_models[i]; i++)
        if (strcmp(mp_models[i]->name, name) == 0) return mp_models[i];
    return NULL;
}

int mp_model_prepare(const mp_model *m, const double *params, size_t np, size_t *dim)
{
    size_t d = m->dim_of ? m->dim_of(params, np) : np == m->nparams ? m->dim : 0;
    if (d == 0) return MP_EDOM;
    *dim = d;
    return m->check(params) == MP_OK ? MP_OK : MP_EDOM;
}
