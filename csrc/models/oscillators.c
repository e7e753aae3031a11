/* One-degree-of-freedom oscillators: the pendulum, Van der Pol, Duffing.
 * State (x, x_dot); each binds the cheapest right-hand side for its
 * parameters (no damping or drive terms computed when they are zero). */
#include "models/models.h"

#include <math.h>

/* ---- Pendulum: theta'' = -(g/L) sin(theta) - b theta' + A cos(w t) ---------- */
enum { PG, PL, PB, PA, PW };
static const mp_model_param pendulum_params[] = {
    MP_PARAM_POSITIVE("g", 9.81),           MP_PARAM_POSITIVE("length", 1.0),
    MP_PARAM_NONNEGATIVE("damping", 0.0),   MP_PARAM("drive_amplitude", 0.0),
    MP_PARAM_NONNEGATIVE("drive_frequency", 0.0),
};

static int pendulum_free(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    (void)t;
    f[0] = y[1];
    f[1] = -(p[PG] / p[PL]) * sin(y[0]);
    return MP_OK;
}

static int pendulum_damped(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    (void)t;
    f[0] = y[1];
    f[1] = -(p[PG] / p[PL]) * sin(y[0]) - p[PB] * y[1];
    return MP_OK;
}

static int pendulum_driven(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    f[0] = y[1];
    f[1] = -(p[PG] / p[PL]) * sin(y[0]) - p[PB] * y[1] + p[PA] * cos(p[PW] * t);
    return MP_OK;
}

static int pendulum_jac(double t, const double *y, double *J, void *d)
{
    const double *p = d;
    (void)t;
    J[0] = 0.0;
    J[1] = 1.0;
    J[2] = -(p[PG] / p[PL]) * cos(y[0]);
    J[3] = -p[PB];
    return MP_OK;
}

/* the fixed-step blocks of each (the driven one is separable when undamped) */
MP_ODE_BLOCKS(pendulum_free_blocks, pendulum_free, 2, 1);
MP_ODE_BLOCKS(pendulum_damped_blocks, pendulum_damped, 2, 0);
MP_ODE_BLOCKS(pendulum_driven_blocks, pendulum_driven, 2, 1);

static void pendulum_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set_blocks(prob, 2,
                        p[PA] != 0.0   ? &pendulum_driven_blocks
                        : p[PB] != 0.0 ? &pendulum_damped_blocks
                                       : &pendulum_free_blocks,
                        pendulum_jac, p, p[PB] == 0.0 ? 1 : 0); /* separable unless damped */
}

/* energy per unit mass: L^2 theta'^2 / 2 + g L (1 - cos theta)  [J/kg] */
static double pendulum_energy(const double *p, const double *y)
{
    double L = p[PL];
    return 0.5 * L * L * y[1] * y[1] + p[PG] * L * 2.0 * pow(sin(0.5 * y[0]), 2);
}

/* Per unit mass, with the Caldirola-Kanai factor that makes the damped
 * equation an Euler-Lagrange one (x = t, y = theta, p = theta'):
 * L = e^{b t} (L^2 p^2 / 2 + g L cos y + L^2 A cos(Omega t) y)  [J/kg] */
static int pendulum_lagrangian(size_t m, const double *x, const double *y, const double *v,
                               double *out, void *ctx)
{
    const double *k = ctx;
    for (size_t i = 0; i < m; i++) {
        double g = k[PG], L = k[PL], e = exp(k[PB] * x[i]);
        double drive = L * L * k[PA] * cos(k[PW] * x[i]), yi = y[i], vi = v[i];
        mp_var_put1(out + 6 * i, e * (0.5 * L * L * vi * vi + g * L * cos(yi) + drive * yi),
                    e * (-g * L * sin(yi) + drive), e * L * L * vi, -e * g * L * cos(yi), 0.0,
                    e * L * L);
    }
    return MP_OK;
}

/* Lanes (ode/lanes.h): the three right-hand sides above, MP_LANES states at
 * once, with each lane's parameters (y, f, p in SoA layout). */
#define W MP_LANES
MP_LANE_FN static void pendulum_lanes_free(const double *t, const double *y, double *f,
                                           const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        f[l] = y[W + l];
        f[W + l] = -(p[PG * W + l] / p[PL * W + l]) * mp_lane_sin(y[l]);
        st[l] = MP_OK;
    }
}

MP_LANE_FN static void pendulum_lanes_damped(const double *t, const double *y, double *f,
                                             const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        f[l] = y[W + l];
        f[W + l] = -(p[PG * W + l] / p[PL * W + l]) * mp_lane_sin(y[l]) - p[PB * W + l] * y[W + l];
        st[l] = MP_OK;
    }
}

MP_LANE_FN static void pendulum_lanes_driven(const double *t, const double *y, double *f,
                                             const double *p, int *st)
{
    MP_LANE_LOOP {
        f[l] = y[W + l];
        f[W + l] = -(p[PG * W + l] / p[PL * W + l]) * mp_lane_sin(y[l]) - p[PB * W + l] * y[W + l] +
                   p[PA * W + l] * mp_lane_cos(p[PW * W + l] * t[l]);
        st[l] = MP_OK;
    }
}

static mp_lane_rhs pendulum_lanes(const double *p, size_t k, size_t stride)
{
    return mp_model_any_nonzero(p, k, stride, PA)   ? pendulum_lanes_driven
           : mp_model_any_nonzero(p, k, stride, PB) ? pendulum_lanes_damped
                                           : pendulum_lanes_free;
}

static const char *const pendulum_field[] = {
    "y1",
    "-(g/length)*sin(y0) - damping*y1 + drive_amplitude*cos(drive_frequency*t)"
};

const mp_model mp_model_pendulum = {
    .name = "Pendulum", .dim = 2, .nparams = 5, .params = pendulum_params,
    .separable = "damping = 0", .bind = pendulum_bind, .energy = pendulum_energy,
    .lagrangian = pendulum_lagrangian, .lanes = pendulum_lanes,
    .field = pendulum_field,
    .states = MP_NAMES("theta", "theta'"), .coordinates = MP_NAMES("theta"),
    .speeds = MP_NAMES("theta'"), .drawing = "pendulum",
};

/* ---- Van der Pol: x'' - mu (1 - x^2) x' + x = 0 ------------------------------ */
static const mp_model_param vdp_params[] = {MP_PARAM_NONNEGATIVE("mu", 1.0)};

static int vdp_rhs(double t, const double *y, double *f, void *d)
{
    const double mu = *(const double *)d;
    (void)t;
    f[0] = y[1];
    f[1] = mu * (1.0 - y[0] * y[0]) * y[1] - y[0];
    return MP_OK;
}

static int vdp_jac(double t, const double *y, double *J, void *d)
{
    const double mu = *(const double *)d;
    (void)t;
    J[0] = 0.0;
    J[1] = 1.0;
    J[2] = -2.0 * mu * y[0] * y[1] - 1.0;
    J[3] = mu * (1.0 - y[0] * y[0]);
    return MP_OK;
}

MP_ODE_BLOCKS(vdp_blocks, vdp_rhs, 2, 0);

static void vdp_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set_blocks(prob, 2, &vdp_blocks, vdp_jac, p, 0); /* friction depends on x' */
}

/* the harmonic part's energy (x^2 + x'^2) / 2 */
static double vdp_energy(const double *p, const double *y)
{
    (void)p;
    return 0.5 * (y[0] * y[0] + y[1] * y[1]);
}

MP_LANE_FN static void vdp_lanes_rhs(const double *t, const double *y, double *f,
                                     const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        f[l] = y[W + l];
        f[W + l] = p[l] * (1.0 - y[l] * y[l]) * y[W + l] - y[l];
        st[l] = MP_OK;
    }
}

MP_MODEL_ONE_LANE_RHS(vdp_lanes, vdp_lanes_rhs)

static const char *const vdp_field[] = {
    "y1",
    "mu*(1 - y0**2)*y1 - y0"
};

const mp_model mp_model_vanderpol = {
    .name = "VanDerPol", .dim = 2, .nparams = 1, .params = vdp_params, .bind = vdp_bind,
    .energy = vdp_energy, .lanes = vdp_lanes,
    .field = vdp_field,
    .states = MP_NAMES("x", "x'"), .coordinates = MP_NAMES("x"), .speeds = MP_NAMES("x'"),
};

/* ---- Duffing: x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t) ------- */
enum { DA, DB, DD, DG, DW };
static const mp_model_param duffing_params[] = {
    MP_PARAM("alpha", MP_REQUIRED), MP_PARAM("beta", MP_REQUIRED),
    MP_PARAM_NONNEGATIVE("delta", 0.0), MP_PARAM("gamma", 0.0), MP_PARAM("omega", 1.0),
};

static int duffing_free(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    (void)t;
    f[0] = y[1];
    f[1] = -p[DA] * y[0] - p[DB] * y[0] * y[0] * y[0] - p[DD] * y[1];
    return MP_OK;
}

static int duffing_driven(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    f[0] = y[1];
    f[1] = -p[DA] * y[0] - p[DB] * y[0] * y[0] * y[0] - p[DD] * y[1] + p[DG] * cos(p[DW] * t);
    return MP_OK;
}

static int duffing_jac(double t, const double *y, double *J, void *d)
{
    const double *p = d;
    (void)t;
    J[0] = 0.0;
    J[1] = 1.0;
    J[2] = -p[DA] - 3.0 * p[DB] * y[0] * y[0];
    J[3] = -p[DD];
    return MP_OK;
}

/* separable when undamped (delta = 0) */
MP_ODE_BLOCKS(duffing_free_blocks, duffing_free, 2, 1);
MP_ODE_BLOCKS(duffing_driven_blocks, duffing_driven, 2, 1);

static void duffing_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set_blocks(prob, 2, p[DG] != 0.0 ? &duffing_driven_blocks : &duffing_free_blocks,
                        duffing_jac, p, p[DD] == 0.0 ? 1 : 0);
}

/* x'^2/2 + alpha x^2/2 + beta x^4/4 */
static double duffing_energy(const double *p, const double *y)
{
    double x2 = y[0] * y[0];
    return 0.5 * y[1] * y[1] + 0.5 * p[DA] * x2 + 0.25 * p[DB] * x2 * x2;
}

/* L = e^{delta t} (p^2/2 - alpha y^2/2 - beta y^4/4 + gamma cos(omega t) y) */
static int duffing_lagrangian(size_t m, const double *x, const double *y, const double *v,
                              double *out, void *ctx)
{
    const double *k = ctx;
    for (size_t i = 0; i < m; i++) {
        double e = exp(k[DD] * x[i]), drive = k[DG] * cos(k[DW] * x[i]);
        double yi = y[i], vi = v[i], y2 = yi * yi;
        mp_var_put1(out + 6 * i,
                    e * (0.5 * vi * vi - 0.5 * k[DA] * y2 - 0.25 * k[DB] * y2 * y2 + drive * yi),
                    e * (-k[DA] * yi - k[DB] * y2 * yi + drive), e * vi,
                    e * (-k[DA] - 3.0 * k[DB] * y2), 0.0, e);
    }
    return MP_OK;
}

MP_LANE_FN static void duffing_lanes_free(const double *t, const double *y, double *f,
                                          const double *p, int *st)
{
    (void)t;
    MP_LANE_LOOP {
        double x = y[l];
        f[l] = y[W + l];
        f[W + l] = -p[DA * W + l] * x - p[DB * W + l] * x * x * x - p[DD * W + l] * y[W + l];
        st[l] = MP_OK;
    }
}

MP_LANE_FN static void duffing_lanes_driven(const double *t, const double *y, double *f,
                                            const double *p, int *st)
{
    MP_LANE_LOOP {
        double x = y[l];
        f[l] = y[W + l];
        f[W + l] = -p[DA * W + l] * x - p[DB * W + l] * x * x * x - p[DD * W + l] * y[W + l] +
                   p[DG * W + l] * mp_lane_cos(p[DW * W + l] * t[l]);
        st[l] = MP_OK;
    }
}

static mp_lane_rhs duffing_lanes(const double *p, size_t k, size_t stride)
{
    return mp_model_any_nonzero(p, k, stride, DG) ? duffing_lanes_driven : duffing_lanes_free;
}

static const char *const duffing_field[] = {
    "y1",
    "-alpha*y0 - beta*y0**3 - delta*y1 + gamma*cos(omega*t)"
};

const mp_model mp_model_duffing = {
    .name = "Duffing", .dim = 2, .nparams = 5, .params = duffing_params,
    .separable = "delta = 0", .bind = duffing_bind, .energy = duffing_energy,
    .lagrangian = duffing_lagrangian, .lanes = duffing_lanes,
    .field = duffing_field,
    .states = MP_NAMES("x", "x'"), .coordinates = MP_NAMES("x"), .speeds = MP_NAMES("x'"),
};
