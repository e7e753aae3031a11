r"""Forces of constraint from Lagrange multipliers."""
from __future__ import annotations

import numpy as np

from .._validate import as_array, as_scalar
from ..scenes import Pendulum

__all__ = ["constraint_forces", "pendulum_tension"]


def constraint_forces(mass, force, jac, bias):
    r"""Lagrange multipliers and forces of holonomic constraints g(x, t) = 0.

    For :math:`M\ddot{\mathbf x} = \mathbf F + J^T\boldsymbol\lambda` with
    :math:`J = \partial g/\partial\mathbf x` and
    :math:`\ddot g = J\ddot{\mathbf x} + \mathbf b = 0`:

    .. math:: (J M^{-1} J^T)\,\boldsymbol\lambda = -(J M^{-1}\mathbf F + \mathbf b)

    Parameters
    ----------
    mass : float or array (..., d)
        Masses (a diagonal mass matrix), > 0 (kg).
    force : array (..., d)
        Applied forces (N).
    jac : array (..., k, d)
        Constraint Jacobians.
    bias : array (..., k)
        :math:`\mathbf b = \dot J\dot{\mathbf x} + \partial_t(\dots)`, the part
        of :math:`\ddot g` without the acceleration.

    Returns
    -------
    lam : ndarray (..., k)
        Multipliers.
    f : ndarray (..., d)
        Constraint forces :math:`J^T\lambda` (N).

    Examples
    --------
    A bob of mass 2 at rest at the bottom of a rod, the constraint
    ``g = (x^2 + y^2 - l^2)/2`` (``J = (x, y)``, ``b = |v|^2 = 0``): the rod holds
    it up with m g.

    >>> lam, f = mp.variational.constraint_forces(2.0, [0.0, -2.0 * 9.81], [[0.0, -1.0]], [0.0])
    >>> lam, f
    (array([-19.62]), array([ 0.  , 19.62]))
    """
    m = as_array(mass, "mass", positive=True)
    F = as_array(force, "force", min_ndim=1)
    J = as_array(jac, "jac", min_ndim=2)
    b = as_array(bias, "bias", min_ndim=1)
    if J.shape[-1] != F.shape[-1] or J.shape[-2] != b.shape[-1]:
        raise ValueError(f"shapes do not match: jac {J.shape}, force {F.shape}, bias {b.shape}")
    Minv = 1.0 / np.broadcast_to(m, F.shape)
    A = np.einsum("...kd,...d,...ld->...kl", J, Minv, J)
    rhs = -(np.einsum("...kd,...d->...k", J, Minv * F) + b)
    lam = np.linalg.solve(A, rhs[..., None])[..., 0]
    return lam, np.einsum("...kd,...k->...d", J, lam)


def pendulum_tension(scene, y, mass: float = 1.0) -> np.ndarray:
    r"""The string tension of a pendulum along states y (2, ...) (N).

    From the Lagrange multiplier of the constraint :math:`x^2 + y^2 = \ell^2`
    on the bob in Cartesian coordinates (:func:`constraint_forces`); the
    tangential damping and drive forces do not contribute.  Newton's radial
    equation gives the same :math:`T = m(g\cos\theta + \ell\dot\theta^2)`.

    Parameters
    ----------
    scene : mechpy.scenes.Pendulum
    y : array (2, ...)
        States (theta, theta_dot), e.g. ``Solution.y``.
    mass : float
        Bob mass (kg).

    Examples
    --------
    T = m (g cos(theta) + l theta_dot^2): at the bottom moving at 2 rad/s,
    1 * (9.81 + 1 * 4); hanging horizontally at rest, 0:

    >>> pend = mp.scenes.Pendulum(g=9.81, length=1.0)
    >>> y = np.array([[0.0, np.pi / 2], [2.0, 0.0]])                # two states (theta, theta_dot)
    >>> np.round(mp.variational.pendulum_tension(pend, y), 10)
    array([13.81,  0.  ])
    """
    if not isinstance(scene, Pendulum):
        raise TypeError("scene must be a mechpy.scenes.Pendulum")
    m = as_scalar(mass, "mass", positive=True)
    y = as_array(y, "y", min_ndim=1)
    if y.shape[0] != 2:
        raise ValueError(f"y must have 2 components along its first axis, got {y.shape}")
    g, ell = scene.params["g"], scene.params["length"]
    th, thd = y
    pos = ell * np.stack([np.sin(th), -np.cos(th)], axis=-1)
    vel = ell * thd[..., None] * np.stack([np.cos(th), np.sin(th)], axis=-1)
    F = np.zeros_like(pos)
    F[..., 1] = -m * g
    lam, _ = constraint_forces(m, F, pos[..., None, :], np.sum(vel * vel, -1)[..., None])
    return -lam[..., 0] * ell
