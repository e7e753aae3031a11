/* Calculus of variations: discrete Euler-Lagrange equations solved by
 * Newton's method with a tridiagonal (bordered) Hessian; the variational
 * integrator of the same discrete action.  See variational.h. */
#include "variational.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mp_status.h"

/* ---- built-in integrands --------------------------------------------------- */

static const struct {
    const char *name;
    int kind;
    size_t nparams;
} mp_var_table[] = {
    {"brachistochrone", MP_VAR_BRACHISTOCHRONE, 2},
    {"potential", MP_VAR_POTENTIAL, 1},
    {"arclength", MP_VAR_ARCLENGTH, 0},
    {"pendulum", MP_VAR_PENDULUM, 5},
    {"duffing", MP_VAR_DUFFING, 5},
};

int mp_variational_builtin_find(const char *name, int *kind, size_t *nparams)
{
    for (size_t i = 0; i < sizeof mp_var_table / sizeof mp_var_table[0]; i++) {
        if (strcmp(name, mp_var_table[i].name) == 0) {
            *kind = mp_var_table[i].kind;
            *nparams = mp_var_table[i].nparams;
            return MP_OK;
        }
    }
    return MP_EDOM;
}

static void var_put(double *out, size_t m, size_t i, double F, double Fy, double Fp, double Fyy,
                    double Fyp, double Fpp)
{
    out[i] = F;
    out[m + i] = Fy;
    out[2 * m + i] = Fp;
    out[3 * m + i] = Fyy;
    out[4 * m + i] = Fyp;
    out[5 * m + i] = Fpp;
}

/* Brachistochrone in the variables s (x = X s^3) and u = sqrt(y): both x(s)
 * and u(s) are smooth at the start, where y' is infinite. */
static void var_brachistochrone(const double *prm, size_t m, size_t i, double s, double u,
                                double p, double *out)
{
    double X = prm[0], c = 1.0 / sqrt(2.0 * prm[1]);
    if (!(u > 0)) {
        var_put(out, m, i, NAN, NAN, NAN, NAN, NAN, NAN);
        return;
    }
    double xs = 3.0 * X * s * s, A = xs * xs, up = u * p;
    double R = sqrt(A + 4.0 * up * up), R3 = R * R * R;
    double Ru = 4.0 * u * p * p / R, Rp = 4.0 * u * up / R;
    double Ruu = 4.0 * p * p * A / R3, Rpp = 4.0 * u * u * A / R3;
    double Rup = 8.0 * up * (A + 2.0 * up * up) / R3;
    double iu = 1.0 / u;
    var_put(out, m, i, c * R * iu, c * (Ru - R * iu) * iu, c * Rp * iu,
            c * (Ruu - 2.0 * Ru * iu + 2.0 * R * iu * iu) * iu, c * (Rup - Rp * iu) * iu,
            c * Rpp * iu);
}

static int var_builtin_eval(size_t m, const double *x, const double *y, const double *p,
                            double *out, void *ctx)
{
    const mp_var_builtin *b = ctx;
    const double *k = b->params;
    for (size_t i = 0; i < m; i++) {
        double xi = x[i], yi = y[i], pi = p[i];
        switch (b->kind) {
        case MP_VAR_BRACHISTOCHRONE:
            var_brachistochrone(k, m, i, xi, yi, pi, out);
            break;
        case MP_VAR_POTENTIAL: {
            double S = sqrt(1.0 + pi * pi), w = k[0];
            var_put(out, m, i, w * yi * S, w * S, w * yi * pi / S, 0.0, w * pi / S,
                    w * yi / (S * S * S));
            break;
        }
        case MP_VAR_ARCLENGTH: {
            double S = sqrt(1.0 + pi * pi);
            var_put(out, m, i, S, 0.0, pi / S, 0.0, 0.0, 1.0 / (S * S * S));
            break;
        }
        case MP_VAR_PENDULUM: {
            double g = k[0], L = k[1], e = exp(k[2] * xi), drive = L * L * k[3] * cos(k[4] * xi);
            var_put(out, m, i, e * (0.5 * L * L * pi * pi + g * L * cos(yi) + drive * yi),
                    e * (-g * L * sin(yi) + drive), e * L * L * pi, -e * g * L * cos(yi), 0.0,
                    e * L * L);
            break;
        }
        case MP_VAR_DUFFING: {
            double al = k[0], be = k[1], e = exp(k[2] * xi), drive = k[3] * cos(k[4] * xi);
            double y2 = yi * yi;
            var_put(out, m, i,
                    e * (0.5 * pi * pi - 0.5 * al * y2 - 0.25 * be * y2 * y2 + drive * yi),
                    e * (-al * yi - be * y2 * yi + drive), e * pi, e * (-al - 3.0 * be * y2), 0.0,
                    e);
            break;
        }
        default:
            return MP_EDOM;
        }
    }
    return MP_OK;
}

void mp_variational_builtin_bind(mp_var_builtin *b, mp_var_integrand *out)
{
    out->eval = var_builtin_eval;
    out->ctx = b;
}

/* ---- tridiagonal solvers ----------------------------------------------------- */

/* LDL^T of the symmetric tridiagonal (d, e) + shift I, solving for nrhs
 * columns of b (column-major, N rows) in place.  Returns MP_ENOTSPD at a
 * non-positive pivot. */
static int var_ldl_solve(size_t N, const double *d, const double *e, double shift, double *b,
                         size_t nrhs, double *wd, double *wl)
{
    for (size_t i = 0; i < N; i++) {
        double di = d[i] + shift;
        if (i > 0) {
            wl[i - 1] = e[i - 1] / wd[i - 1];
            di -= wl[i - 1] * e[i - 1];
        }
        if (!(di > 0)) return MP_ENOTSPD;
        wd[i] = di;
    }
    for (size_t c = 0; c < nrhs; c++) {
        double *x = b + c * N;
        for (size_t i = 1; i < N; i++) x[i] -= wl[i - 1] * x[i - 1];
        for (size_t i = 0; i < N; i++) x[i] /= wd[i];
        for (size_t i = N - 1; i-- > 0;) x[i] -= wl[i] * x[i + 1];
    }
    return MP_OK;
}

/* Gaussian elimination with partial pivoting for a symmetric tridiagonal
 * (d, e) (the LAPACK dgtsv algorithm): an indefinite matrix is fine.
 * MP_ESINGULAR for an exactly singular one. */
static int var_lu_solve(size_t N, const double *d, const double *e, double *b, size_t nrhs,
                        double *D, double *U1, double *U2, double *Lf, int *piv)
{
    /* rows: lower dl = e, diag D, upper du = e; factor PA = LU with U having two
     * super-diagonals */
    double *du = U1;
    for (size_t i = 0; i < N; i++) {
        D[i] = d[i];
        if (i + 1 < N) du[i] = e[i];
        U2[i] = 0.0;
    }
    for (size_t i = 0; i + 1 < N; i++) {
        double sub = e[i]; /* A[i+1][i] */
        if (fabs(D[i]) >= fabs(sub)) {
            if (D[i] == 0.0) return MP_ESINGULAR;
            piv[i] = 0;
            double f = sub / D[i];
            Lf[i] = f;
            D[i + 1] -= f * du[i];
            U2[i] = 0.0;
        } else {
            /* swap rows i and i+1 */
            piv[i] = 1;
            double f = D[i] / sub;
            Lf[i] = f;
            D[i] = sub;
            double t = D[i + 1];
            double r_up = du[i];
            D[i + 1] = r_up - f * t;
            du[i] = t;
            if (i + 2 < N) {
                U2[i] = du[i + 1];
                du[i + 1] = -f * du[i + 1];
            } else {
                U2[i] = 0.0;
            }
        }
    }
    if (N > 0 && D[N - 1] == 0.0) return MP_ESINGULAR;
    for (size_t c = 0; c < nrhs; c++) {
        double *x = b + c * N;
        for (size_t i = 0; i + 1 < N; i++) {
            if (piv[i]) {
                double t = x[i];
                x[i] = x[i + 1];
                x[i + 1] = t - Lf[i] * x[i + 1];
            } else {
                x[i + 1] -= Lf[i] * x[i];
            }
        }
        for (size_t i = N; i-- > 0;) {
            double s = x[i];
            if (i + 1 < N) s -= du[i] * x[i + 1];
            if (i + 2 < N) s -= U2[i] * x[i + 2];
            x[i] = s / D[i];
        }
    }
    return MP_OK;
}

/* Small dense solve (ncon x ncon, row-major) with partial pivoting. */
static int var_dense_solve(size_t k, double *A, double *b)
{
    for (size_t c = 0; c < k; c++) {
        size_t piv = c;
        for (size_t r = c + 1; r < k; r++)
            if (fabs(A[r * k + c]) > fabs(A[piv * k + c])) piv = r;
        if (A[piv * k + c] == 0.0) return MP_ESINGULAR;
        if (piv != c) {
            for (size_t j = 0; j < k; j++) {
                double t = A[c * k + j];
                A[c * k + j] = A[piv * k + j];
                A[piv * k + j] = t;
            }
            double t = b[c];
            b[c] = b[piv];
            b[piv] = t;
        }
        for (size_t r = c + 1; r < k; r++) {
            double f = A[r * k + c] / A[c * k + c];
            for (size_t j = c; j < k; j++) A[r * k + j] -= f * A[c * k + j];
            b[r] -= f * b[c];
        }
    }
    for (size_t c = k; c-- > 0;) {
        double s = b[c];
        for (size_t j = c + 1; j < k; j++) s -= A[c * k + j] * b[j];
        b[c] = s / A[c * k + c];
    }
    return MP_OK;
}

/* ---- the Newton solver -------------------------------------------------------- */

typedef struct {
    size_t n, N, nc;
    double *h, *xm, *ym, *pm; /* n each */
    double *ev;               /* 6 n (F) */
    double *evg;              /* 6 n nc (constraints) */
    double *g;                /* N: gradient of Phi = J + sum lambda G */
    double *B;                /* N nc: gradients of G_k (column-major) */
    double *d, *e;            /* tridiagonal Hessian of Phi */
    double *Gv;               /* nc: G_k values */
    double J;
    double gscale;            /* max over nodes of the summands' size in g (round-off scale) */
    /* solve workspace */
    double *rhs;              /* N (nc + 1) */
    double *w1, *w2, *w3, *w4;
    int *piv;
    double *S, *sb;           /* nc nc, nc */
    double *ytry, *ltry, *dy, *dl;
} var_ws;

static void var_ws_free(var_ws *w)
{
    free(w->h);
    free(w->evg);
    free(w->piv);
}

static int var_ws_alloc(var_ws *w, size_t n, size_t nc)
{
    memset(w, 0, sizeof *w);
    w->n = n;
    w->N = n - 1;
    w->nc = nc;
    size_t N = n - 1;
    size_t tot = 4 * n + 6 * n + N + N * nc + 2 * N + nc + N * (nc + 1) + 4 * (N + 1) + nc * nc +
                 nc + (n + 1) + nc + N + nc;
    w->h = calloc(tot, sizeof(double));
    w->evg = calloc(6 * n * (nc ? nc : 1), sizeof(double));
    w->piv = calloc(N + 1, sizeof(int));
    if (!w->h || !w->evg || !w->piv) {
        var_ws_free(w);
        return MP_ENOMEM;
    }
    double *q = w->h + n;
    w->xm = q, q += n;
    w->ym = q, q += n;
    w->pm = q, q += n;
    w->ev = q, q += 6 * n;
    w->g = q, q += N;
    w->B = q, q += N * nc;
    w->d = q, q += N;
    w->e = q, q += N;
    w->Gv = q, q += nc;
    w->rhs = q, q += N * (nc + 1);
    w->w1 = q, q += N + 1;
    w->w2 = q, q += N + 1;
    w->w3 = q, q += N + 1;
    w->w4 = q, q += N + 1;
    w->S = q, q += nc * nc;
    w->sb = q, q += nc;
    w->ytry = q, q += n + 1;
    w->ltry = q, q += nc;
    w->dy = q, q += N;
    w->dl = q;
    return MP_OK;
}

/* Evaluate J, G, the gradient of Phi and (if hess) its tridiagonal Hessian.
 * MP_ENONFINITE when a value is not finite (outside the domain). */
static int var_assemble(const mp_var_problem *pb, var_ws *w, const double *y,
                        const double *lam, int hess)
{
    size_t n = w->n, N = w->N, nc = w->nc;
    for (size_t i = 0; i < n; i++) {
        w->ym[i] = 0.5 * (y[i] + y[i + 1]);
        w->pm[i] = (y[i + 1] - y[i]) / w->h[i];
    }
    int st = pb->F.eval(n, w->xm, w->ym, w->pm, w->ev, pb->F.ctx);
    if (st != MP_OK) return st;
    for (size_t k = 0; k < nc; k++) {
        st = pb->G[k].eval(n, w->xm, w->ym, w->pm, w->evg + 6 * n * k, pb->G[k].ctx);
        if (st != MP_OK) return st;
    }
    memset(w->g, 0, N * sizeof(double));
    memset(w->B, 0, N * nc * sizeof(double));
    if (hess) {
        memset(w->d, 0, N * sizeof(double));
        memset(w->e, 0, N * sizeof(double));
    }
    double J = 0.0, gscale = 0.0;
    for (size_t k = 0; k < nc; k++) w->Gv[k] = 0.0;
    for (size_t i = 0; i < n; i++) {
        double h = w->h[i];
        const double *E = w->ev;
        double F = E[i], Fy = E[n + i], Fp = E[2 * n + i];
        double Fyy = E[3 * n + i], Fyp = E[4 * n + i], Fpp = E[5 * n + i];
        J += h * F;
        for (size_t k = 0; k < nc; k++) {
            const double *Q = w->evg + 6 * n * k;
            double a = Q[n + i], b = Q[2 * n + i];
            w->Gv[k] += h * Q[i];
            if (i >= 1) w->B[k * N + i - 1] += 0.5 * h * a - b;
            if (i + 1 <= N) w->B[k * N + i] += 0.5 * h * a + b;
            Fy += lam[k] * a;
            Fp += lam[k] * b;
            Fyy += lam[k] * Q[3 * n + i];
            Fyp += lam[k] * Q[4 * n + i];
            Fpp += lam[k] * Q[5 * n + i];
        }
        /* interval i couples nodes i and i + 1 = unknowns i - 1 and i */
        gscale = fmax(gscale, fabs(0.5 * h * Fy) + fabs(Fp));
        if (i >= 1) w->g[i - 1] += 0.5 * h * Fy - Fp;
        if (i + 1 <= N) w->g[i] += 0.5 * h * Fy + Fp;
        if (hess) {
            if (i >= 1) w->d[i - 1] += 0.25 * h * Fyy - Fyp + Fpp / h;
            if (i + 1 <= N) w->d[i] += 0.25 * h * Fyy + Fyp + Fpp / h;
            if (i >= 1 && i + 1 <= N) w->e[i - 1] += 0.25 * h * Fyy - Fpp / h;
        }
    }
    w->J = J;
    w->gscale = gscale;
    if (!isfinite(J)) return MP_ENONFINITE;
    for (size_t j = 0; j < N; j++)
        if (!isfinite(w->g[j])) return MP_ENONFINITE;
    for (size_t k = 0; k < nc; k++)
        if (!isfinite(w->Gv[k])) return MP_ENONFINITE;
    if (hess)
        for (size_t j = 0; j < N; j++)
            if (!isfinite(w->d[j]) || !isfinite(w->e[j])) return MP_ENONFINITE;
    return MP_OK;
}

/* merit of the residual mode: 1/2 (|grad Phi|^2 + |G - value|^2) */
static double var_merit(const mp_var_problem *pb, const var_ws *w)
{
    double s = 0.0;
    for (size_t j = 0; j < w->N; j++) s += w->g[j] * w->g[j];
    for (size_t k = 0; k < w->nc; k++) {
        double c = w->Gv[k] - pb->value[k];
        s += c * c;
    }
    return 0.5 * s;
}

/* The Newton step (dy, dl) at the current assembly.  In minimise mode
 * without constraints the Hessian is shifted until positive definite, so
 * dy is a descent direction of J. */
static int var_step(const mp_var_problem *pb, var_ws *w, int minimise)
{
    size_t N = w->N, nc = w->nc;
    double *r = w->rhs;
    for (size_t j = 0; j < N; j++) r[j] = w->g[j];
    memcpy(r + N, w->B, N * nc * sizeof(double));
    int st;
    if (minimise) {
        double shift = 0.0, scale = 0.0;
        for (size_t j = 0; j < N; j++) scale = fmax(scale, fabs(w->d[j]));
        for (int tries = 0;; tries++) {
            for (size_t j = 0; j < N; j++) r[j] = w->g[j];
            st = var_ldl_solve(N, w->d, w->e, shift, r, 1, w->w1, w->w2);
            if (st == MP_OK) break;
            if (tries > 60) return MP_ESINGULAR;
            shift = shift == 0.0 ? 1e-8 * (scale > 0 ? scale : 1.0) : 4.0 * shift;
        }
    } else {
        st = var_lu_solve(N, w->d, w->e, r, nc + 1, w->w1, w->w2, w->w3, w->w4, w->piv);
        if (st != MP_OK) return st;
    }
    /* r = H^-1 g (w), r + N k = H^-1 B_k (Z) */
    if (nc > 0) {
        for (size_t a = 0; a < nc; a++) {
            double s = pb->value ? w->Gv[a] - pb->value[a] : 0.0;
            for (size_t j = 0; j < N; j++) s -= w->B[a * N + j] * r[j];
            w->sb[a] = s;
            for (size_t b = 0; b < nc; b++) {
                double t = 0.0;
                for (size_t j = 0; j < N; j++) t += w->B[a * N + j] * r[N * (b + 1) + j];
                w->S[a * nc + b] = t;
            }
        }
        st = var_dense_solve(nc, w->S, w->sb);
        if (st != MP_OK) return st;
        for (size_t a = 0; a < nc; a++) w->dl[a] = w->sb[a];
    }
    for (size_t j = 0; j < N; j++) {
        double s = -r[j];
        for (size_t a = 0; a < nc; a++) s -= r[N * (a + 1) + j] * w->dl[a];
        w->dy[j] = s;
    }
    return MP_OK;
}

int mp_variational_solve(const mp_var_problem *pb, double *y, double *lambda, mp_var_info *info)
{
    size_t n = pb->n, nc = pb->ncon;
    if (n < 2 || !pb->x || !pb->F.eval || (nc > 0 && (!pb->G || !pb->value)) || pb->max_iter < 1)
        return MP_EDOM;
    for (size_t i = 0; i <= n; i++)
        if (!isfinite(y[i]) || !isfinite(pb->x[i])) return MP_EDOM;
    for (size_t k = 0; k < nc; k++)
        if (!isfinite(lambda[k]) || !isfinite(pb->value[k])) return MP_EDOM;
    var_ws w;
    int st = var_ws_alloc(&w, n, nc);
    if (st != MP_OK) return st;
    for (size_t i = 0; i < n; i++) {
        w.h[i] = pb->x[i + 1] - pb->x[i];
        w.xm[i] = 0.5 * (pb->x[i] + pb->x[i + 1]);
        if (!(w.h[i] > 0)) {
            var_ws_free(&w);
            return MP_EDOM;
        }
    }
    int minimise = !pb->stationary && nc == 0;
    double tol = pb->tol > 0 ? pb->tol : 1e-10;
    size_t N = w.N, it = 0;
    int converged = 0;
    st = var_assemble(pb, &w, y, lambda, 1);
    if (st == MP_ENONFINITE) st = MP_EDOM; /* the initial guess is outside the domain */
    while (st == MP_OK && it < pb->max_iter) {
        it++;
        st = var_step(pb, &w, minimise);
        if (st != MP_OK) break;
        double ymax = 0.0, dmax = 0.0, lmax = 0.0, dlmax = 0.0, slope = 0.0;
        for (size_t j = 0; j < N; j++) {
            ymax = fmax(ymax, fabs(y[j + 1]));
            dmax = fmax(dmax, fabs(w.dy[j]));
            slope += w.g[j] * w.dy[j];
        }
        for (size_t k = 0; k < nc; k++) {
            lmax = fmax(lmax, fabs(lambda[k]));
            dlmax = fmax(dlmax, fabs(w.dl[k]));
        }
        double gmax = 0.0, cmax = 0.0, vmax = 0.0;
        for (size_t j = 0; j < N; j++) gmax = fmax(gmax, fabs(w.g[j]));
        for (size_t k = 0; k < nc; k++) {
            cmax = fmax(cmax, fabs(w.Gv[k] - pb->value[k]));
            vmax = fmax(vmax, fabs(pb->value[k]));
        }
        /* a residual at round-off level also ends the iteration (a nearly
           singular Hessian can keep the step from shrinking) */
        if (gmax <= 1e-13 * w.gscale && cmax <= 1e-13 * (1.0 + vmax)) {
            converged = 1;
            break;
        }
        int small = dmax <= tol * (1.0 + ymax) && dlmax <= tol * (1.0 + lmax);
        double J0 = w.J, m0 = var_merit(pb, &w), alpha = 1.0;
        int accepted = 0;
        for (int ls = 0; ls < 40; ls++) {
            w.ytry[0] = y[0];
            w.ytry[n] = y[n];
            for (size_t j = 0; j < N; j++) w.ytry[j + 1] = y[j + 1] + alpha * w.dy[j];
            for (size_t k = 0; k < nc; k++) w.ltry[k] = lambda[k] + alpha * w.dl[k];
            int s2 = var_assemble(pb, &w, w.ytry, w.ltry, 1);
            if (s2 != MP_OK && s2 != MP_ENONFINITE) {
                st = s2;
                break;
            }
            if (s2 == MP_OK) {
                /* near the solution the decrease of J drowns in round-off: the
                   residual's decrease decides there */
                int resid_ok = var_merit(pb, &w) <= (1.0 - 2e-4 * alpha) * m0;
                int ok = minimise ? (w.J <= J0 + 1e-4 * alpha * slope ||
                                     (fabs(slope) <= 1e-10 * (1.0 + fabs(J0)) && resid_ok))
                                  : resid_ok;
                if (ok || small) {
                    accepted = 1;
                    break;
                }
            }
            alpha *= 0.5;
        }
        if (st != MP_OK) break;
        if (!accepted) {
            /* no decrease: at the round-off floor if the step is tiny */
            if (dmax <= 1e-7 * (1.0 + ymax) && dlmax <= 1e-7 * (1.0 + lmax)) {
                st = var_assemble(pb, &w, y, lambda, 0);
                converged = st == MP_OK;
            } else {
                st = MP_ENOCONV;
            }
            break;
        }
        memcpy(y, w.ytry, (n + 1) * sizeof(double));
        memcpy(lambda, w.ltry, nc * sizeof(double));
        if (small) {
            converged = 1;
            break;
        }
    }
    if (st == MP_OK && !converged) st = MP_ENOCONV;
    if (st == MP_ENONFINITE) st = MP_ENOCONV;
    if (info) {
        info->iterations = it;
        info->J = w.J;
        double rmax = 0.0, cmax = 0.0;
        for (size_t j = 0; j < N; j++) rmax = fmax(rmax, fabs(w.g[j]));
        for (size_t k = 0; k < nc; k++) cmax = fmax(cmax, fabs(w.Gv[k] - pb->value[k]));
        info->residual = rmax;
        info->constraint_error = cmax;
    }
    var_ws_free(&w);
    return st;
}

/* ---- the variational integrator ------------------------------------------------ */

int mp_variational_integrate(const mp_var_integrand *L, double t0, double h, size_t nsteps,
                             double q0, double p0, double *q, double *p,
                             int (*interrupt)(void *), void *interrupt_ctx)
{
    if (!L || !L->eval || !(h > 0) || !isfinite(h) || !isfinite(t0) || !isfinite(q0) ||
        !isfinite(p0))
        return MP_EDOM;
    double ev[6];
    q[0] = q0;
    p[0] = p0;
    double v = 0.0; /* last step's mean velocity: the predictor */
    int have_v = 0;
    for (size_t k = 0; k < nsteps; k++) {
        if (interrupt && k % 4096 == 4095) {
            int st = interrupt(interrupt_ctx);
            if (st != MP_OK) return st;
        }
        double t = t0 + ((double)k + 0.5) * h, qk = q[k], pk = p[k];
        double q1 = qk + (have_v ? v * h : 0.0);
        int done = 0;
        for (int it = 0; it < 60; it++) {
            double ym = 0.5 * (qk + q1), pm = (q1 - qk) / h;
            int st = L->eval(1, &t, &ym, &pm, ev, L->ctx);
            if (st != MP_OK) return st;
            /* p_k + D1 L_d = 0 with D1 L_d = h F_y / 2 - F_p */
            double r = pk + 0.5 * h * ev[1] - ev[2];
            double dr = 0.25 * h * ev[3] - ev[5] / h;
            if (!isfinite(r) || !isfinite(dr) || dr == 0.0) return MP_ENOCONV;
            double dq = -r / dr;
            q1 += dq;
            /* the error after this update is O(dq^2) (quadratic convergence) */
            if (fabs(dq) <= 1e-12 * (1.0 + fabs(q1))) {
                done = 1;
                break;
            }
        }
        if (!done) return MP_ENOCONV;
        double ym = 0.5 * (qk + q1), pm = (q1 - qk) / h;
        int st = L->eval(1, &t, &ym, &pm, ev, L->ctx);
        if (st != MP_OK) return st;
        q[k + 1] = q1;
        p[k + 1] = 0.5 * h * ev[1] + ev[2];
        if (!isfinite(p[k + 1])) return MP_ENOCONV;
        v = pm;
        have_v = 1;
    }
    return MP_OK;
}
