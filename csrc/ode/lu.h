/* Solves with LU factors as LAPACK's dgetrf and zgetrf leave them, for one
 * right-hand side: the implicit methods' Newton iterations (radau, gauss4)
 * solve with the same factors several times a step.
 *
 * Why by hand for small systems: dgetrs and zgetrs check their arguments and
 * dispatch through BLAS's triangular solves on every call, which costs about
 * 950 (real) and 1170 (complex) instructions at n = 3, where the
 * substitutions themselves take 40 to 80; on ROBER at rtol 1e-10 those two
 * calls were 61% of radau's step.  From MP_ODE_LU_SMALL on, LAPACK's
 * vectorised kernels win (n = 200: the Brusselator's radau 1.5x faster with
 * them) and are called.  The factorisations stay LAPACK's.  The order of
 * operations is the reference dgetrs's (the row interchanges in dgetrf's
 * order, then column-oriented substitutions, skipping a zero entry of the
 * right-hand side as dtrsm does). */
#ifndef MP_ODE_LU_H
#define MP_ODE_LU_H

#include <complex.h>
#include <math.h>
#include <stddef.h>

#define MP_ODE_LU_SMALL 16 /* by hand below this size, by LAPACK from it */
#define MP_ODE_BAND_WIDE 3 /* see mp_ode_band_pays */

/* Contract: whether an n x n matrix of band ml + mu is factorised in band
 * form (radau): where MP_ODE_BAND_WIDE (ml + mu + 1) <= n and n is not small
 * (MP_ODE_LU_SMALL); below, the dense LU is as cheap.  Python's
 * _validate.band_of_pattern reads both numbers from _core. */
static inline int mp_ode_band_pays(size_t n, size_t ml, size_t mu)
{
    return n >= MP_ODE_LU_SMALL && MP_ODE_BAND_WIDE * (ml + mu + 1) <= n;
}

/* LAPACK (Fortran calling convention): the factorisations radau and gauss4
 * call, and the solves below for MP_ODE_LU_SMALL and larger */
extern void dgetrf_(const int *m, const int *n, double *a, const int *lda, int *ipiv, int *info);
extern void zgetrf_(const int *m, const int *n, double complex *a, const int *lda, int *ipiv,
                    int *info);
extern void dgetrs_(const char *trans, const int *n, const int *nrhs, const double *a,
                    const int *lda, const int *ipiv, double *b, const int *ldb, int *info);
extern void zgetrs_(const char *trans, const int *n, const int *nrhs, const double complex *a,
                    const int *lda, const int *ipiv, double complex *b, const int *ldb,
                    int *info);

/* LAPACK's band factorisations: radau on a banded problem
 * (mp_ode_problem.banded), A in band storage AB (column-major, leading
 * dimension ldab = 2 kl + ku + 1, A_ij at AB[kl + ku + i - j + j ldab]).
 * Their solves are by hand (mp_ode_gbtrs below) at every size: dgbtrs calls
 * BLAS's dger once per column, whose call costs more than the column's few
 * products (the 200-state Brusselator at band 2 + 2: radau 2.x faster). */
extern void dgbtrf_(const int *m, const int *n, const int *kl, const int *ku, double *ab,
                    const int *ldab, int *ipiv, int *info);
extern void zgbtrf_(const int *m, const int *n, const int *kl, const int *ku,
                    double complex *ab, const int *ldab, int *ipiv, int *info);

/* Contract: b := A^-1 b for the n x n matrix A whose factors P A = L U are
 * in LU (column-major, leading dimension n, L unit lower) with 1-based
 * pivots ipiv, as dgetrs("N") with nrhs = 1 computes it. */
static inline void mp_ode_getrs(int n, const double *LU, const int *ipiv, double *b)
{
    if (n >= MP_ODE_LU_SMALL) {
        int one = 1, info;
        dgetrs_("N", &n, &one, LU, &n, ipiv, b, &n, &info);
        return;
    }
    for (int i = 0; i < n; i++) {
        int p = ipiv[i] - 1;
        if (p != i) {
            double s = b[i];
            b[i] = b[p];
            b[p] = s;
        }
    }
    for (int k = 0; k < n; k++) {
        double bk = b[k];
        if (bk == 0.0) continue;
        const double *col = LU + (size_t)k * (size_t)n;
        for (int i = k + 1; i < n; i++) b[i] -= bk * col[i];
    }
    for (int k = n - 1; k >= 0; k--) {
        if (b[k] == 0.0) continue;
        const double *col = LU + (size_t)k * (size_t)n;
        double bk = b[k] /= col[k];
        for (int i = 0; i < k; i++) b[i] -= bk * col[i];
    }
}

/* Contract: the complex counterpart, as zgetrs("N") with nrhs = 1: products
 * by the plain formula (as Fortran's), quotients by Smith's, which neither
 * overflows nor underflows where the quotient is representable. */
static inline void mp_ode_zgetrs(int n, const double complex *LU, const int *ipiv,
                                 double complex *b)
{
    if (n >= MP_ODE_LU_SMALL) {
        int one = 1, info;
        zgetrs_("N", &n, &one, LU, &n, ipiv, b, &n, &info);
        return;
    }
    for (int i = 0; i < n; i++) {
        int p = ipiv[i] - 1;
        if (p != i) {
            double complex s = b[i];
            b[i] = b[p];
            b[p] = s;
        }
    }
    for (int k = 0; k < n; k++) {
        double br = creal(b[k]), bi = cimag(b[k]);
        if (br == 0.0 && bi == 0.0) continue;
        const double complex *col = LU + (size_t)k * (size_t)n;
        for (int i = k + 1; i < n; i++) {
            double ar = creal(col[i]), ai = cimag(col[i]);
            b[i] = CMPLX(creal(b[i]) - (br * ar - bi * ai), cimag(b[i]) - (br * ai + bi * ar));
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        double br = creal(b[k]), bi = cimag(b[k]);
        if (br == 0.0 && bi == 0.0) continue;
        const double complex *col = LU + (size_t)k * (size_t)n;
        double c = creal(col[k]), d = cimag(col[k]), qr, qi;
        if (fabs(c) >= fabs(d)) { /* Smith: divide by the larger part */
            double r = d / c, den = c + d * r;
            qr = (br + bi * r) / den;
            qi = (bi - br * r) / den;
        } else {
            double r = c / d, den = c * r + d;
            qr = (br * r + bi) / den;
            qi = (bi * r - br) / den;
        }
        b[k] = CMPLX(qr, qi);
        for (int i = 0; i < k; i++) {
            double ar = creal(col[i]), ai = cimag(col[i]);
            b[i] = CMPLX(creal(b[i]) - (qr * ar - qi * ai), cimag(b[i]) - (qr * ai + qi * ar));
        }
    }
}

/* Contract: b := A^-1 b for the n x n band matrix A (kl sub-, ku
 * super-diagonals) whose factors dgbtrf left in AB (leading dimension ld =
 * 2 kl + ku + 1) with 1-based pivots ipiv, as dgbtrs("N") with nrhs = 1
 * computes it: L's columns applied with their interchanges in dgbtrf's
 * order (dger's updates, skipping a zero entry as dger does), then U
 * (bandwidth kl + ku) by rows: each entry of the solution one sum of at
 * most kl + ku products, accumulated in a register (dtbsv's columns store
 * into b at every product), times dinv[i] = 1 / U_ii (mp_ode_gbdinv: a
 * product where dtbsv divides, the solves outnumbering the factorisations
 * tenfold and more). */
static inline void mp_ode_gbtrs(int n, int kl, int ku, const double *AB, int ld, const int *ipiv,
                                const double *dinv, double *b)
{
    int k = kl + ku;
    for (int j = 0; kl > 0 && j < n - 1; j++) {
        int lm = kl < n - 1 - j ? kl : n - 1 - j, p = ipiv[j] - 1;
        if (p != j) {
            double s = b[j];
            b[j] = b[p];
            b[p] = s;
        }
        double bj = b[j];
        if (bj == 0.0) continue;
        const double *l = AB + (size_t)j * (size_t)ld + k + 1;
        for (int r = 0; r < lm; r++) b[j + 1 + r] -= bj * l[r];
    }
    /* U by rows: U_ij = AB[k + i + j (ld - 1)], a row's entries ld - 1 apart */
    for (int i = n - 1; i >= 0; i--) {
        const double *row = AB + (size_t)i * (size_t)ld + k;
        int m = k < n - 1 - i ? k : n - 1 - i;
        double s = b[i];
        for (int c = 1; c <= m; c++) s -= row[(size_t)c * (size_t)(ld - 1)] * b[i + c];
        b[i] = s * dinv[i];
    }
}

/* Contract: dinv[i] = 1 / U_ii of dgbtrf's factors in AB (kl + ku super-
 * diagonals, leading dimension ld), for mp_ode_gbtrs. */
static inline void mp_ode_gbdinv(int n, int k, const double *AB, int ld, double *dinv)
{
    for (int i = 0; i < n; i++) dinv[i] = 1.0 / AB[(size_t)i * (size_t)ld + k];
}

/* Contract: the complex counterpart of mp_ode_gbdinv: 1 / U_ii by Smith's
 * formula, which neither overflows nor underflows where it is
 * representable. */
static inline void mp_ode_zgbdinv(int n, int k, const double complex *AB, int ld,
                                  double complex *dinv)
{
    for (int i = 0; i < n; i++) {
        double complex u = AB[(size_t)i * (size_t)ld + k];
        double c = creal(u), d = cimag(u);
        if (fabs(c) >= fabs(d)) {
            double r = d / c, den = c + d * r;
            dinv[i] = CMPLX(1.0 / den, -r / den);
        } else {
            double r = c / d, den = c * r + d;
            dinv[i] = CMPLX(r / den, -1.0 / den);
        }
    }
}

/* Contract: the complex counterpart of mp_ode_gbtrs (zgbtrf's factors, dinv
 * from mp_ode_zgbdinv), its products plain (as Fortran's). */
static inline void mp_ode_zgbtrs(int n, int kl, int ku, const double complex *AB, int ld,
                                 const int *ipiv, const double complex *dinv, double complex *b)
{
    int k = kl + ku;
    for (int j = 0; kl > 0 && j < n - 1; j++) {
        int lm = kl < n - 1 - j ? kl : n - 1 - j, p = ipiv[j] - 1;
        if (p != j) {
            double complex s = b[j];
            b[j] = b[p];
            b[p] = s;
        }
        double br = creal(b[j]), bi = cimag(b[j]);
        if (br == 0.0 && bi == 0.0) continue;
        const double complex *l = AB + (size_t)j * (size_t)ld + k + 1;
        for (int r = 0; r < lm; r++) {
            double ar = creal(l[r]), ai = cimag(l[r]);
            double complex *x = b + j + 1 + r;
            *x = CMPLX(creal(*x) - (br * ar - bi * ai), cimag(*x) - (br * ai + bi * ar));
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        const double complex *row = AB + (size_t)i * (size_t)ld + k;
        int m = k < n - 1 - i ? k : n - 1 - i;
        double br = creal(b[i]), bi = cimag(b[i]);
        for (int c = 1; c <= m; c++) {
            double complex a = row[(size_t)c * (size_t)(ld - 1)], x = b[i + c];
            double ar = creal(a), ai = cimag(a), xr = creal(x), xi = cimag(x);
            br -= ar * xr - ai * xi;
            bi -= ar * xi + ai * xr;
        }
        double dr = creal(dinv[i]), di = cimag(dinv[i]);
        b[i] = CMPLX(br * dr - bi * di, br * di + bi * dr);
    }
}

#endif
