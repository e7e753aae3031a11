"""Rigid-body dynamics: the exact torque-free motion and the heavy top.

The scenes are :class:`mechpy.scenes.RigidBody` (Euler's equations, an
optional torque, constant in the body frame or a C callback, and quaternion
orientation) and :class:`mechpy.scenes.HeavyTop`; the geometric methods
``"rigid:split"`` and ``"rigid:split4"`` of :func:`mechpy.solve` integrate a
torque-free or constant-torque ``RigidBody`` keeping |L| and |q| to round-off
(about 1e-15 relative after 10^6 steps).
"""
from __future__ import annotations

import numpy as np

from . import _core
from ._validate import as_array, as_scalar

__all__ = ["free_rotation", "flip_period", "nutation_bounds"]


def _moments_omega(moments, omega0):
    from .scenes import _moments
    return _moments(moments), as_array(omega0, "omega0", shape=(3,))


def free_rotation(moments, omega0, t) -> np.ndarray:
    r"""The exact torque-free body angular velocity omega(t).

    With the axes relabelled (a, b, c), b the intermediate axis,

    .. math:: \omega_a = A\,\mathrm{cn}(u, k),\ \omega_b = \pm B\,\mathrm{sn}(u, k),\
              \omega_c = \pm C\,\mathrm{dn}(u, k),\quad u = \lambda t + u_0

    (Landau & Lifshitz, section 37), on either side of the separatrix
    :math:`L^2 = 2 E I_b`; amplitudes and modulus are formed from sums of
    same-signed terms so that nothing cancels near it.

    Parameters
    ----------
    moments : array_like, shape (3,)
        Principal moments (kg m^2): positive, triangle inequality.
    omega0 : array_like, shape (3,)
        Body angular velocity at t = 0 (rad/s).
    t : array_like, shape (n,) or scalar
        Times (s).

    Returns
    -------
    ndarray, shape (n, 3)
        omega(t) in the body frame (rad/s).
    """
    m, w = _moments_omega(moments, omega0)
    ta = as_array(t, "t", allow_empty=True)
    flat = np.ascontiguousarray(ta.reshape(-1))
    out = _core.rigid_free_rotation(m, w, flat)
    return out.reshape(ta.shape + (3,))


def flip_period(moments, omega0) -> float:
    r"""The period T of the torque-free omega(t): :math:`T = 4K(k)/|\lambda|`.

    Near the intermediate axis (the Dzhanibekov or tennis-racket flip) the
    intermediate component reverses every T/2.  ``inf`` on the separatrix or
    for a steady rotation about a principal axis.  Moments must be distinct.

    Returns
    -------
    float
        Period (s).
    """
    m, w = _moments_omega(moments, omega0)
    return _core.rigid_flip_period(m, w)


def nutation_bounds(I1, I3, mass, g, l, theta0, theta_dot0, phi_dot0, psi_dot0):
    r"""The nutation range (theta_min, theta_max) of the heavy symmetric top.

    With u = cos(theta) the energy and the conserved momenta give

    .. math:: \dot u^2 = f(u) = (1-u^2)(\alpha - \beta u) - (b - a u)^2,

    :math:`\alpha = 2E'/I_1`, :math:`\beta = 2Mgl/I_1`, :math:`a = p_\psi/I_1`,
    :math:`b = p_\phi/I_1`; the motion lies between the two roots of the cubic f
    in [-1, 1] that bracket u0 = cos(theta0).

    Parameters
    ----------
    I1, I3 : float
        Moments about a transverse axis through the fixed point and about the
        symmetry axis (kg m^2).
    mass, g, l : float
        Mass (kg), gravity (m/s^2), pivot to centre of mass (m).
    theta0, theta_dot0, phi_dot0, psi_dot0 : float
        Initial angles and rates (rad, rad/s); 0 < theta0 < pi.

    Returns
    -------
    (theta_min, theta_max) : tuple of float
        In rad.
    """
    I1 = as_scalar(I1, "I1", positive=True)
    I3 = as_scalar(I3, "I3", positive=True)
    mass = as_scalar(mass, "mass", positive=True)
    g = as_scalar(g, "g", nonnegative=True)
    l = as_scalar(l, "l")
    th = as_scalar(theta0, "theta0")
    if not 0 < th < np.pi:
        raise ValueError(f"theta0 must be in (0, pi), got {th}")
    thd = as_scalar(theta_dot0, "theta_dot0")
    phd = as_scalar(phi_dot0, "phi_dot0")
    psd = as_scalar(psi_dot0, "psi_dot0")
    s, c = np.sin(th), np.cos(th)
    w3 = psd + phd * c
    a = I3 * w3 / I1
    b = (I1 * phd * s * s + I3 * w3 * c) / I1
    beta = 2.0 * mass * g * l / I1
    alpha = thd * thd + phd * phd * s * s + beta * c  # 2 E' / I1
    coef = [beta, -(alpha + a * a), 2.0 * a * b - beta, alpha - b * b]

    def f(u):
        return (1 - u * u) * (alpha - beta * u) - (b - a * u) ** 2

    def fp(u):
        return -2 * u * (alpha - beta * u) - beta * (1 - u * u) + 2 * a * (b - a * u)

    roots = np.roots(coef) if beta != 0 else np.roots(coef[1:])
    real = sorted(r.real for r in roots if abs(r.imag) <= 1e-7 * max(1.0, abs(r)))
    polished = []
    for r in real:
        for _ in range(8):  # Newton on the cubic itself
            d = fp(r)
            if d == 0:
                break
            step = f(r) / d
            r -= step
            if abs(step) < 1e-17:
                break
        polished.append(r)
    lo = [r for r in polished if r <= c + 1e-12]
    hi = [r for r in polished if r >= c - 1e-12]
    if thd == 0.0:  # u0 is itself a turning point
        lo_u = max([r for r in lo if r < c - 1e-12], default=None)
        hi_u = min([r for r in hi if r > c + 1e-12], default=None)
        if lo_u is None and hi_u is None:
            return th, th  # steady precession
        u_min, u_max = (lo_u, c) if lo_u is not None and (hi_u is None or f(0.5 * (lo_u + c)) >= 0) else (c, hi_u)
    else:
        u_min, u_max = max(lo), min(hi)
    u_min, u_max = max(u_min, -1.0), min(u_max, 1.0)
    return float(np.arccos(u_max)), float(np.arccos(u_min))
