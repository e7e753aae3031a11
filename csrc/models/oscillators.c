/* One-degree-of-freedom oscillators: the pendulum, Van der Pol, Duffing.
 * State (x, x_dot); each binds the cheapest right-hand side for its
 * parameters (no damping or drive terms computed when they are zero). */
#include "models/models.h"

#include <math.h>

/* ---- Pendulum: theta'' = -(g/L) sin(theta) - b theta' + A cos(w t) ---------- */
enum { PG, PL, PB, PA, PW };
static const char *const pendulum_names[] = {"g", "length", "damping", "drive_amplitude",
                                             "drive_frequency"};

static int pendulum_check(const double *p)
{
    for (int i = 0; i < 5; i++)
        if (!isfinite(p[i])) return MP_EDOM;
    return (p[PG] > 0 && p[PL] > 0 && p[PB] >= 0 && p[PW] >= 0) ? MP_OK : MP_EDOM;
}

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

static void pendulum_bind(const double *p, mp_ode_problem *prob)
{
    prob->n = 2;
    prob->rhs = p[PA] != 0.0 ? pendulum_driven : p[PB] != 0.0 ? pendulum_damped : pendulum_free;
    prob->jac = pendulum_jac;
    prob->data = (void *)p;
    prob->nq = p[PB] == 0.0 ? 1 : 0; /* separable unless damped */
}

/* energy per unit mass: L^2 theta'^2 / 2 + g L (1 - cos theta)  [J/kg] */
static double pendulum_energy(const double *p, const double *y)
{
    double L = p[PL];
    return 0.5 * L * L * y[1] * y[1] + p[PG] * L * 2.0 * pow(sin(0.5 * y[0]), 2);
}

const mp_model mp_model_pendulum = {"Pendulum", 2, 5, pendulum_names, pendulum_check,
                                    pendulum_bind, pendulum_energy};

/* ---- Van der Pol: x'' - mu (1 - x^2) x' + x = 0 ------------------------------ */
static const char *const vdp_names[] = {"mu"};

static int vdp_check(const double *p) { return isfinite(p[0]) && p[0] >= 0 ? MP_OK : MP_EDOM; }

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

static void vdp_bind(const double *p, mp_ode_problem *prob)
{
    prob->n = 2;
    prob->rhs = vdp_rhs;
    prob->jac = vdp_jac;
    prob->data = (void *)p;
    prob->nq = 0; /* the friction term depends on x' */
}

/* the harmonic part's energy (x^2 + x'^2) / 2 */
static double vdp_energy(const double *p, const double *y)
{
    (void)p;
    return 0.5 * (y[0] * y[0] + y[1] * y[1]);
}

const mp_model mp_model_vanderpol = {"VanDerPol", 2, 1, vdp_names, vdp_check, vdp_bind,
                                     vdp_energy};

/* ---- Duffing: x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t) ------- */
enum { DA, DB, DD, DG, DW };
static const char *const duffing_names[] = {"alpha", "beta", "delta", "gamma", "omega"};

static int duffing_check(const double *p)
{
    for (int i = 0; i < 5; i++)
        if (!isfinite(p[i])) return MP_EDOM;
    return p[DD] >= 0 ? MP_OK : MP_EDOM;
}

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

static void duffing_bind(const double *p, mp_ode_problem *prob)
{
    prob->n = 2;
    prob->rhs = p[DG] != 0.0 ? duffing_driven : duffing_free;
    prob->jac = duffing_jac;
    prob->data = (void *)p;
    prob->nq = p[DD] == 0.0 ? 1 : 0;
}

/* x'^2/2 + alpha x^2/2 + beta x^4/4 */
static double duffing_energy(const double *p, const double *y)
{
    double x2 = y[0] * y[0];
    return 0.5 * y[1] * y[1] + 0.5 * p[DA] * x2 + 0.25 * p[DB] * x2 * x2;
}

const mp_model mp_model_duffing = {"Duffing", 2, 5, duffing_names, duffing_check, duffing_bind,
                                   duffing_energy};
