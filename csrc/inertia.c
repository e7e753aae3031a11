/* mechpy C core: inertia tensors, Steiner's theorem, symmetric 3x3 eigen-solver. */
#include "inertia.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- point masses */

int mp_inertia_point_masses(size_t nbody, size_t n, const double *m, const double *x,
                            const double *origin, double *out)
{
    for (size_t b = 0; b < nbody; b++) {
        const double *mb = m + b * n, *xb = x + b * n * 3, *o = origin + b * 3;
        double s[6] = {0, 0, 0, 0, 0, 0};   /* xx, yy, zz (as sums of squares), xy, yz, zx */
        for (size_t k = 0; k < n; k++) {
            double mk = mb[k];
            if (!(mk > 0) || !isfinite(mk)) return MP_EDOM;
            double rx = xb[3 * k] - o[0], ry = xb[3 * k + 1] - o[1], rz = xb[3 * k + 2] - o[2];
            double x2 = rx * rx, y2 = ry * ry, z2 = rz * rz;
            s[0] += mk * (y2 + z2);
            s[1] += mk * (z2 + x2);
            s[2] += mk * (x2 + y2);
            s[3] -= mk * rx * ry;
            s[4] -= mk * ry * rz;
            s[5] -= mk * rz * rx;
        }
        double *I = out + 9 * b;
        I[0] = s[0]; I[4] = s[1]; I[8] = s[2];
        I[1] = I[3] = s[3];
        I[5] = I[7] = s[4];
        I[2] = I[6] = s[5];
    }
    return MP_OK;
}

/* ---------------------------------------------------------------- Steiner */

/* Error-free transformations: a*b = p + e and a + b = s + e exactly. */
static inline double mp_two_prod(double a, double b, double *e)
{
    double p = a * b;
    *e = fma(a, b, -p);
    return p;
}

static inline double mp_two_sum(double a, double b, double *e)
{
    double s = a + b, bb = s - a;
    *e = (a - (s - bb)) + (b - bb);
    return s;
}

/* i + sign * M * g, with g = gh + gl given as a double-double; one final rounding
 * on top of an error O(eps^2) relative to the terms. */
static double mp_shift_entry(double i, double mass, double gh, double gl, int sign)
{
    double e1, e2;
    double q = mp_two_prod(mass, gh, &e1);
    double lo = e1 + mass * gl;
    if (sign < 0) { q = -q; lo = -lo; }
    double r = mp_two_sum(i, q, &e2);
    return r + (e2 + lo);
}

int mp_inertia_shift(size_t n, const double *inertia, const double *mass, const double *a,
                     int sign, double *out)
{
    for (size_t b = 0; b < n; b++) {
        const double *I = inertia + 9 * b, *v = a + 3 * b;
        double M = mass[b], *O = out + 9 * b;
        if (!isfinite(M) || M < 0) return MP_EDOM;
        double sq[3], sqe[3];
        for (int k = 0; k < 3; k++) sq[k] = mp_two_prod(v[k], v[k], &sqe[k]);
        for (int i = 0; i < 3; i++) {
            int j = (i + 1) % 3, k = (i + 2) % 3;
            double es, gh = mp_two_sum(sq[j], sq[k], &es);
            double gl = es + sqe[j] + sqe[k];
            O[4 * i] = mp_shift_entry(I[4 * i], M, gh, gl, sign);
        }
        /* off-diagonal (i, j), i < j, computed once and mirrored */
        static const int pr[3][2] = {{0, 1}, {1, 2}, {0, 2}};
        for (int t = 0; t < 3; t++) {
            int i = pr[t][0], j = pr[t][1];
            double pe, ph = mp_two_prod(v[i], v[j], &pe);
            double val = mp_shift_entry(0.5 * (I[3 * i + j] + I[3 * j + i]), M, -ph, -pe, sign);
            O[3 * i + j] = O[3 * j + i] = val;
        }
    }
    return MP_OK;
}

/* ---------------------------------------------------------------- eigen-solver */

static int mp_eigh3(const double *A, double *w, double *V)
{
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    double scale = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++) {
            double x = A[3 * i + j];
            if (!isfinite(x)) return MP_EDOM;
            if (fabs(x) > scale) scale = fabs(x);
        }
    int ex = 0;
    if (scale > 0) frexp(scale, &ex);
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++) a[i][j] = a[j][i] = ldexp(A[3 * i + j], -ex);

    int converged = 0;
    for (int sweep = 0; sweep < 60; sweep++) {
        if (a[0][1] == 0.0 && a[0][2] == 0.0 && a[1][2] == 0.0) { converged = 1; break; }
        for (int p = 0; p < 2; p++) {
            for (int q = p + 1; q < 3; q++) {
                double apq = a[p][q];
                if (apq == 0.0) continue;
                double app = a[p][p], aqq = a[q][q];
                /* negligible against both diagonal entries (or underflow): drop it */
                if (fabs(apq) <= 1e-18 * (fabs(app) + fabs(aqq)) || fabs(apq) < 1e-300) {
                    a[p][q] = a[q][p] = 0.0;
                    continue;
                }
                double theta = (aqq - app) / (2.0 * apq), t;
                if (fabs(theta) > 1e150) t = 0.5 / theta;
                else t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c, tau = s / (1.0 + c);
                a[p][p] = app - t * apq;
                a[q][q] = aqq + t * apq;
                a[p][q] = a[q][p] = 0.0;
                int r = 3 - p - q;
                double arp = a[r][p], arq = a[r][q];
                a[r][p] = a[p][r] = arp - s * (arq + tau * arp);
                a[r][q] = a[q][r] = arq + s * (arp - tau * arq);
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = vkp - s * (vkq + tau * vkp);
                    v[k][q] = vkq + s * (vkp - tau * vkq);
                }
            }
        }
    }
    if (!converged) return MP_ENOCONV;

    /* sort ascending */
    int idx[3] = {0, 1, 2};
    double d[3] = {a[0][0], a[1][1], a[2][2]};
    for (int i = 1; i < 3; i++)
        for (int j = i; j > 0 && d[idx[j]] < d[idx[j - 1]]; j--) {
            int tmp = idx[j]; idx[j] = idx[j - 1]; idx[j - 1] = tmp;
        }
    double col[3][3];
    for (int c = 0; c < 3; c++) {
        w[c] = ldexp(d[idx[c]], ex);
        for (int k = 0; k < 3; k++) col[c][k] = v[k][idx[c]];
    }
    /* sign rule on columns 1, 2; column 3 completes a right-handed frame */
    for (int c = 0; c < 2; c++) {
        int big = 0;
        for (int k = 1; k < 3; k++)
            if (fabs(col[c][k]) > fabs(col[c][big]) * (1.0 + 1e-12)) big = k;
        if (col[c][big] < 0)
            for (int k = 0; k < 3; k++) col[c][k] = -col[c][k];
    }
    col[2][0] = col[0][1] * col[1][2] - col[0][2] * col[1][1];
    col[2][1] = col[0][2] * col[1][0] - col[0][0] * col[1][2];
    col[2][2] = col[0][0] * col[1][1] - col[0][1] * col[1][0];
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++) V[3 * k + c] = col[c][k];
    return MP_OK;
}

int mp_inertia_eigh(size_t n, const double *a, double *w, double *v)
{
    for (size_t b = 0; b < n; b++) {
        int rc = mp_eigh3(a + 9 * b, w + 3 * b, v + 9 * b);
        if (rc != MP_OK) return rc;
    }
    return MP_OK;
}

/* ---------------------------------------------------------------- meshes */

/* Inertia tensor from the second moments S = int rho x x^T about the same
 * point, given as (xx, yy, zz, xy, yz, zx): I = tr(S) E - S, the diagonal
 * formed as sums of the two other moments (no cancellation). */
static void mp_inertia_from_moments(const double s[6], double *inertia)
{
    inertia[0] = s[1] + s[2];
    inertia[4] = s[2] + s[0];
    inertia[8] = s[0] + s[1];
    inertia[1] = inertia[3] = 0.0 - s[3];
    inertia[5] = inertia[7] = 0.0 - s[4];
    inertia[2] = inertia[6] = 0.0 - s[5];
}

static int mp_mesh_fail(struct mp_mesh_report *rep, int defect, int64_t face, int64_t v0,
                        int64_t v1)
{
    rep->defect = defect;
    rep->face = face;
    rep->v0 = v0;
    rep->v1 = v1;
    return MP_EMESH;
}

/* Buckets up to this size are scanned; larger ones are sorted and searched. */
#define MP_MESH_SMALL_BUCKET 16

/* Number of times `b` occurs in the outgoing list of `a` (3 meaning "more
 * than two"): a linear scan of a small bucket, two binary searches of a
 * large (sorted) one, so O(min(deg a, log deg a + 16)). */
static int mp_mesh_count(const size_t *off, const int64_t *to, int64_t a, int64_t b)
{
    size_t lo = off[a], hi = off[a + 1];
    if (hi - lo <= MP_MESH_SMALL_BUCKET) {
        int c = 0;
        for (size_t k = lo; k < hi; k++) c += (to[k] == b);
        return c > 2 ? 3 : c;
    }
    while (lo < hi) {                       /* first entry >= b */
        size_t mid = lo + (hi - lo) / 2;
        if (to[mid] < b) lo = mid + 1; else hi = mid;
    }
    size_t first = lo;
    hi = off[a + 1];
    while (lo < hi) {                       /* first entry > b */
        size_t mid = lo + (hi - lo) / 2;
        if (to[mid] <= b) lo = mid + 1; else hi = mid;
    }
    return lo - first > 2 ? 3 : (int)(lo - first);
}

/* qsort order of int64 values: ascending. */
static int mp_mesh_cmp_i64(const void *x, const void *y)
{
    int64_t a = *(const int64_t *)x, b = *(const int64_t *)y;
    return (a > b) - (a < b);
}

/* Faces between two interrupt checks in the long loops. */
#define MP_MESH_CHECK_EVERY 65536

/* Every edge shared by exactly two faces that traverse it in opposite
 * directions.  Directed edges a->b are bucketed by a (CSR), each bucket is
 * sorted, and an edge and its reverse are counted by binary search:
 * O(nf log d) time for the largest vertex degree d (a pole shared by half
 * the faces costs log nf per lookup, not nf), 3 nf + 2 nv + 1 words of
 * memory.  `interrupt` (may be NULL) is polled every MP_MESH_CHECK_EVERY
 * faces; its non-zero status is returned. */
static int mp_mesh_check_edges(size_t nv, size_t nf, const int64_t *F,
                               struct mp_mesh_report *rep, int (*interrupt)(void *),
                               void *ctx)
{
    size_t *off = calloc(nv + 1, sizeof *off);
    int64_t *to = malloc(3 * nf * sizeof *to);
    size_t *fill = malloc(nv * sizeof *fill);
    int rc = MP_OK;
    if (!off || !to || !fill) { rc = MP_ENOMEM; goto done; }
    for (size_t f = 0; f < 3 * nf; f++) off[F[f] + 1]++;
    for (size_t i = 0; i < nv; i++) off[i + 1] += off[i];
    memcpy(fill, off, nv * sizeof *fill);
    for (size_t f = 0; f < nf; f++)
        for (int e = 0; e < 3; e++) to[fill[F[3 * f + e]]++] = F[3 * f + (e + 1) % 3];
    for (size_t i = 0, done_edges = 0; i < nv; i++) {
        size_t d = off[i + 1] - off[i];
        if (d <= MP_MESH_SMALL_BUCKET) continue;
        qsort(to + off[i], d, sizeof *to, mp_mesh_cmp_i64);
        done_edges += d;
        if (interrupt && done_edges >= MP_MESH_CHECK_EVERY) {
            done_edges = 0;
            if ((rc = interrupt(ctx)) != MP_OK) goto done;
        }
    }
    for (size_t f = 0; f < nf && rc == MP_OK; f++) {
        if (interrupt && f % MP_MESH_CHECK_EVERY == MP_MESH_CHECK_EVERY - 1 &&
            (rc = interrupt(ctx)) != MP_OK)
            break;
        for (int e = 0; e < 3; e++) {
            int64_t a = F[3 * f + e], b = F[3 * f + (e + 1) % 3];
            int fw = mp_mesh_count(off, to, a, b), bw = mp_mesh_count(off, to, b, a);
            if (fw == 1 && bw == 1) continue;
            int defect = fw + bw == 1 ? MP_MESH_OPEN
                       : fw + bw > 2 ? MP_MESH_NONMANIFOLD : MP_MESH_ORIENTATION;
            rc = mp_mesh_fail(rep, defect, (int64_t)f, a, b);
            break;
        }
    }
done:
    free(off);
    free(to);
    free(fill);
    return rc;
}

/* Contract in inertia.h: validate, then Eberly's integrals in scaled coordinates. */
int mp_inertia_mesh(size_t nv, const double *X, size_t nf, const int64_t *F,
                    double *volume, double com[3], double inertia[9],
                    struct mp_mesh_report *rep, int (*interrupt)(void *), void *ctx)
{
    memset(rep, 0, sizeof *rep);
    rep->face = rep->v0 = rep->v1 = -1;
    if (nv < 4 || nf < 4) return mp_mesh_fail(rep, MP_MESH_OPEN, -1, -1, -1);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            double x = X[3 * i + k];
            if (!isfinite(x)) return MP_EDOM;
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    /* faces: index range, repeated vertices, zero area */
    for (size_t f = 0; f < nf; f++) {
        const int64_t *t = F + 3 * f;
        for (int e = 0; e < 3; e++)
            if (t[e] < 0 || (uint64_t)t[e] >= nv)
                return mp_mesh_fail(rep, MP_MESH_INDEX, (int64_t)f, t[e], -1);
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
            return mp_mesh_fail(rep, MP_MESH_REPEATED, (int64_t)f, -1, -1);
    }
    int rc = mp_mesh_check_edges(nv, nf, F, rep, interrupt, ctx);
    if (rc != MP_OK) return rc;

    /* Eberly's integrals about the bounding-box centre, in coordinates scaled
     * by a power of two near the extent (exact), so that nothing over- or
     * underflows before the results are scaled back; summed in blocks. */
    double ref[3] = {0.5 * lo[0] + 0.5 * hi[0], 0.5 * lo[1] + 0.5 * hi[1],
                     0.5 * lo[2] + 0.5 * hi[2]};
    double ext = fmax(0.5 * hi[0] - 0.5 * lo[0],
                      fmax(0.5 * hi[1] - 0.5 * lo[1], 0.5 * hi[2] - 0.5 * lo[2]));
    int ex = 0;
    if (ext > 0) frexp(ext, &ex);
    rep->extent = 2.0 * ext;
    /* differences of coordinates must exist in float64 */
    for (int k = 0; k < 3; k++)
        if (!isfinite(hi[k] - lo[k])) return mp_mesh_fail(rep, MP_MESH_RANGE, -1, -1, -1);
    /* 2^-ex as two normal factors (2^-ex alone may be subnormal or overflow);
     * (x * sa) * sb is exact */
    const double sa = ldexp(1.0, -(ex / 2)), sb = ldexp(1.0, -(ex - ex / 2));
    double tot[10] = {0}, blk[10];
    const size_t B = 2048;
    for (size_t f0 = 0; f0 < nf; f0 += B) {
        if (interrupt && f0 % MP_MESH_CHECK_EVERY == 0 && f0 && (rc = interrupt(ctx)) != MP_OK)
            return rc;
        memset(blk, 0, sizeof blk);
        size_t fend = f0 + B < nf ? f0 + B : nf;
        for (size_t f = f0; f < fend; f++) {
            const double *p0 = X + 3 * F[3 * f], *p1 = X + 3 * F[3 * f + 1],
                         *p2 = X + 3 * F[3 * f + 2];
            double x0 = (p0[0] - ref[0]) * sa * sb, y0 = (p0[1] - ref[1]) * sa * sb,
                   z0 = (p0[2] - ref[2]) * sa * sb;
            double x1 = (p1[0] - ref[0]) * sa * sb, y1 = (p1[1] - ref[1]) * sa * sb,
                   z1 = (p1[2] - ref[2]) * sa * sb;
            double x2 = (p2[0] - ref[0]) * sa * sb, y2 = (p2[1] - ref[1]) * sa * sb,
                   z2 = (p2[2] - ref[2]) * sa * sb;
            double a1 = x1 - x0, b1 = y1 - y0, c1 = z1 - z0;
            double a2 = x2 - x0, b2 = y2 - y0, c2 = z2 - z0;
            double d0 = b1 * c2 - b2 * c1, d1 = a2 * c1 - a1 * c2, d2 = a1 * b2 - a2 * b1;
            double l2 = a1 * a1 + b1 * b1 + c1 * c1, m2 = a2 * a2 + b2 * b2 + c2 * c2;
            double n2 = (a2 - a1) * (a2 - a1) + (b2 - b1) * (b2 - b1) + (c2 - c1) * (c2 - c1);
            double L2 = fmax(l2, fmax(m2, n2));
            if (sqrt(d0 * d0 + d1 * d1 + d2 * d2) <= 64 * DBL_EPSILON * L2)
                return mp_mesh_fail(rep, MP_MESH_ZERO_AREA, (int64_t)f, -1, -1);
            /* subexpressions of Eberly's "Polyhedral Mass Properties" */
            double w[3][3] = {{x0, x1, x2}, {y0, y1, y2}, {z0, z1, z2}};
            double f1[3], f2[3], f3[3], g0[3], g1[3], g2[3];
            for (int k = 0; k < 3; k++) {
                double u0 = w[k][0], u1 = w[k][1], u2 = w[k][2];
                double t0 = u0 + u1, t1 = u0 * u0, t2 = t1 + u1 * t0;
                f1[k] = t0 + u2;
                f2[k] = t2 + u2 * f1[k];
                f3[k] = u0 * t1 + u1 * t2 + u2 * f2[k];
                g0[k] = f2[k] + u0 * (f1[k] + u0);
                g1[k] = f2[k] + u1 * (f1[k] + u1);
                g2[k] = f2[k] + u2 * (f1[k] + u2);
            }
            blk[0] += d0 * f1[0];
            blk[1] += d0 * f2[0];
            blk[2] += d1 * f2[1];
            blk[3] += d2 * f2[2];
            blk[4] += d0 * f3[0];
            blk[5] += d1 * f3[1];
            blk[6] += d2 * f3[2];
            blk[7] += d0 * (y0 * g0[0] + y1 * g1[0] + y2 * g2[0]);
            blk[8] += d1 * (z0 * g0[1] + z1 * g1[1] + z2 * g2[1]);
            blk[9] += d2 * (x0 * g0[2] + x1 * g1[2] + x2 * g2[2]);
        }
        for (int k = 0; k < 10; k++) tot[k] += blk[k];
    }
    static const double mult[10] = {1.0 / 6,   1.0 / 24,  1.0 / 24,  1.0 / 24, 1.0 / 60,
                                    1.0 / 60,  1.0 / 60,  1.0 / 120, 1.0 / 120, 1.0 / 120};
    for (int k = 0; k < 10; k++) tot[k] *= mult[k];
    double V = tot[0];
    rep->volume = ldexp(V, 3 * ex);
    /* the scaled mesh fits in [-1, 1]^3: its volume is O(1) unless flat */
    if (!(fabs(V) > 8e-12)) return mp_mesh_fail(rep, MP_MESH_FLAT, -1, -1, -1);
    if (V < 0) return mp_mesh_fail(rep, MP_MESH_INSIDE_OUT, -1, -1, -1);
    double c[3] = {tot[1] / V, tot[2] / V, tot[3] / V};
    /* second moments about the centre of mass (scaled units) */
    double sxx = tot[4] - V * c[0] * c[0], syy = tot[5] - V * c[1] * c[1],
           szz = tot[6] - V * c[2] * c[2];
    double sxy = tot[7] - V * c[0] * c[1], syz = tot[8] - V * c[1] * c[2],
           szx = tot[9] - V * c[2] * c[0];
    const double sm[6] = {sxx, syy, szz, sxy, syz, szx};
    double J[9];
    mp_inertia_from_moments(sm, J);
    /* back to the input's units: lengths x 2^ex, volume x 2^3ex, inertia x 2^5ex */
    double Vout = ldexp(V, 3 * ex);
    int range_ok = isfinite(Vout) && Vout >= DBL_MIN;
    for (int k = 0; k < 9; k++) {
        double v = ldexp(J[k], 5 * ex);
        if (!isfinite(v) || (J[k] != 0.0 && fabs(v) < DBL_MIN)) range_ok = 0;
        inertia[k] = v;
    }
    if (!range_ok) return mp_mesh_fail(rep, MP_MESH_RANGE, -1, -1, -1);
    *volume = Vout;
    for (int k = 0; k < 3; k++) com[k] = ref[k] + ldexp(c[k], ex);
    return MP_OK;
}

/* ---------------------------------------------------------------- sampled density */

int mp_inertia_grid(size_t nx, size_t ny, size_t nz, const double *rho, const double h[3],
                    const double origin[3], double *mass, double com[3], double inertia[9])
{
    double ctr[3] = {0.5 * (double)(nx - 1) * h[0], 0.5 * (double)(ny - 1) * h[1],
                     0.5 * (double)(nz - 1) * h[2]};
    double s0 = 0, s1[3] = {0, 0, 0}, s2[6] = {0, 0, 0, 0, 0, 0};
    for (size_t i = 0; i < nx; i++) {
        double x = (double)i * h[0] - ctr[0];
        double p0 = 0, p1[3] = {0, 0, 0}, p2[6] = {0, 0, 0, 0, 0, 0};
        for (size_t j = 0; j < ny; j++) {
            double y = (double)j * h[1] - ctr[1];
            const double *r = rho + (i * ny + j) * nz;
            double q0 = 0, qz = 0, qzz = 0;
            for (size_t k = 0; k < nz; k++) {
                double v = r[k];
                if (!(v >= 0) || !isfinite(v)) return MP_EDOM;
                double z = (double)k * h[2] - ctr[2];
                q0 += v;
                qz += v * z;
                qzz += v * z * z;
            }
            p0 += q0;
            p1[1] += q0 * y;
            p1[2] += qz;
            p2[1] += q0 * y * y;
            p2[2] += qzz;
            p2[4] += qz * y;
        }
        s0 += p0;
        s1[0] += p0 * x;
        s1[1] += p1[1];
        s1[2] += p1[2];
        s2[0] += p0 * x * x;
        s2[1] += p2[1];
        s2[2] += p2[2];
        s2[3] += p1[1] * x;
        s2[4] += p2[4];
        s2[5] += p1[2] * x;
    }
    if (!(s0 > 0)) return MP_EDOM;
    double dv = h[0] * h[1] * h[2], M = s0 * dv;
    double c[3] = {s1[0] / s0, s1[1] / s0, s1[2] / s0};
    double sxx = (s2[0] / s0 - c[0] * c[0] + h[0] * h[0] / 12.0) * M;
    double syy = (s2[1] / s0 - c[1] * c[1] + h[1] * h[1] / 12.0) * M;
    double szz = (s2[2] / s0 - c[2] * c[2] + h[2] * h[2] / 12.0) * M;
    double sxy = (s2[3] / s0 - c[0] * c[1]) * M;
    double syz = (s2[4] / s0 - c[1] * c[2]) * M;
    double szx = (s2[5] / s0 - c[2] * c[0]) * M;
    *mass = M;
    for (int k = 0; k < 3; k++) com[k] = origin[k] + ctr[k] + c[k];
    const double sm[6] = {sxx, syy, szz, sxy, syz, szx};
    mp_inertia_from_moments(sm, inertia);
    return MP_OK;
}
