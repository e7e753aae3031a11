/* Calculus of variations with d unknown functions: the discrete
 * Euler-Lagrange equations solved by Newton's method with a block-tridiagonal
 * (banded LU or Cholesky) Hessian; the variational integrator and the discrete
 * Legendre transform of the same discrete action.  See variational.h. */
#include "variational.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mp_status.h"

/* max(a, b) for an accumulator a that is never NaN (a NaN b is skipped, as by
 * fmax, which is a library call at -O2 and too slow in the inner loops). */
static inline double var_max(double a, double b)
{
    return b > a ? b : a;
}

/* ---- built-in integrands --------------------------------------------------- */

/* The built-ins: name, kind, number of parameters, dimension d. */
static const struct {
    const char *name;
    int kind;
    size_t nparams, d;
} mp_var_table[] = {
    {"brachistochrone", MP_VAR_BRACHISTOCHRONE, 2, 1},
    {"potential", MP_VAR_POTENTIAL, 1, 1},
    {"arclength", MP_VAR_ARCLENGTH, 0, 1},
};

/* Look up a built-in by name: its kind, parameter count and dimension. */
int mp_variational_builtin_find(const char *name, int *kind, size_t *nparams, size_t *d)
{
    for (size_t i = 0; i < sizeof mp_var_table / sizeof mp_var_table[0]; i++) {
        if (strcmp(name, mp_var_table[i].name) == 0) {
            *kind = mp_var_table[i].kind;
            *nparams = mp_var_table[i].nparams;
            *d = mp_var_table[i].d;
            return MP_OK;
        }
    }
    return MP_EDOM;
}

/* Brachistochrone in the variables s (x = X s^3) and u = sqrt(y): both x(s)
 * and u(s) are smooth at the start, where y' is infinite.  o: 6 values. */
static void var_brachistochrone(const double *prm, double s, double u, double p, double *o)
{
    double X = prm[0], c = 1.0 / sqrt(2.0 * prm[1]);
    if (!(u > 0)) {
        mp_var_put1(o, NAN, NAN, NAN, NAN, NAN, NAN);
        return;
    }
    double xs = 3.0 * X * s * s, A = xs * xs, up = u * p;
    double R = sqrt(A + 4.0 * up * up), R3 = R * R * R;
    double Ru = 4.0 * u * p * p / R, Rp = 4.0 * u * up / R;
    double Ruu = 4.0 * p * p * A / R3, Rpp = 4.0 * u * u * A / R3;
    double Rup = 8.0 * up * (A + 2.0 * up * up) / R3;
    double iu = 1.0 / u;
    mp_var_put1(o, c * R * iu, c * (Ru - R * iu) * iu, c * Rp * iu,
                c * (Ruu - 2.0 * Ru * iu + 2.0 * R * iu * iu) * iu, c * (Rup - Rp * iu) * iu,
                c * Rpp * iu);
}

/* Evaluate a built-in at m points (the mp_var_eval_fn of every built-in). */
static int var_builtin_eval(size_t m, const double *x, const double *y, const double *p,
                            double *out, void *ctx)
{
    const mp_var_builtin *b = ctx;
    const double *k = b->params;
    for (size_t i = 0; i < m; i++) {
        double xi = x[i], yi = y[i], pi = p[i], *o = out + 6 * i;
        switch (b->kind) {
        case MP_VAR_BRACHISTOCHRONE:
            var_brachistochrone(k, xi, yi, pi, o);
            break;
        case MP_VAR_POTENTIAL: {
            double S = sqrt(1.0 + pi * pi), w = k[0];
            mp_var_put1(o, w * yi * S, w * S, w * yi * pi / S, 0.0, w * pi / S,
                        w * yi / (S * S * S));
            break;
        }
        case MP_VAR_ARCLENGTH: {
            double S = sqrt(1.0 + pi * pi);
            mp_var_put1(o, S, 0.0, pi / S, 0.0, 0.0, 1.0 / (S * S * S));
            break;
        }
        default:
            return MP_EDOM;
        }
    }
    return MP_OK;
}

/* Bind built-in b (which must outlive out) as an integrand. */
void mp_variational_builtin_bind(mp_var_builtin *b, mp_var_integrand *out)
{
    out->eval = var_builtin_eval;
    out->ctx = b;
    out->d = 1;
    for (size_t i = 0; i < sizeof mp_var_table / sizeof mp_var_table[0]; i++)
        if (mp_var_table[i].kind == b->kind) out->d = mp_var_table[i].d;
}

/* Points per call of an integrand: bounds what a Python integrand builds at once
 * (its finite-difference stencil multiplies the points). */
#define MP_VAR_CHUNK 4096

/* Points between two interrupt checks of an assembly (about 10 ms of a
 * built-in integrand). */
#define MP_VAR_BLOCK (64 * MP_VAR_CHUNK)

/* Evaluate L at m points, MP_VAR_CHUNK at a time; an out-of-domain status
 * becomes MP_ENONFINITE, as does any non-finite value among the m * K outputs. */
static int var_eval(const mp_var_integrand *L, size_t m, const double *x, const double *y,
                    const double *p, double *out)
{
    size_t d = L->d, K = mp_var_nvalues(d);
    for (size_t i = 0; i < m; i += MP_VAR_CHUNK) {
        size_t c = m - i < MP_VAR_CHUNK ? m - i : MP_VAR_CHUNK;
        int st = L->eval(c, x + i, y + i * d, p + i * d, out + i * K, L->ctx);
        if (st == MP_EDOM) return MP_ENONFINITE;
        if (st != MP_OK) return st;
    }
    size_t tot = m * K;
    for (size_t i = 0; i < tot; i++)
        if (!isfinite(out[i])) return MP_ENONFINITE;
    return MP_OK;
}

/* ---- small dense systems ------------------------------------------------------ */

/* Gaussian elimination with partial pivoting on the k x k row-major A (destroyed),
 * solving A x = b in place when b is not NULL.  *pivmin and *pivmax (may be
 * NULL) receive the smallest and largest |pivot|.  MP_ESINGULAR for a zero or
 * non-finite pivot. */
static int var_gauss(size_t k, double *A, double *b, double *pivmin, double *pivmax)
{
    double lo = INFINITY, hi = 0.0;
    for (size_t c = 0; c < k; c++) {
        size_t piv = c;
        for (size_t r = c + 1; r < k; r++)
            if (fabs(A[r * k + c]) > fabs(A[piv * k + c])) piv = r;
        double a = fabs(A[piv * k + c]);
        lo = a < lo ? a : lo;
        hi = a > hi ? a : hi;
        if (!(a > 0) || !isfinite(a)) {
            if (pivmin) *pivmin = 0.0;
            if (pivmax) *pivmax = hi;
            return MP_ESINGULAR;
        }
        if (piv != c) {
            for (size_t j = 0; j < k; j++) {
                double t = A[c * k + j];
                A[c * k + j] = A[piv * k + j];
                A[piv * k + j] = t;
            }
            if (b) {
                double t = b[c];
                b[c] = b[piv];
                b[piv] = t;
            }
        }
        for (size_t r = c + 1; r < k; r++) {
            double f = A[r * k + c] / A[c * k + c];
            for (size_t j = c; j < k; j++) A[r * k + j] -= f * A[c * k + j];
            if (b) b[r] -= f * b[c];
        }
    }
    if (b)
        for (size_t c = k; c-- > 0;) {
            double s = b[c];
            for (size_t j = c + 1; j < k; j++) s -= A[c * k + j] * b[j];
            b[c] = s / A[c * k + c];
        }
    if (pivmin) *pivmin = k ? lo : 0.0;
    if (pivmax) *pivmax = hi;
    return MP_OK;
}

/* max |a_i| over k values (0 for k = 0). */
static double var_maxabs(size_t k, const double *a)
{
    double m = 0.0; /* NaN entries are skipped, as by fmax (a call at -O2: too slow here) */
    for (size_t i = 0; i < k; i++) m = fabs(a[i]) > m ? fabs(a[i]) : m;
    return m;
}

/* Is d2L/dqdot dqdot (the d x d block Lvv of one evaluation o) singular?  Its
 * smallest LU pivot is compared with sing_tol times the scale
 * max(|Lvv|, h |Lqv|, h^2 |Lqq|) (all of the units of Lvv); work: d*d. */
static int var_vv_singular(size_t d, const double *o, double h, double sing_tol, double *work)
{
    size_t dd = d * d;
    const double *Lqq = o + 1 + 2 * d, *Lqv = Lqq + dd, *Lvv = Lqv + dd;
    double scale = var_max(var_maxabs(dd, Lvv),
                           var_max(h * var_maxabs(dd, Lqv), h * h * var_maxabs(dd, Lqq)));
    if (d == 1) return !(fabs(Lvv[0]) > sing_tol * scale); /* the one pivot */
    memcpy(work, Lvv, dd * sizeof(double));
    double lo, hi;
    if (var_gauss(d, work, NULL, &lo, &hi) != MP_OK) return 1;
    return !(lo > sing_tol * scale);
}

/* ---- band solvers (half-bandwidth kd, column-major band storage) --------------------- */

/* LU with partial pivoting of the N x N band matrix with kl = ku = kd, stored
 * as LAPACK's dgbtrf takes it: A[i][j] at ab[2kd + i - j + j ldab] with
 * ldab >= 3kd + 1 and the top kd rows of the storage zero (room for the
 * fill-in).  The factor overwrites ab, the row interchanges go to ipiv (the
 * algorithm of LAPACK's dgbtf2, written out: no library call per column for
 * the narrow bands here).  MP_ESINGULAR at a zero pivot. */
static int var_band_lu(size_t N, size_t kd, double *ab, size_t ldab, size_t *ipiv)
{
    size_t kv = 2 * kd, ju = 0;
    for (size_t j = 0; j < N; j++) {
        size_t km = kd < N - 1 - j ? kd : N - 1 - j;
        double *col = ab + kv + j * ldab; /* col[r] = A[j + r][j] */
        size_t jp = 0;
        for (size_t r = 1; r <= km; r++)
            if (fabs(col[r]) > fabs(col[jp])) jp = r;
        ipiv[j] = j + jp;
        if (!(col[jp] != 0.0) || !isfinite(col[jp])) return MP_ESINGULAR;
        size_t last = j + kd + jp < N - 1 ? j + kd + jp : N - 1;
        ju = ju > last ? ju : last;
        if (jp != 0)
            for (size_t c = j; c <= ju; c++) {
                double *x = ab + kv + j - c + c * ldab, *y = x + jp, t = *x;
                *x = *y;
                *y = t;
            }
        double inv = 1.0 / col[0];
        for (size_t r = 1; r <= km; r++) col[r] *= inv;
        for (size_t c = j + 1; c <= ju; c++) {
            double *u = ab + kv + j - c + c * ldab, t = *u; /* u[r] = A[j + r][c] */
            if (t != 0.0)
                for (size_t r = 1; r <= km; r++) u[r] -= col[r] * t;
        }
    }
    return MP_OK;
}

/* Solve A x = b in place with the factor of var_band_lu (nrhs columns of b,
 * column-major, N rows each). */
static void var_band_lu_solve(size_t N, size_t kd, const double *ab, size_t ldab,
                              const size_t *ipiv, double *b, size_t nrhs)
{
    size_t kv = 2 * kd;
    for (size_t c = 0; c < nrhs; c++) {
        double *x = b + c * N;
        for (size_t j = 0; j + 1 < N; j++) {
            size_t lm = kd < N - 1 - j ? kd : N - 1 - j, l = ipiv[j];
            if (l != j) {
                double t = x[l];
                x[l] = x[j];
                x[j] = t;
            }
            const double *col = ab + kv + j * ldab;
            for (size_t r = 1; r <= lm; r++) x[j + r] -= col[r] * x[j];
        }
        for (size_t j = N; j-- > 0;) {
            const double *col = ab + kv + j * ldab; /* col[-k] = U[j - k][j] */
            x[j] /= col[0];
            size_t top = j > kv ? j - kv : 0;
            for (size_t i = top; i < j; i++) x[i] -= col[(ptrdiff_t)i - (ptrdiff_t)j] * x[j];
        }
    }
}

/* Cholesky L L^T of the symmetric positive definite band matrix with its lower
 * band in ab: A[i][j] at ab[i - j + j ldh] for 0 <= i - j <= kd; overwritten
 * by L.  MP_ENOTSPD at a non-positive pivot. */
static int var_band_cholesky(size_t N, size_t kd, double *ab, size_t ldh)
{
    for (size_t j = 0; j < N; j++) {
        size_t k0 = j > kd ? j - kd : 0;
        double s = ab[j * ldh];
        for (size_t k = k0; k < j; k++) {
            double l = ab[(j - k) + k * ldh];
            s -= l * l;
        }
        if (!(s > 0) || !isfinite(s)) return MP_ENOTSPD;
        double ljj = sqrt(s);
        ab[j * ldh] = ljj;
        size_t imax = j + kd < N - 1 ? j + kd : N - 1;
        for (size_t i = j + 1; i <= imax; i++) {
            double t = ab[(i - j) + j * ldh];
            for (size_t k = i > kd ? i - kd : 0; k < j; k++)
                t -= ab[(i - k) + k * ldh] * ab[(j - k) + k * ldh];
            ab[(i - j) + j * ldh] = t / ljj;
        }
    }
    return MP_OK;
}

/* The number of negative eigenvalues of the symmetric band matrix with its
 * lower band in ab (layout of var_band_cholesky), from L D L^T without
 * pivoting (the band is kept; Sylvester's law of inertia): the pivots
 * D_j < -tau.  A pivot within tau of zero is round-off of a flat direction
 * (a degenerate minimum, as the brachistochrone's free-fall limit): it is
 * set to tau and not counted; with tau = 0 an exact zero or a non-finite
 * pivot ends the factorisation and counts the remaining columns.  ab is
 * overwritten (L below the diagonal, D on it).  O(N kd^2). */
static size_t var_band_ldlt_negative(size_t N, size_t kd, double *ab, size_t ldh, double tau)
{
    size_t count = 0;
    for (size_t j = 0; j < N; j++) {
        size_t k0 = j > kd ? j - kd : 0;
        double dj = ab[j * ldh];
        for (size_t k = k0; k < j; k++) {
            double l = ab[(j - k) + k * ldh];
            dj -= l * l * ab[k * ldh];
        }
        if (!isfinite(dj) || (tau == 0.0 && dj == 0.0)) return count + (N - j);
        if (dj < -tau) count++;
        else if (dj <= tau) dj = tau;
        ab[j * ldh] = dj;
        size_t imax = j + kd < N - 1 ? j + kd : N - 1;
        for (size_t i = j + 1; i <= imax; i++) {
            double t = ab[(i - j) + j * ldh];
            for (size_t k = i > kd ? i - kd : 0; k < j; k++)
                t -= ab[(i - k) + k * ldh] * ab[(j - k) + k * ldh] * ab[k * ldh];
            ab[(i - j) + j * ldh] = t / dj;
        }
    }
    return count;
}

/* Solve L L^T x = b in place with the factor of var_band_cholesky. */
static void var_band_cholesky_solve(size_t N, size_t kd, const double *ab, size_t ldh, double *x)
{
    for (size_t i = 0; i < N; i++) {
        double s = x[i];
        for (size_t k = i > kd ? i - kd : 0; k < i; k++) s -= ab[(i - k) + k * ldh] * x[k];
        x[i] = s / ab[i * ldh];
    }
    for (size_t i = N; i-- > 0;) {
        double s = x[i];
        size_t kmax = i + kd < N - 1 ? i + kd : N - 1;
        for (size_t k = i + 1; k <= kmax; k++) s -= ab[(k - i) + i * ldh] * x[k];
        x[i] = s / ab[i * ldh];
    }
}

/* ---- the Newton solver -------------------------------------------------------- */

typedef struct {
    size_t n, d, N, K, nc, kd; /* intervals, coordinates, unknowns, values, constraints,
                                  half-bandwidth 2d - 1 */
    size_t ldh, ldab;          /* kd + 1 (symmetric lower band), 3 kd + 1 (LU band) */
    double *h, *xm, *ym, *pm;  /* n, n, n d, n d */
    double *ev;                /* n K (F) */
    double *evg;               /* n K nc (constraints) */
    double *loc;               /* K: F + sum lambda_k G_k on one interval */
    double *g;                 /* N: gradient of Phi = J + sum lambda G */
    double *B;                 /* N nc: gradients of G_k (column-major) */
    double *H;                 /* ldh N: Hessian of Phi, lower band storage */
    double *AB;                /* ldab N: its factor */
    double *Gv;                /* nc: G_k values */
    double J;
    double gscale;             /* max over nodes of the summands' size in g (round-off scale) */
    double *rhs;               /* N (nc + 1) */
    size_t *ipiv;              /* N */
    double *S, *sb;            /* nc nc, nc */
    double *ytry, *ltry, *dy, *dl; /* (n + 1) d, nc, N, nc */
} var_ws;

/* Free a workspace (safe on a zeroed or partly allocated one). */
static void var_ws_free(var_ws *w)
{
    free(w->h);
    free(w->ipiv);
}

/* size_t product with overflow detection (returns 0 on overflow). */
static size_t var_mul(size_t a, size_t b)
{
    return (a != 0 && b > (size_t)-1 / a) ? 0 : a * b;
}

/* Allocate the workspace of n intervals, d coordinates and nc constraints.
 * MP_ENOMEM on failure or when the sizes overflow size_t. */
static int var_ws_alloc(var_ws *w, size_t n, size_t d, size_t nc)
{
    memset(w, 0, sizeof *w);
    w->n = n;
    w->d = d;
    w->N = (n - 1) * d;
    w->K = mp_var_nvalues(d);
    w->nc = nc;
    w->kd = 2 * d - 1;
    size_t N = w->N, K = w->K, kd = w->kd;
    if (d > 4096 || var_mul(N, 3 * kd + 1) == 0 || var_mul(N, nc + 1) == 0 ||
        var_mul(var_mul(n, K), nc + 1) == 0 || var_mul(N, 4 * kd + 2 * nc + 8) == 0)
        return MP_ENOMEM;
    w->ldh = kd + 1;
    w->ldab = 3 * kd + 1;
    size_t tot = 2 * n + 2 * n * d + n * K * (nc + 1) + K + N + N * nc + N * (kd + 1) +
                 N * (3 * kd + 1) + nc + N * (nc + 1) + nc * nc + nc + (n + 1) * d + nc + N +
                 nc;
    w->h = calloc(tot, sizeof(double));
    w->ipiv = calloc(N, sizeof(size_t));
    if (!w->h || !w->ipiv) {
        var_ws_free(w);
        return MP_ENOMEM;
    }
    double *q = w->h + n;
    w->xm = q, q += n;
    w->ym = q, q += n * d;
    w->pm = q, q += n * d;
    w->ev = q, q += n * K;
    w->evg = q, q += n * K * nc;
    w->loc = q, q += K;
    w->g = q, q += N;
    w->B = q, q += N * nc;
    w->H = q, q += N * (kd + 1);
    w->AB = q, q += N * (3 * kd + 1);
    w->Gv = q, q += nc;
    w->rhs = q, q += N * (nc + 1);
    w->S = q, q += nc * nc;
    w->sb = q, q += nc;
    w->ytry = q, q += (n + 1) * d;
    w->ltry = q, q += nc;
    w->dy = q, q += N;
    w->dl = q;
    return MP_OK;
}

/* H[r][c] += v for unknowns r >= c (the lower band). */
static void var_hadd(var_ws *w, size_t r, size_t c, double v)
{
    w->H[(r - c) + c * w->ldh] += v;
}

/* Evaluate J, G, the gradient of Phi and (if hess) its block-tridiagonal
 * Hessian at the path y ((n + 1) x d).  MP_ENONFINITE when a value is not
 * finite or a point is outside the domain, or the interrupt's status. */
static int var_assemble(const mp_var_problem *pb, var_ws *w, const double *y,
                        const double *lam, int hess)
{
    size_t n = w->n, d = w->d, N = w->N, K = w->K, nc = w->nc, dd = d * d;
    for (size_t i = 0; i < n; i++)
        for (size_t a = 0; a < d; a++) {
            w->ym[i * d + a] = 0.5 * (y[i * d + a] + y[(i + 1) * d + a]);
            w->pm[i * d + a] = (y[(i + 1) * d + a] - y[i * d + a]) / w->h[i];
        }
    /* the evaluations by blocks of MP_VAR_BLOCK points, asking the interrupt
       between blocks (a long path answers Ctrl-C within one block) */
    int st = MP_OK;
    for (size_t i0 = 0; i0 < n; i0 += MP_VAR_BLOCK) {
        size_t c = n - i0 < MP_VAR_BLOCK ? n - i0 : MP_VAR_BLOCK;
        if (i0 > 0 && pb->interrupt && (st = pb->interrupt(pb->interrupt_ctx)) != MP_OK)
            return st;
        st = var_eval(&pb->F, c, w->xm + i0, w->ym + i0 * d, w->pm + i0 * d, w->ev + i0 * K);
        if (st != MP_OK) return st;
        for (size_t k = 0; k < nc; k++) {
            st = var_eval(&pb->G[k], c, w->xm + i0, w->ym + i0 * d, w->pm + i0 * d,
                          w->evg + n * K * k + i0 * K);
            if (st != MP_OK) return st;
        }
    }
    memset(w->g, 0, N * sizeof(double));
    memset(w->B, 0, N * nc * sizeof(double));
    if (hess) memset(w->H, 0, N * w->ldh * sizeof(double));
    double J = 0.0, gscale = 0.0;
    for (size_t k = 0; k < nc; k++) w->Gv[k] = 0.0;
    for (size_t i = 0; i < n; i++) {
        double h = w->h[i];
        /* interval i couples nodes i and i + 1 = unknown blocks i - 1 and i */
        int left = i >= 1, right = i + 1 <= n - 1;
        size_t ul = (i - 1) * d, ur = i * d;
        const double *E = w->ev + i * K;
        J += h * E[0];
        memcpy(w->loc, E, K * sizeof(double));
        for (size_t k = 0; k < nc; k++) {
            const double *Q = w->evg + (k * n + i) * K;
            w->Gv[k] += h * Q[0];
            for (size_t a = 0; a < d; a++) {
                double bl = 0.5 * h * Q[1 + a], bp = Q[1 + d + a];
                if (left) w->B[k * N + ul + a] += bl - bp;
                if (right) w->B[k * N + ur + a] += bl + bp;
            }
            for (size_t j = 1; j < K; j++) w->loc[j] += lam[k] * Q[j];
        }
        const double *Fy = w->loc + 1, *Fp = Fy + d, *A = Fp + d, *Bm = A + dd, *C = Bm + dd;
        for (size_t a = 0; a < d; a++) {
            gscale = var_max(gscale, fabs(0.5 * h * Fy[a]) + fabs(Fp[a]));
            if (left) w->g[ul + a] += 0.5 * h * Fy[a] - Fp[a];
            if (right) w->g[ur + a] += 0.5 * h * Fy[a] + Fp[a];
        }
        if (!hess) continue;
        for (size_t a = 0; a < d; a++)
            for (size_t b = 0; b <= a; b++) {
                double base = 0.25 * h * A[a * d + b] + C[a * d + b] / h;
                double sym = 0.5 * (Bm[a * d + b] + Bm[b * d + a]);
                if (left) var_hadd(w, ul + a, ul + b, base - sym);
                if (right) var_hadd(w, ur + a, ur + b, base + sym);
            }
        if (left && right)
            for (size_t a = 0; a < d; a++)
                for (size_t b = 0; b < d; b++)
                    var_hadd(w, ur + a, ul + b,
                             0.25 * h * A[a * d + b] + 0.5 * (Bm[b * d + a] - Bm[a * d + b]) -
                                 C[a * d + b] / h);
    }
    w->J = J;
    w->gscale = gscale;
    if (!isfinite(J)) return MP_ENONFINITE;
    for (size_t j = 0; j < N; j++)
        if (!isfinite(w->g[j])) return MP_ENONFINITE;
    for (size_t k = 0; k < nc; k++)
        if (!isfinite(w->Gv[k])) return MP_ENONFINITE;
    if (hess)
        for (size_t j = 0; j < N * w->ldh; j++)
            if (!isfinite(w->H[j])) return MP_ENONFINITE;
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
 * (no constraints) the Hessian is shifted until positive definite (banded
 * Cholesky), so dy is a descent direction of J; otherwise banded LU with
 * partial pivoting (indefinite is fine) and the bordered system of the
 * constraints through its Schur complement. */
static int var_step(const mp_var_problem *pb, var_ws *w, int minimise)
{
    size_t N = w->N, nc = w->nc, kd = w->kd, ldh = w->ldh, ldab = w->ldab;
    double *r = w->rhs;
    if (minimise) {
        double shift = 0.0, scale = 0.0;
        for (size_t j = 0; j < N; j++) scale = var_max(scale, fabs(w->H[j * ldh]));
        for (int tries = 0;; tries++) {
            /* each try is an O(n) factorisation (up to 62 of them) */
            int st;
            if (tries > 0 && pb->interrupt && (st = pb->interrupt(pb->interrupt_ctx)) != MP_OK)
                return st;
            memcpy(w->AB, w->H, N * ldh * sizeof(double));
            for (size_t j = 0; j < N; j++) w->AB[j * ldh] += shift;
            if (var_band_cholesky(N, kd, w->AB, ldh) == MP_OK) break;
            if (tries > 60) return MP_ESINGULAR;
            shift = shift == 0.0 ? 1e-8 * (scale > 0 ? scale : 1.0) : 4.0 * shift;
        }
        memcpy(r, w->g, N * sizeof(double));
        var_band_cholesky_solve(N, kd, w->AB, ldh, r);
    } else {
        memset(w->AB, 0, N * ldab * sizeof(double));
        for (size_t c = 0; c < N; c++) {
            size_t rmax = c + kd < N - 1 ? c + kd : N - 1;
            for (size_t rr = c; rr <= rmax; rr++) {
                double v = w->H[(rr - c) + c * ldh];
                w->AB[(2 * kd + rr - c) + c * ldab] = v;
                w->AB[(2 * kd + c - rr) + rr * ldab] = v;
            }
        }
        if (var_band_lu(N, kd, w->AB, ldab, w->ipiv) != MP_OK) return MP_ESINGULAR;
        memcpy(r, w->g, N * sizeof(double));
        memcpy(r + N, w->B, N * nc * sizeof(double));
        var_band_lu_solve(N, kd, w->AB, ldab, w->ipiv, r, nc + 1);
    }
    /* r = H^-1 g (w), r + N k = H^-1 B_k (Z) */
    if (nc > 0) {
        for (size_t a = 0; a < nc; a++) {
            double s = w->Gv[a] - pb->value[a];
            for (size_t j = 0; j < N; j++) s -= w->B[a * N + j] * r[j];
            w->sb[a] = s;
            for (size_t b = 0; b < nc; b++) {
                double t = 0.0;
                for (size_t j = 0; j < N; j++) t += w->B[a * N + j] * r[N * (b + 1) + j];
                w->S[a * nc + b] = t;
            }
        }
        int st = var_gauss(nc, w->S, w->sb, NULL, NULL);
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

/* Newton's method with a line search on the discrete Euler-Lagrange
 * equations of pb (see variational.h for the contract). */
int mp_variational_solve(const mp_var_problem *pb, double *y, double *lambda, mp_var_info *info)
{
    if (info) memset(info, 0, sizeof *info);
    size_t n = pb->n, nc = pb->ncon, d = pb->F.d;
    if (n < 2 || d < 1 || !pb->x || !pb->F.eval || (nc > 0 && (!pb->G || !pb->value)) ||
        pb->max_iter < 1)
        return MP_EDOM;
    for (size_t k = 0; k < nc; k++)
        if (pb->G[k].d != d || !pb->G[k].eval) return MP_EDOM;
    if (n > (size_t)-1 / (d + 1) - 1) return MP_ENOMEM;
    for (size_t i = 0; i <= n; i++) {
        if (!isfinite(pb->x[i])) return MP_EDOM;
        for (size_t a = 0; a < d; a++)
            if (!isfinite(y[i * d + a])) return MP_EDOM;
    }
    for (size_t k = 0; k < nc; k++)
        if (!isfinite(lambda[k]) || !isfinite(pb->value[k])) return MP_EDOM;
    var_ws w;
    int st = var_ws_alloc(&w, n, d, nc);
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
        if (pb->interrupt && (st = pb->interrupt(pb->interrupt_ctx)) != MP_OK) break;
        it++;
        st = var_step(pb, &w, minimise);
        if (st != MP_OK) break;
        double ymax = 0.0, dmax = 0.0, lmax = 0.0, dlmax = 0.0, slope = 0.0;
        for (size_t j = 0; j < N; j++) {
            ymax = var_max(ymax, fabs(y[d + j]));
            dmax = var_max(dmax, fabs(w.dy[j]));
            slope += w.g[j] * w.dy[j];
        }
        for (size_t k = 0; k < nc; k++) {
            lmax = var_max(lmax, fabs(lambda[k]));
            dlmax = var_max(dlmax, fabs(w.dl[k]));
        }
        double gmax = 0.0, cmax = 0.0, vmax = 0.0;
        for (size_t j = 0; j < N; j++) gmax = var_max(gmax, fabs(w.g[j]));
        for (size_t k = 0; k < nc; k++) {
            cmax = var_max(cmax, fabs(w.Gv[k] - pb->value[k]));
            vmax = var_max(vmax, fabs(pb->value[k]));
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
            /* each trial is an O(n) assembly: the line search (up to 40 of them
               per iteration) answers Ctrl-C between trials */
            if (ls > 0 && pb->interrupt && (st = pb->interrupt(pb->interrupt_ctx)) != MP_OK)
                break;
            memcpy(w.ytry, y, d * sizeof(double));
            memcpy(w.ytry + n * d, y + n * d, d * sizeof(double));
            for (size_t j = 0; j < N; j++) w.ytry[d + j] = y[d + j] + alpha * w.dy[j];
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
                st = var_assemble(pb, &w, y, lambda, 1);
                converged = st == MP_OK;
            } else {
                st = MP_ENOCONV;
            }
            break;
        }
        memcpy(y, w.ytry, (n + 1) * d * sizeof(double));
        memcpy(lambda, w.ltry, nc * sizeof(double));
        if (small) {
            converged = 1;
            break;
        }
    }
    if (st == MP_OK && !converged) st = MP_ENOCONV;
    if (st == MP_ENONFINITE) st = MP_ENOCONV;
    size_t nonpos = 0;
    if (st == MP_OK && minimise) {
        /* the second variation: a minimum needs the Hessian of J_h at y (w.H,
           assembled there) positive definite; a stationary point with a
           non-positive direction is a saddle or a maximum (past a conjugate
           point, or F not convex in y') and is not reported as a minimum */
        /* round-off scale of the Hessian: the gradient's summands (gscale,
           units F / y) over the largest step between nodes (units y); 0 (an
           exact test) for a constant path */
        double dymax = 0.0;
        for (size_t i = 0; i < n; i++)
            for (size_t a = 0; a < d; a++)
                dymax = var_max(dymax, fabs(y[(i + 1) * d + a] - y[i * d + a]));
        double tau = dymax > 0 ? 1e-8 * w.gscale / dymax : 0.0;
        memcpy(w.AB, w.H, N * w.ldh * sizeof(double));
        nonpos = var_band_ldlt_negative(N, w.kd, w.AB, w.ldh, isfinite(tau) ? tau : 0.0);
        if (nonpos > 0) st = MP_ENOTSPD;
    }
    if (info) {
        info->negative = nonpos;
        info->iterations = it;
        info->J = w.J;
        double rmax = 0.0, cmax = 0.0;
        for (size_t j = 0; j < N; j++) rmax = var_max(rmax, fabs(w.g[j]));
        for (size_t k = 0; k < nc; k++) cmax = var_max(cmax, fabs(w.Gv[k] - pb->value[k]));
        info->residual = rmax;
        info->constraint_error = cmax;
    }
    var_ws_free(&w);
    return st;
}

/* ---- discrete momenta and the Legendre transform back ---------------------------- */

/* p_0 = -D1 L_d(y_0, y_1), p_k = D2 L_d(y_{k-1}, y_k) along a path. */
int mp_variational_momenta(const mp_var_integrand *L, size_t n, const double *x,
                           const double *y, double *p)
{
    size_t d = L->d, K = mp_var_nvalues(d);
    if (n < 1 || d < 1 || !L->eval) return MP_EDOM;
    if (var_mul(n, K + 2 * d + 2) == 0) return MP_ENOMEM;
    double *buf = malloc(n * (K + 2 * d + 1) * sizeof(double));
    if (!buf) return MP_ENOMEM;
    double *xm = buf, *ym = xm + n, *pm = ym + n * d, *ev = pm + n * d;
    int st = MP_OK;
    for (size_t i = 0; i < n && st == MP_OK; i++) {
        double h = x[i + 1] - x[i];
        if (!(h > 0)) st = MP_EDOM;
        xm[i] = 0.5 * (x[i] + x[i + 1]);
        for (size_t a = 0; a < d; a++) {
            ym[i * d + a] = 0.5 * (y[i * d + a] + y[(i + 1) * d + a]);
            pm[i * d + a] = (y[(i + 1) * d + a] - y[i * d + a]) / h;
        }
    }
    if (st == MP_OK) st = var_eval(L, n, xm, ym, pm, ev);
    if (st == MP_OK) {
        for (size_t i = 0; i < n; i++) {
            double h = x[i + 1] - x[i];
            const double *o = ev + i * K;
            for (size_t a = 0; a < d; a++) {
                if (i == 0) p[a] = -(0.5 * h * o[1 + a] - o[1 + d + a]);
                p[(i + 1) * d + a] = 0.5 * h * o[1 + a] + o[1 + d + a];
            }
        }
    }
    free(buf);
    return st;
}

/* Newton for the velocities of m <= MP_VAR_CHUNK points (see
 * mp_variational_velocities); ev: m K, A and work: d d, r: d. */
static int var_velocities_chunk(const mp_var_integrand *L, size_t m, const double *x,
                                const double *y, const double *p, double *v, double *energy,
                                double h, double sing_tol, double *ev, double *A, double *work,
                                double *r)
{
    size_t d = L->d, K = mp_var_nvalues(d), dd = d * d;
    for (int it = 0; it < 50; it++) {
        int st = var_eval(L, m, x, y, v, ev);
        if (st != MP_OK) return st;
        double worst = 0.0;
        for (size_t i = 0; i < m; i++) {
            const double *o = ev + i * K;
            if (var_vv_singular(d, o, h, sing_tol, work)) return MP_ESINGULAR;
            memcpy(A, o + 1 + 2 * d + 2 * dd, dd * sizeof(double));
            for (size_t a = 0; a < d; a++) r[a] = o[1 + d + a] - p[i * d + a];
            if (var_gauss(d, A, r, NULL, NULL) != MP_OK) return MP_ESINGULAR;
            double *vi = v + i * d;
            for (size_t a = 0; a < d; a++) vi[a] -= r[a];
            worst = var_max(worst, var_maxabs(d, r) / (1.0 + var_maxabs(d, vi)));
        }
        if (worst <= 1e-11) {
            st = var_eval(L, m, x, y, v, ev);
            if (st == MP_OK && energy)
                for (size_t i = 0; i < m; i++) {
                    const double *o = ev + i * K;
                    double e = -o[0];
                    for (size_t a = 0; a < d; a++) e += v[i * d + a] * o[1 + d + a];
                    energy[i] = e;
                }
            return st;
        }
    }
    return MP_ENOCONV;
}

/* Solve dL/dv(x_i, y_i, v_i) = p_i for the m velocities v (Newton, by chunks). */
int mp_variational_velocities(const mp_var_integrand *L, size_t m, const double *x,
                              const double *y, const double *p, double *v, double *energy,
                              double sing_tol)
{
    size_t d = L->d, K = mp_var_nvalues(d), dd = d * d, c = MP_VAR_CHUNK;
    if (d < 1 || d > 4096 || !L->eval) return MP_EDOM;
    if (m == 0) return MP_OK;
    /* the time scale of the singularity test: the mean spacing of x */
    double h = m > 1 ? fabs(x[m - 1] - x[0]) / (double)(m - 1) : 1.0;
    if (!(h > 0) || !isfinite(h)) h = 1.0;
    double *ev = malloc((c * K + 2 * dd + d) * sizeof(double));
    if (!ev) return MP_ENOMEM;
    double *A = ev + c * K, *work = A + dd, *r = work + dd;
    int st = MP_OK;
    for (size_t i = 0; i < m && st == MP_OK; i += c) {
        size_t k = m - i < c ? m - i : c;
        st = var_velocities_chunk(L, k, x + i, y + i * d, p + i * d, v + i * d,
                                  energy ? energy + i : NULL, h, sing_tol, ev, A, work, r);
    }
    free(ev);
    return st;
}

/* ---- the variational integrator ------------------------------------------------ */

/* One step's Newton iteration: q1 (in: predictor, out: q_{k+1}) with
 * p_k + D1 L_d(q_k, q1) = 0; ev receives the evaluation at the solution. */
static int var_vi_step(const mp_var_integrand *L, double t, double h, const double *qk,
                       const double *pk, double *q1, double *ev, double *J, double *r,
                       double *dq, double *qm, double *pm)
{
    size_t d = L->d, dd = d * d;
    const double *Lq = ev + 1, *Lv = Lq + d, *Lqq = Lv + d, *Lqv = Lqq + dd, *Lvv = Lqv + dd;
    for (size_t a = 0; a < d; a++) dq[a] = q1[a] - qk[a];
    int backoff = 0;
    for (int it = 0; it < 60;) {
        for (size_t a = 0; a < d; a++) {
            qm[a] = 0.5 * (qk[a] + q1[a]);
            pm[a] = (q1[a] - qk[a]) / h;
        }
        int st = var_eval(L, 1, &t, qm, pm, ev);
        if (st == MP_ENONFINITE) {
            /* outside the domain: halve the last update */
            if (++backoff > 40) return MP_ENOCONV;
            for (size_t a = 0; a < d; a++) {
                dq[a] *= 0.5;
                q1[a] -= dq[a];
            }
            continue;
        }
        if (st != MP_OK) return st;
        if (it > 0 && var_maxabs(d, dq) <= 1e-12 * (1.0 + var_maxabs(d, q1))) return MP_OK;
        it++;
        /* p_k + D1 L_d = 0, D1 L_d = h Lq / 2 - Lv */
        for (size_t a = 0; a < d; a++) {
            r[a] = -(pk[a] + 0.5 * h * Lq[a] - Lv[a]);
            for (size_t b = 0; b < d; b++)
                J[a * d + b] = 0.25 * h * Lqq[a * d + b] +
                               0.5 * (Lqv[a * d + b] - Lqv[b * d + a]) - Lvv[a * d + b] / h;
        }
        if (var_gauss(d, J, r, NULL, NULL) != MP_OK) return MP_ESINGULAR;
        for (size_t a = 0; a < d; a++) {
            dq[a] = r[a];
            q1[a] += r[a];
        }
        if (!(var_maxabs(d, q1) < INFINITY)) return MP_ENOCONV;
    }
    return MP_ENOCONV;
}

/* The variational integrator (see variational.h for the contract). */
int mp_variational_integrate(const mp_var_integrand *L, double t0, double h, size_t nsteps,
                             const double *q0, const double *p0, const double *v0,
                             double sing_tol, double *q, double *p,
                             int (*interrupt)(void *), void *interrupt_ctx)
{
    if (!L || !L->eval || L->d < 1 || L->d > 4096 || !(h > 0) || !isfinite(h) ||
        !isfinite(t0))
        return MP_EDOM;
    size_t d = L->d, K = mp_var_nvalues(d), dd = d * d;
    for (size_t a = 0; a < d; a++)
        if (!isfinite(q0[a]) || !isfinite(p0[a]) || !isfinite(v0[a])) return MP_EDOM;
    double *buf = malloc((K + 2 * dd + 5 * d) * sizeof(double));
    if (!buf) return MP_ENOMEM;
    double *ev = buf, *J = ev + K, *work = J + dd, *r = work + dd, *dq = r + d, *qm = dq + d,
           *pm = qm + d, *vbar = pm + d;
    memcpy(q, q0, d * sizeof(double));
    memcpy(p, p0, d * sizeof(double));
    memcpy(vbar, v0, d * sizeof(double)); /* the last step's mean velocity: the predictor */
    int st = MP_OK;
    for (size_t k = 0; k < nsteps; k++) {
        if (interrupt && k % 4096 == 4095 && (st = interrupt(interrupt_ctx)) != MP_OK) break;
        double t = t0 + ((double)k + 0.5) * h;
        const double *qk = q + k * d, *pk = p + k * d;
        double *q1 = q + (k + 1) * d, *p1 = p + (k + 1) * d;
        for (size_t a = 0; a < d; a++) q1[a] = qk[a] + h * vbar[a];
        st = var_vi_step(L, t, h, qk, pk, q1, ev, J, r, dq, qm, pm);
        if (st != MP_OK) break;
        if (var_vv_singular(d, ev, h, sing_tol, work)) {
            st = MP_ESINGULAR;
            break;
        }
        for (size_t a = 0; a < d; a++) {
            p1[a] = 0.5 * h * ev[1 + a] + ev[1 + d + a];
            vbar[a] = pm[a];
        }
    }
    free(buf);
    return st;
}
