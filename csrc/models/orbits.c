/* Orbits: the Kepler problem and the planar circular restricted three-body
 * problem in the rotating frame (Arenstorf's orbits). */
#include "models/models.h"

#include <math.h>

/* ---- Kepler: r'' = -mu r / |r|^3, state (x, y, vx, vy) ----------------------- */
static const mp_model_param kepler_params[] = {MP_PARAM_POSITIVE("mu", 1.0)};

static int kepler_rhs(double t, const double *y, double *f, void *d)
{
    const double mu = *(const double *)d;
    (void)t;
    double r2 = y[0] * y[0] + y[1] * y[1];
    double k = -mu / (r2 * sqrt(r2));
    f[0] = y[2];
    f[1] = y[3];
    f[2] = k * y[0];
    f[3] = k * y[1];
    return MP_OK;
}

static int kepler_jac(double t, const double *y, double *J, void *d)
{
    const double mu = *(const double *)d;
    (void)t;
    double x = y[0], yy = y[1], r2 = x * x + yy * yy, r = sqrt(r2);
    double r3 = r2 * r, r5 = r3 * r2;
    for (int i = 0; i < 16; i++) J[i] = 0.0;
    J[0 * 4 + 2] = 1.0;
    J[1 * 4 + 3] = 1.0;
    J[2 * 4 + 0] = -mu * (1.0 / r3 - 3.0 * x * x / r5);
    J[2 * 4 + 1] = 3.0 * mu * x * yy / r5;
    J[3 * 4 + 0] = 3.0 * mu * x * yy / r5;
    J[3 * 4 + 1] = -mu * (1.0 / r3 - 3.0 * yy * yy / r5);
    return MP_OK;
}

MP_ODE_BLOCKS(kepler_blocks, kepler_rhs, 4, 2);

static void kepler_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set_blocks(prob, 4, &kepler_blocks, kepler_jac, p, 2);
}

/* specific energy |v|^2/2 - mu/r */
static double kepler_energy(const double *p, const double *y)
{
    return 0.5 * (y[2] * y[2] + y[3] * y[3]) - p[0] / hypot(y[0], y[1]);
}

/* Lanes (ode/lanes.h): MP_LANES states at once, SoA, each lane's mu. */
#define W MP_LANES
MP_LANE_FN static void kepler_lanes_rhs(const double *t, const double *y, double *f,
                                        const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        double r2 = y[l] * y[l] + y[W + l] * y[W + l];
        double k = -p[l] / (r2 * sqrt(r2));
        f[l] = y[2 * W + l];
        f[W + l] = y[3 * W + l];
        f[2 * W + l] = k * y[l];
        f[3 * W + l] = k * y[W + l];
        st[l] = MP_OK;
    }
}

MP_MODEL_ONE_LANE_RHS(kepler_lanes, kepler_lanes_rhs)

static const char *const kepler_field[] = {
    "y2",
    "y3",
    "-mu*y0/(y0**2 + y1**2)**(3/2)",
    "-mu*y1/(y0**2 + y1**2)**(3/2)"
};

const mp_model mp_model_kepler = {
    .name = "Kepler", .dim = 4, .nparams = 1, .params = kepler_params,
    .separable = MP_SEPARABLE_ALWAYS, .bind = kepler_bind, .energy = kepler_energy,
    .lanes = kepler_lanes,
    .field = kepler_field,
    .states = MP_NAMES("x", "y", "vx", "vy"), .coordinates = MP_NAMES("x", "y"),
    .speeds = MP_NAMES("vx", "vy"),
};

/* ---- restricted three-body problem, rotating frame -------------------------
 * x'' = x + 2 y' - mu' (x + mu)/r1^3 - mu (x - mu')/r2^3
 * y'' = y - 2 x' - mu' y / r1^3 - mu y / r2^3,   mu' = 1 - mu */
static const mp_model_param r3b_params[] = {MP_PARAM_OPEN("mu", 0.012277471, 0.0, 1.0)};

static int r3b_rhs(double t, const double *y, double *f, void *d)
{
    const double mu = *(const double *)d, mp1 = 1.0 - mu;
    (void)t;
    double u = y[0] + mu, w = y[0] - mp1, y2 = y[1] * y[1];
    double r1 = u * u + y2, r2 = w * w + y2;
    double d1 = r1 * sqrt(r1), d2 = r2 * sqrt(r2);
    f[0] = y[2];
    f[1] = y[3];
    f[2] = y[0] + 2.0 * y[3] - mp1 * u / d1 - mu * w / d2;
    f[3] = y[1] - 2.0 * y[2] - mp1 * y[1] / d1 - mu * y[1] / d2;
    return MP_OK;
}

static int r3b_jac(double t, const double *y, double *J, void *d)
{
    const double mu = *(const double *)d, mp1 = 1.0 - mu;
    (void)t;
    double u = y[0] + mu, w = y[0] - mp1, yy = y[1];
    double r1s = u * u + yy * yy, r2s = w * w + yy * yy;
    double r1 = sqrt(r1s), r2 = sqrt(r2s);
    double i3a = 1.0 / (r1s * r1), i5a = i3a / r1s, i3b = 1.0 / (r2s * r2), i5b = i3b / r2s;
    for (int i = 0; i < 16; i++) J[i] = 0.0;
    J[0 * 4 + 2] = 1.0;
    J[1 * 4 + 3] = 1.0;
    J[2 * 4 + 0] = 1.0 - mp1 * (i3a - 3.0 * u * u * i5a) - mu * (i3b - 3.0 * w * w * i5b);
    J[2 * 4 + 1] = 3.0 * (mp1 * u * yy * i5a + mu * w * yy * i5b);
    J[2 * 4 + 3] = 2.0;
    J[3 * 4 + 0] = J[2 * 4 + 1];
    J[3 * 4 + 1] = 1.0 - mp1 * (i3a - 3.0 * yy * yy * i5a) - mu * (i3b - 3.0 * yy * yy * i5b);
    J[3 * 4 + 2] = -2.0;
    return MP_OK;
}

static void r3b_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set(prob, 4, r3b_rhs, r3b_jac, p, 0); /* Coriolis terms depend on the velocity */
}

/* the Jacobi integral in energy form: |v|^2/2 - (x^2 + y^2)/2 - mu'/r1 - mu/r2 */
static double r3b_energy(const double *p, const double *y)
{
    double mu = p[0], mp1 = 1.0 - mu;
    double r1 = hypot(y[0] + mu, y[1]), r2 = hypot(y[0] - mp1, y[1]);
    return 0.5 * (y[2] * y[2] + y[3] * y[3]) - 0.5 * (y[0] * y[0] + y[1] * y[1]) - mp1 / r1 -
           mu / r2;
}

MP_LANE_FN static void r3b_lanes_rhs(const double *t, const double *y, double *f,
                                     const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        double mu = p[l], mp1 = 1.0 - mu, x = y[l], yy = y[W + l];
        double u = x + mu, w = x - mp1, y2 = yy * yy;
        double r1 = u * u + y2, r2 = w * w + y2;
        double d1 = r1 * sqrt(r1), d2 = r2 * sqrt(r2);
        f[l] = y[2 * W + l];
        f[W + l] = y[3 * W + l];
        f[2 * W + l] = x + 2.0 * y[3 * W + l] - mp1 * u / d1 - mu * w / d2;
        f[3 * W + l] = yy - 2.0 * y[2 * W + l] - mp1 * yy / d1 - mu * yy / d2;
        st[l] = MP_OK;
    }
}
MP_MODEL_ONE_LANE_RHS(r3b_lanes, r3b_lanes_rhs)

static const char *const r3b_field[] = {
    "y2",
    "y3",
    "y0 + 2*y3 - (1 - mu)*(y0 + mu)/((y0 + mu)**2 + y1**2)**(3/2) - mu*(y0 - 1 + mu)/((y0 - 1 + mu)**2 + y1**2)**(3/2)",
    "y1 - 2*y2 - (1 - mu)*y1/((y0 + mu)**2 + y1**2)**(3/2) - mu*y1/((y0 - 1 + mu)**2 + y1**2)**(3/2)"
};

const mp_model mp_model_r3b = {
    .name = "RestrictedThreeBody", .dim = 4, .nparams = 1, .params = r3b_params,
    .bind = r3b_bind, .energy = r3b_energy, .lanes = r3b_lanes,
    .field = r3b_field,
    .states = MP_NAMES("x", "y", "vx", "vy"), .coordinates = MP_NAMES("x", "y"),
    .speeds = MP_NAMES("vx", "vy"),
};
