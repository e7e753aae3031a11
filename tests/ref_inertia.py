"""Pure NumPy / Fraction reference implementations used by the inertia and
stress tests (the tests compare; they do not re-derive)."""
from __future__ import annotations

from fractions import Fraction

import numpy as np


def point_masses_ref(m, x, origin=(0.0, 0.0, 0.0)):
    """I_ij = sum m (delta_ij r^2 - r_i r_j) with einsum, batched (..., n), (..., n, 3)."""
    m = np.asarray(m, float)
    r = np.asarray(x, float) - np.asarray(origin, float)[..., None, :]
    r2 = np.einsum("...ni,...ni->...n", r, r)
    return (np.einsum("...n,...n->...", m, r2)[..., None, None] * np.eye(3)
            - np.einsum("...n,...ni,...nj->...ij", m, r, r))


def shift_exact(I, M, a, sign=+1):
    """Steiner's theorem in exact rational arithmetic, rounded once to float."""
    Ifr = [[Fraction(float(I[i][j])) for j in range(3)] for i in range(3)]
    af = [Fraction(float(v)) for v in a]
    Mf = Fraction(float(M))
    a2 = sum(v * v for v in af)
    out = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            g = (a2 if i == j else 0) - af[i] * af[j]
            out[i, j] = float(Ifr[i][j] + sign * Mf * g)
    return out


def box_mesh(a, b, c, center=(0.0, 0.0, 0.0)):
    """Closed outward-oriented 12-triangle mesh of an a x b x c box."""
    v = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    v = v * [a, b, c] + np.asarray(center, float)
    # vertex index = 4 ix + 2 iy + iz; each quad listed counter-clockwise from outside
    quads = [(0, 1, 3, 2), (4, 6, 7, 5),      # x = -, x = +
             (0, 4, 5, 1), (2, 3, 7, 6),      # y = -, y = +
             (0, 2, 6, 4), (1, 5, 7, 3)]      # z = -, z = +
    f = []
    for q in quads:
        f += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    return v, np.array(f, dtype=np.int64)


def cone_mesh(radius, height, n):
    """Closed outward-oriented mesh of a cone: apex at z = 3h/4, base (n-gon
    fan around its centre) at z = -h/4, so the centre of mass is at 0."""
    ph = 2 * np.pi * np.arange(n) / n
    ring = np.stack([radius * np.cos(ph), radius * np.sin(ph), np.full(n, -height / 4)], -1)
    v = np.concatenate([ring, [[0, 0, 3 * height / 4], [0, 0, -height / 4]]])
    apex, base = n, n + 1
    j = np.arange(n)
    jn = (j + 1) % n
    side = np.stack([j, jn, np.full(n, apex)], -1)
    bottom = np.stack([jn, j, np.full(n, base)], -1)
    return v, np.concatenate([side, bottom]).astype(np.int64)


def polygon_cone_closed_form(mass, radius, height, n):
    """Inertia about the centre of mass of the pyramid on a regular n-gon
    inscribed in the circle of radius R (exact for the mesh above).

    Each of the n triangles (centre, P, Q) with |P| = |Q| = R has the polar
    second moment A (|P|^2 + |Q|^2 + P.Q) / 6 about the centre, so the n-gon
    has J / A = R^2 (2 + cos(2pi/n)) / 6 (-> R^2 / 2, the disk, as n -> inf).
    Slices of a pyramid scale as s^2, so Izz = (3/5) M (J / A) and
    Ixx = (3/10) M (J / A) + (3/80) M h^2, as for the circular cone.
    """
    t = 2 * np.pi / n
    k = radius ** 2 * (2 + np.cos(t)) / 6       # J / A for the regular n-gon
    izz = 0.6 * mass * k
    ixx = 0.3 * mass * k + 3.0 / 80.0 * mass * height ** 2
    return np.diag([ixx, ixx, izz])


def random_rotation(rng, size=None):
    """Uniform random proper rotations via QR of Gaussian matrices."""
    shape = (() if size is None else (size,)) + (3, 3)
    q, r = np.linalg.qr(rng.normal(size=shape))
    q = q * np.sign(np.diagonal(r, axis1=-2, axis2=-1))[..., None, :]
    d = np.linalg.det(q)
    q[..., :, 0] *= d[..., None]
    return q


def von_mises_ref(sigma):
    """sqrt(3/2 s:s) with s the deviator, via NumPy."""
    s = np.asarray(sigma, float)
    dev = s - np.trace(s, axis1=-2, axis2=-1)[..., None, None] / 3 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", dev, dev))
