/* Normal modes of coupled oscillators: the generalized symmetric eigenproblem
 *
 *     K v = w M v,   w = omega^2,   V^T M V = I,
 *
 * solved densely with LAPACK's dsygvd, or, for a chain (diagonal M,
 * tridiagonal K), by scaling to the symmetric tridiagonal matrix
 * M^{-1/2} K M^{-1/2} and calling LAPACK's dstemr (MRRR, O(n^2) for all
 * vectors) on chunks of eigenvalue indices.
 *
 * Output convention shared by both solvers: `w` (n) ascending eigenvalues
 * omega^2; `z` (n*n) holds mode k in z[k*n .. k*n + n - 1] (that is, the
 * row-major array is V^T; its transpose has the modes as columns).  Every
 * vector is M-normalised and signed by the rule of mp_modes_sign: its first
 * component with |v_i| > 1e-8 max_j |v_j| is positive.  With the round-off
 * bound r = mp_modes_roundoff(n) = 16 n eps and zr = zero_rtol (r when
 * zero_rtol < 0): eigenvalues with |w| <= zr max|w|, and negative ones
 * within max(r, zr) max|w| of zero, are set to exactly 0 (zero modes: free
 * translation/rotation); an eigenvalue below that means the system is
 * unstable (MP_EUNSTABLE, *w_bad receives it). */
#ifndef MP_MODES_H
#define MP_MODES_H

#include <stddef.h>

/* Dense problem.  k (n*n, symmetric) is overwritten by the vectors (layout
 * above), m (n*n, symmetric positive definite) by its Cholesky factor.
 * Returns MP_ENOTSPD when m is not positive definite, MP_ENOCONV when LAPACK
 * does not converge, MP_EUNSTABLE for a negative eigenvalue beyond round-off,
 * MP_ENONFINITE for a NaN/inf result, MP_EDOM for n < 1 or n too large. */
int mp_modes_dense(int n, double *k, double *m, double zero_rtol, double *w, double *w_bad);

/* Chain problem: K tridiagonal with diagonal `kd` (n) and off-diagonal `ke`
 * (n-1), M = diag(`md`) (n).  Inputs are not modified.  Same outputs and
 * statuses as mp_modes_dense; MP_ENOTSPD when some md[i] <= 0.  The pairs are
 * computed in chunks of max(256, n/16) indices (dstemr, RANGE = 'I');
 * `interrupt` (NULL: none) is asked between chunks and a non-OK status from
 * it (MP_EINTR) is returned at once, w and z then undefined, nothing leaked. */
int mp_modes_tridiag(int n, const double *kd, const double *ke, const double *md,
                     double zero_rtol, double *w, double *z, double *w_bad,
                     int (*interrupt)(void *), void *ctx);

/* The relative round-off bound 16 n eps used for zero modes and stability. */
double mp_modes_roundoff(int n);

/* Whether the row-major symmetric n x n matrices k and m are a chain
 * (k zero beyond the first off-diagonals, m diagonal): 1 or 0.  When 1,
 * fills kd (n), ke (n-1) and md (n).  Reads each entry once. */
int mp_modes_is_chain(int n, const double *k, const double *m,
                      double *kd, double *ke, double *md);

/* The sign rule, applied to one vector v (n). */
void mp_modes_sign(int n, double *v);

#endif
