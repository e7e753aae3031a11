/* Calculus of variations: discretised functionals J[y] = int F(x, y, y') dx
 * with fixed ends, minimised (or made stationary) by Newton's method on the
 * discrete Euler-Lagrange equations, with optional integral constraints
 * through Lagrange multipliers; and the variational integrator built from
 * the same discrete action.
 *
 * Discretisation: nodes x_0 < ... < x_n, values y_0..y_n (ends fixed),
 * J_h = sum_i h_i F(xm_i, (y_i + y_{i+1})/2, (y_{i+1} - y_i)/h_i) with
 * h_i = x_{i+1} - x_i and xm_i the interval midpoint (the midpoint rule,
 * second order).  The Hessian of J_h in the interior values is tridiagonal,
 * so one Newton iteration costs O(n). */
#ifndef MP_VARIATIONAL_H
#define MP_VARIATIONAL_H

#include <stddef.h>

/* A vectorised integrand F(x, y, p), p = y': for the m points fill
 * out[k * m + i], k = 0..5, with F, F_y, F_p, F_yy, F_yp, F_pp.  A point
 * outside the integrand's domain gets NaN (the solver then shortens its
 * step).  Returns a status (MP_ECALLBACK when a user callback failed). */
typedef int (*mp_var_eval_fn)(size_t m, const double *x, const double *y, const double *p,
                              double *out, void *ctx);

typedef struct {
    mp_var_eval_fn eval;
    void *ctx;
} mp_var_integrand;

/* The integrands built into the C core (ctx is a mp_var_builtin). */
enum mp_var_kind {
    MP_VAR_BRACHISTOCHRONE, /* params X, g: unknown u = sqrt(y) of s in [0, 1], x = X s^3:
                               F = sqrt(x'(s)^2 + 4 u^2 u'^2) / (sqrt(2 g) u) */
    MP_VAR_POTENTIAL,       /* params w: F = w y sqrt(1 + y'^2) (a hanging chain) */
    MP_VAR_ARCLENGTH,       /* no params: F = sqrt(1 + y'^2) */
    MP_VAR_PENDULUM,        /* params g, L, b, A, Omega, x = t, y = theta (per unit mass):
                               F = e^{b t} (L^2 p^2 / 2 + g L cos y + L^2 A cos(Omega t) y) */
    MP_VAR_DUFFING,         /* params alpha, beta, delta, gamma, omega:
                               F = e^{delta t} (p^2/2 - alpha y^2/2 - beta y^4/4
                                                + gamma cos(omega t) y) */
    MP_VAR_NKINDS
};

#define MP_VAR_MAXPARAMS 5

typedef struct {
    int kind;
    double params[MP_VAR_MAXPARAMS];
} mp_var_builtin;

/* Look up a built-in integrand by name ("brachistochrone", "potential",
 * "arclength", "pendulum", "duffing"); sets *kind and *nparams.  MP_EDOM if
 * unknown. */
int mp_variational_builtin_find(const char *name, int *kind, size_t *nparams);

/* Fill an integrand that evaluates the built-in b (b must outlive it). */
void mp_variational_builtin_bind(mp_var_builtin *b, mp_var_integrand *out);

typedef struct {
    size_t n;                      /* number of intervals (>= 2) */
    const double *x;               /* n + 1 strictly increasing nodes */
    mp_var_integrand F;            /* the functional */
    size_t ncon;                   /* number of integral constraints */
    const mp_var_integrand *G;     /* ncon constraint integrands: int G_k = value_k */
    const double *value;           /* ncon constraint values */
    int stationary;                /* 0: minimise J (descent, shifted Newton);
                                      1: any stationary point (Newton on the residual) */
    double tol;                    /* relative step tolerance */
    size_t max_iter;               /* Newton iteration budget */
} mp_var_problem;

typedef struct {
    size_t iterations;
    double J;                      /* J_h at the solution */
    double residual;               /* max |dJ_h/dy_j + sum lambda_k dG_k/dy_j| */
    double constraint_error;       /* max |G_k - value_k| */
} mp_var_info;

/* Solve the problem.  y (n + 1) holds the initial guess with the fixed end
 * values and receives the solution; lambda (ncon) holds the initial
 * multipliers and receives them (the stationarity condition is
 * grad J + sum lambda_k grad G_k = 0).  MP_EDOM for a bad problem
 * (n < 2, nodes not increasing, non-finite guess), MP_ENOCONV when the
 * budget runs out or no step decreases the merit function, MP_ESINGULAR
 * for a singular Newton matrix, MP_ENOMEM. */
int mp_variational_solve(const mp_var_problem *pb, double *y, double *lambda, mp_var_info *info);

/* The variational integrator of the discrete Lagrangian
 * L_d(q0, q1) = h F(t + h/2, (q0 + q1)/2, (q1 - q0)/h) in position-momentum
 * form: p_k = -D1 L_d(q_k, q_{k+1}) solved for q_{k+1} by Newton, then
 * p_{k+1} = D2 L_d(q_k, q_{k+1}).  The map (q_k, p_k) -> (q_{k+1}, p_{k+1})
 * is symplectic.  q and p receive nsteps + 1 values each (q[0] = q0,
 * p[0] = p0).  MP_ENOCONV if a step's Newton iteration fails; interrupt
 * (may be NULL) is asked every 4096 steps, and its status ends the run. */
int mp_variational_integrate(const mp_var_integrand *L, double t0, double h, size_t nsteps,
                             double q0, double p0, double *q, double *p,
                             int (*interrupt)(void *), void *interrupt_ctx);

#endif
