/* mechpy C core: rotations.  Euler-angle sequences, quaternions, and the
 * maps between Euler-angle rates and angular velocity.
 *
 * Conventions (those of scipy.spatial.transform.Rotation):
 *   - a sequence is three axis letters from "xyz"; upper case is intrinsic
 *     (rotations about the moving axes), lower case extrinsic (fixed axes);
 *     consecutive axes differ (12 sequences of each kind);
 *   - the active matrix R of intrinsic "ABC" with angles (a1, a2, a3) is
 *     R = R_A(a1) R_B(a2) R_C(a3); of extrinsic "abc" it is
 *     R = R_c(a3) R_b(a2) R_a(a1); R maps body components to space ones;
 *   - the passive matrix (the coordinate transformation, x_body = L x_space)
 *     is L = R^T;
 *   - quaternions are scalar-last (x, y, z, w).
 *
 * Every batch function works on n items stored contiguously (n x 3 angles,
 * n x 9 row-major matrices, n x 4 quaternions).  No function allocates. */
#ifndef MP_ROTATION_H
#define MP_ROTATION_H

#include <stddef.h>

/* A parsed Euler sequence. */
struct mp_rotation_seq {
    int axes[3];    /* 0 = x, 1 = y, 2 = z, in the order written */
    int extrinsic;  /* 1 for lower-case (fixed axes), 0 for upper case */
};

/* Parse "ZXZ", "xyz", ...; MP_EDOM if the string is not one of the 24. */
int mp_rotation_seq_parse(const char *text, struct mp_rotation_seq *seq);

/* Matrices (n x 9) from Euler angles (n x 3); passive != 0 gives R^T. */
int mp_rotation_euler_matrix(size_t n, const double *angles, const struct mp_rotation_seq *seq,
                             int passive, double *R);

/* Euler angles (n x 3) from matrices (n x 9).  Each matrix must satisfy
 * max|R R^T - I| <= orth_tol and det R > 0, else MP_EDOM with *bad set to
 * its index.  The middle angle is in [0, pi] (proper Euler) or
 * [-pi/2, pi/2] (Tait-Bryan), the others in [-pi, pi].  The angles are
 * atan2 of pairs of entries (exact to round-off while the sine of the middle
 * angle's distance from lock is a normal number).  At gimbal lock (that sine
 * below DBL_MIN, or the distance within lock_tol radians) the third angle is
 * set to 0, the first read from the rest, and *nlock counts such items. */
int mp_rotation_euler_angles(size_t n, const double *R, const struct mp_rotation_seq *seq,
                             int passive, double orth_tol, double lock_tol, double *angles,
                             size_t *nlock, size_t *bad);

/* Unit quaternions (n x 4) from matrices (n x 9); the same orthogonality
 * check as above.  Markley's/Shepperd's method: the largest of
 * (trace, R00, R11, R22) picks the stable formula. */
int mp_rotation_quat_from_matrix(size_t n, const double *R, double orth_tol, double *q,
                                 size_t *bad);

/* Matrices (n x 9) from quaternions (n x 4), normalised first; a zero (or
 * sub-normal) quaternion is MP_EDOM with *bad set. */
int mp_rotation_matrix_from_quat(size_t n, const double *q, double *R, size_t *bad);

/* Hamilton products r = p q (n x 4 each); r may alias neither input. */
int mp_rotation_quat_multiply(size_t n, const double *p, const double *q, double *r);

/* q / |q| (n x 4); zero quaternions are MP_EDOM with *bad set. */
int mp_rotation_quat_normalize(size_t n, const double *q, double *out, size_t *bad);

/* Quaternions (n x 4) of the matrices mp_rotation_euler_matrix gives. */
int mp_rotation_quat_from_euler(size_t n, const double *angles,
                                const struct mp_rotation_seq *seq, int passive, double *q);

/* Euler angles from (not necessarily unit) quaternions: the method of
 * Bernardes and Viollet (2022); lock handling as mp_rotation_euler_angles. */
int mp_rotation_euler_from_quat(size_t n, const double *q, const struct mp_rotation_seq *seq,
                                int passive, double lock_tol, double *angles, size_t *nlock,
                                size_t *bad);

/* Angular velocity (n x 3) from Euler angles and their rates (n x 3 each):
 * body components (space == 0, omega_body = R^T omega_space) or space ones. */
int mp_rotation_angular_velocity(size_t n, const double *angles, const double *rates,
                                 const struct mp_rotation_seq *seq, int space, double *omega);

/* The inverse map: Euler-angle rates from angular velocity.  MP_ESINGULAR
 * (with *bad set) where |det J| = |sin a2| (proper) or |cos a2| (Tait-Bryan)
 * is below lock_tol. */
int mp_rotation_euler_rates(size_t n, const double *angles, const double *omega,
                            const struct mp_rotation_seq *seq, int space, double lock_tol,
                            double *rates, size_t *bad);

#endif
