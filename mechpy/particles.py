r"""Systems of particles: collisions and the centre-of-mass frame.

Two bodies collide along a line (1D) or along a contact ``normal`` (2D and
3D, the tangential components unchanged, no friction); the coefficient of
restitution e relates the normal relative velocities after and before,
:math:`u_2' - u_1' = -e\,(u_2 - u_1)`, and momentum is conserved:

.. math:: u_1' = \frac{m_1u_1 + m_2u_2 - m_2e(u_1 - u_2)}{m_1 + m_2},\qquad
          u_2' = \frac{m_1u_1 + m_2u_2 + m_1e(u_1 - u_2)}{m_1 + m_2},

losing the kinetic energy :math:`\Delta T = \tfrac12(1 - e^2)\,\mu\,(u_1 - u_2)^2`,
:math:`\mu = m_1m_2/(m_1 + m_2)` (Marion & Thornton, sections 9.6-9.7).

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
batches first, the vector axis last: velocities (..., d) with ``normal``;
without it each element is one 1D collision.
"""
from __future__ import annotations

import numpy as np

from ._validate import as_array

__all__ = ["collide", "to_cm", "from_cm"]


def _masses(m, name: str) -> np.ndarray:
    m = as_array(m, name)
    if not (m > 0).all():
        raise ValueError(f"{name} must be positive (kg), got min {float(m.min())!r}")
    return m


def _broadcast(arrays: dict) -> list:
    try:
        return np.broadcast_arrays(*arrays.values())
    except ValueError:
        shapes = ", ".join(f"{k} {np.shape(v)}" for k, v in arrays.items())
        raise ValueError(f"shape mismatch: {shapes} do not broadcast together") from None


def collide(m1, v1, m2, v2, e=1.0, normal=None):
    r"""Velocities after a collision of two bodies with coefficient of
    restitution e.

    Parameters
    ----------
    m1, m2 : float or array_like (...)
        Masses (kg), positive.
    v1, v2 : array_like
        Velocities before (m/s): without ``normal``, 1D velocities of any
        shape (...) (each element one collision along the line); with
        ``normal``, vectors (..., d), d = 2 or 3.
    e : float or array_like (...)
        Coefficient of restitution, 0 <= e <= 1 (1 elastic, 0 the bodies
        move on together along the normal).
    normal : array_like (..., d), optional
        The contact normal (the line of centres at impact for spheres); any
        length but zero.  Only the velocity components along it change.

    Returns
    -------
    v1_after, v2_after : ndarray
        The velocities after (m/s), of the broadcast shape of the inputs
        ((...) or (..., d)).

    Raises
    ------
    ValueError
        Non-positive or non-finite masses, e outside [0, 1], a zero normal,
        a normal or velocities of length other than 2 or 3, shapes that do
        not broadcast.

    Notes
    -----
    The formula is applied whether or not the bodies approach
    (:math:`(v_1 - v_2)\cdot\hat n > 0`): checking contact is the caller's.

    Examples
    --------
    Equal masses, elastic, in 1D: the velocities are exchanged.

    >>> import mechpy as mp
    >>> [float(v) for v in mp.particles.collide(1.0, 2.0, 1.0, 0.0)]
    [0.0, 2.0]
    """
    m1, m2 = _masses(m1, "m1"), _masses(m2, "m2")
    v1, v2 = as_array(v1, "v1"), as_array(v2, "v2")
    e = as_array(e, "e")
    if not ((e >= 0) & (e <= 1)).all():
        raise ValueError(f"e (the coefficient of restitution) must lie in [0, 1], got {e}")
    M = m1 + m2
    if normal is None:
        m1, v1, m2, v2, e = _broadcast(dict(m1=m1, v1=v1, m2=m2, v2=v2, e=e))
        p = m1 * v1 + m2 * v2
        du = v1 - v2
        return (p - m2 * e * du) / M, (p + m1 * e * du) / M
    n = as_array(normal, "normal", min_ndim=1)
    d = n.shape[-1]
    if d not in (2, 3):
        raise ValueError(f"normal must be a 2D or 3D vector (last axis of length 2 or 3), "
                         f"got shape {n.shape}")
    for name, v in (("v1", v1), ("v2", v2)):
        if v.ndim < 1 or v.shape[-1] != d:
            raise ValueError(f"{name} must have a last axis of length {d} (the normal's), "
                             f"got shape {v.shape}")
    nn = np.linalg.norm(n, axis=-1, keepdims=True)
    if not (nn > 0).all():
        raise ValueError("normal must not be the zero vector")
    n = n / nn
    # scalars per collision get a trailing axis of 1 to meet the vectors
    m1, m2, e, M = (np.asarray(a)[..., None] for a in (m1, m2, e, M))
    v1, v2, n, m1, m2, e, M = _broadcast(dict(v1=v1, v2=v2, normal=n, m1=m1, m2=m2, e=e, M=M))
    u1 = np.sum(v1 * n, axis=-1, keepdims=True)
    u2 = np.sum(v2 * n, axis=-1, keepdims=True)
    p = m1 * u1 + m2 * u2
    du = u1 - u2
    u1a, u2a = (p - m2 * e * du) / M, (p + m1 * e * du) / M
    return v1 + (u1a - u1) * n, v2 + (u2a - u2) * n


def _system(masses, velocities):
    m = _masses(masses, "masses")
    if m.ndim < 1:
        raise ValueError(f"masses must hold one mass per particle (shape (..., k)), "
                         f"got shape {m.shape}")
    v = as_array(velocities, "velocities", min_ndim=1)
    if v.shape == m.shape:
        return m, v, False
    if v.ndim == m.ndim + 1 and v.shape[:-1] == m.shape:
        return m, v, True
    raise ValueError(f"velocities must have the masses' shape {m.shape} (1D motion) or "
                     f"{m.shape + ('d',)} (vectors), got {v.shape}")


def to_cm(masses, velocities):
    r"""The centre-of-mass velocity and the velocities relative to it.

    .. math:: \mathbf V = \frac{\sum_i m_i\mathbf v_i}{\sum_i m_i},\qquad
              \mathbf u_i = \mathbf v_i - \mathbf V,\qquad \sum_i m_i\mathbf u_i = 0

    Parameters
    ----------
    masses : array_like (..., k)
        The k particles' masses (kg), positive.
    velocities : array_like (..., k) or (..., k, d)
        Their velocities (m/s): 1D, or vectors along the last axis.

    Returns
    -------
    V : ndarray (...) or (..., d)
        Centre-of-mass velocity (m/s).
    u : ndarray, the shape of ``velocities``
        Velocities in the centre-of-mass frame (m/s).

    Examples
    --------
    >>> import mechpy as mp
    >>> V, u = mp.particles.to_cm([1.0, 3.0], [4.0, 0.0])
    >>> float(V), u.tolist()
    (1.0, [3.0, -1.0])
    """
    m, v, vec = _system(masses, velocities)
    M = np.sum(m, axis=-1)
    if vec:
        V = np.sum(m[..., None] * v, axis=-2) / M[..., None]
        return V, v - V[..., None, :]
    V = np.sum(m * v, axis=-1) / M
    return V, v - V[..., None]


def from_cm(V, u):
    r"""Velocities in the lab frame from the centre-of-mass velocity and the
    velocities relative to the centre of mass: :math:`\mathbf v_i = \mathbf u_i
    + \mathbf V` (the inverse of :func:`to_cm`).

    Parameters
    ----------
    V : array_like (...) or (..., d)
        Centre-of-mass velocity (m/s).
    u : array_like (..., k) or (..., k, d)
        Velocities relative to the centre of mass (m/s).  When both
        readings fit (V (3,) and u (3, 3)), u is read as 1D velocities.

    Returns
    -------
    ndarray, the shape of ``u``
        Lab-frame velocities (m/s).

    Examples
    --------
    >>> u = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])   # equal masses, opposite velocities
    >>> mp.particles.from_cm([0.5, 2.0, 0.0], u)
    array([[ 1.5,  2. ,  0. ],
           [-0.5,  2. ,  0. ]])
    """
    V = as_array(V, "V")
    u = as_array(u, "u", min_ndim=1)
    if V.shape == u.shape[:-1]:
        return u + V[..., None]
    if V.ndim >= 1 and u.ndim >= 2 and V.shape == u.shape[:-2] + u.shape[-1:]:
        return u + V[..., None, :]
    raise ValueError(f"V of shape {V.shape} does not match u of shape {u.shape}: expected "
                     f"V (...) with u (..., k), or V (..., d) with u (..., k, d)")
