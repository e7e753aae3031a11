#if NA > 1
/* For each lane l: mp_lu on the NA x NA matrix A (entry (i, j) at
 * A[(i * NA + j) * MP_LANES + l]) in place, then mp_lu_solve on b (entry i at
 * b[i * MP_LANES + l]) in place; st[l] = mp_lu's status for that lane
 * (MP_ENONFINITE before MP_ESINGULAR, as mp_lu checks).  A failed lane's
 * values are computed but meaningless. */
static MP_INLINE void mp_lu_lanes(double *A, double *b, int *st)
{
    double amax[MP_LANES], tol[MP_LANES], best[MP_LANES], piv[MP_LANES], lf[MP_LANES];
    double bad[MP_LANES], sing[MP_LANES], dinv[NA * MP_LANES];
    MP_LANE_LOOP { amax[l] = 0.0; bad[l] = 0.0; sing[l] = 0.0; }
    for (int i = 0; i < NA * NA; i++)
        MP_LANE_LOOP {
            const double a = fabs(A[i * MP_LANES + l]);
            bad[l] = isfinite(a) ? bad[l] : 1.0;
            amax[l] = a > amax[l] ? a : amax[l];
        }
    MP_LANE_LOOP tol[l] = NA * DBL_EPSILON * amax[l];
    for (int k = 0; k < NA; k++) {
        MP_LANE_LOOP {
            piv[l] = k;
            best[l] = fabs(A[(k * NA + k) * MP_LANES + l]);
        }
        for (int i = k + 1; i < NA; i++) {
            const double di = i; /* (an int in the select stops the vectoriser) */
            MP_LANE_LOOP {
                const double a = fabs(A[(i * NA + k) * MP_LANES + l]);
                piv[l] = a > best[l] ? di : piv[l];
                best[l] = a > best[l] ? a : best[l];
            }
        }
        MP_LANE_LOOP sing[l] = best[l] > tol[l] ? sing[l] : 1.0;
        /* rows k and piv[l] exchanged, in A and in b */
        for (int i = k + 1; i < NA; i++) {
            const double di = i;
            for (int j = 0; j < NA; j++) {
                double *ak = A + (k * NA + j) * MP_LANES, *ai = A + (i * NA + j) * MP_LANES;
                MP_LANE_LOOP {
                    const double x = ak[l], y = ai[l];
                    ak[l] = piv[l] == di ? y : x;
                    ai[l] = piv[l] == di ? x : y;
                }
            }
            MP_LANE_LOOP {
                const double x = b[k * MP_LANES + l], y = b[i * MP_LANES + l];
                b[k * MP_LANES + l] = piv[l] == di ? y : x;
                b[i * MP_LANES + l] = piv[l] == di ? x : y;
            }
        }
        MP_LANE_LOOP dinv[k * MP_LANES + l] = 1.0 / A[(k * NA + k) * MP_LANES + l];
        for (int i = k + 1; i < NA; i++) {
            MP_LANE_LOOP {
                lf[l] = A[(i * NA + k) * MP_LANES + l] * dinv[k * MP_LANES + l];
                A[(i * NA + k) * MP_LANES + l] = lf[l];
            }
            for (int j = k + 1; j < NA; j++)
                MP_LANE_LOOP {
                    const double a = A[(i * NA + j) * MP_LANES + l];
                    const double u = a - lf[l] * A[(k * NA + j) * MP_LANES + l];
                    A[(i * NA + j) * MP_LANES + l] = lf[l] != 0.0 ? u : a;
                }
        }
    }
    for (int i = 1; i < NA; i++)
        for (int j = 0; j < i; j++)
            MP_LANE_LOOP b[i * MP_LANES + l] -= A[(i * NA + j) * MP_LANES + l] * b[j * MP_LANES + l];
    for (int i = NA - 1; i >= 0; i--) {
        for (int j = i + 1; j < NA; j++)
            MP_LANE_LOOP b[i * MP_LANES + l] -= A[(i * NA + j) * MP_LANES + l] * b[j * MP_LANES + l];
        MP_LANE_LOOP b[i * MP_LANES + l] *= dinv[i * MP_LANES + l];
    }
    MP_LANE_LOOP st[l] = bad[l] != 0.0 ? MP_ENONFINITE : sing[l] != 0.0 ? MP_ESINGULAR : MP_OK;
}
#endif
