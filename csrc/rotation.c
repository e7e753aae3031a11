/* mechpy C core: Euler sequences, quaternions, angular-velocity maps.
 * Conventions: see rotation.h. */
#include "rotation.h"

#include <float.h>
#include <math.h>

#include "mp_status.h"

#define MP_PI 3.14159265358979323846

int mp_rotation_seq_parse(const char *text, struct mp_rotation_seq *seq)
{
    int upper = 0, lower = 0;
    if (!text || !seq) return MP_EDOM;
    for (int i = 0; i < 3; i++) {
        char ch = text[i];
        if (ch >= 'X' && ch <= 'Z') {
            upper++;
            seq->axes[i] = ch - 'X';
        } else if (ch >= 'x' && ch <= 'z') {
            lower++;
            seq->axes[i] = ch - 'x';
        } else {
            return MP_EDOM;   /* also catches a string shorter than 3 */
        }
    }
    if (text[3] != '\0' || (upper != 3 && lower != 3)) return MP_EDOM;
    if (seq->axes[0] == seq->axes[1] || seq->axes[1] == seq->axes[2]) return MP_EDOM;
    seq->extrinsic = lower == 3;
    return MP_OK;
}

/* The sequence as the equivalent intrinsic one: extrinsic "abc" with angles
 * (a1, a2, a3) is intrinsic "CBA" with angles (a3, a2, a1).  perm[k] is the
 * user's index of intrinsic angle k. */
static void intrinsic_form(const struct mp_rotation_seq *seq, int axes[3], int perm[3])
{
    for (int k = 0; k < 3; k++) {
        perm[k] = seq->extrinsic ? 2 - k : k;
        axes[k] = seq->axes[perm[k]];
    }
}

/* M <- R_axis(c, s) M for a row-major 3x3 M (active rotation). */
static inline void rot_rows(int axis, double c, double s, double *M)
{
    int j = (axis + 1) % 3, k = (axis + 2) % 3;
    for (int col = 0; col < 3; col++) {
        double mj = M[3 * j + col], mk = M[3 * k + col];
        M[3 * j + col] = c * mj - s * mk;
        M[3 * k + col] = s * mj + c * mk;
    }
}

/* v <- R_axis(c, s) v. */
static inline void rot_vec(int axis, double c, double s, double *v)
{
    int j = (axis + 1) % 3, k = (axis + 2) % 3;
    double vj = v[j], vk = v[k];
    v[j] = c * vj - s * vk;
    v[k] = s * vj + c * vk;
}

int mp_rotation_euler_matrix(size_t n, const double *angles, const struct mp_rotation_seq *seq,
                             int passive, double *R)
{
    int axes[3], perm[3];
    intrinsic_form(seq, axes, perm);
    for (size_t i = 0; i < n; i++) {
        const double *a = angles + 3 * i;
        double M[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        /* R = R_0(t0) R_1(t1) R_2(t2): apply the rightmost factor first */
        for (int k = 2; k >= 0; k--) {
            double t = a[perm[k]];
            rot_rows(axes[k], cos(t), sin(t), M);
        }
        double *out = R + 9 * i;
        if (passive) {
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) out[3 * r + c] = M[3 * c + r];
        } else {
            for (int m = 0; m < 9; m++) out[m] = M[m];
        }
    }
    return MP_OK;
}

/* max |M M^T - I| <= tol and det M > 0 (and every entry finite). */
static int is_rotation(const double *M, double tol)
{
    double worst = 0.0;
    for (int r = 0; r < 3; r++) {
        for (int c = r; c < 3; c++) {
            double d = M[3 * r] * M[3 * c] + M[3 * r + 1] * M[3 * c + 1] +
                       M[3 * r + 2] * M[3 * c + 2] - (r == c ? 1.0 : 0.0);
            d = fabs(d);
            if (!(d <= worst)) worst = d;   /* NaN propagates into worst */
        }
    }
    double det = M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
                 M[2] * (M[3] * M[7] - M[4] * M[6]);
    return worst <= tol && det > 0.0;
}

/* Unit quaternion of the active matrix M (row-major), or of M^T when
 * transpose != 0.  The branch follows Markley (2008), as SciPy does, so that
 * the sign agrees with scipy's Rotation.from_matrix. */
static void quat_of(const double *M, int transpose, double *q)
{
#define E(r, c) (transpose ? M[3 * (c) + (r)] : M[3 * (r) + (c)])
    double tr = E(0, 0) + E(1, 1) + E(2, 2);
    int choice = 3;
    double best = tr;
    for (int d = 0; d < 3; d++) {
        if (E(d, d) > best) {
            best = E(d, d);
            choice = d;
        }
    }
    if (choice != 3) {
        int i = choice, j = (i + 1) % 3, k = (j + 1) % 3;
        q[i] = 1.0 - tr + 2.0 * E(i, i);
        q[j] = E(j, i) + E(i, j);
        q[k] = E(k, i) + E(i, k);
        q[3] = E(k, j) - E(j, k);
    } else {
        q[0] = E(2, 1) - E(1, 2);
        q[1] = E(0, 2) - E(2, 0);
        q[2] = E(1, 0) - E(0, 1);
        q[3] = 1.0 + tr;
    }
#undef E
    double nrm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int m = 0; m < 4; m++) q[m] /= nrm;
}

int mp_rotation_quat_from_matrix(size_t n, const double *R, double orth_tol, double *q,
                                 size_t *bad)
{
    for (size_t i = 0; i < n; i++) {
        if (!is_rotation(R + 9 * i, orth_tol)) {
            if (bad) *bad = i;
            return MP_EDOM;
        }
        quat_of(R + 9 * i, 0, q + 4 * i);
    }
    return MP_OK;
}

int mp_rotation_matrix_from_quat(size_t n, const double *q, double *R, size_t *bad)
{
    for (size_t i = 0; i < n; i++) {
        const double *p = q + 4 * i;
        double n2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
        if (!(n2 > 1e-300) || !isfinite(n2)) {
            if (bad) *bad = i;
            return MP_EDOM;
        }
        double s = 2.0 / n2;
        double x = p[0], y = p[1], z = p[2], w = p[3];
        double xx = s * x * x, yy = s * y * y, zz = s * z * z;
        double xy = s * x * y, xz = s * x * z, yz = s * y * z;
        double xw = s * x * w, yw = s * y * w, zw = s * z * w;
        double *M = R + 9 * i;
        M[0] = 1.0 - yy - zz; M[1] = xy - zw;       M[2] = xz + yw;
        M[3] = xy + zw;       M[4] = 1.0 - xx - zz; M[5] = yz - xw;
        M[6] = xz - yw;       M[7] = yz + xw;       M[8] = 1.0 - xx - yy;
    }
    return MP_OK;
}

/* r = p q (Hamilton product, scalar last). */
static inline void qmul(const double *p, const double *q, double *r)
{
    double px = p[0], py = p[1], pz = p[2], pw = p[3];
    double qx = q[0], qy = q[1], qz = q[2], qw = q[3];
    r[0] = pw * qx + px * qw + py * qz - pz * qy;
    r[1] = pw * qy - px * qz + py * qw + pz * qx;
    r[2] = pw * qz + px * qy - py * qx + pz * qw;
    r[3] = pw * qw - px * qx - py * qy - pz * qz;
}

int mp_rotation_quat_multiply(size_t n, const double *p, const double *q, double *r)
{
    for (size_t i = 0; i < n; i++) qmul(p + 4 * i, q + 4 * i, r + 4 * i);
    return MP_OK;
}

int mp_rotation_quat_normalize(size_t n, const double *q, double *out, size_t *bad)
{
    for (size_t i = 0; i < n; i++) {
        const double *p = q + 4 * i;
        /* scale first so that huge or tiny quaternions do not over/underflow */
        double big = 0.0;
        for (int m = 0; m < 4; m++)
            if (fabs(p[m]) > big) big = fabs(p[m]);
        if (!(big > 0.0) || !isfinite(big)) {
            if (bad) *bad = i;
            return MP_EDOM;
        }
        double u[4], n2 = 0.0;
        for (int m = 0; m < 4; m++) {
            u[m] = p[m] / big;
            n2 += u[m] * u[m];
        }
        double inv = 1.0 / sqrt(n2);
        for (int m = 0; m < 4; m++) out[4 * i + m] = u[m] * inv;
    }
    return MP_OK;
}

int mp_rotation_quat_from_euler(size_t n, const double *angles,
                                const struct mp_rotation_seq *seq, int passive, double *q)
{
    int axes[3], perm[3];
    intrinsic_form(seq, axes, perm);
    for (size_t i = 0; i < n; i++) {
        const double *a = angles + 3 * i;
        /* q = q_0(t0) q_1(t1) q_2(t2) for the intrinsic form */
        double acc[4] = {0, 0, 0, 1}, tmp[4];
        for (int k = 0; k < 3; k++) {
            double h = 0.5 * a[perm[k]];
            double e[4] = {0, 0, 0, cos(h)};
            e[axes[k]] = sin(h);
            qmul(acc, e, tmp);
            for (int m = 0; m < 4; m++) acc[m] = tmp[m];
        }
        double *out = q + 4 * i;
        double sgn = passive ? -1.0 : 1.0;
        out[0] = sgn * acc[0];
        out[1] = sgn * acc[1];
        out[2] = sgn * acc[2];
        out[3] = acc[3];
    }
    return MP_OK;
}

static inline double wrap_pi(double t)
{
    if (t < -MP_PI) return t + 2.0 * MP_PI;
    if (t > MP_PI) return t - 2.0 * MP_PI;
    return t;
}

/* sqrt(x^2 + y^2) without hypot's cost where the sum of squares is a normal
 * number (the usual case), hypot where it is not (nothing underflows). */
static inline double norm2(double x, double y)
{
    double s = x * x + y * y;
    return s >= DBL_MIN && s <= DBL_MAX ? sqrt(s) : hypot(x, y);
}

/* Angles of the active rotation with unit-or-not quaternion q (Bernardes and
 * Viollet 2022, "Quaternion to Euler angles conversion: a direct, general
 * and computationally efficient method", PLoS ONE 17(11): e0276302).  The
 * paper's algorithm is for extrinsic sequences; intrinsic ones are the
 * reversed sequence with reversed angles.  tl = tan(lock_tol / 2) (the
 * gimbal-lock band).  Returns 1 at gimbal lock. */
static int euler_of_quat(const double *q, const int axes_in[3], int extrinsic, double tl,
                         double *out)
{
    int i, j, k;
    if (extrinsic) {
        i = axes_in[0]; j = axes_in[1]; k = axes_in[2];
    } else {
        i = axes_in[2]; j = axes_in[1]; k = axes_in[0];
    }
    int proper = i == k;
    if (proper) k = 3 - i - j;
    int sign = (i - j) * (j - k) * (k - i) / 2;   /* +1 even, -1 odd permutation */

    double a, b, c, d;
    if (proper) {
        a = q[3]; b = q[i]; c = q[j]; d = q[k] * sign;
    } else {
        a = q[3] - q[j]; b = q[i] + q[k] * sign; c = q[j] + q[3]; d = q[k] * sign - q[i];
    }
    /* theta = 2 atan2(|(c, d)|, |(a, b)|): accurate near 0 and pi, unlike acos;
     * the norms so that nothing underflows before theta does (norm2) */
    double t[3];
    /* the two atan2 of the components first: they run while the square roots
     * of the norms complete, which the third waits for (10^6 conversions:
     * 163 ms with the third first, 116 ms so; SciPy's Rotation 136 ms) */
    double half_sum = atan2(b, a);
    double half_diff = atan2(-d, c);
    double ncd = norm2(c, d), nab = norm2(a, b);
    t[1] = 2.0 * atan2(ncd, nab);
    /* tan(theta/2) = ncd/nab and tan((pi - theta)/2) = nab/ncd: lock only where the
     * smaller norm is no longer a normal number relative to the larger (the first and
     * third angles are then indeterminate) or within lock_tol of it (tl = tan(lock_tol/2),
     * the caller's) */
    double big = ncd > nab ? ncd : nab; /* both >= 0 and finite: no fmax call */
    int safe1 = ncd > tl * nab && ncd >= DBL_MIN * big;
    int safe2 = nab > tl * ncd && nab >= DBL_MIN * big;
    int lock = !(safe1 && safe2);
    if (!lock) {
        t[0] = half_sum + half_diff;
        t[2] = half_sum - half_diff;
    } else if (extrinsic) {
        t[2] = 0.0;
        t[0] = !safe1 ? 2.0 * half_sum : 2.0 * half_diff;
    } else {
        /* the reversed sequence's first angle is the user's third one */
        t[0] = 0.0;
        t[2] = !safe1 ? 2.0 * half_sum : -2.0 * half_diff;
    }
    if (!proper) {
        t[2] *= sign;
        t[1] -= 0.5 * MP_PI;
    }
    if (!extrinsic) {
        double s = t[0];
        t[0] = t[2];
        t[2] = s;
    }
    for (int m = 0; m < 3; m++) out[m] = wrap_pi(t[m]);
    /* -0.0 from a sign flip reads oddly; the value is the same */
    if (lock && out[2] == 0.0) out[2] = 0.0;
    return lock;
}

int mp_rotation_euler_from_quat(size_t n, const double *q, const struct mp_rotation_seq *seq,
                                int passive, double lock_tol, double *angles, size_t *nlock,
                                size_t *bad)
{
    size_t locks = 0;
    double tl = lock_tol < MP_PI ? tan(0.5 * lock_tol) : INFINITY; /* once, not per angle */
    for (size_t i = 0; i < n; i++) {
        const double *p = q + 4 * i;
        double u[4] = {p[0], p[1], p[2], p[3]};
        double n2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3];
        if (!(n2 > 1e-300) || !isfinite(n2)) {
            if (bad) *bad = i;
            return MP_EDOM;
        }
        if (passive) {
            u[0] = -u[0]; u[1] = -u[1]; u[2] = -u[2];
        }
        locks += (size_t)euler_of_quat(u, seq->axes, seq->extrinsic, tl, angles + 3 * i);
    }
    if (nlock) *nlock = locks;
    return MP_OK;
}

/* Intrinsic-form angles t of the active matrix A = R_i(t0) R_j(t1) R_k(t2)
 * (row-major; ax = (i, j, k)) read from atan2 of pairs of entries, each pair
 * proportional to sin and cos of its angle with the same factor, so that the
 * first and third angles are exact (to round-off) as long as that factor
 * (`small`, sin t1 for proper sequences, cos t1 for Tait-Bryan ones) is a
 * normal number.  At lock (small < DBL_MIN or <= sin(lock_tol)) the user's
 * third angle is set to 0: t2 for an intrinsic sequence (zero_first = 0), t0
 * for an extrinsic one (zero_first = 1), and the other one is read from
 * what is left of A.  Returns 1 at lock. */
static int euler_of_matrix(const double *A, const int ax[3], int zero_first, double lock_tol,
                           double t[3])
{
#define E(r, c) A[3 * (r) + (c)]
    int i = ax[0], j = ax[1], k = ax[2], l = 3 - i - j;
    double sgn = j == (i + 1) % 3 ? 1.0 : -1.0;   /* +1 when (i, j, l) is cyclic */
    double small;
    if (i == k) {   /* proper Euler: R_i R_j R_i */
        small = hypot(E(i, j), E(i, l));
        t[1] = atan2(small, E(i, i));
        t[2] = atan2(E(i, j), sgn * E(i, l));
        t[0] = atan2(E(j, i), -sgn * E(l, i));
    } else {        /* Tait-Bryan: k = l */
        small = hypot(E(i, i), E(i, j));
        t[1] = atan2(sgn * E(i, k), small);
        t[2] = atan2(-sgn * E(i, j), E(i, i));
        t[0] = atan2(-sgn * E(j, k), E(k, k));
    }
    double sl = lock_tol < 0.5 * MP_PI ? sin(lock_tol) : 1.0;
    if (small >= DBL_MIN && small > sl) return 0;
    /* lock: Rj = R_j(t1); intrinsic: R_i(t0) = A Rj^T; extrinsic: R_k(t2) = Rj^T A */
    double Rj[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, N[9];
    rot_rows(j, cos(t[1]), sin(t[1]), Rj);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double acc = 0.0;
            for (int m = 0; m < 3; m++)
                acc += zero_first ? Rj[3 * m + r] * E(m, c) : E(r, m) * Rj[3 * c + m];
            N[3 * r + c] = acc;
        }
    int axis = zero_first ? k : i, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    double free_angle = atan2(N[3 * a2 + a1], N[3 * a1 + a1]);
    if (zero_first) {
        t[0] = 0.0;
        t[2] = free_angle;
    } else {
        t[0] = free_angle;
        t[2] = 0.0;
    }
    return 1;
#undef E
}

int mp_rotation_euler_angles(size_t n, const double *R, const struct mp_rotation_seq *seq,
                             int passive, double orth_tol, double lock_tol, double *angles,
                             size_t *nlock, size_t *bad)
{
    int axes[3], perm[3];
    intrinsic_form(seq, axes, perm);
    size_t locks = 0;
    for (size_t i = 0; i < n; i++) {
        const double *M = R + 9 * i;
        if (!is_rotation(M, orth_tol)) {
            if (bad) *bad = i;
            return MP_EDOM;
        }
        double A[9], t[3];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) A[3 * r + c] = passive ? M[3 * c + r] : M[3 * r + c];
        locks += (size_t)euler_of_matrix(A, axes, seq->extrinsic, lock_tol, t);
        double *out = angles + 3 * i;
        for (int k = 0; k < 3; k++) out[perm[k]] = t[k];
        /* -0.0 from a sign flip reads oddly; the value is the same */
        for (int k = 0; k < 3; k++)
            if (out[k] == 0.0) out[k] = 0.0;
    }
    if (nlock) *nlock = locks;
    return MP_OK;
}

/* Columns of the rate-to-omega map in the intrinsic form: omega = sum_k
 * rate_k J_k.  Space components: J_0 = e_0, J_1 = R_0 e_1, J_2 = R_0 R_1 e_2;
 * body components: J_2 = e_2, J_1 = R_2^T e_1, J_0 = R_2^T R_1^T e_0. */
static void rate_columns(const double *a, const int axes[3], const int perm[3], int space,
                         double J[3][3])
{
    double c[3], s[3];
    for (int k = 0; k < 3; k++) {
        double t = a[perm[k]];
        c[k] = cos(t);
        s[k] = sin(t);
    }
    for (int k = 0; k < 3; k++) {
        J[k][0] = J[k][1] = J[k][2] = 0.0;
        J[k][axes[k]] = 1.0;
    }
    if (space) {
        rot_vec(axes[0], c[0], s[0], J[1]);
        rot_vec(axes[1], c[1], s[1], J[2]);
        rot_vec(axes[0], c[0], s[0], J[2]);
    } else {
        rot_vec(axes[2], c[2], -s[2], J[1]);
        rot_vec(axes[1], c[1], -s[1], J[0]);
        rot_vec(axes[2], c[2], -s[2], J[0]);
    }
}

int mp_rotation_angular_velocity(size_t n, const double *angles, const double *rates,
                                 const struct mp_rotation_seq *seq, int space, double *omega)
{
    int axes[3], perm[3];
    intrinsic_form(seq, axes, perm);
    for (size_t i = 0; i < n; i++) {
        double J[3][3];
        rate_columns(angles + 3 * i, axes, perm, space, J);
        const double *r = rates + 3 * i;
        double *w = omega + 3 * i;
        for (int m = 0; m < 3; m++)
            w[m] = J[0][m] * r[perm[0]] + J[1][m] * r[perm[1]] + J[2][m] * r[perm[2]];
    }
    return MP_OK;
}

static inline void cross(const double *u, const double *v, double *w)
{
    w[0] = u[1] * v[2] - u[2] * v[1];
    w[1] = u[2] * v[0] - u[0] * v[2];
    w[2] = u[0] * v[1] - u[1] * v[0];
}

int mp_rotation_euler_rates(size_t n, const double *angles, const double *omega,
                            const struct mp_rotation_seq *seq, int space, double lock_tol,
                            double *rates, size_t *bad)
{
    int axes[3], perm[3];
    intrinsic_form(seq, axes, perm);
    for (size_t i = 0; i < n; i++) {
        double J[3][3], C[3][3];
        rate_columns(angles + 3 * i, axes, perm, space, J);
        /* rows of J^{-1} are the cross products of the columns over det */
        cross(J[1], J[2], C[0]);
        cross(J[2], J[0], C[1]);
        cross(J[0], J[1], C[2]);
        double det = J[0][0] * C[0][0] + J[0][1] * C[0][1] + J[0][2] * C[0][2];
        if (!(fabs(det) > lock_tol)) {
            if (bad) *bad = i;
            return MP_ESINGULAR;
        }
        const double *w = omega + 3 * i;
        for (int k = 0; k < 3; k++)
            rates[3 * i + perm[k]] = (C[k][0] * w[0] + C[k][1] * w[1] + C[k][2] * w[2]) / det;
    }
    return MP_OK;
}
