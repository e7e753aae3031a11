/* A rocket flying straight up (Marion & Thornton, section 9.11): exhaust
 * speed u relative to the rocket, propellant burnt at the constant rate b
 * while the mass exceeds the dry mass, gravity g and quadratic drag k:
 *
 *   h' = v,   v' = T/m - g - (k/m) v|v|,   m' = -b,   T = u b   while m > m_dry,
 *   h' = v,   v' = -g - (k/m) v|v|,          m' = 0             after burn-out.
 *
 * State (height, speed, mass) in m, m/s, kg; parameters exhaust_speed u
 * (m/s), burn_rate b (kg/s), m0 (kg, the launch mass: the Python face's
 * initial state), m_dry (kg, 0 < m_dry <= m0), g (m/s^2), drag k (kg/m).
 * Burn-out is a switch the engine crosses (ode.h's mp_ode_switch): the
 * burning branch runs until the mass reaches m_dry, located as an event, where
 * the mass is set to m_dry exactly and the coasting branch takes over, so no
 * step straddles the kink in time at (m0 - m_dry)/b.  A state is on the
 * branch of its mass (mp_ode_problem_at: what the scene's rhs evaluates). */
#include "models/models.h"

#include <math.h>

#include <stdio.h>

enum { RU, RB, RM0, RMD, RG, RK, RN };
static const mp_model_param rocket_params[] = {
    MP_PARAM_NONNEGATIVE("exhaust_speed", MP_REQUIRED), MP_PARAM_NONNEGATIVE("burn_rate", MP_REQUIRED),
    MP_PARAM_POSITIVE("m0", MP_REQUIRED),               MP_PARAM_POSITIVE("m_dry", MP_REQUIRED),
    MP_PARAM_NONNEGATIVE("g", 0.0),                     MP_PARAM_NONNEGATIVE("drag", 0.0),
};

/* What the bounds cannot say: the dry mass does not exceed the launch mass. */
static int rocket_check(const double *p, char *why, size_t len)
{
    if (p[RMD] <= p[RM0]) return MP_OK;
    if (why)
        snprintf(why, len, "m_dry must not exceed m0 (the launch mass), got m_dry=%g > m0=%g",
                 p[RMD], p[RM0]);
    return MP_EDOM;
}

/* The branches the engine integrates: burning (thrust on for every mass > 0,
 * so that a step's stages past burn-out see the same smooth field) and
 * coasting.  A trial stage of a long step can reach a mass <= 0 (the mass
 * falls linearly, so nothing in the error estimate holds the step back): the
 * field is not defined there, and NaN makes the driver reject the step and
 * shrink it (its non-finite stage rule) rather than end the solve. */
static int rocket_branch(const double *p, const double *y, double *f, double thrust,
                         double dm)
{
    if (!(y[2] > 0)) {
        f[0] = f[1] = f[2] = NAN;
        return MP_OK;
    }
    f[0] = y[1];
    f[1] = (thrust - p[RK] * y[1] * fabs(y[1])) / y[2] - p[RG];
    f[2] = dm;
    return MP_OK;
}

static int rocket_rhs_burn(double t, const double *y, double *f, void *d)
{
    const double *p = d;
    (void)t;
    return rocket_branch(p, y, f, p[RU] * p[RB], -p[RB]);
}

static int rocket_rhs_coast(double t, const double *y, double *f, void *d)
{
    (void)t;
    return rocket_branch(d, y, f, 0.0, 0.0);
}

/* df/dy of a branch with the given thrust */
static int rocket_jac_branch(const double *p, const double *y, double *J, double thrust)
{
    const double m = y[2];
    if (!(m > 0)) return MP_EDOM;
    for (int i = 0; i < 9; i++) J[i] = 0.0;
    J[0 * 3 + 1] = 1.0;
    J[1 * 3 + 1] = -2.0 * p[RK] * fabs(y[1]) / m;
    J[1 * 3 + 2] = -(thrust - p[RK] * y[1] * fabs(y[1])) / (m * m);
    return MP_OK;
}

static int rocket_jac_burn(double t, const double *y, double *J, void *d)
{
    const double *p = d;
    (void)t;
    return rocket_jac_branch(p, y, J, p[RU] * p[RB]);
}

static int rocket_jac_coast(double t, const double *y, double *J, void *d)
{
    (void)t;
    return rocket_jac_branch(d, y, J, 0.0);
}

/* burn-out: the propellant above the dry mass reaches 0; the mass is then
 * exactly the dry mass */
static double rocket_fuel(double t, const double *y, const void *d)
{
    const double *p = d;
    (void)t;
    return y[2] - p[RMD];
}

static void rocket_burnout(double t, double *y, const void *d)
{
    const double *p = d;
    (void)t;
    y[2] = p[RMD];
}

static const mp_ode_switch rocket_switch = {
    .g = rocket_fuel, .act = rocket_burnout, .rhs = rocket_rhs_coast, .jac = rocket_jac_coast,
};

/* Bind the burning branch with burn-out ahead (the engine takes the coasting
 * branch at once for a state already at the dry mass); not separable: the
 * mass is not a position. */
static void rocket_bind(const double *p, mp_ode_problem *prob)
{
    mp_model_set(prob, 3, rocket_rhs_burn, rocket_jac_burn, p, 0);
    prob->sw = &rocket_switch;
}

/* the vehicle's mechanical energy m v^2/2 + m g h (J): not conserved (the
 * thrust does work, the exhaust carries energy away, drag dissipates). */
static double rocket_energy(const double *p, const double *y)
{
    return y[2] * (0.5 * y[1] * y[1] + p[RG] * y[0]);
}

static const char *const rocket_field[] = {
    "y1",
    "(Piecewise((exhaust_speed*burn_rate, y2 > m_dry), (0, True)) - drag*y1*Abs(y1))/y2 - g",
    "Piecewise((-burn_rate, y2 > m_dry), (0, True))"
};

const mp_model mp_model_rocket = {
    .name = "Rocket", .dim = 3, .nparams = RN, .params = rocket_params, .check = rocket_check,
    .bind = rocket_bind, .energy = rocket_energy,
    .field = rocket_field,
    .states = MP_NAMES("height", "speed", "mass"), .coordinates = MP_NAMES("height"),
    .speeds = MP_NAMES("speed"),
};
