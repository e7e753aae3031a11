/* LU factorisation with partial pivoting of the n x n row-major matrix A,
 * in place; piv receives the row exchanges, dinv the inverses of the pivots
 * (the solve multiplies: no division waits on the right-hand side).  Returns
 * MP_ENONFINITE for a NaN
 * or inf entry, MP_ESINGULAR when a pivot is zero or below n eps max|A|
 * (numerically singular), MP_OK otherwise. */
static MP_INLINE int mp_lu_n(double *A, int n, int *piv, double *dinv)
{
    double amax = 0.0;
    for (int i = 0; i < n * n; i++) {
        double a = fabs(A[i]);
        if (!isfinite(a)) return MP_ENONFINITE;
        if (a > amax) amax = a;
    }
    const double tol = n * DBL_EPSILON * amax;
    for (int k = 0; k < n; k++) {
        int p = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; i++) {
            double a = fabs(A[i * n + k]);
            if (a > best) { best = a; p = i; }
        }
        if (!(best > tol)) return MP_ESINGULAR;
        piv[k] = p;
        if (p != k)
            for (int j = 0; j < n; j++) {
                double s = A[k * n + j]; A[k * n + j] = A[p * n + j]; A[p * n + j] = s;
            }
        const double inv = 1.0 / A[k * n + k];
        dinv[k] = inv;
        for (int i = k + 1; i < n; i++) {
            double l = A[i * n + k] * inv;
            A[i * n + k] = l;
            if (l != 0.0)
                for (int j = k + 1; j < n; j++) A[i * n + j] -= l * A[k * n + j];
        }
    }
    return MP_OK;
}

/* Solve A x = b in place (x holds b on entry) with the factors of mp_lu_n. */
static MP_INLINE void mp_lu_solve_n(const double *LU, int n, const int *piv,
                                    const double *dinv, double *x)
{
    for (int k = 0; k < n; k++) {
        int p = piv[k];
        if (p != k) { double s = x[k]; x[k] = x[p]; x[p] = s; }
    }
    for (int i = 1; i < n; i++) {
        double s = x[i];
        for (int j = 0; j < i; j++) s -= LU[i * n + j] * x[j];
        x[i] = s;
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = x[i];
        for (int j = i + 1; j < n; j++) s -= LU[i * n + j] * x[j];
        x[i] = s * dinv[i];
    }
}

/* The NA x NA system's (mp_gen_rhs's, the Jacobian's). */
#define mp_lu(A, piv, dinv) mp_lu_n((A), NA, (piv), (dinv))
#define mp_lu_solve(LU, piv, dinv, x) mp_lu_solve_n((LU), NA, (piv), (dinv), (x))
