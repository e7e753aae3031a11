/* Whether det, the determinant of a k x k block of A whose entries' absolute
 * values sum to asum, is clearly away from 0 and from overflow:
 * |det| > k eps asum^k and DBL_MIN < |det| <= DBL_MAX (false for a NaN). */
static MP_INLINE int mp_closed_ok(double det, double asum, int k)
{
    double tol = k * DBL_EPSILON;
    for (int i = 0; i < k; i++) tol *= asum;
    const double d = fabs(det);
    return d > tol && d > DBL_MIN && d <= DBL_MAX;
}

/* mp_closed_ok(det, |det|, 1), the test of a 1 x 1 block: whether det is a
 * normal number, DBL_MIN < |det| <= DBL_MAX (false for a NaN). */
static MP_INLINE int mp_closed_normal(double det)
{
    const double d = fabs(det);
    return d > DBL_MIN && d <= DBL_MAX;
}
