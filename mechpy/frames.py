r"""Rotating reference frames (Marion & Thornton, chapter 10).

In a frame turning with angular velocity :math:`\boldsymbol\omega(t)` about a
fixed origin, a particle feels, per unit mass,

.. math:: \mathbf a_{\rm rot} = \mathbf a_{\rm in}
          \underbrace{-\,2\boldsymbol\omega\times\mathbf v_{\rm rot}}_{\rm Coriolis}
          \underbrace{-\,\boldsymbol\omega\times(\boldsymbol\omega\times\mathbf r)}_{\rm centrifugal}
          \underbrace{-\,\dot{\boldsymbol\omega}\times\mathbf r}_{\rm Euler}.

Local Earth frame used by :func:`drop`, :func:`projectile` and
:func:`projectile_drift`: x east, y north, z up; there
:math:`\boldsymbol\omega = \Omega(0, \cos\lambda, \sin\lambda)` at latitude
:math:`\lambda`, and g (the effective gravity, centrifugal term included)
points along -z.

Units: SI (m, s, rad/s); latitudes in degrees.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
NumPy stacks: vectors (..., 3), a series at times t (len(t), 3).
"""
from __future__ import annotations

import numpy as np

from ._validate import as_array, as_int, as_scalar, as_vector3
from .errors import StepBudgetError
from .integrate import solve

__all__ = ["OMEGA_EARTH", "FLIGHT_MAX_STEPS", "fictitious", "to_rotating", "from_rotating",
           "foucault_period", "earth_omega", "eastward_deflection", "drop", "projectile_drift", "projectile"]

#: The Earth's sidereal rotation rate [rad/s].
OMEGA_EARTH = 7.2921159e-5


def fictitious(omega, r, v, omega_dot=(0.0, 0.0, 0.0)) -> dict:
    r"""Fictitious accelerations in a frame rotating at ``omega``.

    Parameters
    ----------
    omega : array_like, shape (..., 3)
        Angular velocity of the frame [rad/s] at the instant considered (any
        omega(t): pass its value at t).
    r, v : array_like, shape (..., 3)
        Position [m] and velocity [m/s] measured in the rotating frame.
    omega_dot : array_like, shape (..., 3)
        Angular acceleration of the frame [rad/s^2].

    Returns
    -------
    dict
        ``"coriolis"`` :math:`-2\omega\times v`, ``"centrifugal"``
        :math:`-\omega\times(\omega\times r)`, ``"euler"``
        :math:`-\dot\omega\times r` and their sum ``"total"``, each (..., 3)
        in m/s^2 (per unit mass), broadcast over leading axes.

    Examples
    --------
    A body at rest 2 m from the axis of a frame turning at 3 rad/s: the centrifugal
    acceleration omega^2 r = 18 m/s^2 points outward; moving at 1 m/s along y it
    also feels the Coriolis -2 omega x v = (6, 0, 0).

    >>> a = mp.frames.fictitious([0.0, 0.0, 3.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    >>> a["centrifugal"] + 0.0, a["coriolis"] + 0.0, a["total"] + 0.0   # + 0.0: no -0.0
    (array([18.,  0.,  0.]), array([6., 0., 0.]), array([24.,  0.,  0.]))
    """
    w = as_vector3(omega, "omega")
    r = as_vector3(r, "r")
    v = as_vector3(v, "v")
    wd = as_vector3(omega_dot, "omega_dot")
    cor = -2.0 * np.cross(w, v)
    cen = -np.cross(w, np.cross(w, r))
    eul = -np.cross(wd, r)
    return {"coriolis": cor, "centrifugal": cen, "euler": eul, "total": cor + cen + eul}


def _rotation(omega, t):
    """R(t) = exp(t [omega]x), the frame's attitude (Rodrigues), shape (..., 3, 3)."""
    w = as_vector3(omega, "omega")
    t = _arr(t, "t")
    wt = w * t[..., None]
    ang = np.linalg.norm(wt, axis=-1)
    safe = np.where(ang > 0, ang, 1.0)
    k = wt / safe[..., None]
    K = np.zeros(k.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2] = -k[..., 2], k[..., 1]
    K[..., 1, 0], K[..., 1, 2] = k[..., 2], -k[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -k[..., 1], k[..., 0]
    s = np.sin(ang)[..., None, None]
    c = np.cos(ang)[..., None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K), w


def to_rotating(r, v, omega, t):
    r"""Inertial position and velocity -> the frame rotating at constant ``omega``.

    The frames coincide at t = 0; the rotating frame's attitude is
    :math:`R(t) = \exp(t[\omega]_\times)`, so
    :math:`r' = R^T r` and :math:`v' = R^T(v - \omega\times r)`.

    Parameters
    ----------
    r, v : array_like, shape (..., 3)
        Inertial position [m] and velocity [m/s].
    omega : array_like, shape (3,) or (..., 3)
        Constant angular velocity of the rotating frame [rad/s], inertial axes.
    t : float or array_like
        Time [s] (broadcast with the leading axes).

    Returns
    -------
    r_rot, v_rot : ndarray, shape (..., 3)
        Components on the rotating axes.

    Examples
    --------
    A point at rest in the inertial frame, seen from a frame turning at 1 rad/s,
    after a quarter turn, sits at -90 degrees and moves backwards at omega r:

    >>> r, v = mp.frames.to_rotating([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], np.pi / 2)
    >>> np.round(r, 12), np.round(v, 12)
    (array([ 0., -1.,  0.]), array([-1., -0.,  0.]))
    """
    r = as_vector3(r, "r")
    v = as_vector3(v, "v")
    R, w = _rotation(omega, t)
    Rt = np.swapaxes(R, -1, -2)
    return (Rt @ r[..., None])[..., 0], (Rt @ (v - np.cross(w, r))[..., None])[..., 0]


def from_rotating(r_rot, v_rot, omega, t):
    r"""Rotating-frame position and velocity -> inertial; the inverse of
    :func:`to_rotating`: :math:`r = R r'`, :math:`v = R v' + \omega\times r`.

    Units as in :func:`to_rotating`.

    Examples
    --------
    >>> r0, v0, w = [1.0, 2.0, 0.5], [0.3, -0.1, 0.2], [0.0, 0.0, 0.7]
    >>> r1, v1 = mp.frames.to_rotating(r0, v0, w, 1.3)
    >>> r2, v2 = mp.frames.from_rotating(r1, v1, w, 1.3)
    >>> np.round(r2, 12), np.round(v2, 12)
    (array([1. , 2. , 0.5]), array([ 0.3, -0.1,  0.2]))
    """
    rr = as_vector3(r_rot, "r_rot")
    vr = as_vector3(v_rot, "v_rot")
    R, w = _rotation(omega, t)
    r = (R @ rr[..., None])[..., 0]
    return r, (R @ vr[..., None])[..., 0] + np.cross(w, r)


def _arr(x, name, **kw):
    """as_array keeping a scalar 0-d."""
    return as_array(x, name, **kw).reshape(np.shape(x))


def _latitude(latitude):
    lat = _arr(latitude, "latitude")
    if np.any(np.abs(lat) > 90.0):
        raise ValueError(f"latitude must lie in [-90, 90] degrees, got {latitude!r}")
    return lat


def foucault_period(latitude, omega=OMEGA_EARTH):
    r"""Time for a Foucault pendulum's plane of swing to turn once.

    .. math:: T = \frac{2\pi}{\Omega\,|\sin\lambda|}

    Parameters
    ----------
    latitude : float or array_like
        Degrees in [-90, 90] (north positive); at the equator T is infinite.
    omega : float
        Rotation rate of the planet [rad/s] (default: the Earth's sidereal rate).

    Returns
    -------
    float or ndarray
        Period in seconds (31.78 h at Paris, 48.857 N).

    Examples
    --------
    At the pole the plane turns once a sidereal day, 2 pi / Omega = 86164 s; at
    Paris (48.857 N) in about 31.8 h:

    >>> round(mp.frames.foucault_period(90.0)), round(2 * np.pi / 7.2921159e-05)
    (86164, 86164)
    >>> round(mp.frames.foucault_period(48.857) / 3600, 2)
    31.78
    """
    lat = _latitude(latitude)
    om = as_scalar(omega, "omega", positive=True)
    s = np.abs(np.sin(np.radians(lat)))
    with np.errstate(divide="ignore"):
        T = np.where(s > 0, 2.0 * np.pi / (om * np.where(s > 0, s, 1.0)), np.inf)
    return float(T) if T.ndim == 0 else T


def earth_omega(latitude, omega=OMEGA_EARTH) -> np.ndarray:
    r"""The planet's angular velocity in the local frame (east, north, up):
    :math:`\Omega(0, \cos\lambda, \sin\lambda)` [rad/s]; latitude in degrees.

    Examples
    --------
    >>> np.round(mp.frames.earth_omega(30.0) / 7.2921159e-05, 12)   # (0, cos 30, sin 30)
    array([0.       , 0.8660254, 0.5      ])
    """
    lat = np.radians(_latitude(latitude))
    om = as_scalar(omega, "omega", nonnegative=True)
    return om * np.stack([np.zeros_like(lat), np.cos(lat), np.sin(lat)], axis=-1)


def eastward_deflection(height, latitude, g=9.81, omega=OMEGA_EARTH):
    r"""Closed-form eastward deflection of a body dropped from rest (M&T Example 10.4).

    .. math:: d = \frac{\Omega\cos\lambda}{3}\sqrt{\frac{8h^3}{g}}

    to first order in :math:`\Omega`, no air drag.  ``height`` h in m,
    ``latitude`` in degrees, ``g`` in m/s^2, ``omega`` in rad/s; returns m
    (positive: east).

    Examples
    --------
    A drop of 100 m at the equator lands about 2.2 cm to the east:

    >>> d = mp.frames.eastward_deflection(100.0, 0.0)
    >>> round(d, 6), round(7.2921159e-05 / 3 * (8 * 100.0**3 / 9.81) ** 0.5, 6)
    (0.02195, 0.02195)
    """
    h = _arr(height, "height", nonnegative=True)
    lat = np.radians(_latitude(latitude))
    g = as_scalar(g, "g", positive=True)
    om = as_scalar(omega, "omega", nonnegative=True)
    d = om * np.cos(lat) / 3.0 * np.sqrt(8.0 * h ** 3 / g)
    return float(d) if d.ndim == 0 else d


#: Step budget of :func:`drop` and :func:`projectile` (a flight of a few
#: hundred metres takes a few dozen steps; the budget ends absurd flights,
#: e.g. a drop from 1e300 m, in about a second).
FLIGHT_MAX_STEPS = 20_000


def _coriolis_flight(r0, v0, latitude, g, omega, rtol, max_steps):
    """Integrate r'' = g - 2 omega x v in the local frame until z = 0."""
    max_steps = as_int(max_steps, "max_steps", minimum=1)
    wx, wy, wz = (2.0 * float(c) for c in earth_omega(latitude, omega))

    def f(t, y):   # (v, g - 2 omega x v) in plain floats: a few microseconds a call
        vx, vy, vz = float(y[3]), float(y[4]), float(y[5])
        return [vx, vy, vz, -(wy * vz - wz * vy), -(wz * vx - wx * vz),
                -g - (wx * vy - wy * vx)]

    def ground(t, y):
        return y[2]
    ground.terminal = True
    ground.direction = -1
    # a generous time bound: the vacuum flight time, doubled
    vz = v0[2]
    with np.errstate(over="ignore", invalid="ignore"):
        T = 2.0 * (vz + np.sqrt(vz * vz + 2.0 * g * max(r0[2], 0.0))) / g + 1.0
    if not np.isfinite(T):
        raise ValueError(f"the flight time overflows float64 (launch speed {float(vz):.3g} m/s, "
                         f"height {float(r0[2]):.3g} m, g = {g:.3g} m/s^2): use other units")
    s = solve(f, (0.0, T), np.concatenate([r0, v0]), rtol=rtol, atol=1e-12, events=ground,
              max_steps=max_steps)
    if s.status < 0 and "max_steps" in s.message:
        raise StepBudgetError(
            f"the flight (vacuum flight time about {T:.3g} s) needs more than max_steps = "
            f"{max_steps} steps: {s.message} The flat-Earth model (constant g, no curvature) "
            "holds for flights of at most a few km; raise max_steps to go on")
    if not s.t_events[0].size:
        raise RuntimeError("the body did not reach the ground")
    return s.y_events[0][0, :3], float(s.t_events[0][0])


def drop(height, latitude, g=9.81, omega=OMEGA_EARTH, *, rtol=1e-11,
         max_steps=FLIGHT_MAX_STEPS):
    """Numerically drop a body from rest at ``height`` (m) in the rotating frame
    (Coriolis term in full, no drag) and return its landing point (east, north,
    0) in m and the fall time in s.  Compare :func:`eastward_deflection`.

    ``max_steps`` (default :data:`FLIGHT_MAX_STEPS`) bounds the integration:
    a flight that needs more raises :class:`mechpy.StepBudgetError` (an absurd
    height ran for hours); Ctrl-C raises ``KeyboardInterrupt``.

    Examples
    --------
    The full Coriolis term agrees with the first-order closed form of
    :func:`eastward_deflection` (to O(Omega^2)), and the fall time with sqrt(2h/g):

    >>> (east, north, up), t = mp.frames.drop(100.0, 45.0)
    >>> round(float(east), 6), round(mp.frames.eastward_deflection(100.0, 45.0), 6)
    (0.015521, 0.015521)
    >>> round(t, 4), round((2 * 100.0 / 9.81) ** 0.5, 4)
    (4.5152, 4.5152)
    """
    h = as_scalar(height, "height", positive=True)
    g = as_scalar(g, "g", positive=True)
    return _coriolis_flight(np.array([0.0, 0.0, h]), np.zeros(3), latitude, g, omega, rtol,
                            max_steps)


def projectile_drift(v0, t, latitude, g=9.81, omega=OMEGA_EARTH) -> np.ndarray:
    r"""Closed-form Coriolis drift of a projectile, first order in :math:`\Omega`.

    .. math:: \Delta\mathbf r(t) = -\boldsymbol\omega\times\mathbf v_0\,t^2
              - \tfrac13\,\boldsymbol\omega\times\mathbf g\,t^3

    the displacement from the non-rotating parabola
    :math:`\mathbf v_0 t + \mathbf g t^2/2`.  ``v0`` (3,) in m/s on (east,
    north, up); ``t`` in s (array-like, broadcast); latitude in degrees.
    Returns (..., 3) in m.

    Examples
    --------
    A shell fired north at 45 N drifts east (to the right in the northern hemisphere):

    >>> drift = mp.frames.projectile_drift([0.0, 100.0, 100.0], 10.0, 45.0)
    >>> np.round(drift, 4) + 0.0
    array([0.1686, 0.    , 0.    ])
    """
    v0 = as_vector3(v0, "v0")
    t = _arr(t, "t")[..., None]
    w = earth_omega(latitude, omega)
    gv = np.array([0.0, 0.0, -as_scalar(g, "g", positive=True)])
    return -np.cross(w, v0) * t ** 2 - np.cross(w, gv) * t ** 3 / 3.0


def projectile(v0, latitude, g=9.81, omega=OMEGA_EARTH, *, rtol=1e-11,
               max_steps=FLIGHT_MAX_STEPS):
    """Numerically fly a projectile launched from the ground with velocity
    ``v0`` (east, north, up; m/s, up-component > 0) in the rotating frame and
    return its landing point (m) and flight time (s).  Its offset from the
    vacuum range ``v0_h * 2 v0_z / g`` is the Coriolis drift of
    :func:`projectile_drift`.  ``max_steps`` bounds the integration as in
    :func:`drop`.

    Examples
    --------
    Its landing point against the vacuum range v0_h 2 v0_z / g plus the drift of
    :func:`projectile_drift` at the flight time:

    >>> v0 = [0.0, 100.0, 100.0]
    >>> landing, t = mp.frames.projectile(v0, 45.0)
    >>> round(float(landing[1]), 2), round(100.0 * 2 * 100.0 / 9.81, 2)
    (2038.74, 2038.74)
    >>> round(float(landing[0]), 3), round(float(mp.frames.projectile_drift(v0, t, 45.0)[0]), 3)
    (1.429, 1.429)
    """
    v0 = as_vector3(v0, "v0")
    if v0.shape != (3,) or not v0[2] > 0:
        raise ValueError("v0 must be one 3-vector with a positive upward component")
    g = as_scalar(g, "g", positive=True)
    return _coriolis_flight(np.zeros(3), v0, latitude, g, omega, rtol, max_steps)
