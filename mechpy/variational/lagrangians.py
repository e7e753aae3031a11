r"""Lagrangians of the scenes, generalized momenta, cyclic coordinates, and two
small systems with constraints (a central force, a bead on a spinning hoop).

A system's Lagrangian reaches the C core as an integrand spec (see
``csrc/py/py_variational.c``): the Lagrangian in a scene's C row
(``("scene", name, params)``: Pendulum, Duffing, HeavyTop), the compiled
``mp_gen_lagrangian`` of a scene built by ``mp.lagrangian`` (its
``_lagrangian_c`` attribute), or finite differences of a Python callable.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from .. import _core
from .._validate import as_array, as_scalar
from ..scenes import Scene
from .constraints import constraint_forces

__all__ = ["lagrangian", "generalized_momenta", "cyclic_coordinates", "CentralForce",
           "RotatingHoop"]


def _compiled_spec(system):
    """The spec ``("c", capsule, params, d)`` of a compiled scene, or None."""
    lc = getattr(system, "_lagrangian_c", None)
    if lc is None:
        return None
    try:
        address, params = lc
    except (TypeError, ValueError):
        raise TypeError(f"{type(system).__name__}._lagrangian_c must be a pair (address, "
                        "params)") from None
    if not isinstance(address, (int, np.integer)) or isinstance(address, bool) or address <= 0:
        raise TypeError(f"{type(system).__name__}._lagrangian_c[0] must be the function's "
                        f"address (a positive int), got {address!r}")
    params = np.ascontiguousarray(as_array(params, "_lagrangian_c params", ndim=1,
                                           allow_empty=True), dtype=np.float64)
    dim = getattr(system, "dim", None)
    if not isinstance(dim, (int, np.integer)) or dim < 2 or dim % 2:
        raise TypeError(f"{type(system).__name__}.dim must be an even int >= 2 (the state "
                        f"is (q, qdot)), got {dim!r}")
    return ("c", _core._variational_capsule(int(address)), params, int(dim) // 2)


def _has_lagrangian(system) -> bool:
    """Whether system gives a Lagrangian to the C core (a scene's row, or a
    compiled scene's ``_lagrangian_c``)."""
    return ((isinstance(system, Scene) and system._lagrangian_spec() is not None)
            or getattr(system, "_lagrangian_c", None) is not None)


def _scene_spec(scene):
    """The C spec of a scene's Lagrangian L(t, q, qdot): its compiled one, or
    the one in its C row."""
    spec = _compiled_spec(scene)
    if spec is None and isinstance(scene, Scene):
        spec = scene._lagrangian_spec()
    if spec is None:
        raise TypeError(f"{type(scene).__name__} has no Lagrangian of the form L(t, q, qdot) "
                        "here; use Pendulum, Duffing, HeavyTop, a scene from mp.lagrangian or "
                        "a callable L(q, qdot[, t])")
    return spec


def _spec_dim(spec) -> int:
    if spec[0] == "python":
        return spec[2]
    if spec[0] == "c":
        return spec[3]
    if spec[0] == "scene":
        return _core.scene_check(spec[1], spec[2]) // 2
    return 1


def lagrangian(scene) -> Callable:
    r"""The Lagrangian ``L(q, qdot, t=0)`` of a scene, as a vectorised callable.

    Pendulum (per unit mass, J/kg):
    :math:`e^{bt}(\tfrac12\ell^2\dot\theta^2 + g\ell\cos\theta + \ell^2A\cos(\Omega t)\,\theta)`;
    Duffing: :math:`e^{\delta t}(\tfrac12\dot x^2 - \tfrac12\alpha x^2 - \tfrac14\beta x^4
    + \gamma\cos(\omega t)\,x)`.  The factor :math:`e^{bt}` (Caldirola-Kanai)
    makes the damped equation of motion an Euler-Lagrange equation.
    HeavyTop (J), coordinates q = (phi, theta, psi) of shape (3, ...):
    :math:`\tfrac{I_1}{2}(\dot\theta^2 + \dot\phi^2\sin^2\theta)
    + \tfrac{I_3}{2}(\dot\psi + \dot\phi\cos\theta)^2 - Mgl\cos\theta`.
    A compiled scene of d coordinates (``mp.lagrangian``): q of shape (d, ...).

    Parameters
    ----------
    scene : Pendulum, Duffing, HeavyTop or a compiled scene

    Returns
    -------
    callable
        ``L(q, qdot, t=0.0)``; one-coordinate scenes take q of any shape.

    Raises
    ------
    TypeError
        ``scene`` is not a scene with a Lagrangian.

    Examples
    --------
    The pendulum's L = l^2 theta_dot^2 / 2 + g l cos(theta) per unit mass:

    >>> L = mp.variational.lagrangian(mp.scenes.Pendulum(g=9.81, length=2.0))
    >>> round(float(L(0.0, 1.0)), 10), 2.0**2 * 1.0**2 / 2 + 9.81 * 2.0
    (21.62, 21.62)
    """
    if not isinstance(scene, Scene) and getattr(scene, "_lagrangian_c", None) is None:
        raise TypeError("scene must be a mechpy scene with a Lagrangian (Pendulum, Duffing, "
                        f"HeavyTop or a compiled mp.lagrangian scene), got {type(scene).__name__}")
    spec = _scene_spec(scene)
    d = _spec_dim(spec)

    def L(q, qdot, t=0.0):
        q = np.asarray(q, dtype=np.float64)
        qdot = np.asarray(qdot, dtype=np.float64)
        if d == 1:
            q, qdot, tt = np.broadcast_arrays(q, qdot, np.asarray(t, dtype=np.float64))
            shape = q.shape
            Q, V = q.reshape(-1, 1), qdot.reshape(-1, 1)
        else:
            if q.shape[:1] != (d,) or qdot.shape != q.shape:
                raise ValueError(f"q and qdot must have shape ({d}, ...), got {q.shape} and "
                                 f"{qdot.shape}")
            shape = q.shape[1:]
            tt = np.broadcast_to(np.asarray(t, dtype=np.float64), shape)
            Q, V = q.reshape(d, -1).T, qdot.reshape(d, -1).T
        out = _core.variational_eval(spec, np.ascontiguousarray(tt, dtype=np.float64).ravel(),
                                     np.ascontiguousarray(Q), np.ascontiguousarray(V))
        return out[:, 0].reshape(shape)
    L.__doc__ = f"Lagrangian of {scene!r}."
    return L


def _split(q, qdot):
    q = as_array(q, "q")
    qdot = as_array(qdot, "qdot")
    if q.shape != qdot.shape:
        raise ValueError(f"q and qdot must have the same shape, got {q.shape} and {qdot.shape}")
    return q, qdot


def _partials(L, q, qdot, which):
    """dL/dq_i (which = 0) or dL/dqdot_i (which = 1) by 4th-order central
    differences; q of shape (d, ...) or (...) for one coordinate."""
    q, qdot = _split(q, qdot)
    one = q.ndim == 0
    if one:
        q, qdot = q[None], qdot[None]
    base = [q, qdot]
    out = np.empty_like(q)
    for i in range(q.shape[0]):
        z = base[which]
        hh = 1e-3 * (1 + np.abs(z[i]))
        vals = []
        for k in (1, -1, 2, -2):
            zz = z.copy()
            zz[i] = z[i] + k * hh
            args = [q, qdot]
            args[which] = zz
            if one:
                args = [a[0] for a in args]
            val = np.asarray(L(*args), dtype=float)
            if not one and q.shape[0] == 1 and val.shape == q.shape:
                val = val[0]     # a one-coordinate L that keeps the leading axis
            vals.append(val)
        out[i] = (8 * (vals[0] - vals[1]) - (vals[2] - vals[3])) / (12 * hh)
    return out[0] if one else out


def generalized_momenta(L: Callable, q, qdot) -> np.ndarray:
    r"""Generalized momenta :math:`p_i = \partial L/\partial\dot q_i`.

    Parameters
    ----------
    L : callable ``L(q, qdot)`` or a scene
        Vectorised: q and qdot of shape (d, ...) (or scalars for one
        coordinate); a one-coordinate scene takes q of any shape (samples of
        it), a HeavyTop q = (phi, theta, psi) of shape (3, ...).
    q, qdot : array_like
        Coordinates and velocities, same shape.

    Returns
    -------
    ndarray
        Same shape as q (units of L times s per unit of q).

    Examples
    --------
    For the pendulum p = l^2 theta_dot; for a central force p_phi = m r^2 phi_dot:

    >>> p = mp.variational.generalized_momenta(mp.scenes.Pendulum(length=2.0), 0.3, 1.5)
    >>> round(float(p), 6)
    6.0
    >>> cf = mp.variational.CentralForce(m=2.0)
    >>> np.round(mp.variational.generalized_momenta(cf, [3.0, 0.0], [0.5, 0.1]), 6)
    array([1. , 1.8])
    """
    if _has_lagrangian(L) and _spec_dim(_scene_spec(L)) == 1:  # one coordinate: any shape
        q, qdot = _split(q, qdot)
        return _partials(lagrangian(L), q[None], qdot[None], 1)[0]
    return _partials(_as_lagrangian(L), q, qdot, 1)


def cyclic_coordinates(L: Callable, q, qdot, *, atol: float = 1e-8) -> tuple:
    r"""Indices i of the coordinates that L does not depend on,
    :math:`\partial L/\partial q_i = 0` (so that :math:`p_i` is conserved),
    tested at the sample states (q, qdot) of shape (d, ...).

    Examples
    --------
    >>> cf = mp.variational.CentralForce()
    >>> q, qdot = np.array([[1.0, 2.0], [0.3, 0.7]]), np.array([[0.1, 0.2], [1.0, 0.5]])
    >>> mp.variational.cyclic_coordinates(cf, q, qdot)              # phi: p_phi is conserved
    (1,)
    """
    q, qdot = _split(q, qdot)
    if q.ndim == 0:
        q, qdot = q[None], qdot[None]
    dLdq = _partials(_as_lagrangian(L), q, qdot, 0)
    scale = np.max(np.abs(_partials(_as_lagrangian(L), q, qdot, 1))) + 1.0
    flat = np.abs(dLdq.reshape(q.shape[0], -1))
    return tuple(int(i) for i in range(q.shape[0]) if np.all(flat[i] <= atol * scale))


def _as_lagrangian(L):
    if isinstance(L, Scene) or getattr(L, "_lagrangian_c", None) is not None:
        return lagrangian(L)
    if not callable(L):
        raise TypeError("L must be a callable L(q, qdot) or a scene")
    return L


class CentralForce:
    r"""A particle in the plane under an attractive inverse-square force.

    .. math:: L(r, \varphi, \dot r, \dot\varphi) = \tfrac12 m(\dot r^2 + r^2\dot\varphi^2)
              + \frac{k}{r}

    Coordinates q = (r, phi): phi is cyclic, so
    :math:`p_\varphi = m r^2\dot\varphi` (the angular momentum) is conserved.
    Units: m (kg), k (J m).

    Examples
    --------
    A circular orbit of radius r has phi_dot^2 = k / (m r^3); p_phi stays at
    m r^2 phi_dot:

    >>> cf = mp.variational.CentralForce(m=1.0, k=1.0)
    >>> y0 = np.array([1.0, 0.0, 0.0, 1.0])                         # (r, phi, r', phi')
    >>> s = mp.solve(cf.rhs, (0, 2 * np.pi), y0, rtol=1e-11, atol=1e-12)
    >>> np.round(s.y[:, -1], 7)                                     # one period later
    array([1.       , 6.2831853, 0.       , 1.       ])
    >>> np.round(cf.momenta(s.y[:, -1]), 10) + 0.0
    array([0., 1.])
    """

    def __init__(self, m: float = 1.0, k: float = 1.0):
        self.m = as_scalar(m, "m", positive=True)
        self.k = as_scalar(k, "k", positive=True)

    def __call__(self, q, qdot):
        r, _ = q
        rd, phid = qdot
        return 0.5 * self.m * (rd * rd + r * r * phid * phid) + self.k / r

    def rhs(self, t, y):
        """d/dt of the state (r, phi, r_dot, phi_dot), for :func:`mechpy.solve`."""
        r, _, rd, phid = y
        return np.array([rd, phid, r * phid * phid - self.k / (self.m * r * r),
                         -2 * rd * phid / r], dtype=np.float64)

    def momenta(self, y):
        """(p_r, p_phi) = (m r_dot, m r^2 phi_dot) for states (4, ...)."""
        y = np.asarray(y, dtype=float)
        return np.stack([self.m * y[2], self.m * y[0] ** 2 * y[3]])


class RotatingHoop:
    r"""A bead on a hoop of radius R spun at a constant rate omega about its
    vertical diameter; theta is measured from the bottom.

    .. math:: L = \tfrac12 mR^2(\dot\theta^2 + \omega^2\sin^2\theta) + mgR\cos\theta

    The hoop's rotation is imposed (phi = omega t is not a coordinate): the
    energy is not conserved, but L has no explicit time, so the energy function
    :math:`h = \tfrac12 mR^2(\dot\theta^2 - \omega^2\sin^2\theta) - mgR\cos\theta`
    (the Jacobi integral) is.  Units: SI.

    Examples
    --------
    Above omega^2 = g / R the bottom is unstable and the bead rests at
    cos(theta) = g / (omega^2 R); the Jacobi integral is conserved:

    >>> hoop = mp.variational.RotatingHoop(R=1.0, omega=5.0)
    >>> th0 = np.arccos(9.81 / 25.0)
    >>> np.round(hoop.rhs(0.0, np.array([th0, 0.0])), 12) + 0.0      # at rest there
    array([0., 0.])
    >>> s = mp.solve(hoop.rhs, (0, 5), [0.3, 0.0], rtol=1e-11, atol=1e-12)
    >>> bool(abs(hoop.jacobi_integral(s.y[:, -1]) - hoop.jacobi_integral(s.y[:, 0])) < 1e-8)
    True
    """

    def __init__(self, R: float = 1.0, omega: float = 5.0, g: float = 9.81, m: float = 1.0):
        self.R = as_scalar(R, "R", positive=True)
        self.omega = as_scalar(omega, "omega")
        self.g = as_scalar(g, "g", positive=True)
        self.m = as_scalar(m, "m", positive=True)

    def __call__(self, q, qdot):
        m, R, w, g = self.m, self.R, self.omega, self.g
        return 0.5 * m * R * R * (qdot ** 2 + (w * np.sin(q)) ** 2) + m * g * R * np.cos(q)

    def rhs(self, t, y):
        """d/dt (theta, theta_dot), for :func:`mechpy.solve`."""
        th, thd = y
        return np.array([thd, np.sin(th) * (self.omega ** 2 * np.cos(th) - self.g / self.R)],
                        dtype=np.float64)

    def jacobi_integral(self, y):
        """h(theta, theta_dot) (J) for states (2, ...)."""
        th, thd = np.asarray(y, dtype=float)
        m, R, w = self.m, self.R, self.omega
        return 0.5 * m * R * R * (thd ** 2 - (w * np.sin(th)) ** 2) - m * self.g * R * np.cos(th)

    def normal_force(self, t, y) -> np.ndarray:
        r"""The hoop's force on the bead from Lagrange multipliers, shape (3, ...).

        The bead is a free particle in Cartesian coordinates with two
        constraints, :math:`|\mathbf r|^2 = R^2` and
        :math:`-\sin(\omega t)x + \cos(\omega t)y = 0` (the hoop's plane);
        :func:`constraint_forces` gives the multipliers.  Returned are the
        components (radial outward, azimuthal along the rotation, vertical
        plane tangent) in N: the radial one is
        :math:`-mR(\dot\theta^2 + \omega^2\sin^2\theta) - mg\cos\theta`, the
        azimuthal one :math:`2mR\omega\dot\theta\cos\theta` (the Coriolis
        push), the tangential one 0.

        Parameters
        ----------
        t : float or array_like
            Time(s) (s), broadcast against the states' trailing axes.
        y : array_like, shape (2, ...)
            States (theta, theta_dot), e.g. ``Solution.y``.

        Returns
        -------
        ndarray, shape (3, ...)
            A function of states: the component axis first, then the states'
            axes broadcast with t (the layout rule in :mod:`mechpy`).
        """
        y = as_array(y, "y", min_ndim=1)
        if y.shape[0] != 2:
            raise ValueError(f"y must have 2 components (theta, theta_dot) along its first "
                             f"axis, got shape {y.shape}")
        t = as_array(t, "t")
        try:
            t, th, thd = np.broadcast_arrays(t, y[0], y[1])
        except ValueError:
            raise ValueError(f"t of shape {t.shape} does not broadcast against the states' "
                             f"axes {y.shape[1:]}") from None
        R, w, m, g = self.R, self.omega, self.m, self.g
        c, s = np.cos(w * t), np.sin(w * t)
        st, ct = np.sin(th), np.cos(th)
        zero = np.zeros_like(th)
        # Cartesian vectors as stacks (..., 3) for constraint_forces
        rhat = np.stack([st * c, st * s, -ct], axis=-1)
        phat = np.stack([-s, c, zero], axis=-1)
        that = np.stack([ct * c, ct * s, st], axis=-1)
        vel = R * thd[..., None] * that + R * w * st[..., None] * phat
        J = np.stack([R * rhat, phat], axis=-2)                                  # (..., 2, 3)
        bias = np.stack([np.sum(vel * vel, axis=-1),
                         -2 * w * (c * vel[..., 0] + s * vel[..., 1])], axis=-1)
        F = np.stack([zero, zero, np.full_like(th, -m * g)], axis=-1)
        _, N = constraint_forces(m, F, J, bias)
        return np.stack([np.sum(N * rhat, -1), np.sum(N * phat, -1), np.sum(N * that, -1)])
