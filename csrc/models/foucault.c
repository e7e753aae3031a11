/* The Foucault pendulum on the rotating Earth, small swings, in the local
 * horizontal plane (Marion & Thornton, Example 10.5): x east, y north,
 *
 *   x'' = -(g/L) x + 2 Omega_z y',   y'' = -(g/L) y - 2 Omega_z x',
 *
 * with Omega_z = omega sin(latitude).  State (x, y, vx, vy) in m and m/s;
 * parameters latitude (degrees, in [-90, 90]), length L (m), g (m/s^2),
 * omega (rad/s). */
#include "models/models.h"

#include <math.h>

enum { FLAT, FLEN, FG, FOM, FN };
static const mp_model_param foucault_params[] = {
    MP_PARAM_RANGE("latitude", MP_REQUIRED, -90.0, 90.0), MP_PARAM_POSITIVE("length", MP_REQUIRED),
    MP_PARAM_POSITIVE("g", 9.81), MP_PARAM("omega", 7.2921159e-5),
};

/* the vertical component of the Earth's rotation [rad/s] */
static double foucault_omega_z(const double *p)
{
    return p[FOM] * sin(p[FLAT] * (3.14159265358979323846 / 180.0));
}

static int foucault_rhs(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    const double w2 = p[FG] / p[FLEN], oz = foucault_omega_z(p);
    (void)t;
    f[0] = y[2];
    f[1] = y[3];
    f[2] = -w2 * y[0] + 2.0 * oz * y[3];
    f[3] = -w2 * y[1] - 2.0 * oz * y[2];
    return MP_OK;
}

static int foucault_jac(double t, const double *y, double *J, void *d)
{
    const double *p = d;
    const double w2 = p[FG] / p[FLEN], oz = foucault_omega_z(p);
    (void)t;
    (void)y;
    for (int i = 0; i < 16; i++) J[i] = 0.0;
    J[0 * 4 + 2] = 1.0;
    J[1 * 4 + 3] = 1.0;
    J[2 * 4 + 0] = -w2;
    J[2 * 4 + 3] = 2.0 * oz;
    J[3 * 4 + 1] = -w2;
    J[3 * 4 + 2] = -2.0 * oz;
    return MP_OK;
}

static void foucault_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set(prob, 4, foucault_rhs, foucault_jac, p, 0); /* Coriolis depends on velocity */
}

/* per unit mass: (vx^2 + vy^2)/2 + (g/L)(x^2 + y^2)/2 [J/kg]; the Coriolis
 * force does no work, so this is conserved. */
static double foucault_energy(const double *p, const double *y)
{
    return 0.5 * (y[2] * y[2] + y[3] * y[3]) + 0.5 * (p[FG] / p[FLEN]) * (y[0] * y[0] + y[1] * y[1]);
}

/* Lanes (ode/lanes.h): foucault_rhs for MP_LANES states at once (SoA). */
#define W MP_LANES
MP_LANE_FN static void foucault_lanes_rhs(const double *t, const double *y, double *f,
                                          const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        double w2 = p[FG * W + l] / p[FLEN * W + l];
        double oz = p[FOM * W + l] * mp_lane_sin(p[FLAT * W + l] * (3.14159265358979323846 / 180.0));
        f[l] = y[2 * W + l];
        f[W + l] = y[3 * W + l];
        f[2 * W + l] = -w2 * y[l] + 2.0 * oz * y[3 * W + l];
        f[3 * W + l] = -w2 * y[W + l] - 2.0 * oz * y[2 * W + l];
        st[l] = MP_OK;
    }
}
MP_MODEL_ONE_LANE_RHS(foucault_lanes, foucault_lanes_rhs)

static const char *const foucault_field[] = {
    "y2",
    "y3",
    "-(g/length)*y0 + 2*omega*sin(latitude*pi/180)*y3",
    "-(g/length)*y1 - 2*omega*sin(latitude*pi/180)*y2"
};

const mp_model mp_model_foucault = {
    .name = "Foucault", .dim = 4, .nparams = FN, .params = foucault_params,
    .bind = foucault_bind, .energy = foucault_energy,
    .lanes = foucault_lanes,
    .field = foucault_field,
    .states = MP_NAMES("x", "y", "vx", "vy"), .coordinates = MP_NAMES("x", "y"),
    .speeds = MP_NAMES("vx", "vy"), .drawing = "foucault",
};
