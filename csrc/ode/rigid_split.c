/* Geometric methods for the free rigid body (RigidBody scenes): the
 * Hamiltonian H = sum L_i^2 / (2 I_i) split into its three terms, each flowed
 * exactly (a rotation of the body angular momentum L about a principal axis,
 * and the same rotation composed onto the orientation quaternion), composed
 * symmetrically: 1(h/2) 2(h/2) 3(h) 2(h/2) 1(h/2) (order 2, "rigid:split"),
 * and Yoshida's triple jump of it (order 4, "rigid:split4").  A constant
 * body torque adds the exact kick L += tau h/2 at both ends.
 *
 * Every sub-step is an orthogonal rotation, so |L| and |q| are kept to
 * round-off; the energy oscillates without drift.  L is carried from step to
 * step in the method's state (converting back from omega would add a rounding
 * per step); it is re-derived whenever the state handed in is not the one the
 * last step produced. */
#include "ode/ode.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "models/rigid.h"

typedef struct {
    int kind;         /* 1: omega, 2: omega and quaternion */
    int checked;      /* the initial quaternion was checked */
    double L[3];      /* body angular momentum matching `last` */
    double last[7];   /* the state last produced */
} split_state;

static int split_alloc(mp_ode_ws *w)
{
    int kind = mp_rigid_is_body(w->p);
    if (!kind) return MP_EDOM; /* only RigidBody scenes */
    split_state *s = calloc(1, sizeof *s);
    if (!s) return MP_ENOMEM;
    s->kind = kind;
    w->state = s;
    return MP_OK;
}

static void split_free(mp_ode_ws *w)
{
    free(w->state);
    w->state = NULL;
}

/* the exact flow of L_i^2/(2 I_i) for time h: L rotates about e_i by -L_i h / I_i,
 * the orientation by +L_i h / I_i (q <- q (x) exp(angle e_i / 2)) */
static void flow_axis(int i, double h, const double *I, double *L, double *q)
{
    int j = (i + 1) % 3, k = (i + 2) % 3;
    double ang = L[i] / I[i] * h;
    double c = cos(ang), s = sin(ang);
    double lj = L[j], lk = L[k];
    L[j] = c * lj + s * lk;
    L[k] = -s * lj + c * lk;
    if (q) {
        double ch = cos(0.5 * ang), sh = sin(0.5 * ang);
        /* q (x) (sh e_i, ch), scalar last */
        double v[3] = {q[0], q[1], q[2]}, qw = q[3];
        double r[3] = {0.0, 0.0, 0.0};
        r[i] = sh;
        q[0] = qw * r[0] + ch * v[0] + (v[1] * r[2] - v[2] * r[1]);
        q[1] = qw * r[1] + ch * v[1] + (v[2] * r[0] - v[0] * r[2]);
        q[2] = qw * r[2] + ch * v[2] + (v[0] * r[1] - v[1] * r[0]);
        q[3] = qw * ch - (v[0] * r[0] + v[1] * r[1] + v[2] * r[2]);
    }
}

static void strang(double h, const double *p, double *L, double *q, int torque)
{
    if (torque)
        for (int i = 0; i < 3; i++) L[i] += 0.5 * h * p[3 + i];
    flow_axis(0, 0.5 * h, p, L, q);
    flow_axis(1, 0.5 * h, p, L, q);
    flow_axis(2, h, p, L, q);
    flow_axis(1, 0.5 * h, p, L, q);
    flow_axis(0, 0.5 * h, p, L, q);
    if (torque)
        for (int i = 0; i < 3; i++) L[i] += 0.5 * h * p[3 + i];
}

#define Y4_W1 1.3512071919596576340476878089715
#define Y4_W0 (-1.7024143839193152680953756179429)

static int split_run(mp_ode_ws *w, double h, const double *c, int nc)
{
    split_state *s = w->state;
    const double *p = w->p->data;
    size_t n = w->n;
    if (!s->checked) {
        if (s->kind == 2) {
            const double *q = w->y + 3;
            double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            if (!(fabs(nq - 1.0) <= 1e-12)) return MP_EDOM;
        }
        s->checked = 1;
    }
    if (memcmp(w->y, s->last, n * sizeof(double)) != 0)
        for (int i = 0; i < 3; i++) s->L[i] = p[i] * w->y[i];
    memcpy(w->ynew, w->y, n * sizeof(double));
    double *q = s->kind == 2 ? w->ynew + 3 : NULL;
    int torque = p[3] != 0.0 || p[4] != 0.0 || p[5] != 0.0;
    for (int k = 0; k < nc; k++) strang(c[k] * h, p, s->L, q, torque);
    for (int i = 0; i < 3; i++) w->ynew[i] = s->L[i] / p[i];
    memcpy(s->last, w->ynew, n * sizeof(double));
    return MP_OK;
}

static const double split2_c[1] = {1.0};
static const double split4_c[3] = {Y4_W1, Y4_W0, Y4_W1};

static int split2_step(mp_ode_ws *w, double t, double h, double *err)
{
    (void)t;
    *err = 0.0;
    return split_run(w, h, split2_c, 1);
}

static int split4_step(mp_ode_ws *w, double t, double h, double *err)
{
    (void)t;
    *err = 0.0;
    return split_run(w, h, split4_c, 3);
}

/* Lie-Poisson integrators, not canonical ones: .symplectic stays 0 (that flag
 * means q'' = a(t, q) in this engine). */
const mp_ode_method mp_ode_rigid_split = {
    .name = "rigid:split", .order = 2, .adaptive = 0, .dense_order = 3, .ncoef = 4,
    .nscratch = 0, .alloc = split_alloc, .free = split_free, .step = split2_step,
    .finish = mp_ode_finish_fnew_hermite,
};

const mp_ode_method mp_ode_rigid_split4 = {
    .name = "rigid:split4", .order = 4, .adaptive = 0, .dense_order = 3, .ncoef = 4,
    .nscratch = 0, .alloc = split_alloc, .free = split_free, .step = split4_step,
    .finish = mp_ode_finish_fnew_hermite,
};
