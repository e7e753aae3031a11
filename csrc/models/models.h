/* Scene models: one file per scene family, one `const mp_model` row each.
 *
 * A model states its dimension and parameters, checks them, and binds the
 * cheapest right-hand side for the given parameters into an ODE problem (an
 * optional term that is off costs nothing).  Its Jacobian and energy are
 * analytic. */
#ifndef MP_MODELS_H
#define MP_MODELS_H

#include <stddef.h>

#include "ode/ode.h"

typedef struct mp_model {
    const char *name;
    size_t dim;
    size_t nparams;
    const char *const *param_names;
    /* MP_EDOM when a parameter is out of its domain */
    int (*check)(const double *params);
    /* Fill prob->rhs, prob->jac, prob->n and prob->data (= params). */
    void (*bind)(const double *params, mp_ode_problem *prob);
    /* Energy (or the scene's natural invariant) of one state. */
    double (*energy)(const double *params, const double *y);
    /* Variable-size scenes (a chain of N masses): the state dimension their
     * np parameters describe, 0 when np does not fit.  NULL for a scene of
     * fixed dim and nparams. */
    size_t (*dim_of)(const double *params, size_t np);
} mp_model;

extern const mp_model *const mp_models[];
const mp_model *mp_model_find(const char *name);
/* The one parameter check: np values for m, in their domain (MP_EDOM
 * otherwise); *dim receives the state dimension they describe. */
int mp_model_prepare(const mp_model *m, const double *params, size_t np, size_t *dim);

#endif
