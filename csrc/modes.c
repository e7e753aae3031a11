/* Normal modes: the generalized symmetric eigenproblem K v = omega^2 M v.
 * See modes.h for the conventions.  LAPACK is called through its Fortran
 * symbols (OpenBLAS's liblapack); the prototypes are declared here. */
#include "modes.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "mp_status.h"

/* LAPACK (Fortran calling convention, gfortran's hidden string lengths). */
extern void dsygvd_(const int *itype, const char *jobz, const char *uplo, const int *n,
                    double *a, const int *lda, double *b, const int *ldb, double *w,
                    double *work, const int *lwork, int *iwork, const int *liwork, int *info,
                    size_t jobz_len, size_t uplo_len);
extern void dstemr_(const char *jobz, const char *range, const int *n, double *d, double *e,
                    const double *vl, const double *vu, const int *il, const int *iu, int *m,
                    double *w, double *z, const int *ldz, const int *nzc, int *isuppz,
                    int *tryrac, double *work, const int *lwork, int *iwork,
                    const int *liwork, int *info, size_t jobz_len, size_t range_len);
extern void dstevd_(const char *jobz, const int *n, double *d, double *e, double *z,
                    const int *ldz, double *work, const int *lwork, int *iwork,
                    const int *liwork, int *info, size_t jobz_len);

/* A LAPACK workspace, sized from a workspace query (wq, iwq). */
struct mp_modes_work {
    double *work;
    int *iwork;
    int lwork, liwork;
};

static int mp_modes_work_alloc(struct mp_modes_work *ws, double wq, int iwq)
{
    ws->work = NULL;
    ws->iwork = NULL;
    if (!(wq < (double)INT_MAX - 1.0)) return MP_ENOMEM;   /* beyond LAPACK's int sizes */
    ws->lwork = (int)wq + 1;
    ws->liwork = iwq > 1 ? iwq : 1;
    ws->work = malloc((size_t)ws->lwork * sizeof *ws->work);
    ws->iwork = malloc((size_t)ws->liwork * sizeof *ws->iwork);
    if (!ws->work || !ws->iwork) {
        free(ws->work);
        free(ws->iwork);
        ws->work = NULL;
        ws->iwork = NULL;
        return MP_ENOMEM;
    }
    return MP_OK;
}

static void mp_modes_work_free(struct mp_modes_work *ws)
{
    free(ws->work);
    free(ws->iwork);
}

/* Relative threshold below which a vector component does not decide the sign. */
#define MP_MODES_SIGN_RTOL 1e-8

void mp_modes_sign(int n, double *v)
{
    double vmax = 0.0;
    for (int i = 0; i < n; i++) {
        double a = fabs(v[i]);
        if (a > vmax) vmax = a;
    }
    double thr = MP_MODES_SIGN_RTOL * vmax;
    for (int i = 0; i < n; i++) {
        if (fabs(v[i]) > thr) {
            if (v[i] < 0.0)
                for (int j = 0; j < n; j++) v[j] = -v[j];
            return;
        }
    }
}

double mp_modes_roundoff(int n)
{
    return 16.0 * (double)n * DBL_EPSILON;
}

/* Shared post-processing: finiteness, stability, zero-mode clamp, signs. */
static int mp_modes_finish(int n, double zero_rtol, double *w, double *z, double *w_bad)
{
    double wmax = 0.0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(w[i])) return MP_ENONFINITE;
        if (fabs(w[i]) > wmax) wmax = fabs(w[i]);
    }
    double tol = mp_modes_roundoff(n) * wmax;
    double ztol = (zero_rtol < 0.0 ? mp_modes_roundoff(n) : zero_rtol) * wmax;
    for (int i = 0; i < n; i++) {
        if (w[i] < -(tol > ztol ? tol : ztol)) {
            if (w_bad) *w_bad = w[i];
            return MP_EUNSTABLE;
        }
        if (w[i] < 0.0 || w[i] <= ztol) w[i] = 0.0;
    }
    for (size_t k = 0; k < (size_t)n; k++) {
        double *v = z + k * (size_t)n;
        for (int i = 0; i < n; i++)
            if (!isfinite(v[i])) return MP_ENONFINITE;
        mp_modes_sign(n, v);
    }
    return MP_OK;
}

int mp_modes_dense(int n, double *k, double *m, double zero_rtol, double *w, double *w_bad)
{
    if (n < 1 || (size_t)n > (size_t)INT_MAX / 2) return MP_EDOM;
    const int itype = 1;
    int lwork = -1, liwork = -1, info = 0, iwq = 0;
    double wq = 0.0;
    dsygvd_(&itype, "V", "L", &n, k, &n, m, &n, w, &wq, &lwork, &iwq, &liwork, &info, 1, 1);
    if (info != 0) return MP_EDOM;
    struct mp_modes_work ws;
    int status = mp_modes_work_alloc(&ws, wq, iwq);
    if (status != MP_OK) return status;
    dsygvd_(&itype, "V", "L", &n, k, &n, m, &n, w, ws.work, &ws.lwork, ws.iwork, &ws.liwork,
            &info, 1, 1);
    mp_modes_work_free(&ws);
    if (info > n) return MP_ENOTSPD;
    if (info > 0) return MP_ENOCONV;
    if (info < 0) return MP_EDOM;
    return mp_modes_finish(n, zero_rtol, w, k, w_bad);
}

/* Pairs per dstemr call: all of them (RANGE = 'A', dqds for the eigenvalues)
 * up to n = 1024, where the whole solve is short; above, 128 or n/48,
 * whichever is larger (RANGE = 'I': bisection, about twice the time of
 * dqds whatever the chunk size: n = 6000 took 17.8 s in 16 chunks and 16.9 s
 * in 47 on a loaded machine), so that Ctrl-C waits for at most ~0.4 s. */
static int mp_modes_chunk(int n)
{
    if (n <= 1024) return n;
    int c = n / 48;
    return c > 128 ? c : 128;
}

/* Eigen-decomposition of the symmetric tridiagonal (d0, e0): d0 (n) and e0
 * (n, e0[n-1] unused) are read only; w gets the eigenvalues, z the unit
 * vectors (mode k in z[k*n ...]).  MRRR (dstemr, RANGE = 'I') in chunks of
 * mp_modes_chunk(n) indices, asking `interrupt` (may be NULL) between chunks:
 * its non-OK status is returned at once, everything freed.  Divide and
 * conquer (dstevd, one call) if MRRR fails on some chunk. */
static int mp_modes_stev(int n, const double *d0, const double *e0, double *w, double *z,
                         int (*interrupt)(void *), void *ctx)
{
    int chunk = mp_modes_chunk(n);
    const char *range = chunk == n ? "A" : "I";
    int m = 0, info = 0, tryrac = 1, il = 1, iu = chunk, nzc = chunk;
    int lwork = -1, liwork = -1, iwq = 0;
    double vl = 0.0, vu = 0.0, wq = 0.0;
    int *isuppz = malloc(2 * (size_t)chunk * sizeof *isuppz);
    /* d, e: dstemr's copy of the input; wt (n): its eigenvalue array, which
     * it also uses for the whole spectrum's approximations. */
    double *d = malloc(3 * (size_t)n * sizeof *d);
    if (!isuppz || !d) {
        free(isuppz);
        free(d);
        return MP_ENOMEM;
    }
    double *e = d + n, *wt = d + 2 * (size_t)n;
    for (int i = 0; i < n; i++) {
        d[i] = d0[i];
        e[i] = e0[i];
    }
    /* The workspace (18n, 10n for vectors) does not depend on the range. */
    dstemr_("V", range, &n, d, e, &vl, &vu, &il, &iu, &m, wt, z, &n, &nzc, isuppz, &tryrac,
            &wq, &lwork, &iwq, &liwork, &info, 1, 1);
    int status = MP_OK, mrrr_ok = (info == 0);
    struct mp_modes_work ws = {NULL, NULL, 0, 0};
    if (mrrr_ok) status = mp_modes_work_alloc(&ws, wq, iwq);
    for (int lo = 0; status == MP_OK && mrrr_ok && lo < n; lo += chunk) {
        if (lo > 0 && interrupt) {
            status = interrupt(ctx);
            if (status != MP_OK) break;
        }
        /* dstemr overwrites d and e: each chunk starts from the input. */
        for (int i = 0; i < n; i++) {
            d[i] = d0[i];
            e[i] = e0[i];
        }
        il = lo + 1;
        iu = lo + chunk < n ? lo + chunk : n;
        nzc = iu - il + 1;
        tryrac = 1;
        dstemr_("V", range, &n, d, e, &vl, &vu, &il, &iu, &m, wt, z + (size_t)lo * n, &n,
                &nzc, isuppz, &tryrac, ws.work, &ws.lwork, ws.iwork, &ws.liwork, &info, 1, 1);
        if (info != 0 || m != nzc) mrrr_ok = 0;
        else
            for (int i = 0; i < m; i++) w[lo + i] = wt[i];
    }
    mp_modes_work_free(&ws);
    free(isuppz);
    if (status == MP_OK && !mrrr_ok) {
        /* MRRR declined (rare): divide and conquer on the input, in one call. */
        for (int i = 0; i < n; i++) {
            w[i] = d0[i];
            e[i] = e0[i];
        }
        lwork = -1;
        liwork = -1;
        dstevd_("V", &n, w, e, z, &n, &wq, &lwork, &iwq, &liwork, &info, 1);
        if (info != 0) {
            status = MP_ENOCONV;
        } else {
            status = mp_modes_work_alloc(&ws, wq, iwq);
            if (status == MP_OK) {
                dstevd_("V", &n, w, e, z, &n, ws.work, &ws.lwork, ws.iwork, &ws.liwork, &info,
                        1);
                if (info != 0) status = MP_ENOCONV;
            }
            mp_modes_work_free(&ws);
        }
    }
    free(d);
    return status;
}

int mp_modes_tridiag(int n, const double *kd, const double *ke, const double *md,
                     double zero_rtol, double *w, double *z, double *w_bad,
                     int (*interrupt)(void *), void *ctx)
{
    if (n < 1 || (size_t)n > (size_t)INT_MAX / 2) return MP_EDOM;
    for (int i = 0; i < n; i++)
        if (!(md[i] > 0.0)) return MP_ENOTSPD;
    double *buf = malloc(3 * (size_t)n * sizeof *buf);
    if (!buf) return MP_ENOMEM;
    double *d = buf, *e = buf + n, *s = buf + 2 * (size_t)n;
    for (int i = 0; i < n; i++) s[i] = 1.0 / sqrt(md[i]);
    /* T = M^{-1/2} K M^{-1/2}: symmetric tridiagonal with the same spectrum. */
    for (int i = 0; i < n; i++) d[i] = kd[i] * s[i] * s[i];
    for (int i = 0; i + 1 < n; i++) e[i] = ke[i] * s[i] * s[i + 1];
    e[n - 1] = 0.0;
    int status = mp_modes_stev(n, d, e, w, z, interrupt, ctx);
    if (status == MP_OK) {
        /* v = M^{-1/2} u is M-orthonormal when u is orthonormal. */
        for (size_t k = 0; k < (size_t)n; k++) {
            double *v = z + k * (size_t)n;
            for (int i = 0; i < n; i++) v[i] *= s[i];
        }
        status = mp_modes_finish(n, zero_rtol, w, z, w_bad);
    }
    free(buf);
    return status;
}

int mp_modes_is_chain(int n, const double *k, const double *m,
                      double *kd, double *ke, double *md)
{
    for (size_t i = 0; i < (size_t)n; i++) {
        const double *kr = k + i * (size_t)n, *mr = m + i * (size_t)n;
        for (size_t j = 0; j < (size_t)n; j++) {
            if (j == i) {
                kd[i] = kr[j];
                md[i] = mr[j];
            } else {
                if (mr[j] != 0.0) return 0;
                if (j == i + 1) ke[i] = kr[j];
                else if (j + 1 != i && kr[j] != 0.0) return 0;
            }
        }
    }
    return 1;
}
