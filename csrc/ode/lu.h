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

#endif
