/* Geometric methods for the free rigid body (RigidBody scenes): the
 * Hamiltonian H = sum L_i^2 / (2 I_i) split into its three terms, each flowed
 * exactly (a rotation of the body angular momentum L about a principal axis,
 * and the same rotation composed onto the orientation quaternion), composed
 * symmetrically: 1(h/2) 2(h/2) 3(h) 2(h/2) 1(h/2) (order 2, "rigid:split"),
 * and Yoshida's triple jump of it (order 4, "rigid:split4").  A constant
 * body torque adds the exact kick L += tau h/2 at both ends.
 *
 * Every sub-step is an orthogonal rotation, applied as a small increment
 * with compensated summation (see flow_axis), so |L| and |q| are kept to a
 * few roundings over 10^6 steps; the energy oscillates without drift.  L is carried from step to
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
    double Lc[3];     /* its compensation (the low-order part rounding left out) */
    double qc[4];     /* the quaternion's compensation */
    double last[7];   /* the state last produced */
} split_state;

static int split_alloc(mp_ode_ws *w)
{
    int kind = mp_rigid_is_body(w->p);
    if (!kind) return MP_EDOM; /* only RigidBody scenes without a torque callback */
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

/* x <- x + d with Kahan's compensated summation (Hairer, Lubich and Wanner,
 * Geometric Numerical Integration, VIII.5): c keeps what rounding cut off. */
static inline void comp_add(double *x, double *c, double d)
{
    double a = *x, y = d + *c;
    *x = a + y;
    *c = (a - *x) + y;
}

/* The exact flow of L_i^2/(2 I_i) for time h: L rotates about e_i by -L_i h / I_i,
 * the orientation by +L_i h / I_i (q <- q (x) exp(angle e_i / 2)).
 *
 * Round-off: a rotation applied as L <- R L moves |L| by about one rounding
 * per sub-step, a random walk of sqrt(5 N) eps after N steps (2e-13 at
 * N = 10^6).  Written as an increment, L <- L + (R - 1) L with
 * R - 1 = [[-2 s^2, 2 s c], [-2 s c, -2 s^2]] (s, c = sin, cos of half the
 * angle), the increment is small and rounds relative to itself, R stays
 * orthogonal to O(angle^2 eps) whatever the rounding of s and c, and the
 * compensated sum carries what each addition to L loses: the error per
 * sub-step falls from eps to about eps * angle.  The quaternion is advanced
 * the same way with q (x) (sin(a/2) e_i, cos(a/2) - 1), from the quarter angle. */
static void flow_axis(int i, double h, const double *I, double *L, double *Lc, double *q,
                      double *qc)
{
    int j = (i + 1) % 3, k = (i + 2) % 3;
    double ang = L[i] / I[i] * h;
    double sh, ch;                      /* sin, cos of ang/2 */
    double sq = 0.0, cq = 0.0;          /* sin, cos of ang/4 (quaternion) */
    if (q) {
        sq = sin(0.25 * ang);
        cq = cos(0.25 * ang);
        sh = 2.0 * sq * cq;
        ch = 1.0 - 2.0 * sq * sq;
    } else {
        sh = sin(0.5 * ang);
        ch = cos(0.5 * ang);
    }
    double s = 2.0 * sh * ch, cm = -2.0 * sh * sh; /* sin(ang), cos(ang) - 1 */
    double lj = L[j], lk = L[k];
    comp_add(&L[j], &Lc[j], cm * lj + s * lk);
    comp_add(&L[k], &Lc[k], cm * lk - s * lj);
    if (q) {
        /* q (x) (sh e_i, ch) - q = q (x) (sh e_i, ch - 1), scalar last */
        double hm = -2.0 * sq * sq;
        double v[3] = {q[0], q[1], q[2]}, qw = q[3];
        double r[3] = {0.0, 0.0, 0.0};
        r[i] = sh;
        comp_add(&q[0], &qc[0], qw * r[0] + hm * v[0] + (v[1] * r[2] - v[2] * r[1]));
        comp_add(&q[1], &qc[1], qw * r[1] + hm * v[1] + (v[2] * r[0] - v[0] * r[2]));
        comp_add(&q[2], &qc[2], qw * r[2] + hm * v[2] + (v[0] * r[1] - v[1] * r[0]));
        comp_add(&q[3], &qc[3], hm * qw - (v[0] * r[0] + v[1] * r[1] + v[2] * r[2]));
    }
}

static void strang(double h, const double *p, split_state *s, double *q, int torque)
{
    if (torque)
        for (int i = 0; i < 3; i++) comp_add(&s->L[i], &s->Lc[i], 0.5 * h * p[3 + i]);
    flow_axis(0, 0.5 * h, p, s->L, s->Lc, q, s->qc);
    flow_axis(1, 0.5 * h, p, s->L, s->Lc, q, s->qc);
    flow_axis(2, h, p, s->L, s->Lc, q, s->qc);
    flow_axis(1, 0.5 * h, p, s->L, s->Lc, q, s->qc);
    flow_axis(0, 0.5 * h, p, s->L, s->Lc, q, s->qc);
    if (torque)
        for (int i = 0; i < 3; i++) comp_add(&s->L[i], &s->Lc[i], 0.5 * h * p[3 + i]);
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
    if (memcmp(w->y, s->last, n * sizeof(double)) != 0) {
        for (int i = 0; i < 3; i++) s->L[i] = p[i] * w->y[i];
        memset(s->Lc, 0, sizeof s->Lc);
        memset(s->qc, 0, sizeof s->qc);
    }
    memcpy(w->ynew, w->y, n * sizeof(double));
    double *q = s->kind == 2 ? w->ynew + 3 : NULL;
    int torque = p[3] != 0.0 || p[4] != 0.0 || p[5] != 0.0;
    for (int k = 0; k < nc; k++) strang(c[k] * h, p, s, q, torque);
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
    .name = "rigid:split", .rigid = 1, .order = 2, .adaptive = 0, .dense_order = 3, .ncoef = 4,
    .nscratch = 0, .alloc = split_alloc, .free = split_free, .step = split2_step,
    .finish = mp_ode_finish_fnew_hermite,
};

const mp_ode_method mp_ode_rigid_split4 = {
    .name = "rigid:split4", .rigid = 1, .order = 4, .adaptive = 0, .dense_order = 3, .ncoef = 4,
    .nscratch = 0, .alloc = split_alloc, .free = split_free, .step = split4_step,
    .finish = mp_ode_finish_fnew_hermite,
};
