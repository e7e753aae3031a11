"""Inertia tensors, rigid bodies and systems of particles.

A body is described by point masses, a closed-form solid, a closed triangle
mesh or a density sampled on a grid; each gives a :class:`Body` with its mass,
centre of mass and inertia tensor about the centre of mass,

.. math:: I_{ij} = \\int \\rho(r)\\,(\\delta_{ij} r^2 - x_i x_j)\\,d^3r
          \\quad\\text{or}\\quad \\sum_\\alpha m_\\alpha(\\delta_{ij} r_\\alpha^2
          - x_{\\alpha i} x_{\\alpha j}),

and from it the inertia about any point (Steiner), principal moments and axes,
the type of top, angular momentum ``L = I omega`` and rotational energy
``T = omega^T I omega / 2``.  Units are those of the input: mass [M], lengths
[L], inertia [M L^2], angular velocity [1/T], energy [M L^2 / T^2].

The numerical work (point-mass sums, Steiner's theorem with exact products,
the symmetric 3x3 eigen-solver, mesh validation and integration, grids) runs
in mechpy's C core.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
NumPy stacks: vectors (..., 3), tensors (..., 3, 3).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from . import _core
from ._validate import as_array, as_finite_result, as_scalar, as_symmetric, as_vector3

__all__ = [
    "Body", "point_masses", "solid", "SHAPES", "mesh", "density_grid", "shift",
    "principal_axes", "classify", "angular_momentum", "kinetic_energy",
    "center_of_mass", "total_momentum", "angular_momentum_about", "kinetic_energy_split",
    "EnergySplit", "uv_sphere",
]


# --------------------------------------------------------------------------- helpers

def _eigh(a: np.ndarray):
    """Batched symmetric 3x3 eigen-decomposition in C: (..., 3), (..., 3, 3)."""
    batch = a.shape[:-2]
    w, v = _core.inertia_eigh(np.ascontiguousarray(a.reshape(-1, 3, 3)))
    return w.reshape(batch + (3,)), v.reshape(batch + (3, 3))


def _as_inertia(I, name: str = "I", *, batch: bool = True) -> np.ndarray:
    return as_symmetric(I, name, n=3, batch=batch)


# --------------------------------------------------------------------------- point masses

def point_masses(masses, positions, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Inertia tensor of a system of point masses about ``origin``.

    .. math:: I_{ij} = \\sum_\\alpha m_\\alpha\\,(\\delta_{ij}\\,|r_\\alpha|^2
              - r_{\\alpha i} r_{\\alpha j}), \\qquad r_\\alpha = x_\\alpha - \\text{origin}

    Parameters
    ----------
    masses : array_like, shape (..., n)
        Positive masses [M].
    positions : array_like, shape (..., n, 3)
        Positions [L].
    origin : array_like, shape (..., 3), optional
        The point the tensor is taken about [L].  Leading axes of the three
        arguments broadcast: many bodies are computed in one C call.

    Returns
    -------
    I : ndarray, shape (..., 3, 3)
        Inertia tensor [M L^2].

    Raises
    ------
    mechpy.NonFiniteError
        When the tensor overflows float64 (a ``ValueError``).

    Examples
    --------
    Masses along the x axis give ``I_yy = I_zz > 0`` and every other entry 0:

    >>> import mechpy as mp
    >>> mp.inertia.point_masses([1.0, 2.0], [[1, 0, 0], [-2, 0, 0]])
    array([[0., 0., 0.],
           [0., 9., 0.],
           [0., 0., 9.]])
    """
    m = as_array(masses, "masses", min_ndim=1, positive=True)
    x = as_vector3(positions, "positions")
    if x.ndim < 2:
        raise ValueError(f"positions must have shape (..., n, 3), got {x.shape}")
    o = as_vector3(origin, "origin")
    if m.shape[-1] != x.shape[-2]:
        raise ValueError(f"masses has {m.shape[-1]} entries but positions has "
                         f"{x.shape[-2]} points")
    n = m.shape[-1]
    try:
        batch = np.broadcast_shapes(m.shape[:-1], x.shape[:-2], o.shape[:-1])
    except ValueError:
        raise ValueError(f"the leading (batch) axes of masses {m.shape}, positions "
                         f"{x.shape} and origin {o.shape} do not broadcast") from None
    mb = np.ascontiguousarray(np.broadcast_to(m, batch + (n,)).reshape(-1, n))
    xb = np.ascontiguousarray(np.broadcast_to(x, batch + (n, 3)).reshape(-1, n, 3))
    ob = np.ascontiguousarray(np.broadcast_to(o, batch + (3,)).reshape(-1, 3))
    out = _core.inertia_point_masses(mb, xb, ob).reshape(batch + (3, 3))
    return as_finite_result(out, "point_masses: the inertia tensor",
                            "the sums of mass x distance^2 exceed float64; use other units "
                            "(or an origin nearer the masses)")


# --------------------------------------------------------------------------- Steiner

def shift(I, mass, a, to: str = "point") -> np.ndarray:
    """Steiner's parallel-axis theorem, both ways.

    .. math:: I^{(a)}_{ij} = I^{(cm)}_{ij} + M\\,(|a|^2 \\delta_{ij} - a_i a_j)

    ``to="point"``: ``I`` is about the centre of mass, the result is about the
    point at displacement ``a`` from it.  ``to="com"``: ``I`` is about that
    point, the result is about the centre of mass.  The products ``M a_i a_j``
    are formed exactly (fused multiply-add) and each entry is rounded once, so
    a shift by 10^6 body sizes loses nothing beyond what the input carries.

    Parameters
    ----------
    I : array_like, shape (..., 3, 3)
        Symmetric inertia tensor [M L^2].
    mass : float or array_like, shape (...)
        Total mass M >= 0 [M].
    a : array_like, shape (..., 3)
        Displacement of the point from the centre of mass [L].
    to : {"point", "com"}

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The shifted tensor [M L^2].

    Raises
    ------
    ValueError
        With ``to="com"``, when the result is not the inertia tensor of any
        mass distribution (a negative principal moment, or I1 + I2 < I3,
        beyond the round-off of the shift): a body of mass M whose centre of
        mass lies at ``-a`` from the point cannot have the tensor ``I`` about
        that point (its moments about the point are at least those of M
        concentrated at its centre of mass).  Typical causes: ``I`` is about
        the centre of mass already, or ``a`` or ``mass`` is too large.

    Examples
    --------
    A uniform rod of mass 3 and length 2 along x: about its centre I = M L^2/12 = 1;
    about its end M L^2/3 = 4.

    >>> I_cm = np.diag([0.0, 1.0, 1.0])
    >>> np.diag(mp.inertia.shift(I_cm, 3.0, [1.0, 0.0, 0.0]))
    array([0., 4., 4.])
    >>> np.diag(mp.inertia.shift(np.diag([0.0, 4.0, 4.0]), 3.0, [1.0, 0.0, 0.0], to="com"))
    array([0., 1., 1.])
    """
    if to not in ("point", "com"):
        raise ValueError(f'to must be "point" or "com", got {to!r}')
    I = _as_inertia(I)
    M = as_array(mass, "mass", nonnegative=True).reshape(np.shape(mass))
    a = as_vector3(a, "a")
    try:
        batch = np.broadcast_shapes(I.shape[:-2], M.shape, a.shape[:-1])
    except ValueError:
        raise ValueError(f"the batch axes of I {I.shape}, mass {M.shape} and a {a.shape} "
                         "do not broadcast") from None
    Ib = np.ascontiguousarray(np.broadcast_to(I, batch + (3, 3)).reshape(-1, 3, 3))
    Mb = np.ascontiguousarray(np.broadcast_to(M, batch).reshape(-1))
    ab = np.ascontiguousarray(np.broadcast_to(a, batch + (3,)).reshape(-1, 3))
    out = _core.inertia_shift(Ib, Mb, ab, 1 if to == "point" else -1)
    if to == "com" and out.size:
        _check_com_tensor(out, Ib, Mb, ab)
    return out.reshape(batch + (3, 3))


def _check_com_tensor(out, I, M, a):
    """Raise unless each tensor shifted to the centre of mass is one of a mass
    distribution: principal moments >= 0 and I1 + I2 >= I3, to the round-off of
    the shift (16 eps times the larger of |I| and M |a|^2)."""
    w, _ = _eigh(out)
    scale = np.maximum(np.max(np.abs(I), axis=(-2, -1)), M * np.einsum("...k,...k->...", a, a))
    tol = 16.0 * np.finfo(float).eps * scale
    bad = (w[:, 0] < -tol) | (w[:, 0] + w[:, 1] < w[:, 2] - tol)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"shift(to='com'): no mass distribution has the tensor I about the point a and its "
            f"centre of mass at distance |a| = {float(np.linalg.norm(a[k])):.6g} with mass "
            f"{float(M[k]):.6g}: the result would have principal moments "
            f"{np.array2string(w[k], precision=6)} (negative, or I1 + I2 < I3)"
            + (f" (item {k} of the batch)" if out.shape[0] > 1 else "")
            + "; check that I is about the point a and a is measured from the centre of mass")


# --------------------------------------------------------------------------- principal axes

def principal_axes(I):
    """Principal moments and principal axes of an inertia tensor.

    Diagonalises ``I = R diag(moments) R^T`` with a cyclic Jacobi method in C
    (high relative accuracy, also for moments that differ by many orders).

    Parameters
    ----------
    I : array_like, shape (..., 3, 3)
        Symmetric positive semi-definite tensor [M L^2].

    Returns
    -------
    moments : ndarray, shape (..., 3)
        Principal moments, ascending [M L^2].
    axes : ndarray, shape (..., 3, 3)
        The principal axes as columns of a proper rotation matrix
        (``det = +1``, right-handed): ``axes[..., :, k]`` belongs to
        ``moments[..., k]``.  Columns 0 and 1 have their largest-magnitude
        component positive; column 2 is their cross product.

    Examples
    --------
    >>> I = np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 5.0]])
    >>> moments, axes = mp.inertia.principal_axes(I)
    >>> np.round(moments, 12)    # 2 -+ 1 in the xy plane, 5 about z
    array([1., 3., 5.])
    >>> np.round(axes[:, 1] * np.sqrt(2), 12)    # the axis of 3 is (1, 1, 0)/sqrt(2)
    array([1., 1., 0.])
    """
    I = _as_inertia(I)
    w, v = _eigh(I)
    scale = np.max(np.abs(w), axis=-1, keepdims=True)
    if np.any(w < -1e-10 * scale):
        raise ValueError("I must be positive semi-definite (it has a negative principal "
                         f"moment {float(np.min(w)):.6g}); it is not an inertia tensor")
    return w, v


def classify(I, rtol: float = 1e-9) -> str:
    """The type of top: ``"spherical"``, ``"symmetric"``, ``"asymmetric"`` or ``"rotor"``.

    With principal moments ``I1 <= I2 <= I3``: ``"rotor"`` when ``I1 <= rtol I3``
    (a linear body, a moment of zero), ``"spherical"`` when ``I3 - I1 <= rtol I3``,
    ``"symmetric"`` when ``I2 - I1`` or ``I3 - I2`` is ``<= rtol I3``, otherwise
    ``"asymmetric"``.

    Parameters
    ----------
    I : array_like, shape (3, 3)
        Inertia tensor [M L^2] (about the centre of mass for the body's type).
    rtol : float
        Relative tolerance on the moments.

    Examples
    --------
    >>> mp.inertia.classify(np.eye(3))
    'spherical'
    >>> mp.inertia.classify(np.diag([1.0, 1.0, 2.0]))
    'symmetric'
    >>> mp.inertia.classify(np.diag([1.0, 2.0, 3.0]))
    'asymmetric'
    >>> mp.inertia.classify(np.diag([0.0, 1.0, 1.0]))
    'rotor'
    """
    rtol = as_scalar(rtol, "rtol", nonnegative=True)
    w, _ = principal_axes(_as_inertia(I, batch=False))
    top = w[2]
    if top <= 0:
        raise ValueError("I is zero (all the mass at one point): no type of top")
    tol = rtol * top
    if w[0] <= tol:
        return "rotor"
    if w[2] - w[0] <= tol:
        return "spherical"
    if w[1] - w[0] <= tol or w[2] - w[1] <= tol:
        return "symmetric"
    return "asymmetric"


def angular_momentum(I, omega) -> np.ndarray:
    """Angular momentum ``L = I omega`` [M L^2 / T].

    Parameters
    ----------
    I : array_like, shape (..., 3, 3)
        Inertia tensor about the fixed point or the centre of mass [M L^2].
    omega : array_like, shape (..., 3)
        Angular velocity [rad/T] in the same frame.

    Examples
    --------
    >>> mp.inertia.angular_momentum(np.diag([1.0, 2.0, 3.0]), [1.0, 1.0, 1.0])
    array([1., 2., 3.])
    """
    I = _as_inertia(I)
    w = as_vector3(omega, "omega")
    return np.einsum("...ij,...j->...i", I, w)


def kinetic_energy(I, omega) -> np.ndarray | float:
    """Rotational kinetic energy ``T = omega^T I omega / 2`` [M L^2 / T^2].

    Parameters
    ----------
    I : array_like, shape (..., 3, 3)
        Inertia tensor [M L^2].
    omega : array_like, shape (..., 3)
        Angular velocity [rad/T].

    Examples
    --------
    >>> print(mp.inertia.kinetic_energy(np.diag([1.0, 2.0, 3.0]), [0.0, 0.0, 2.0]))  # 3 * 2**2 / 2
    6.0
    """
    I = _as_inertia(I)
    w = as_vector3(omega, "omega")
    t = 0.5 * np.einsum("...i,...ij,...j->...", w, I, w)
    return float(t) if np.ndim(t) == 0 else t


# --------------------------------------------------------------------------- Body

class Body:
    """A rigid body: mass, centre of mass and inertia about the centre of mass.

    Parameters
    ----------
    mass : float
        Total mass M > 0 [M].
    com : array_like, shape (3,)
        Centre of mass [L].
    inertia : array_like, shape (3, 3)
        Inertia tensor about the centre of mass [M L^2]: symmetric, positive
        semi-definite, with principal moments obeying I1 + I2 >= I3.
    volume : float, optional
        Volume [L^3] when the body has one (``None`` for shells, rods,
        point masses).

    Notes
    -----
    ``body1 + body2`` is the composite body; ``sum(bodies)`` works too.

    Examples
    --------
    Two unit point masses 2 apart, as bodies, added: the dumbbell's moment about
    a perpendicular axis through the centre is 2 m (d/2)^2 = 2.

    >>> a = mp.inertia.Body(1.0, com=[-1.0, 0.0, 0.0], inertia=np.zeros((3, 3)))
    >>> b = mp.inertia.Body(1.0, com=[1.0, 0.0, 0.0], inertia=np.zeros((3, 3)))
    >>> d = a + b
    >>> d.mass, d.com
    (2.0, array([0., 0., 0.]))
    >>> np.diag(d.inertia)
    array([0., 2., 2.])
    >>> np.diag(d.inertia_about([0.0, 0.0, 1.0]))   # Steiner: + M |a|^2 off the axis
    array([2., 4., 2.])
    """

    __slots__ = ("mass", "com", "inertia", "volume")

    def __init__(self, mass, com=(0.0, 0.0, 0.0), inertia=None, volume=None):
        self.mass = as_scalar(mass, "mass", positive=True)
        self.com = as_array(com, "com", shape=(3,))
        if inertia is None:
            raise TypeError("Body needs an inertia tensor (about the centre of mass)")
        I = _as_inertia(inertia, "inertia", batch=False)
        w, _ = _eigh(I)
        tol = 1e-9 * max(float(w[2]), 0.0)
        if w[0] < -tol or w[0] + w[1] < w[2] - tol:
            raise ValueError("inertia is not the inertia tensor of a mass distribution "
                             f"(principal moments {w.tolist()} must be >= 0 and obey "
                             "I1 + I2 >= I3)")
        self.inertia = I
        self.volume = None if volume is None else as_scalar(volume, "volume", positive=True)

    @classmethod
    def from_point_masses(cls, masses, positions) -> "Body":
        """The body made of point masses (rigidly connected)."""
        m = as_array(masses, "masses", ndim=1, positive=True)
        x = as_array(positions, "positions", shape=(m.shape[0], 3))
        c = center_of_mass(m, x)
        return cls(float(m.sum()), c, point_masses(m, x, c))

    @property
    def density(self):
        """Mean density M / V [M / L^3] (``None`` without a volume)."""
        return None if self.volume is None else self.mass / self.volume

    def inertia_about(self, point) -> np.ndarray:
        """Inertia tensor about ``point`` [M L^2] (Steiner's theorem)."""
        p = as_array(point, "point", shape=(3,))
        return shift(self.inertia, self.mass, p - self.com, to="point")

    def moved(self, offset) -> "Body":
        """The same body translated by ``offset`` [L]."""
        d = as_array(offset, "offset", shape=(3,))
        return Body(self.mass, self.com + d, self.inertia, self.volume)

    def rotated(self, R) -> "Body":
        """The body rotated about the origin by the rotation matrix ``R``:
        ``com' = R com``, ``I' = R I R^T``."""
        R = as_array(R, "R", shape=(3, 3))
        if (np.max(np.abs(R @ R.T - np.eye(3))) > 1e-9) or np.linalg.det(R) < 0:
            raise ValueError("R must be a proper rotation matrix (orthogonal, det = +1)")
        I = R @ self.inertia @ R.T
        return Body(self.mass, R @ self.com, 0.5 * (I + I.T), self.volume)

    def principal(self):
        """Principal moments (ascending) and axes (columns, right-handed) about the
        centre of mass; see :func:`principal_axes`."""
        return principal_axes(self.inertia)

    def classify(self, rtol: float = 1e-9) -> str:
        """Type of top about the centre of mass; see :func:`classify`."""
        return classify(self.inertia, rtol)

    def __add__(self, other):
        if not isinstance(other, Body):
            return NotImplemented
        M = self.mass + other.mass
        c = (self.mass * self.com + other.mass * other.com) / M
        I = (shift(self.inertia, self.mass, self.com - c)
             + shift(other.inertia, other.mass, other.com - c))
        vol = (None if self.volume is None or other.volume is None
               else self.volume + other.volume)
        return Body(M, c, I, vol)

    def __radd__(self, other):
        if isinstance(other, (int, float)) and other == 0:   # sum(bodies)
            return self
        return NotImplemented

    def __repr__(self) -> str:
        w = np.linalg.eigvalsh(self.inertia)
        return (f"Body(mass={self.mass:.6g}, com={np.array2string(self.com, precision=6)}, "
                f"principal moments={np.array2string(w, precision=6)})")


# --------------------------------------------------------------------------- solids

def _sphere(M, radius):
    i = 0.4 * M * radius ** 2
    return (i, i, i), 4.0 / 3.0 * math.pi * radius ** 3


def _shell(M, radius):
    i = 2.0 / 3.0 * M * radius ** 2
    return (i, i, i), None


def _box(M, a, b, c):
    return ((M * (b * b + c * c) / 12, M * (a * a + c * c) / 12, M * (a * a + b * b) / 12),
            a * b * c)


def _cube(M, side):
    i = M * side ** 2 / 6.0
    return (i, i, i), side ** 3


def _cylinder(M, radius, height):
    t = M * (3 * radius ** 2 + height ** 2) / 12.0
    return (t, t, 0.5 * M * radius ** 2), math.pi * radius ** 2 * height


def _tube(M, radius, inner_radius, height):
    if not inner_radius < radius:
        raise ValueError("tube: inner_radius must be smaller than radius")
    r2 = radius ** 2 + inner_radius ** 2
    t = M * (3 * r2 + height ** 2) / 12.0
    return (t, t, 0.5 * M * r2), math.pi * (radius ** 2 - inner_radius ** 2) * height


def _cone(M, radius, height):
    t = M * (3.0 / 20.0 * radius ** 2 + 3.0 / 80.0 * height ** 2)
    return (t, t, 0.3 * M * radius ** 2), math.pi * radius ** 2 * height / 3.0


def _hemisphere(M, radius):
    t = 83.0 / 320.0 * M * radius ** 2
    return (t, t, 0.4 * M * radius ** 2), 2.0 / 3.0 * math.pi * radius ** 3


def _rod(M, length):
    t = M * length ** 2 / 12.0
    return (t, t, 0.0), None


def _disk(M, radius):
    t = 0.25 * M * radius ** 2
    return (t, t, 0.5 * M * radius ** 2), None


def _ring(M, radius):
    t = 0.5 * M * radius ** 2
    return (t, t, M * radius ** 2), None


def _ellipsoid(M, a, b, c):
    return ((M * (b * b + c * c) / 5, M * (a * a + c * c) / 5, M * (a * a + b * b) / 5),
            4.0 / 3.0 * math.pi * a * b * c)


#: shape -> (dimension names, formula, description).  Every solid has its
#: centre of mass at the origin and its symmetry axis along z.
SHAPES = {
    "sphere": (("radius",), _sphere,
               "solid ball: I = 2/5 M R^2 about every axis"),
    "shell": (("radius",), _shell,
              "thin spherical shell: I = 2/3 M R^2 about every axis"),
    "box": (("a", "b", "c"), _box,
            "cuboid with edges a, b, c along x, y, z: I_xx = M (b^2 + c^2) / 12, ..."),
    "cube": (("side",), _cube, "cube of edge s: I = M s^2 / 6 about every axis"),
    "cylinder": (("radius", "height"), _cylinder,
                 "solid cylinder, axis z: I_zz = M R^2 / 2, I_xx = I_yy = M (3 R^2 + h^2) / 12"),
    "tube": (("radius", "inner_radius", "height"), _tube,
             "hollow cylinder: I_zz = M (R^2 + r^2) / 2, I_xx = M (3 (R^2 + r^2) + h^2) / 12"),
    "cone": (("radius", "height"), _cone,
             "solid cone, apex at z = +3h/4, base at z = -h/4: I_zz = 3/10 M R^2, "
             "I_xx = I_yy = 3/20 M R^2 + 3/80 M h^2 (about the apex: 3/20 M R^2 + 3/5 M h^2)"),
    "hemisphere": (("radius",), _hemisphere,
                   "solid half ball, flat face at z = -3R/8, dome towards +z: "
                   "I_zz = 2/5 M R^2, I_xx = I_yy = 83/320 M R^2"),
    "rod": (("length",), _rod, "thin rod along z: I_xx = I_yy = M L^2 / 12, I_zz = 0"),
    "disk": (("radius",), _disk,
             "thin disk in the xy plane: I_zz = M R^2 / 2, I_xx = I_yy = M R^2 / 4"),
    "ring": (("radius",), _ring,
             "thin hoop in the xy plane: I_zz = M R^2, I_xx = I_yy = M R^2 / 2"),
    "ellipsoid": (("a", "b", "c"), _ellipsoid,
                  "solid ellipsoid, semi-axes a, b, c along x, y, z: I_xx = M (b^2 + c^2) / 5, ..."),
}


def solid(shape: str, mass, **dims) -> Body:
    """A homogeneous solid from its closed form.

    Every solid is placed with its centre of mass at the origin and its
    symmetry axis along z; its inertia tensor is diagonal there.

    ==============  ===========================  ===========================================
    shape           dims                         inertia about the centre of mass
    ==============  ===========================  ===========================================
    ``sphere``      radius R                     2/5 M R^2 (all axes)
    ``shell``       radius R (thin)              2/3 M R^2 (all axes)
    ``box``         edges a, b, c along x, y, z  I_xx = M (b^2 + c^2)/12, cyclic
    ``cube``        side s                       M s^2 / 6 (all axes)
    ``cylinder``    radius R, height h           I_zz = M R^2/2, I_xx = I_yy = M (3R^2 + h^2)/12
    ``tube``        radius R, inner_radius r, h  I_zz = M (R^2 + r^2)/2,
                                                 I_xx = M (3(R^2 + r^2) + h^2)/12
    ``cone``        radius R, height h           apex at z = 3h/4, base at z = -h/4;
                                                 I_zz = 3/10 M R^2, I_xx = 3/20 M R^2 + 3/80 M h^2
    ``hemisphere``  radius R                     flat face at z = -3R/8; I_zz = 2/5 M R^2,
                                                 I_xx = I_yy = 83/320 M R^2
    ``rod``         length L (thin, along z)     I_xx = I_yy = M L^2/12, I_zz = 0
    ``disk``        radius R (thin, xy plane)    I_zz = M R^2/2, I_xx = I_yy = M R^2/4
    ``ring``        radius R (thin hoop, xy)     I_zz = M R^2, I_xx = I_yy = M R^2/2
    ``ellipsoid``   a, b, c (semi-axes x, y, z)  I_xx = M (b^2 + c^2)/5, cyclic
    ==============  ===========================  ===========================================

    Parameters
    ----------
    shape : str
        One of :data:`SHAPES`.
    mass : float
        Mass M > 0 [M].
    **dims : float
        The dimensions named in the table, > 0 [L].

    Returns
    -------
    Body
        ``volume`` is set for solids (``None`` for shells, rods, disks, rings).

    Examples
    --------
    >>> import mechpy as mp
    >>> cone = mp.inertia.solid("cone", 2.0, radius=1.0, height=4.0)
    >>> float(cone.inertia_about([0, 0, 3.0])[0, 0])   # about the apex: 3/5 M (R^2/4 + h^2)
    19.5
    """
    if not isinstance(shape, str) or shape not in SHAPES:
        raise ValueError(f"unknown shape {shape!r}; expected one of {sorted(SHAPES)}")
    names, fn, _ = SHAPES[shape]
    extra = set(dims) - set(names)
    if extra:
        raise TypeError(f"solid({shape!r}) got unexpected dimension(s) {sorted(extra)}; "
                        f"it takes {list(names)}")
    missing = [n for n in names if n not in dims]
    if missing:
        raise TypeError(f"solid({shape!r}) needs the dimension(s) {missing}")
    M = as_scalar(mass, "mass", positive=True)
    vals = [as_scalar(dims[n], n, positive=True) for n in names]
    with np.errstate(over="ignore", under="ignore"):  # float64 arithmetic: overflow is inf
        diag, vol = fn(np.float64(M), *map(np.float64, vals))
    if not (np.all(np.isfinite(diag)) and (vol is None or np.isfinite(vol))):
        raise ValueError(f"solid({shape!r}): the inertia (mass x size^2) overflows float64; "
                         "use smaller units")
    return Body(M, np.zeros(3), np.diag(np.asarray(diag, dtype=float)), vol)


# --------------------------------------------------------------------------- meshes

def mesh(vertices, faces, density=None, mass=None) -> Body:
    """Mass properties of a closed triangle mesh (divergence theorem).

    Each face contributes surface integrals that the divergence theorem turns
    into the volume integrals of 1, x, x^2 and x y over the enclosed solid
    (Eberly, *Polyhedral Mass Properties*); the results are exact for the
    polyhedron, so a mesh of a smooth body converges to it as O(h^2) in the
    edge length h.

    The mesh is checked first, in C and in O(n log n) time (Ctrl-C is answered):
    every face index exists,
    no face repeats a vertex or has zero area, every edge is shared by exactly
    two faces that traverse it in opposite directions (closed, manifold,
    consistently oriented), and the signed volume is positive (faces
    counter-clockwise seen from outside).  A defect raises
    :class:`mechpy.MeshError` that says which ("open", "non-manifold",
    "inconsistently oriented", "inside out", "degenerate", "out of range" for a
    volume or inertia beyond float64) and where.

    Parameters
    ----------
    vertices : array_like, shape (nv, 3)
        Vertex positions [L].
    faces : array_like of int, shape (nf, 3)
        Vertex indices of each triangle, counter-clockwise seen from outside.
    density : float, optional
        Density [M / L^3]; default 1 when ``mass`` is not given either.
    mass : float, optional
        Total mass [M] (then density = mass / volume).  Give at most one of
        ``density`` and ``mass``.

    Returns
    -------
    Body
        With ``volume`` set.

    Examples
    --------
    The unit cube from 12 triangles: mass 1 and I = M (1 + 1) / 12 about each axis
    through the centre (exact for a polyhedron).

    >>> v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> f = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
    ...      [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    >>> cube = mp.inertia.mesh(v, f, density=1.0)
    >>> round(cube.volume, 12), np.round(cube.com, 12)
    (1.0, array([0.5, 0.5, 0.5]))
    >>> np.round(np.diag(cube.inertia), 9), round(2 / 12, 9)
    (array([0.16666667, 0.16666667, 0.16666667]), 0.166666667)
    """
    V = as_array(vertices, "vertices", ndim=2)
    if V.shape[1] != 3:
        raise ValueError(f"vertices must have shape (nv, 3), got {V.shape}")
    if isinstance(faces, (str, bytes)) or faces is None:
        raise TypeError("faces must be an integer array of shape (nf, 3)")
    F = np.asarray(faces)
    if F.dtype.kind not in "iu":
        raise TypeError(f"faces must be an integer array, got dtype {F.dtype}")
    if F.ndim != 2 or F.shape[1] != 3:
        raise ValueError(f"faces must have shape (nf, 3), got {F.shape}")
    if density is not None and mass is not None:
        raise ValueError("give density or mass, not both")
    F = np.ascontiguousarray(F, dtype=np.int64)
    vol, com, I = _core.inertia_mesh(V, F)
    if mass is not None:
        rho = as_scalar(mass, "mass", positive=True) / vol
    elif density is not None:
        rho = as_scalar(density, "density", positive=True)
    else:
        rho = 1.0
    return Body(rho * vol, com, rho * I, vol)


def uv_sphere(radius: float = 1.0, n_lat: int = 32, n_lon: int = 64):
    """A closed, outward-oriented triangle mesh of a sphere (latitude-longitude).

    Two poles and ``n_lat - 1`` rings of ``n_lon`` vertices on the sphere of
    radius ``radius`` [L]; ``2 n_lon (n_lat - 1)`` triangles.  The enclosed
    polyhedron is inscribed, so its volume and inertia approach the ball's as
    O(1/n^2).

    Returns
    -------
    vertices : ndarray, shape (n_lon (n_lat - 1) + 2, 3)
    faces : ndarray of int64, shape (2 n_lon (n_lat - 1), 3)

    Examples
    --------
    The inscribed polyhedron's volume approaches the ball's 4 pi / 3 as O(1/n^2).

    >>> v, f = mp.inertia.uv_sphere(1.0, n_lat=64, n_lon=128)
    >>> v.shape, f.shape
    ((8066, 3), (16128, 3))
    >>> ball = mp.inertia.mesh(v, f, density=1.0)
    >>> round(ball.volume, 4), round(4 * np.pi / 3, 4)
    (4.1846, 4.1888)
    """
    from ._validate import as_int
    R = as_scalar(radius, "radius", positive=True)
    nl = as_int(n_lat, "n_lat", minimum=2)
    nm = as_int(n_lon, "n_lon", minimum=3)
    th = np.pi * np.arange(1, nl) / nl
    ph = 2 * np.pi * np.arange(nm) / nm
    st, ct = np.sin(th)[:, None], np.cos(th)[:, None]
    ring = np.stack([st * np.cos(ph), st * np.sin(ph), np.broadcast_to(ct, (nl - 1, nm))],
                    axis=-1).reshape(-1, 3)
    verts = R * np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    south = verts.shape[0] - 1
    j = np.arange(nm)
    jn = (j + 1) % nm
    top = np.stack([np.zeros(nm, np.int64), 1 + j, 1 + jn], axis=-1)
    k = np.arange(nl - 2)[:, None]
    a, an = 1 + k * nm + j, 1 + k * nm + jn
    b, bn = a + nm, an + nm
    band = np.stack([np.stack([a, b, bn], -1), np.stack([a, bn, an], -1)], axis=2).reshape(-1, 3)
    last = 1 + (nl - 2) * nm
    bottom = np.stack([last + j, np.full(nm, south), last + jn], axis=-1)
    return verts, np.concatenate([top, band, bottom]).astype(np.int64)


# --------------------------------------------------------------------------- grids

def density_grid(rho, spacing, origin=(0.0, 0.0, 0.0)) -> Body:
    """A body from a density sampled on a regular grid.

    ``rho[i, j, k]`` is the density at ``origin + (i h_x, j h_y, k h_z)``.
    Each sample stands for the voxel of sides ``h`` centred on it (midpoint
    rule), including the voxel's own inertia ``m (h_y^2 + h_z^2) / 12``:

    .. math:: M = \\sum \\rho\\,\\Delta V, \\quad
              I_{ij} = \\sum \\rho\\,\\Delta V\\,(\\delta_{ij} r^2 - x_i x_j)
              + \\text{voxel terms}

    Error: exact for a body made of voxels; O(h^2) for a density that is
    smooth over the grid and vanishes smoothly at its edge; O(h) for a density
    with a jump (a solid's surface sampled as 0/1), where the error is set by
    the boundary voxels.  Sampling the volume fraction of each voxel instead
    of 0/1 restores O(h^2).

    Parameters
    ----------
    rho : array_like, shape (nx, ny, nz)
        Density samples >= 0 [M / L^3], with a positive total.
    spacing : float or array_like, shape (3,)
        Grid spacing h > 0 [L].
    origin : array_like, shape (3,)
        Position of ``rho[0, 0, 0]`` [L].

    Returns
    -------
    Body

    Examples
    --------
    A 10 x 10 x 10 block of unit-density voxels of side 0.1 is the unit cube:
    exact, I = M (1 + 1) / 12 = 1/6 about each axis through its centre.

    >>> cube = mp.inertia.density_grid(np.ones((10, 10, 10)), 0.1, origin=[0.05] * 3)
    >>> round(cube.mass, 12), np.round(cube.com, 12)
    (1.0, array([0.5, 0.5, 0.5]))
    >>> np.round(np.diag(cube.inertia), 9)
    array([0.16666667, 0.16666667, 0.16666667])
    """
    r = as_array(rho, "rho", ndim=3, nonnegative=True)
    h = as_array(spacing, "spacing", positive=True).reshape(np.shape(spacing))
    if h.ndim == 0:
        h = np.full(3, float(h))
    elif h.shape != (3,):
        raise ValueError(f"spacing must be a number or have shape (3,), got {h.shape}")
    o = as_array(origin, "origin", shape=(3,))
    if not np.any(r > 0):
        raise ValueError("rho must have a positive total (it is zero everywhere)")
    M, com, I = _core.inertia_grid(r, np.ascontiguousarray(h), o)
    return Body(M, com, I)


# --------------------------------------------------------------------------- particle systems

class EnergySplit(NamedTuple):
    """Kinetic energy of a system of particles split about the centre of mass.

    ``total = translational + internal``; ``internal = rotational + deformation``
    where ``rotational = omega . I_cm omega / 2`` with ``omega = I_cm^-1 L_cm``
    (the rigid rotation that carries the system's angular momentum about the
    centre of mass).  For a rigid motion ``deformation`` is 0 and
    ``T = T_trans + T_rot``.

    Examples
    --------
    >>> e = mp.inertia.kinetic_energy_split([1.0, 1.0], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
    ...                                     [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    >>> float(e.total), float(e.translational), float(e.internal)   # 2 = 1 + 1
    (2.0, 1.0, 1.0)
    >>> float(e.deformation)   # the pair stretches: its internal energy is not a rotation
    1.0
    """
    total: np.ndarray
    translational: np.ndarray
    internal: np.ndarray
    rotational: np.ndarray
    deformation: np.ndarray
    omega: np.ndarray


def _particles(masses, positions, velocities=None):
    m = as_array(masses, "masses", min_ndim=1, positive=True)
    x = as_vector3(positions, "positions")
    if x.ndim < 2 or x.shape[-2] != m.shape[-1]:
        raise ValueError(f"positions must have shape (..., {m.shape[-1]}, 3), got {x.shape}")
    if velocities is None:
        return m, x, None
    v = as_vector3(velocities, "velocities")
    if v.ndim < 2 or v.shape[-2] != m.shape[-1]:
        raise ValueError(f"velocities must have shape (..., {m.shape[-1]}, 3), got {v.shape}")
    return m, x, v


def center_of_mass(masses, positions) -> np.ndarray:
    """Centre of mass ``R = sum m_a x_a / M`` [L] of point masses.

    masses (..., n) [M], positions (..., n, 3) [L] -> (..., 3).

    Examples
    --------
    >>> mp.inertia.center_of_mass([1.0, 3.0], [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    array([3., 0., 0.])
    """
    m, x, _ = _particles(masses, positions)
    return np.einsum("...n,...nk->...k", m, x) / m.sum(axis=-1)[..., None]


def total_momentum(masses, velocities) -> np.ndarray:
    """Total linear momentum ``P = sum m_a v_a`` [M L / T] (equal to ``M V_cm``).

    masses (..., n) [M], velocities (..., n, 3) [L/T] -> (..., 3).

    Examples
    --------
    >>> mp.inertia.total_momentum([1.0, 3.0], [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    array([2., 3., 0.])
    """
    m, v, _ = _particles(masses, velocities)
    return np.einsum("...n,...nk->...k", m, v)


def angular_momentum_about(masses, positions, velocities, point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Angular momentum of point masses about ``point``:
    ``L = sum m_a (x_a - point) x v_a`` [M L^2 / T].

    masses (..., n), positions and velocities (..., n, 3), point (..., 3) -> (..., 3).

    Examples
    --------
    A unit mass at (1, 0, 0) moving with (0, 2, 0): L = r x p = (0, 0, 2) about the
    origin, 0 about a point on its line of motion.

    >>> mp.inertia.angular_momentum_about([1.0], [[1.0, 0.0, 0.0]], [[0.0, 2.0, 0.0]])
    array([0., 0., 2.])
    >>> mp.inertia.angular_momentum_about([1.0], [[1.0, 0.0, 0.0]], [[0.0, 2.0, 0.0]],
    ...                                   point=[1.0, 5.0, 0.0])
    array([0., 0., 0.])
    """
    m, x, v = _particles(masses, positions, velocities)
    p = as_vector3(point, "point")
    r = x - p[..., None, :]
    return np.einsum("...n,...nk->...k", m, np.cross(r, v))


def kinetic_energy_split(masses, positions, velocities) -> EnergySplit:
    """Kinetic energy of point masses split into centre-of-mass and internal parts.

    .. math:: T = \\tfrac12 M V^2 + \\tfrac12\\sum_a m_a |v_a - V|^2
              = T_{trans} + T_{int}, \\qquad
              T_{int} = T_{rot} + T_{def}, \\quad T_{rot} = \\tfrac12\\,\\omega\\cdot I_{cm}\\omega,
              \\ \\omega = I_{cm}^{-1} L_{cm}

    Parameters
    ----------
    masses : array_like, shape (n,)
        Positive masses [M].
    positions, velocities : array_like, shape (n, 3)
        [L] and [L/T].

    Returns
    -------
    EnergySplit
        ``total``, ``translational``, ``internal``, ``rotational``,
        ``deformation`` [M L^2 / T^2] and ``omega`` [rad/T] (NaN components
        are never produced: for a collinear system the pseudo-inverse of
        ``I_cm`` is used).

    Examples
    --------
    Two unit masses at (+-1, 0, 0) spinning at omega = 3 about z while their centre
    moves at 2 along x: T_trans = M V^2 / 2 = 4, T_rot = I omega^2 / 2 = 9.

    >>> x = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    >>> v = [[2.0, -3.0, 0.0], [2.0, 3.0, 0.0]]
    >>> e = mp.inertia.kinetic_energy_split([1.0, 1.0], x, v)
    >>> float(e.total), float(e.translational), round(float(e.rotational), 12)
    (13.0, 4.0, 9.0)
    >>> round(float(e.deformation), 12), np.round(e.omega, 12)
    (0.0, array([0., 0., 3.]))
    """
    m, x, v = _particles(masses, positions, velocities)
    if m.ndim != 1:
        raise ValueError("kinetic_energy_split takes one system: masses of shape (n,)")
    M = float(m.sum())
    c = m @ x / M
    V = m @ v / M
    u = v - V
    T = 0.5 * float(np.einsum("n,nk,nk->", m, v, v))
    Tt = 0.5 * M * float(V @ V)
    Ti = 0.5 * float(np.einsum("n,nk,nk->", m, u, u))
    Icm = point_masses(m, x, c)
    L = np.einsum("n,nk->k", m, np.cross(x - c, u))
    w, R = principal_axes(Icm)
    inv = np.where(w > 1e-12 * max(w[2], np.finfo(float).tiny), 1.0 / np.where(w > 0, w, 1), 0)
    omega = R @ (inv * (R.T @ L))
    Tr = 0.5 * float(omega @ L)
    return EnergySplit(T, Tt, Ti, Tr, max(Ti - Tr, 0.0), omega)
