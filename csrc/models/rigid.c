/* Rigid bodies: Euler's equations for the body angular velocity (optionally
 * with a constant body-frame torque and the orientation as a unit
 * quaternion, scalar last), the heavy symmetric top in Euler angles, and the
 * exact torque-free motion from Jacobi elliptic functions. */
#include "models/rigid.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_sf_ellint.h>
#include <gsl/gsl_sf_elljac.h>

/* ---- Euler's equations ------------------------------------------------------
 * I1 w1' = (I2 - I3) w2 w3 + tau1 (cyclic); q' = q (x) (w, 0) / 2.
 * Parameters (I1, I2, I3, tau1, tau2, tau3). */
static const mp_model_param rigid_params[] = {
    MP_PARAM_POSITIVE("I1", 1.0), MP_PARAM_POSITIVE("I2", 2.0), MP_PARAM_POSITIVE("I3", 3.0),
    MP_PARAM("tau1", 0.0),        MP_PARAM("tau2", 0.0),        MP_PARAM("tau3", 0.0),
};

int mp_rigid_check_moments(const double *I)
{
    for (int i = 0; i < 3; i++)
        if (!isfinite(I[i]) || !(I[i] > 0)) return MP_EDOM;
    /* the triangle inequality of a real body: each moment at most the sum of the others */
    for (int i = 0; i < 3; i++)
        if (I[i] > (I[(i + 1) % 3] + I[(i + 2) % 3]) * (1.0 + 1e-14)) return MP_EDOM;
    return MP_OK;
}

/* The row's check: the moments of a real body (the bounds made them positive). */
static int rigid_check(const double *p, char *why, size_t len)
{
    if (mp_rigid_check_moments(p) == MP_OK) return MP_OK;
    if (why)
        snprintf(why, len, "moments (%g, %g, %g) violate the triangle inequality "
                 "I_i <= I_j + I_k of a real body", p[0], p[1], p[2]);
    return MP_EDOM;
}

static inline void euler_free(const double *p, const double *w, double *f)
{
    f[0] = (p[1] - p[2]) / p[0] * w[1] * w[2];
    f[1] = (p[2] - p[0]) / p[1] * w[2] * w[0];
    f[2] = (p[0] - p[1]) / p[2] * w[0] * w[1];
}

static inline void quat_rate(const double *w, const double *q, double *f)
{
    f[0] = 0.5 * (q[3] * w[0] + q[1] * w[2] - q[2] * w[1]);
    f[1] = 0.5 * (q[3] * w[1] + q[2] * w[0] - q[0] * w[2]);
    f[2] = 0.5 * (q[3] * w[2] + q[0] * w[1] - q[1] * w[0]);
    f[3] = -0.5 * (q[0] * w[0] + q[1] * w[1] + q[2] * w[2]);
}

int mp_rigid_rhs_free(double t, const double *y, double *f, void *d)
{
    (void)t;
    euler_free(d, y, f);
    return MP_OK;
}

int mp_rigid_rhs_torque(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    (void)t;
    euler_free(p, y, f);
    for (int i = 0; i < 3; i++) f[i] += p[3 + i] / p[i];
    return MP_OK;
}

int mp_rigid_rhs_free_q(double t, const double *y, double *f, void *d)
{
    (void)t;
    euler_free(d, y, f);
    quat_rate(y, y + 3, f + 3);
    return MP_OK;
}

int mp_rigid_rhs_torque_q(double t, const double *y, double *f, void *d)
{
    mp_rigid_rhs_torque(t, y, f, d);
    quat_rate(y, y + 3, f + 3);
    return MP_OK;
}

static void euler_jac(const double *p, const double *w, double *J, size_t n)
{
    double a = (p[1] - p[2]) / p[0], b = (p[2] - p[0]) / p[1], c = (p[0] - p[1]) / p[2];
    for (size_t i = 0; i < n * n; i++) J[i] = 0.0;
    J[0 * n + 1] = a * w[2];
    J[0 * n + 2] = a * w[1];
    J[1 * n + 0] = b * w[2];
    J[1 * n + 2] = b * w[0];
    J[2 * n + 0] = c * w[1];
    J[2 * n + 1] = c * w[0];
}

static int rigid_jac(double t, const double *y, double *J, void *d)
{
    (void)t;
    euler_jac(d, y, J, 3);
    return MP_OK;
}

static int rigid_jac_q(double t, const double *y, double *J, void *d)
{
    (void)t;
    const double *w = y, *q = y + 3;
    euler_jac(d, y, J, 7);
    /* d q'/d w */
    double dw[4][3] = {{q[3], -q[2], q[1]}, {q[2], q[3], -q[0]}, {-q[1], q[0], q[3]},
                       {-q[0], -q[1], -q[2]}};
    /* d q'/d q: q' = M(w) q / 2 */
    double dq[4][4] = {{0, w[2], -w[1], w[0]}, {-w[2], 0, w[0], w[1]}, {w[1], -w[0], 0, w[2]},
                       {-w[0], -w[1], -w[2], 0}};
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 3; j++) J[(3 + i) * 7 + j] = 0.5 * dw[i][j];
        for (int j = 0; j < 4; j++) J[(3 + i) * 7 + 3 + j] = 0.5 * dq[i][j];
    }
    return MP_OK;
}

static int has_torque(const double *p) { return p[3] != 0.0 || p[4] != 0.0 || p[5] != 0.0; }

static void rigid_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set(prob, 3, has_torque(p) ? mp_rigid_rhs_torque : mp_rigid_rhs_free, rigid_jac, p,
                 0);
}

static void rigid_bind_q(const double *p, mp_ode_problem *prob)
{
    mp_model_set(prob, 7, has_torque(p) ? mp_rigid_rhs_torque_q : mp_rigid_rhs_free_q,
                 rigid_jac_q, p, 0);
}

/* rotational kinetic energy (I1 w1^2 + I2 w2^2 + I3 w3^2) / 2 */
static double rigid_energy(const double *p, const double *y)
{
    return 0.5 * (p[0] * y[0] * y[0] + p[1] * y[1] * y[1] + p[2] * y[2] * y[2]);
}

static const char *const rigid_field[] = {
    "(I2 - I3)/I1*y1*y2 + tau1/I1",
    "(I3 - I1)/I2*y2*y0 + tau2/I2",
    "(I1 - I2)/I3*y0*y1 + tau3/I3"
};

const mp_model mp_model_rigid = {
    .name = "RigidBody", .dim = 3, .nparams = 6, .params = rigid_params, .check = rigid_check,
    .bind = rigid_bind, .energy = rigid_energy,
    .field = rigid_field,
    .states = MP_NAMES("omega1", "omega2", "omega3"), .coordinates = MP_NO_NAMES,
    .speeds = MP_NAMES("omega1", "omega2", "omega3"), .drawing = "rigid",
};
static const char *const rigid_q_field[] = {
    "(I2 - I3)/I1*y1*y2 + tau1/I1",
    "(I3 - I1)/I2*y2*y0 + tau2/I2",
    "(I1 - I2)/I3*y0*y1 + tau3/I3",
    "(y6*y0 + y4*y2 - y5*y1)/2",
    "(y6*y1 + y5*y0 - y3*y2)/2",
    "(y6*y2 + y3*y1 - y4*y0)/2",
    "-(y3*y0 + y4*y1 + y5*y2)/2"
};

const mp_model mp_model_rigid_q = {
    .name = "RigidBodyOriented", .dim = 7, .nparams = 6, .params = rigid_params,
    .check = rigid_check, .bind = rigid_bind_q, .energy = rigid_energy,
    .field = rigid_q_field,
    .states = MP_NAMES("omega1", "omega2", "omega3", "qx", "qy", "qz", "qw"),
    .coordinates = MP_NAMES("qx", "qy", "qz", "qw"),
    .speeds = MP_NAMES("omega1", "omega2", "omega3"), .drawing = "rigid",
};

/* a torque callback: the free part, then tau / I (tau is NaN before the call, so
 * that a component the callback leaves unwritten is a NonFiniteError) */
static int rigid_rhs_cb(double t, const double *y, double *f, void *d)
{
    const mp_rigid_torque *tq = d;
    double tau[3] = {NAN, NAN, NAN}; /* unwritten by the callback: NonFiniteError */
    tq->fn(t, y, tau, tq->user_data);
    euler_free(tq->params, y, f);
    for (int i = 0; i < 3; i++) f[i] += tau[i] / tq->params[i];
    return MP_OK;
}

static int rigid_rhs_cb_q(double t, const double *y, double *f, void *d)
{
    rigid_rhs_cb(t, y, f, d);
    quat_rate(y, y + 3, f + 3);
    return MP_OK;
}

int mp_rigid_bind_torque(const mp_model *m, const mp_rigid_torque *tq, mp_ode_problem *prob)
{
    if (m != &mp_model_rigid && m != &mp_model_rigid_q) return MP_EDOM;
    m->bind(tq->params, prob);
    prob->rhs = m == &mp_model_rigid ? rigid_rhs_cb : rigid_rhs_cb_q;
    prob->jac = NULL;
    prob->data = (void *)tq;
    return MP_OK;
}

int mp_rigid_is_body(const mp_ode_problem *p)
{
    if (p->rhs == mp_rigid_rhs_free || p->rhs == mp_rigid_rhs_torque) return p->n == 3 ? 1 : 0;
    if (p->rhs == mp_rigid_rhs_free_q || p->rhs == mp_rigid_rhs_torque_q)
        return p->n == 7 ? 2 : 0;
    return 0;
}

/* ---- the heavy symmetric top -----------------------------------------------
 * State (phi, theta, psi, phi', theta', psi'); w3 = psi' + phi' cos(theta);
 * r = I3/I1, A = m g l:
 *   theta'' = phi'^2 s c - r w3 phi' s + (A/I1) s
 *   phi''   = theta' (r w3 - 2 phi' c) / s
 *   psi''   = -phi'' c + phi' theta' s                                     */
static const mp_model_param top_params[] = {
    MP_PARAM_POSITIVE("I1", MP_REQUIRED), MP_PARAM_POSITIVE("I3", MP_REQUIRED),
    MP_PARAM_POSITIVE("mass", MP_REQUIRED), MP_PARAM_NONNEGATIVE("g", 9.81), MP_PARAM("l", 1.0),
};

/* The quantities the top's rhs and Jacobian share: sin and cos of theta,
 * r = I3/I1, A = m g l / I1, the rates and the spin w3 = psi' + phi' cos(theta). */
typedef struct {
    double s, c, r, A, pd, td, w3;
} top_terms;

static int top_terms_of(const double *p, const double *y, top_terms *k)
{
    k->s = sin(y[1]);
    k->c = cos(y[1]);
    k->r = p[1] / p[0];
    k->A = p[2] * p[3] * p[4] / p[0];
    k->pd = y[3];
    k->td = y[4];
    k->w3 = y[5] + k->pd * k->c;
    return k->s == 0.0 ? MP_ESINGULAR : MP_OK; /* Euler angles fail at theta = 0, pi */
}

static int top_rhs(double t, const double *y, double *f, void *d)
{
    (void)t;
    top_terms k;
    if (top_terms_of(d, y, &k) != MP_OK) return MP_ESINGULAR;
    double s = k.s, c = k.c, r = k.r, A = k.A, pd = k.pd, td = k.td, w3 = k.w3;
    f[0] = pd;
    f[1] = td;
    f[2] = y[5];
    f[3] = td * (r * w3 - 2.0 * pd * c) / s;
    f[4] = pd * pd * s * c - r * w3 * pd * s + A * s;
    f[5] = -f[3] * c + pd * td * s;
    return MP_OK;
}

static int top_jac(double t, const double *y, double *J, void *d)
{
    (void)t;
    top_terms k;
    if (top_terms_of(d, y, &k) != MP_OK) return MP_ESINGULAR;
    double s = k.s, c = k.c, r = k.r, A = k.A, pd = k.pd, td = k.td, w3 = k.w3;
    for (int i = 0; i < 36; i++) J[i] = 0.0;
    J[0 * 6 + 3] = 1.0;
    J[1 * 6 + 4] = 1.0;
    J[2 * 6 + 5] = 1.0;
    double N = r * w3 - 2.0 * pd * c, f3 = td * N / s;
    double dN_th = pd * s * (2.0 - r);
    double d3_th = td * (dN_th * s - N * c) / (s * s), d3_pd = td * c * (r - 2.0) / s,
           d3_td = N / s, d3_ps = td * r / s;
    J[3 * 6 + 1] = d3_th;
    J[3 * 6 + 3] = d3_pd;
    J[3 * 6 + 4] = d3_td;
    J[3 * 6 + 5] = d3_ps;
    J[4 * 6 + 1] = pd * pd * (c * c - s * s) + r * pd * pd * s * s - r * w3 * pd * c + A * c;
    J[4 * 6 + 3] = 2.0 * pd * s * c - r * s * (c * pd + w3);
    J[4 * 6 + 5] = -r * pd * s;
    J[5 * 6 + 1] = -d3_th * c + f3 * s + pd * td * c;
    J[5 * 6 + 3] = -d3_pd * c + td * s;
    J[5 * 6 + 4] = -d3_td * c + pd * s;
    J[5 * 6 + 5] = -d3_ps * c;
    return MP_OK;
}

static void top_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set(prob, 6, top_rhs, top_jac, p, 0);
}

/* E = I1 (theta'^2 + phi'^2 sin^2 theta)/2 + I3 w3^2/2 + m g l cos(theta) */
static double top_energy(const double *p, const double *y)
{
    double s = sin(y[1]), c = cos(y[1]), w3 = y[5] + y[3] * c;
    return 0.5 * p[0] * (y[4] * y[4] + y[3] * y[3] * s * s) + 0.5 * p[1] * w3 * w3 +
           p[2] * p[3] * p[4] * c;
}

/* The top's Lagrangian at m points, q = (phi, theta, psi), 34 values each
 * (variational.h's layout, d = 3):
 * L = I1/2 (th'^2 + ph'^2 sin^2 th) + I3/2 (ps' + ph' cos th)^2 - M g l cos th  [J] */
static int top_lagrangian(size_t m, const double *x, const double *y, const double *v,
                          double *out, void *ctx)
{
    const double *k = ctx;
    double I1 = k[0], I3 = k[1], Mgl = k[2] * k[3] * k[4];
    (void)x;
    for (size_t i = 0; i < m; i++, y += 3, v += 3, out += 34) {
        double s = sin(y[1]), c = cos(y[1]), ph = v[0], th = v[1], ps = v[2];
        double w = ps + ph * c; /* the spin omega_3 */
        memset(out, 0, 34 * sizeof(double));
        out[0] = 0.5 * I1 * (th * th + ph * ph * s * s) + 0.5 * I3 * w * w - Mgl * c;
        out[2] = I1 * ph * ph * s * c - I3 * w * ph * s + Mgl * s; /* dL/dtheta */
        out[4] = I1 * ph * s * s + I3 * w * c;                     /* p_phi */
        out[5] = I1 * th;                                          /* p_theta */
        out[6] = I3 * w;                                           /* p_psi */
        double *Lqq = out + 7, *Lqv = out + 16, *Lvv = out + 25;
        Lqq[4] = I1 * ph * ph * (c * c - s * s) + I3 * (ph * ph * s * s - w * ph * c) + Mgl * c;
        Lqv[3] = 2.0 * I1 * ph * s * c - I3 * s * (ph * c + w); /* d2L/dtheta dphi' */
        Lqv[5] = -I3 * ph * s;                                  /* d2L/dtheta dpsi' */
        Lvv[0] = I1 * s * s + I3 * c * c;
        Lvv[2] = Lvv[6] = I3 * c;
        Lvv[4] = I1;
        Lvv[8] = I3;
    }
    return MP_OK;
}

/* Lanes (ode/lanes.h): top_rhs for MP_LANES states at once (SoA), each
 * lane's parameters; a lane at theta = 0 or pi is singular, as top_rhs says. */
#define W MP_LANES
MP_LANE_FN static void top_lanes_rhs(const double *t, const double *y, double *f,
                                     const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        double s = mp_lane_sin(y[W + l]), c = mp_lane_cos(y[W + l]);
        double r = p[W + l] / p[l], A = p[2 * W + l] * p[3 * W + l] * p[4 * W + l] / p[l];
        double pd = y[3 * W + l], td = y[4 * W + l], w3 = y[5 * W + l] + pd * c;
        double f3 = td * (r * w3 - 2.0 * pd * c) / s;
        f[l] = pd;
        f[W + l] = td;
        f[2 * W + l] = y[5 * W + l];
        f[3 * W + l] = f3;
        f[4 * W + l] = pd * pd * s * c - r * w3 * pd * s + A * s;
        f[5 * W + l] = -f3 * c + pd * td * s;
        st[l] = s == 0.0 ? MP_ESINGULAR : MP_OK;
    }
}
MP_MODEL_ONE_LANE_RHS(top_lanes, top_lanes_rhs)

static const char *const top_field[] = {
    "y3",
    "y4",
    "y5",
    "y4*(I3/I1*(y5 + y3*cos(y1)) - 2*y3*cos(y1))/sin(y1)",
    "y3**2*sin(y1)*cos(y1) - I3/I1*(y5 + y3*cos(y1))*y3*sin(y1) + mass*g*l/I1*sin(y1)",
    "-(y4*(I3/I1*(y5 + y3*cos(y1)) - 2*y3*cos(y1))/sin(y1))*cos(y1) + y3*y4*sin(y1)"
};

const mp_model mp_model_heavy_top = {
    .name = "HeavyTop", .dim = 6, .nparams = 5, .params = top_params, .bind = top_bind,
    .energy = top_energy, .lagrangian = top_lagrangian,
    .lanes = top_lanes,
    .field = top_field,
    .states = MP_NAMES("phi", "theta", "psi", "phi'", "theta'", "psi'"),
    .coordinates = MP_NAMES("phi", "theta", "psi"), .speeds = MP_NAMES("phi'", "theta'", "psi'"),
    .drawing = "top",
};

/* ---- the exact torque-free motion ------------------------------------------
 * Axes relabelled (a, b, c) so that b is the intermediate one and c the axis
 * the motion winds around (largest moment when L^2 > 2 E I_b, smallest
 * otherwise).  Then (Landau & Lifshitz section 37)
 *   w_a = A cn(u), w_b = B sn(u), w_c = C dn(u),  u = lam t + u0,
 *   A^2 = (2E Ic - L^2)/(Ia (Ic - Ia)), B^2 = (2E Ic - L^2)/(Ib (Ic - Ib)),
 *   C^2 = (L^2 - 2E Ia)/(Ic (Ic - Ia)), lam^2 = (Ic - Ib)(L^2 - 2E Ia)/(Ia Ib Ic),
 *   m = k^2 = (Ib - Ia)(2E Ic - L^2)/((Ic - Ib)(L^2 - 2E Ia)).
 * Each difference 2E Ix - L^2 is a sum of same-signed terms
 * sum_i I_i (Ix - I_i) w_i^2, so nothing cancels; 1 - m is formed the same
 * way from L^2 - 2E Ib, the distance to the separatrix.  Signs: w_c keeps
 * its sign, w_b = sgn(w_c) B sn, and lam takes the sign that makes Euler's
 * equations hold in the relabelled (possibly odd-permuted) frame. */
typedef struct {
    int ax[3];          /* a, b, c */
    double A, B, C, lam, u0, m, sc, K;
} free_sol;

static double dsum(const double *I, const double *w, double Ix)
{
    double s = 0.0;
    for (int i = 0; i < 3; i++) s += I[i] * (Ix - I[i]) * w[i] * w[i];
    return s;
}

static int free_setup(const double *I, const double *w, free_sol *S)
{
    if (mp_rigid_check_moments(I) != MP_OK) return MP_EDOM;
    for (int i = 0; i < 3; i++)
        if (!isfinite(w[i])) return MP_EDOM;
    int o[3] = {0, 1, 2};
    /* sort ascending */
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (I[o[j]] < I[o[i]]) { int tmp = o[i]; o[i] = o[j]; o[j] = tmp; }
    if (!(I[o[0]] < I[o[1]] && I[o[1]] < I[o[2]])) {
        /* a symmetric body: the unique axis is c (w_c constant), the pair
         * rotates rigidly; handled by the same formulas with m = 0 */
        if (I[o[0]] == I[o[2]]) return MP_EDOM; /* spherical: caller handles */
        if (I[o[0]] == I[o[1]]) { S->ax[0] = o[0]; S->ax[1] = o[1]; S->ax[2] = o[2]; }
        else { S->ax[0] = o[2]; S->ax[1] = o[1]; S->ax[2] = o[0]; }
    } else {
        double sep = dsum(I, w, I[o[1]]); /* L^2 - 2E Ib... sign: 2E Ib - L^2 */
        if (sep <= 0) { S->ax[0] = o[0]; S->ax[1] = o[1]; S->ax[2] = o[2]; }
        else { S->ax[0] = o[2]; S->ax[1] = o[1]; S->ax[2] = o[0]; }
    }
    int a = S->ax[0], b = S->ax[1], c = S->ax[2];
    double Ia = I[a], Ib = I[b], Ic = I[c];
    double Dc = dsum(I, w, Ic);       /* 2E Ic - L^2 */
    double Da = -dsum(I, w, Ia);      /* L^2 - 2E Ia */
    double Db = -dsum(I, w, Ib);      /* L^2 - 2E Ib */
    if (Da == 0.0) {
        /* a steady rotation: at rest, or (Ia = Ib) w in the plane of the equal
         * pair (w_c = 0; a triaxial body has Da = 0 only at rest).  w stays w0:
         * lam = m = 0, w_a = A cos u0, w_b = B sin u0, w_c = C. */
        S->A = S->B = hypot(w[a], w[b]);
        S->u0 = atan2(w[b], w[a]);
        S->lam = S->m = 0.0;
        S->C = w[c];
        S->sc = 1.0;
        S->K = INFINITY;
        return MP_OK;
    }
    S->A = sqrt(fmax(Dc / (Ia * (Ic - Ia)), 0.0));
    S->B = sqrt(fmax(Dc / (Ib * (Ic - Ib)), 0.0));
    S->C = sqrt(fmax(Da / (Ic * (Ic - Ia)), 0.0));
    double lam = sqrt(fmax((Ic - Ib) * Da / (Ia * Ib * Ic), 0.0));
    double m = (Ib - Ia) * Dc / ((Ic - Ib) * Da);
    double m1 = (Ic - Ia) * Db / ((Ic - Ib) * Da);
    if (m1 < 0) m1 = 0.0;
    m = fmin(fmax(m, 0.0), 1.0);
    /* d w_b/dt = B w_a w_c lam / (A C) must equal Euler's
     * (I_{b+1} - I_{b+2}) / I_b w_{b+1} w_{b+2}: lam has the sign of that coefficient */
    double sc = w[c] >= 0 ? 1.0 : -1.0;
    if (I[(b + 1) % 3] - I[(b + 2) % 3] < 0) lam = -lam;
    S->lam = lam;
    S->m = m;
    S->sc = sc;
    /* phase: cn(u0) = w_a / A, sn(u0) = sc w_b / B */
    double phi = atan2(S->B > 0 ? sc * w[b] / S->B : 0.0, S->A > 0 ? w[a] / S->A : 1.0);
    gsl_sf_result F, K;
    double k = sqrt(m);
    if (m1 == 0.0) {
        /* on the separatrix: F(phi | 1) = atanh(sin phi) */
        S->u0 = atanh(sin(phi));
        S->K = INFINITY;
    } else {
        if (gsl_sf_ellint_Kcomp_e(k, GSL_PREC_DOUBLE, &K) != GSL_SUCCESS) return MP_EGSL;
        /* reduce phi to [-pi/2, pi/2] with F(phi + n pi) = F(phi) + 2 n K */
        double n = 0.0;
        if (phi > M_PI_2) { phi -= M_PI; n = 1.0; }
        else if (phi < -M_PI_2) { phi += M_PI; n = -1.0; }
        if (gsl_sf_ellint_F_e(phi, k, GSL_PREC_DOUBLE, &F) != GSL_SUCCESS) return MP_EGSL;
        S->u0 = F.val + 2.0 * n * K.val;
        S->K = K.val;
    }
    return MP_OK;
}

int mp_rigid_free_rotation(const double *I, const double *w0, const double *t, size_t nt,
                           double *out)
{
    free_sol S;
    if (I[0] == I[1] && I[1] == I[2] && mp_rigid_check_moments(I) == MP_OK) {
        for (size_t j = 0; j < nt; j++) memcpy(out + 3 * j, w0, 3 * sizeof(double));
        return MP_OK;
    }
    int rc = free_setup(I, w0, &S);
    if (rc != MP_OK) return rc;
    for (size_t j = 0; j < nt; j++) {
        if (!isfinite(t[j])) return MP_EDOM;
        double u = S.lam * t[j] + S.u0, sn, cn, dn;
        if (gsl_sf_elljac_e(u, S.m, &sn, &cn, &dn) != GSL_SUCCESS) return MP_EGSL;
        double *o = out + 3 * j;
        o[S.ax[0]] = S.A * cn;
        o[S.ax[1]] = S.sc * S.B * sn;
        o[S.ax[2]] = S.sc * S.C * dn;
    }
    return MP_OK;
}

int mp_rigid_flip_period(const double *I, const double *w0, double *T)
{
    free_sol S;
    if (I[0] == I[1] || I[1] == I[2] || I[0] == I[2]) return MP_EDOM;
    int rc = free_setup(I, w0, &S);
    if (rc != MP_OK) return rc;
    if (S.lam == 0.0 || !isfinite(S.K)) { *T = INFINITY; return MP_OK; }
    *T = 4.0 * S.K / fabs(S.lam);
    return MP_OK;
}
