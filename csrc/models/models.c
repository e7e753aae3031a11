/* The scene table and the one parameter check.  A new scene is one file
 * (its functions and its `const mp_model` row) plus one line in
 * models/list.h. */
#include "models/models.h"

#include <stdio.h>
#include <string.h>

#define MP_MODEL(x) extern const mp_model mp_model_##x;
#include "models/list.h"
#undef MP_MODEL

const mp_model *const mp_models[] = {
#define MP_MODEL(x) &mp_model_##x,
#include "models/list.h"
#undef MP_MODEL
    NULL,
};

/* The row named `name`, or NULL. */
const mp_model *mp_model_find(const char *name)
{
    for (size_t i = 0; mp_models[i]; i++)
        if (strcmp(mp_models[i]->name, name) == 0) return mp_models[i];
    return NULL;
}

/* MP_OK when x lies in the domain of parameter p, else MP_EDOM with why. */
static int model_check_param(const mp_model_param *p, double x, char *why, size_t len)
{
    const char *want = NULL;
    char range[80];
    int below = p->lo_open ? !(x > p->lo) : x < p->lo;
    int above = p->hi_open ? !(x < p->hi) : x > p->hi;
    if (!isfinite(x)) want = "finite";
    else if (below || above) {
        if (p->lo == 0.0 && isinf(p->hi)) want = p->lo_open ? "positive" : "non-negative";
        else {
            snprintf(range, sizeof range, "in %c%g, %g%c", p->lo_open ? '(' : '[', p->lo, p->hi,
                     p->hi_open ? ')' : ']');
            want = range;
        }
    }
    if (!want) return MP_OK;
    if (why) snprintf(why, len, "%s must be %s, got %g", p->name, want, x);
    return MP_EDOM;
}

int mp_model_check(const mp_model *m, const double *params, size_t np, size_t *dim, char *why,
                   size_t len)
{
    size_t d = m->dim_of ? m->dim_of(params, np) : np == m->nparams ? m->dim : 0;
    for (size_t i = 0; i < m->nparams && i < np; i++)
        if (model_check_param(&m->params[i], params[i], why, len) != MP_OK) return MP_EDOM;
    if (d == 0) {
        if (why) snprintf(why, len, "%zu parameter values do not describe a %s", np, m->name);
        return MP_EDOM;
    }
    if (m->check && m->check(params, why, len) != MP_OK) return MP_EDOM;
    *dim = d;
    return MP_OK;
}

int mp_model_prepare(const mp_model *m, const double *params, size_t np, size_t *dim)
{
    return mp_model_check(m, params, np, dim, NULL, 0);
}

void mp_model_separable_hint(const char *scene, char *buf, size_t len)
{
    const mp_model *m = scene ? mp_model_find(scene) : NULL;
    if (m && !m->separable) {
        snprintf(buf, len, "%s is never separable", m->name);
        return;
    }
    if (m) {
        snprintf(buf, len, "%s is separable only when %s", m->name, m->separable);
        return;
    }
    size_t at = (size_t)snprintf(buf, len, "a separable scene (");
    const char *sep = "";
    for (size_t i = 0; mp_models[i] && at < len; i++) {
        const mp_model *r = mp_models[i];
        if (!r->separable) continue;
        int always = strcmp(r->separable, MP_SEPARABLE_ALWAYS) == 0;
        at += (size_t)snprintf(buf + at, len - at, "%s%s%s%s", sep, r->name,
                               always ? "" : " with ", always ? "" : r->separable);
        sep = ", ";
    }
    if (at < len) snprintf(buf + at, len - at, ") or mp.SecondOrder(accel)");
}
