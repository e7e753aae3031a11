/* Scene models: one file per scene family, one `const mp_model` row each.
 *
 * The row is the one description of a scene: its name, state dimension,
 * parameters (names, defaults, bounds), the extra check a bound cannot say,
 * when it is separable, and its functions.  The binding exposes it through
 * _core.scene_info, and the Python face (mechpy.scenes) builds its
 * signatures, defaults and checks from it.
 *
 * A model binds the cheapest right-hand side for the given parameters into
 * an ODE problem (an optional term that is off costs nothing).  Its
 * Jacobian and energy are analytic; a mechanical scene also gives its
 * Lagrangian L(t, q, qdot) with the partial derivatives the variational
 * tools use. */
#ifndef MP_MODELS_H
#define MP_MODELS_H

#include <math.h>
#include <stddef.h>

#include "mp_status.h"
#include "ode/fixed.h"
#include "ode/lanes.h"
#include "ode/ode.h"
#include "variational.h"

/* One scalar parameter: its default (MP_REQUIRED: none) and its domain,
 * finite and lo <= x <= hi, a bound excluded when its *_open flag is set. */
typedef struct mp_model_param {
    const char *name;
    double def;
    double lo, hi;
    int lo_open, hi_open;
} mp_model_param;

#define MP_REQUIRED NAN
/* any finite value, x > 0, x >= 0, lo <= x <= hi, lo < x < hi */
#define MP_PARAM(name, def) {name, def, -INFINITY, INFINITY, 0, 0}
#define MP_PARAM_POSITIVE(name, def) {name, def, 0.0, INFINITY, 1, 0}
#define MP_PARAM_NONNEGATIVE(name, def) {name, def, 0.0, INFINITY, 0, 0}
#define MP_PARAM_RANGE(name, def, lo, hi) {name, def, lo, hi, 0, 0}
#define MP_PARAM_OPEN(name, def, lo, hi) {name, def, lo, hi, 1, 1}

/* A NULL-terminated list of names, for a row's states, coordinates and
 * speeds (a file-scope compound literal: static storage). */
#define MP_NAMES(...) ((const char *const[]){__VA_ARGS__, NULL})
#define MP_NO_NAMES ((const char *const[]){NULL})

/* How the separable flag reads: never (NULL), always, or a condition. */
#define MP_SEPARABLE_ALWAYS "always"

typedef struct mp_model {
    const char *name;
    /* state dimension; 0 for a variable-size scene (dim_of gives it) */
    size_t dim;
    /* the scalar parameters at the head of the parameter vector; a
     * variable-size scene has more values after them (dim_of, check) */
    size_t nparams;
    const mp_model_param *params;
    /* NULL: never of the form q'' = a(t, q) with y = (q, v); otherwise when
     * it is (MP_SEPARABLE_ALWAYS or a condition such as "damping = 0");
     * bind sets prob->nq > 0 exactly then. */
    const char *separable;
    /* What the bounds cannot say (NULL: nothing): MP_OK, or MP_EDOM with a
     * message naming the parameter written to why (len bytes; why may be
     * NULL).  Called after the bounds and dim_of accepted the vector. */
    int (*check)(const double *params, char *why, size_t len);
    /* Fill prob->rhs, prob->jac, prob->n, prob->nq and prob->data (= params). */
    void (*bind)(const double *params, mp_ode_problem *prob);
    /* Energy (or the scene's natural invariant) of one state. */
    double (*energy)(const double *params, const double *y);
    /* Variable-size scenes (a chain of N masses): the state dimension their
     * np parameters describe, 0 when np does not fit.  NULL for a scene of
     * fixed dim and nparams. */
    size_t (*dim_of)(const double *params, size_t np);
    /* The Lagrangian with y = (q, qdot), q of dim / 2 coordinates, as the
     * variational tools take it (ctx = params); NULL: none. */
    mp_var_eval_fn lagrangian;
    /* The lane right-hand side (ode/lanes.h) for an ensemble whose k
     * parameter rows lie `stride` doubles apart at params: the variant that
     * serves them all (as bind picks for one row).  NULL (the field or its
     * result): the lanes run bind's scalar rhs through the generic wrapper. */
    mp_lane_rhs (*lanes)(const double *params, size_t k, size_t stride);
    /* The right-hand side as text, one expression per state component, in
     * the state y0, y1, ..., the time t and the parameters by name (SymPy's
     * syntax; Piecewise for a switch): the symbolic form that the live views
     * print to GLSL and JavaScript.  A test checks it against rhs at random
     * states and parameters.  NULL: none (a variable-size scene). */
    const char *const *field;
    /* What the state holds, by name (NULL-terminated lists, MP_NAMES): every
     * reader in Python (events, live views, plots, the docs' table, the
     * tests' lists) takes them from here through _core.scene_info.
     * states: every component, in order; a variable-size scene gives one
     * pattern per block of equal length, "#" standing for the index in the
     * block ("x#", "v#": x0, x1, ..., v0, v1, ...).  coordinates: the
     * configuration among them (same rule).  speeds: the coordinates'
     * velocities in the coordinates' order (then speeds[i] is the velocity
     * of coordinates[i]: as many of them), or the generalized speeds the
     * state holds when they are no coordinate's velocity (a rigid body's
     * omega: a different count). */
    const char *const *states;
    const char *const *coordinates;
    const char *const *speeds;
    /* How the animations draw it: the name of an entry of the drawing
     * registry (mechpy/_motion.py); NULL: no drawing of its own. */
    const char *drawing;
} mp_model;

extern const mp_model *const mp_models[];
const mp_model *mp_model_find(const char *name);

/* The one parameter check: np values for m, each head parameter finite and
 * within its bounds, the layout (dim_of) and the row's check; MP_EDOM with a
 * message in why (len bytes, why may be NULL) otherwise.  *dim receives the
 * state dimension they describe. */
int mp_model_check(const mp_model *m, const double *params, size_t np, size_t *dim, char *why,
                   size_t len);

/* mp_model_check without the message. */
int mp_model_prepare(const mp_model *m, const double *params, size_t np, size_t *dim);

/* Why a system is not separable, for a message after "needs a separable
 * system q'' = a(t, q) with y = (q, v): ": for the scene named `scene`,
 * when its row says it is (or that it never is); for anything else (scene
 * NULL or not a row), the scenes whose rows say they can be. */
void mp_model_separable_hint(const char *scene, char *buf, size_t len);

/* Whether parameter j is non-zero in any of k rows `stride` apart (a lanes
 * function's choice of variant). */
static inline int mp_model_any_nonzero(const double *p, size_t k, size_t stride, size_t j)
{
    for (size_t i = 0; i < k; i++)
        if (p[i * stride + j] != 0.0) return 1;
    return 0;
}

/* The lanes field of a scene with one lane rhs for every parameter row. */
#define MP_MODEL_ONE_LANE_RHS(name, fn)                                    \
    static mp_lane_rhs name(const double *p, size_t k, size_t stride)     \
    {                                                                      \
        (void)p, (void)k, (void)stride;                                    \
        return fn;                                                         \
    }

/* What a row's bind writes, in one call. */
static inline void mp_model_set(mp_ode_problem *prob, size_t n, mp_ode_rhs rhs, mp_ode_jac jac,
                                const double *params, size_t nq)
{
    prob->n = n;
    prob->rhs = rhs;
    prob->jac = jac;
    prob->data = (void *)params;
    prob->nq = nq;
    prob->blocks = NULL;
    prob->sw = NULL;
}

/* mp_model_set for a right-hand side with its own fixed-step blocks
 * (ode/fixed.h's MP_ODE_BLOCKS): rhs is blocks->rhs. */
static inline void mp_model_set_blocks(mp_ode_problem *prob, size_t n, const mp_ode_blocks *b,
                                       mp_ode_jac jac, const double *params, size_t nq)
{
    mp_model_set(prob, n, b->rhs, jac, params, nq);
    prob->blocks = b;
}

#endif
