"""The Cauchy stress tensor: principal stresses, pressure, von Mises, shear.

``sigma`` is a symmetric 3x3 tensor (tension positive), or a stack of them
(..., 3, 3); a non-symmetric input is an error.  Units are those of the input
(Pa = N/m^2 in SI).  The principal stresses come from the same symmetric 3x3
eigen-solver (cyclic Jacobi, in C) as the principal axes of inertia.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
NumPy stacks: tensors (..., 3, 3), vectors (..., 3).
"""
from __future__ import annotations

import numpy as np

from ._validate import as_symmetric, as_vector3
from .inertia import _eigh

__all__ = ["principal", "pressure", "von_mises", "max_shear", "deviator", "traction"]


def _as_stress(sigma) -> np.ndarray:
    return as_symmetric(sigma, "sigma", n=3, batch=True)


def _out(x):
    return float(x) if np.ndim(x) == 0 else x


def principal(sigma):
    """Principal stresses and directions.

    ``sigma = D diag(values) D^T``.

    Parameters
    ----------
    sigma : array_like, shape (..., 3, 3)
        Symmetric stress tensor [Pa].

    Returns
    -------
    values : ndarray, shape (..., 3)
        Principal stresses, ascending like ``numpy.linalg.eigh`` (so the
        engineering sigma_1 >= sigma_2 >= sigma_3 is ``values[..., ::-1]``) [Pa].
    directions : ndarray, shape (..., 3, 3)
        Unit principal directions as columns of a proper rotation matrix
        (det = +1): ``directions[..., :, k]`` belongs to ``values[..., k]``.

    Examples
    --------
    >>> sigma = np.array([[50.0, 30.0, 0.0], [30.0, -20.0, 0.0], [0.0, 0.0, 10.0]])  # MPa
    >>> values, directions = mp.stress.principal(sigma)
    >>> np.round(values, 6)   # in plane: 15 -+ sqrt(35**2 + 30**2); out of plane 10
    array([-31.097722,  10.      ,  61.097722])
    >>> round(float(15 + np.hypot(35, 30)), 6)
    61.097722
    >>> round(float(np.linalg.det(directions)), 12)
    1.0
    """
    return _eigh(_as_stress(sigma))


def pressure(sigma):
    """Mechanical pressure ``p = -tr(sigma) / 3`` [Pa] (positive in compression).

    Examples
    --------
    >>> print(mp.stress.pressure(-2.0e5 * np.eye(3)))   # hydrostatic compression of 2 bar
    200000.0
    """
    s = _as_stress(sigma)
    return _out(-np.trace(s, axis1=-2, axis2=-1) / 3.0)


def deviator(sigma) -> np.ndarray:
    """Deviatoric stress ``s = sigma + p E`` (traceless) [Pa], shape (..., 3, 3).

    Examples
    --------
    >>> s = mp.stress.deviator(np.diag([30.0, 0.0, 0.0]))
    >>> np.diag(s), float(np.trace(s))   # sigma minus its mean 10
    (array([ 20., -10., -10.]), 0.0)
    """
    s = _as_stress(sigma)
    p = np.trace(s, axis1=-2, axis2=-1) / 3.0
    return s - p[..., None, None] * np.eye(3)


def von_mises(sigma):
    """Von Mises equivalent stress [Pa].

    .. math:: \\sigma_v = \\sqrt{\\tfrac32\\, s : s}
              = \\sqrt{\\tfrac12[(\\sigma_{xx}-\\sigma_{yy})^2 + (\\sigma_{yy}-\\sigma_{zz})^2
              + (\\sigma_{zz}-\\sigma_{xx})^2] + 3(\\sigma_{xy}^2 + \\sigma_{yz}^2
              + \\sigma_{zx}^2)}

    computed from the components (no eigen-decomposition; exactly 0 for a
    hydrostatic state).

    Examples
    --------
    Uniaxial tension: the von Mises stress is the applied stress; pure shear
    tau gives sqrt(3) tau.

    >>> print(mp.stress.von_mises(np.diag([250.0, 0.0, 0.0])))
    250.0
    >>> shear = np.array([[0.0, 100.0, 0.0], [100.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    >>> round(float(mp.stress.von_mises(shear)), 6), round(100 * float(np.sqrt(3)), 6)
    (173.205081, 173.205081)
    """
    s = _as_stress(sigma)
    xx, yy, zz = s[..., 0, 0], s[..., 1, 1], s[..., 2, 2]
    xy, yz, zx = s[..., 0, 1], s[..., 1, 2], s[..., 2, 0]
    q = 0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) + 3.0 * (xy * xy + yz * yz
                                                                          + zx * zx)
    return _out(np.sqrt(q))


def max_shear(sigma):
    """Maximum shear stress ``tau_max = (sigma_max - sigma_min) / 2`` [Pa]
    (Tresca), on the planes at 45 degrees to the extreme principal directions.

    Examples
    --------
    >>> print(mp.stress.max_shear(np.diag([120.0, 40.0, -30.0])))   # (120 - (-30)) / 2
    75.0
    """
    w, _ = _eigh(_as_stress(sigma))
    return _out(0.5 * (w[..., 2] - w[..., 0]))


def traction(sigma, normal) -> np.ndarray:
    """Traction vector ``t = sigma n`` on the plane with unit normal ``n`` [Pa];
    ``normal`` is normalised here.

    Examples
    --------
    >>> sigma = np.array([[10.0, 5.0, 0.0], [5.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    >>> mp.stress.traction(sigma, [2.0, 0.0, 0.0])   # the normal is normalised: sigma e_x
    array([10.,  5.,  0.])
    """
    s = _as_stress(sigma)
    n = as_vector3(normal, "normal")
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    if np.any(norm == 0):
        raise ValueError("normal must be a non-zero vector")
    return np.einsum("...ij,...j->...i", s, n / norm)
