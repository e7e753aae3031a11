/* Calculus of variations with d unknown functions: discretised functionals
 * J[y] = int F(x, y, y') dx with fixed ends (y and y' in R^d), minimised (or
 * made stationary) by Newton's method on the discrete Euler-Lagrange
 * equations, with optional integral constraints through Lagrange
 * multipliers; the variational integrator built from the same discrete
 * action; the discrete Legendre transform back to velocities.
 *
 * Discretisation: nodes x_0 < ... < x_n, values y_0..y_n in R^d (ends
 * fixed), J_h = sum_i h_i F(xm_i, (y_i + y_{i+1})/2, (y_{i+1} - y_i)/h_i)
 * with h_i = x_{i+1} - x_i and xm_i the interval midpoint (the midpoint
 * rule, second order).  The Hessian of J_h in the interior values is
 * block-tridiagonal with d x d blocks, a band matrix of half-bandwidth
 * 2d - 1, so one Newton iteration costs O(n d^3) (banded LU with partial
 * pivoting, or banded Cholesky when minimising).
 *
 * Array layout: point-major.  A path y is (n + 1) x d row-major; an
 * evaluation of F at m points is m x K row-major with K = 1 + 2d + 3d^2. */
#ifndef MP_VARIATIONAL_H
#define MP_VARIATIONAL_H

#include <stddef.h>

/* The Lagrangian (integrand) and its derivatives at m points, d coordinates:
 * K = 1 + 2d + 3d^2 values per point, out[i*K + k]: F, F_y (d), F_p (d),
 * F_yy (d x d row-major), F_yp ([a][b] = d2F/dy_a dp_b), F_pp (d x d).
 * x: m values; y, p: m x d row-major.  Returns MP_OK, MP_EDOM for a point
 * outside the domain (treated like NaN: the solvers shorten their step) or
 * another status (MP_ECALLBACK when a Python callback raised).  This is the
 * signature of the generated mp_gen_lagrangian(m, t, q, qd, out, params). */
typedef int (*mp_var_eval_fn)(size_t m, const double *x, const double *y, const double *p,
                              double *out, void *ctx);

typedef struct {
    mp_var_eval_fn eval;
    void *ctx;
    size_t d; /* number of unknown functions (coordinates), >= 1 */
} mp_var_integrand;

/* Values per point of an evaluation with d coordinates. */
static inline size_t mp_var_nvalues(size_t d) { return 1 + 2 * d + 3 * d * d; }

/* Store the six values of a one-coordinate integrand at o[0..5]:
 * F, F_y, F_p, F_yy, F_yp, F_pp. */
static inline void mp_var_put1(double *o, double F, double Fy, double Fp, double Fyy, double Fyp,
                               double Fpp)
{
    o[0] = F;
    o[1] = Fy;
    o[2] = Fp;
    o[3] = Fyy;
    o[4] = Fyp;
    o[5] = Fpp;
}

/* The functionals built into the C core (ctx is a mp_var_builtin).  The
 * Lagrangians of the scenes are in their rows (models/models.h). */
enum mp_var_kind {
    MP_VAR_BRACHISTOCHRONE, /* d = 1, params X, g: unknown u = sqrt(y) of s in [0, 1],
                               x = X s^3: F = sqrt(x'(s)^2 + 4 u^2 u'^2) / (sqrt(2 g) u) */
    MP_VAR_POTENTIAL,       /* d = 1, params w: F = w y sqrt(1 + y'^2) (a hanging chain) */
    MP_VAR_ARCLENGTH,       /* d = 1, no params: F = sqrt(1 + y'^2) */
    MP_VAR_NKINDS
};

#define MP_VAR_MAXPARAMS 2

typedef struct {
    int kind;
    double params[MP_VAR_MAXPARAMS];
} mp_var_builtin;

/* Look up a built-in integrand by name ("brachistochrone", "potential",
 * "arclength"); sets *kind, *nparams and *d.  MP_EDOM if unknown. */
int mp_variational_builtin_find(const char *name, int *kind, size_t *nparams, size_t *d);

/* Fill an integrand that evaluates the built-in b (b must outlive it). */
void mp_variational_builtin_bind(mp_var_builtin *b, mp_var_integrand *out);

typedef struct {
    size_t n;                      /* number of intervals (>= 2) */
    const double *x;               /* n + 1 strictly increasing nodes */
    mp_var_integrand F;            /* the functional (F.d unknown functions) */
    size_t ncon;                   /* number of integral constraints */
    const mp_var_integrand *G;     /* ncon constraint integrands (same d): int G_k = value_k */
    const double *value;           /* ncon constraint values */
    int stationary;                /* 0: minimise J (descent, shifted Newton);
                                      1: any stationary point (Newton on the residual) */
    double tol;                    /* relative step tolerance */
    size_t max_iter;               /* Newton iteration budget */
    int (*interrupt)(void *);      /* asked before each Newton iteration and each line-search
                                      trial, i.e. every O(n) assembly (may be NULL); its
                                      status ends the solve */
    void *interrupt_ctx;
} mp_var_problem;

typedef struct {
    size_t iterations;
    double J;                      /* J_h at the solution */
    double residual;               /* max |dJ_h/dy_j + sum lambda_k dG_k/dy_j| */
    double constraint_error;       /* max |G_k - value_k| */
    size_t negative;               /* minimise mode: negative eigenvalues of the Hessian of J_h
                                      at the stationary point found (0 for a minimum) */
} mp_var_info;

/* Solve the problem.  y ((n + 1) x d) holds the initial guess with the fixed
 * end values and receives the solution; lambda (ncon) holds the initial
 * multipliers and receives them (the stationarity condition is
 * grad J + sum lambda_k grad G_k = 0).  MP_EDOM for a bad problem (n < 2,
 * d = 0, nodes not increasing, a non-finite or out-of-domain guess),
 * MP_ENOCONV when the budget runs out or no step decreases the merit
 * function, MP_ESINGULAR for a singular Newton matrix, MP_ENOMEM, or the
 * interrupt's status.  Minimise mode (stationary = 0, no constraints) checks
 * the second variation at the stationary point found: MP_ENOTSPD (with
 * info->negative > 0) when the Hessian of J_h has a negative eigenvalue
 * (counted by a band L D L^T; beyond round-off: 1e-8 of the gradient's
 * summands over the largest step between nodes), i.e. the point is a saddle
 * or a maximum, not a minimum (y holds it); a flat direction (a degenerate
 * minimum) passes. */
int mp_variational_solve(const mp_var_problem *pb, double *y, double *lambda, mp_var_info *info);

/* Discrete momenta of a path (x, y) with n intervals: p_0 = -D1 L_d(y_0, y_1),
 * p_k = D2 L_d(y_{k-1}, y_k) (k = 1..n), where L_d is the midpoint discrete
 * Lagrangian of one interval.  p: (n + 1) x d.  MP_ENONFINITE for a point
 * outside the domain. */
int mp_variational_momenta(const mp_var_integrand *L, size_t n, const double *x,
                           const double *y, double *p);

/* The discrete Legendre transform back: solve dL/dp(x_i, y_i, v_i) = p_i for
 * v_i at m points by Newton's method (d x d per point, all points at once).
 * v (m x d) holds the initial guess and receives the velocities; energy (m,
 * may be NULL) receives v . dL/dp - L there.  MP_ESINGULAR when d2L/dp dp
 * is singular at a point (relative pivot below sing_tol), MP_ENOCONV when
 * Newton does not converge in 50 iterations. */
int mp_variational_velocities(const mp_var_integrand *L, size_t m, const double *x,
                              const double *y, const double *p, double *v, double *energy,
                              double sing_tol);

/* The variational integrator of the discrete Lagrangian
 * L_d(q0, q1) = h F(t + h/2, (q0 + q1)/2, (q1 - q0)/h) in position-momentum
 * form: p_k = -D1 L_d(q_k, q_{k+1}) solved for q_{k+1} by Newton's method
 * (a d x d system), then p_{k+1} = D2 L_d(q_k, q_{k+1}).  The map
 * (q_k, p_k) -> (q_{k+1}, p_{k+1}) is symplectic.  q and p ((nsteps + 1) x d)
 * receive the orbit (row 0 = q0, p0); v0 (d) is the initial velocity (the
 * first predictor).  MP_ESINGULAR when d2L/dqdot dqdot is singular (relative
 * pivot below sing_tol, the scale including h d2L/dq dqdot and
 * h^2 d2L/dq dq), MP_ENOCONV if a step's Newton iteration fails;
 * interrupt (may be NULL) is asked every 4096 steps and its status ends the
 * run. */
int mp_variational_integrate(const mp_var_integrand *L, double t0, double h, size_t nsteps,
                             const double *q0, const double *p0, const double *v0,
                             double sing_tol, double *q, double *p,
                             int (*interrupt)(void *), void *interrupt_ctx);

#endif
