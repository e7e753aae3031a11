/* mechpy C core: inertia tensors (point masses, triangle meshes, sampled
 * densities), Steiner's theorem, and the symmetric 3x3 eigen-solver shared
 * by principal axes of inertia and principal stresses.
 *
 * Matrices are 3x3, row-major, 9 doubles.  Batched functions take `n`
 * matrices stored one after another.  Every fallible function returns an
 * enum mp_status; results go through out-parameters. */
#ifndef MP_INERTIA_H
#define MP_INERTIA_H

#include <stddef.h>
#include <stdint.h>

#include "mp_status.h"

/* Inertia tensors of `nbody` systems of `n` point masses each:
 *   I_ij = sum_a m_a (delta_ij |r_a|^2 - r_ai r_aj),  r_a = x_a - origin.
 * m: nbody*n masses (> 0), x: nbody*n*3 positions, origin: nbody*3,
 * out: nbody*9.  MP_EDOM on a non-positive or non-finite mass. */
int mp_inertia_point_masses(size_t nbody, size_t n, const double *m, const double *x,
                            const double *origin, double *out);

/* Steiner's theorem for `n` tensors, without cancellation beyond the input's:
 *   sign = +1:  out = I + M (|a|^2 E - a a^T)   (about the centre of mass -> about a)
 *   sign = -1:  out = I - M (|a|^2 E - a a^T)   (about a -> about the centre of mass)
 * The products are formed exactly (FMA) and the sum is rounded once more. */
int mp_inertia_shift(size_t n, const double *inertia, const double *mass, const double *a,
                     int sign, double *out);

/* Eigen-decomposition of `n` symmetric 3x3 matrices by cyclic Jacobi
 * rotations: w (n*3) ascending, V (n*9) the eigenvectors as columns of a
 * proper rotation (det = +1); columns 1 and 2 have their largest-magnitude
 * component positive, column 3 = column 1 x column 2.  Only the upper
 * triangle is read.  MP_EDOM on a non-finite entry. */
int mp_inertia_eigh(size_t n, const double *a, double *w, double *v);

/* Defects reported by mp_inertia_mesh (with MP_EMESH). */
enum mp_mesh_defect {
    MP_MESH_OK = 0,
    MP_MESH_INDEX,        /* a face index is out of range */
    MP_MESH_REPEATED,     /* a face repeats a vertex */
    MP_MESH_ZERO_AREA,    /* a face has zero area */
    MP_MESH_OPEN,         /* an edge belongs to only one face */
    MP_MESH_NONMANIFOLD,  /* an edge belongs to more than two faces */
    MP_MESH_ORIENTATION,  /* two faces traverse an edge in the same direction */
    MP_MESH_INSIDE_OUT,   /* the enclosed signed volume is negative */
    MP_MESH_FLAT,         /* the enclosed volume is zero */
    MP_MESH_RANGE         /* the volume or inertia over- or underflows float64 */
};

/* Where a defect was found: a face index and/or an edge (two vertices). */
struct mp_mesh_report {
    int defect;
    int64_t face;
    int64_t v0, v1;
    double volume;        /* signed volume (inside out, flat) */
    double extent;        /* largest bounding-box side (MP_MESH_RANGE) */
};

/* Volume, centre of mass and inertia about the centre of mass (unit
 * density) of a closed, consistently and outward oriented triangle mesh
 * (Eberly's polyhedral mass properties, the divergence theorem applied to
 * each face).  vertices: nv*3, faces: nf*3 vertex indices.  The mesh is
 * validated first (indices, repeated vertices, zero-area faces, every edge
 * shared by exactly two faces traversing it in opposite directions,
 * positive volume); a defect returns MP_EMESH and fills `report`
 * (MP_EDOM for a non-finite vertex).  A mesh whose volume or inertia is
 * beyond float64's normal range (extent above about 1e61 or below 1e-61)
 * is MP_EMESH with defect MP_MESH_RANGE, never a silent inf or 0.
 * O(nf log d) time (d the largest vertex degree) and O(nf) memory;
 * `interrupt` (NULL: none) is polled every 65536 faces in the long loops and
 * a non-zero status from it is returned at once (MP_EINTR for Ctrl-C). */
int mp_inertia_mesh(size_t nv, const double *vertices, size_t nf, const int64_t *faces,
                    double *volume, double com[3], double inertia[9],
                    struct mp_mesh_report *report, int (*interrupt)(void *), void *ctx);

/* Mass, centre of mass and inertia about the centre of mass of a density
 * sampled on a regular grid: rho (nx*ny*nz, C order) at origin + (i h0,
 * j h1, k h2); each sample stands for a voxel of sides h centred on it
 * (midpoint rule; the voxel's own inertia is included).  MP_EDOM on a
 * negative or non-finite density or a zero total mass. */
int mp_inertia_grid(size_t nx, size_t ny, size_t nz, const double *rho, const double h[3],
                    const double origin[3], double *mass, double com[3], double inertia[9]);

#endif
