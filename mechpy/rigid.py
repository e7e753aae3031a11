"""Rigid-body dynamics: the exact torque-free motion and the heavy top.

The scenes are :class:`mechpy.scenes.RigidBody` (Euler's equations, an
optional torque, constant in the body frame or a C callback, and quaternion
orientation) and :class:`mechpy.scenes.HeavyTop`; the geometric methods
``"rigid:split"`` and ``"rigid:split4"`` of :func:`mechpy.solve` integrate a
torque-free or constant-torque ``RigidBody`` keeping ``|L|`` and ``|q|`` to round-off
(about 1e-15 relative after 10^6 steps).

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
a series at times t is (len(t), 3).
"""
from __future__ import annotations

import numpy as np

from . import _core
from ._validate import as_array, as_scalar

__all__ = ["free_rotation", "flip_period", "nutation_bounds"]


def _moments_omega(moments, omega0):
    """The moments, checked by the RigidBody scene's row (positive, the
    triangle inequality), and omega0."""
    m = as_array(moments, "moments", shape=(3,))
    try:
        _core.scene_check("RigidBody", np.concatenate([m, np.zeros(3)]))
    except ValueError as exc:
        raise ValueError(f"moments: {exc}") from None
    return m, as_array(omega0, "omega0", shape=(3,))


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

    Examples
    --------
    A symmetric body (I1 = I2 = 1, I3 = 2) precesses at Omega = omega3 (I3 - I1)/I1
    in the body frame: omega1 = A cos(Omega t).

    >>> t = np.array([0.0, 0.5, 1.0])
    >>> w = mp.rigid.free_rotation([1.0, 1.0, 2.0], [0.1, 0.0, 1.0], t)
    >>> np.round(w[:, 0], 10), np.round(0.1 * np.cos(1.0 * t), 10)
    (array([0.1       , 0.08775826, 0.05403023]), array([0.1       , 0.08775826, 0.05403023]))
    >>> np.round(w[:, 2], 12)       # omega3 is constant
    array([1., 1., 1.])
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

    Examples
    --------
    Far from the separatrix, close to the axis of largest moment, the period tends
    to that of the linearised wobble, 2 pi / (omega3 sqrt((I3-I1)(I3-I2)/(I1 I2))):

    >>> I = [1.0, 2.0, 3.0]
    >>> T = mp.rigid.flip_period(I, [1e-6, 0.0, 1.0])
    >>> round(T, 6), round(2 * np.pi / np.sqrt((3 - 1) * (3 - 2) / (1 * 2)).item(), 6)
    (6.283185, 6.283185)
    """
    m, w = _moments_omega(moments, omega0)
    return _core.rigid_flip_period(m, w)


def nutation_bounds(I1, I3, mass, g, l, theta0, theta_dot0, phi_dot0, psi_dot0):
    r"""The nutation range (theta_min, theta_max) of the heavy symmetric top.

    With u = cos(theta) the energy and the conserved momenta give

    .. math:: \dot u^2 = f(u) = (1-u^2)(\alpha - \beta u) - (b - a u)^2,

    :math:`\alpha = 2E'/I_1`, :math:`\beta = 2Mgl/I_1`, :math:`a = p_\psi/I_1`,
    :math:`b = p_\phi/I_1`; the motion lies between the two roots of the cubic f
    in [-1, 1] that bracket u0 = cos(theta0).  They are found by bisection on f
    written about u0, :math:`f(u_0 + x) = (\dot\theta_0\sin\theta_0)^2 + f'(u_0)x
    + \tfrac12 f''(u_0)x^2 + \beta x^3`, with the coefficients formed from the rates
    without cancellation, so the bounds are accurate to round-off also next to steady
    precession (the double root :math:`\dot\theta_0 = f'(u_0) = 0`, where both
    bounds are theta0).

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

    Examples
    --------
    Released at theta0 = 1 rad with phi_dot0 = theta_dot0 = 0, the top starts at
    one bound (the cusps): theta0 is the upper bound of u = cos(theta), i.e.
    theta_min.

    >>> lo, hi = mp.rigid.nutation_bounds(1.0, 0.5, 1.0, 9.81, 0.3, 1.0, 0.0, 0.0, 20.0)
    >>> round(lo, 12), round(hi, 6)
    (1.0, 1.051905)
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
    beta = 2.0 * mass * g * l / I1
    # f expanded about u0 = cos(theta0), x = u - u0, with coefficients formed from
    # the physical rates (b - a u0 = phi_dot s^2, alpha - beta u0 = theta_dot^2 +
    # phi_dot^2 s^2): no cancellation in f(u0) = (s theta_dot)^2, and the two roots
    # next to u0 come out accurate to round-off in x even where they merge into the
    # double root of steady precession (roots of the cubic in u found from its
    # power-basis coefficients are only sqrt(eps) accurate there).
    p = phd * s * s
    q = thd * thd + phd * phd * s * s
    g0 = (s * thd) ** 2                             # f(u0) >= 0
    g1 = -2.0 * c * q - beta * s * s + 2.0 * a * p  # f'(u0)
    g2 = -q + 2.0 * beta * c - a * a                # f''(u0) / 2
    g3 = beta                                       # f'''(u0) / 6

    def gx(x):
        return g0 + x * (g1 + x * (g2 + x * g3))

    # f(-1) = -(b + a)^2 <= 0 <= f(u0) and f(1) = -(b - a)^2 <= 0: one root on each
    # side of u0 within [-1, 1] (u0 itself when theta_dot0 = 0 and f falls that way)
    if g0 == 0.0 and g1 == 0.0:
        return th, th                               # steady precession
    x_lo = _bracketed_root(gx, 0.0, -1.0 - c) if g0 > 0.0 or g1 < 0.0 else 0.0
    x_hi = _bracketed_root(gx, 0.0, 1.0 - c) if g0 > 0.0 or g1 > 0.0 else 0.0
    return _theta_of(th, x_hi), _theta_of(th, x_lo)


def _theta_of(th0, x):
    """theta in [0, pi] with cos(theta) = cos(theta0) + x, from (1 -+ cos theta) / 2 =
    sin^2 or cos^2 (theta0 / 2) -+ x / 2 (accurate near 0 and pi too)."""
    if x == 0.0:
        return float(th0)
    w = np.sin(0.5 * th0) ** 2 - 0.5 * x           # sin^2(theta / 2)
    if w <= 0.5:
        return float(2.0 * np.arcsin(np.sqrt(min(max(w, 0.0), 1.0))))
    v = np.cos(0.5 * th0) ** 2 + 0.5 * x           # cos^2(theta / 2)
    return float(2.0 * np.arccos(np.sqrt(min(max(v, 0.0), 1.0))))


def _bracketed_root(g, x_in, x_out):
    """The root of g between x_in (where g >= 0, g rising from 0 into the interval
    when g(x_in) = 0) and x_out (where g <= 0), by bisection to adjacent floats:
    the end nearer in |g| is returned."""
    lo, hi = x_in, x_out            # invariant: g >= 0 at lo (or lo = x_in), g <= 0 at hi
    for _ in range(2100):           # enough for any pair of floats in [-2, 2]
        m = 0.5 * (lo + hi)
        if m == lo or m == hi:
            break
        if g(m) > 0.0:
            lo = m
        else:
            hi = m
    if lo == x_in and g(x_in) == 0.0:
        return hi
    return lo if abs(g(lo)) < abs(g(hi)) else hi


def _top_args(I1, I3, mass, g, l):
    return (as_scalar(I1, "I1", positive=True), as_scalar(I3, "I3", positive=True),
            as_scalar(mass, "mass", positive=True), as_scalar(g, "g", nonnegative=True),
            as_scalar(l, "l"))


def steady_precession(I1, I3, mass, g, l, theta, omega3):
    r"""The two steady precession rates of the heavy symmetric top at a
    constant tilt theta.

    With :math:`\dot\theta = \ddot\theta = 0` the theta equation of
    :class:`mechpy.scenes.HeavyTop` leaves a quadratic in the precession rate
    :math:`\Omega = \dot\phi` (Goldstein, section 5.7):

    .. math:: I_1\cos\theta\,\Omega^2 - I_3\omega_3\,\Omega + Mgl = 0,\qquad
              \Omega_{slow} \to \frac{Mgl}{I_3\omega_3},\quad
              \Omega_{fast} \to \frac{I_3\omega_3}{I_1\cos\theta}
              \quad (I_3^2\omega_3^2 \gg 4I_1Mgl\cos\theta).

    The roots are formed without cancellation
    (:math:`q = (I_3\omega_3 + \mathrm{sgn}(\omega_3)\sqrt D)/2`, roots
    :math:`Mgl/q` and :math:`q/(I_1\cos\theta)`).

    Parameters
    ----------
    I1, I3 : float
        Moments about a transverse axis through the fixed point and about the
        symmetry axis (kg m^2).
    mass, g, l : float
        Mass (kg), gravity (m/s^2), pivot to centre of mass (m).
    theta : float
        Tilt from the upward vertical (rad), in (0, pi).
    omega3 : float
        Spin about the symmetry axis, :math:`\omega_3 = \dot\psi + \dot\phi\cos\theta`
        (rad/s), non-zero.

    Returns
    -------
    (slow, fast) : tuple of float
        Precession rates (rad/s), the smaller in magnitude first; ``fast`` is
        inf at theta = pi/2 (the quadratic is linear there).  Start a
        :class:`~mechpy.scenes.HeavyTop` at ``(phi, theta, psi, Omega, 0,
        omega3 - Omega cos(theta))`` to see it.

    Raises
    ------
    ValueError
        When :math:`I_3^2\omega_3^2 < 4I_1Mgl\cos\theta`: the top spins too
        slowly to precess steadily at this tilt.

    Examples
    --------
    >>> import mechpy as mp
    >>> slow, fast = mp.rigid.steady_precession(1.0, 2.0, 1.0, 9.81, 0.5, 0.3, 200.0)
    >>> round(slow, 8), round(9.81 * 0.5 / (2.0 * 200.0), 8)     # Mgl / (I3 omega3)
    (0.01226286, 0.0122625)
    """
    I1, I3, mass, g, l = _top_args(I1, I3, mass, g, l)
    th = as_scalar(theta, "theta")
    if not 0 < th < np.pi:
        raise ValueError(f"theta must be in (0, pi), got {th}")
    w3 = as_scalar(omega3, "omega3")
    if w3 == 0.0:
        raise ValueError("omega3 must be non-zero (a top that does not spin does not precess "
                         "steadily)")
    a, b, c = I1 * np.cos(th), I3 * w3, mass * g * l
    D = b * b - 4.0 * a * c
    if D < 0:
        raise ValueError(f"no steady precession at theta = {th}: I3^2 omega3^2 = {b * b:.6g} "
                         f"< 4 I1 M g l cos(theta) = {4.0 * a * c:.6g} (spin faster)")
    q = 0.5 * (b + np.copysign(np.sqrt(D), b))
    slow = c / q
    fast = q / a if a != 0.0 else np.copysign(np.inf, q)
    if abs(slow) > abs(fast):
        slow, fast = fast, slow
    return float(slow), float(fast)


def sleeping_top(I1, I3, mass, g, l, omega3) -> bool:
    r"""Whether the heavy top spinning upright is stable (a "sleeping" top):

    .. math:: I_3^2\,\omega_3^2 > 4\,I_1\,M g l

    (Goldstein, section 5.7; below it a small tilt grows, the top wobbles and
    falls).  Arguments as :func:`steady_precession`; ``l > 0`` puts the
    centre of mass above the pivot (with l <= 0 the upright top hangs and is
    always stable).

    Examples
    --------
    The criterion I3^2 omega3^2 > 4 I1 M g l, here 4 * 1 * 1 * 9.81 * 0.3 = 11.772
    against (0.5 omega3)^2: stable above omega3 = 6.862 rad/s.

    >>> round(2 * (4 * 1.0 * 1.0 * 9.81 * 0.3) ** 0.5, 3)
    6.862
    >>> mp.rigid.sleeping_top(1.0, 0.5, 1.0, 9.81, 0.3, 7.0)
    True
    >>> mp.rigid.sleeping_top(1.0, 0.5, 1.0, 9.81, 0.3, 6.8)
    False
    """
    I1, I3, mass, g, l = _top_args(I1, I3, mass, g, l)
    w3 = as_scalar(omega3, "omega3")
    return bool((I3 * w3) ** 2 > 4.0 * I1 * mass * g * l)


def free_precession(moments, omega):
    r"""Precession rates of a torque-free symmetric body (I1 = I2).

    In the body frame the angular velocity turns about the symmetry axis at
    :math:`\Omega = \omega_3 (I_3 - I_1)/I_1` (counter-clockwise about
    axis 3 when positive); in space the symmetry axis turns about the fixed
    angular momentum at :math:`\dot\phi = L/I_1 = I_3\omega_3/(I_1\cos\theta)`,
    theta the angle between the axis and L (Marion & Thornton, section 11.10;
    Landau & Lifshitz, section 33).

    Parameters
    ----------
    moments : array_like (3,)
        Principal moments (I1, I2, I3) (kg m^2) with I1 = I2 (to 1e-12
        relative); axis 3 is the symmetry axis.
    omega : array_like (3,)
        Body angular velocity (rad/s).

    Returns
    -------
    (body, space) : tuple of float
        Rates (rad/s).

    Examples
    --------
    The Earth's free nutation as Euler predicted it, with (I3 - I1)/I1 =
    1/305 and a spin of one turn per sidereal day: a period of 305 days in
    the body frame (the Chandler wobble observed is 433 days, the difference
    due to the Earth's elasticity).

    >>> import numpy as np, mechpy as mp
    >>> day = 86164.1
    >>> body, space = mp.rigid.free_precession([1.0, 1.0, 1 + 1 / 305], [1e-9, 0, 2 * np.pi / day])
    >>> round(2 * np.pi / body / day, 9)
    305.0
    """
    m, w = _moments_omega(moments, omega)
    if abs(m[0] - m[1]) > 1e-12 * max(m[0], m[1]):
        raise ValueError(f"moments must be those of a symmetric body, I1 = I2 (axis 3 the "
                         f"symmetry axis), got {m}")
    I1, I3 = 0.5 * (m[0] + m[1]), m[2]
    L = float(np.sqrt((I1 * w[0]) ** 2 + (I1 * w[1]) ** 2 + (I3 * w[2]) ** 2))
    return float(w[2] * (I3 - I1) / I1), L / I1


__all__ += ["steady_precession", "sleeping_top", "free_precession"]
