"""Rotations: Euler angles, quaternions and angular velocity.

Sequences are named as SciPy names them: three letters from ``xyz``, upper
case intrinsic (rotations about the moving axes, ``"ZXZ"``), lower case
extrinsic (about the fixed axes, ``"zxz"``); the twelve proper Euler and
Tait-Bryan sequences of each kind (:data:`SEQUENCES`).

The default is the textbook's (Marion & Thornton, section 5 of the course
notes): ``seq="ZXZ"`` with ``passive=True``, the coordinate transformation

.. math:: \\lambda = \\lambda_\\psi \\lambda_\\theta \\lambda_\\phi, \\qquad x = \\lambda x',

from fixed components :math:`x'` to body components :math:`x`.  It is the
transpose of the *active* matrix that SciPy builds:
``euler_matrix(phi, theta, psi) == Rotation.from_euler("ZXZ", [phi, theta,
psi]).as_matrix().T``.  ``passive=False`` gives SciPy's active matrix
:math:`R = \\lambda^T` (body components to space components).  Every
``passive`` flag defaults to True, the interchange with SciPy's too:
``to_scipy(euler_matrix(phi, theta, psi))`` is ``Rotation.from_euler("ZXZ",
[phi, theta, psi])``, and :func:`from_scipy` is its inverse.

Quaternions are scalar-last ``(x, y, z, w)`` as in SciPy; a quaternion
stands for the matrix that :func:`matrix_from_quat` makes of it.

Every function is vectorised over leading batch axes and runs its loop in C
with the GIL released.  Angles are in radians, rates and angular velocities
in rad/s (any consistent time unit).

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
NumPy stacks: angles (..., 3), matrices (..., 3, 3), quaternions (..., 4).
"""
from __future__ import annotations

import re
import warnings

import numpy as np

from . import _core
from ._validate import as_array, as_scalar, as_square, as_vector3
from .errors import SingularityError  # noqa: F401  (raised by euler_rates)

__all__ = [
    "euler_matrix", "euler_angles", "angular_velocity", "euler_rates",
    "quat_from_matrix", "matrix_from_quat", "quat_multiply", "quat_normalize",
    "quat_from_euler", "euler_from_quat", "GimbalLockWarning", "SEQUENCES",
    "ORTH_TOL", "LOCK_TOL", "RATES_LOCK_TOL", "to_scipy", "from_scipy",
]

#: Every accepted sequence: 12 intrinsic (upper case), then 12 extrinsic.
SEQUENCES = tuple(s for case in (str.upper, str.lower)
                  for s in (case(a + b + c) for a in "xyz" for b in "xyz" for c in "xyz")
                  if s[0] != s[1] and s[1] != s[2])

#: Default tolerance on ``max|R R^T - I|`` for a matrix to count as a rotation.
ORTH_TOL = 1e-6
#: Default distance (radians) of the middle angle from its singular values
#: (0 or pi for proper Euler sequences, +-pi/2 for Tait-Bryan ones) within
#: which :func:`euler_angles` and :func:`euler_from_quat` report gimbal lock:
#: 0, lock only where the first and third angles are indeterminate in float64
#: (the sine of that distance below the smallest normal number, 2.2e-308).
LOCK_TOL = 0.0
#: Default bound on ``|det J|`` below which :func:`euler_rates` raises
#: :class:`mechpy.SingularityError` (the rates grow as 1 / det J).
RATES_LOCK_TOL = 1e-12

_SEQ_RE = re.compile(r"^([XYZ]{3}|[xyz]{3})$")


class GimbalLockWarning(UserWarning):
    """The first and third rotation axes coincide; the third angle was set to 0.

    Silence it with ``warnings.simplefilter("ignore", GimbalLockWarning)``.

    Examples
    --------
    At theta = 0 only phi + psi is determined: psi is set to 0 and phi carries the sum.

    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     angles = mp.rotation.euler_angles(mp.rotation.euler_matrix(0.3, 0.0, 0.4))
    >>> np.round(angles, 12), w[0].category.__name__
    (array([0.7, 0. , 0. ]), 'GimbalLockWarning')
    """


def _seq(seq) -> str:
    if not isinstance(seq, str):
        raise TypeError(f"seq must be a string such as 'ZXZ', got {type(seq).__name__}")
    if not _SEQ_RE.match(seq) or seq[0] == seq[1] or seq[1] == seq[2]:
        raise ValueError("seq must be three axis letters, all upper case (intrinsic) or all "
                         "lower case (extrinsic), no two consecutive alike, one of "
                         f"{', '.join(SEQUENCES)}; got {seq!r}")
    return seq


def _flag(x, name: str) -> bool:
    if isinstance(x, (bool, np.bool_)) or (isinstance(x, (int, np.integer)) and x in (0, 1)):
        return bool(x)
    raise TypeError(f"{name} must be True or False, got {x!r}")


def _frame(frame) -> bool:
    if frame not in ("body", "space"):
        raise ValueError(f"frame must be 'body' or 'space', got {frame!r}")
    return frame == "space"


def _tol(x, name: str) -> float:
    return as_scalar(x, name, nonnegative=True)


def _vectors(x, name: str, k: int) -> np.ndarray:
    a = as_array(x, name, min_ndim=1, allow_empty=True)
    if a.shape[-1] != k:
        raise ValueError(f"{name} must have a last axis of length {k}, got shape {a.shape}")
    return a


def _matrices(R, name: str = "R") -> np.ndarray:
    return as_square(R, name, n=3, batch=True, allow_empty=True)


def _angles(phi, theta, psi, seq, passive):
    """Accept (angles[..., 3]) or (phi, theta, psi); a string in theta's place is seq."""
    if isinstance(theta, str):
        if psi is not None:
            passive = psi
        seq, theta, psi = theta, None, None
    if theta is None and psi is None:
        return _vectors(phi, "angles", 3), seq, passive
    if theta is None or psi is None:
        raise TypeError("give either angles (..., 3) or all three of phi, theta, psi")
    # as_array returns at least 1-d; keep a scalar's shape ()
    p = as_array(phi, "phi", allow_empty=True).reshape(np.shape(phi))
    t = as_array(theta, "theta", allow_empty=True).reshape(np.shape(theta))
    s = as_array(psi, "psi", allow_empty=True).reshape(np.shape(psi))
    try:
        p, t, s = np.broadcast_arrays(p, t, s)
    except ValueError:
        raise ValueError(f"phi, theta and psi must broadcast together, got shapes "
                         f"{p.shape}, {t.shape}, {s.shape}") from None
    return np.stack([p, t, s], axis=-1), seq, passive


def _from_angles(core_fn, item_shape, phi, theta, psi, seq, passive, degrees):
    """Run a C angles -> matrix/quaternion conversion on the batch of angles."""
    angles, seq, passive = _angles(phi, theta, psi, seq, passive)
    if _flag(degrees, "degrees"):
        angles = np.radians(angles)
    out = core_fn(angles.reshape(-1, 3), _seq(seq), _flag(passive, "passive"))
    return out.reshape(angles.shape[:-1] + item_shape)


def _warn_lock(nlock: int, n: int, seq: str) -> None:
    if nlock:
        which = "0 or pi" if seq[0].lower() == seq[2].lower() else "+-pi/2"
        warnings.warn(GimbalLockWarning(
            f"gimbal lock in {nlock} of {n} rotation(s) (middle angle of {seq!r} at {which}): "
            "only the sum or difference of the first and third angles is determined; "
            "the third angle was set to 0"), stacklevel=4)


def _angles_of(core_fn, x, item_ndim, seq, passive, *tols):
    """Run a C matrix/quaternion -> angles conversion on the batch x; warn at lock."""
    seq = _seq(seq)
    passive = _flag(passive, "passive")
    shape = x.shape[:x.ndim - item_ndim]
    k = int(np.prod(x.shape[x.ndim - item_ndim:]))
    out, nlock = core_fn(x.reshape(-1, k), seq, passive, *tols)
    _warn_lock(nlock, out.shape[0], seq)
    return out.reshape(shape + (3,))


def euler_matrix(phi, theta=None, psi=None, seq: str = "ZXZ", passive: bool = True, *,
                 degrees: bool = False) -> np.ndarray:
    r"""Rotation matrix from Euler angles.

    For an intrinsic sequence ``"ABC"`` the active matrix is
    :math:`R = R_A(\phi) R_B(\theta) R_C(\psi)`, for an extrinsic ``"abc"``
    it is :math:`R = R_c(\psi) R_b(\theta) R_a(\phi)`, with
    :math:`R_z(\alpha) = [[\cos\alpha, -\sin\alpha, 0], [\sin\alpha, \cos\alpha, 0], [0, 0, 1]]`.
    The passive matrix (default) is :math:`\lambda = R^T`; for ``"ZXZ"`` it
    is the textbook's :math:`\lambda = \lambda_\psi \lambda_\theta \lambda_\phi`.

    Parameters
    ----------
    phi, theta, psi : array_like
        The first, second and third angles (rad); broadcast together.  Or
        give one array ``angles`` of shape (..., 3) as ``phi`` alone.
    seq : str
        One of :data:`SEQUENCES`; default ``"ZXZ"``.
    passive : bool
        True (default): the coordinate transformation ``x_body = L x_space``;
        False: SciPy's active matrix, ``Rotation.from_euler(seq, angles).as_matrix()``.
    degrees : bool
        Angles in degrees instead of radians (as SciPy's ``degrees``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Orthogonal matrices with determinant +1 (dimensionless).

    Examples
    --------
    >>> import numpy as np, mechpy as mp
    >>> L = mp.rotation.euler_matrix(0.3, 0.2, 0.1)      # lambda_psi lambda_theta lambda_phi
    >>> np.allclose(L @ L.T, np.eye(3))
    True
    """
    return _from_angles(_core.rotation_euler_matrix, (3, 3), phi, theta, psi, seq, passive, degrees)


def euler_angles(R, seq: str = "ZXZ", passive: bool = True, *, degrees: bool = False,
                 orth_tol: float = ORTH_TOL, lock_tol: float = LOCK_TOL) -> np.ndarray:
    r"""Euler angles of rotation matrices (the inverse of :func:`euler_matrix`).

    Ranges: the first and third angles in [-pi, pi]; the middle one in
    [0, pi] for proper Euler sequences (``"ZXZ"``, ...) and [-pi/2, pi/2]
    for Tait-Bryan ones (``"XYZ"``, ...).

    The angles are read from pairs of entries of the matrix, each pair
    proportional to the sine and cosine of its angle with a common factor
    (the sine of the middle angle's distance from lock): for the default
    ``"ZXZ"``, :math:`\theta = \mathrm{atan2}(\sqrt{R_{20}^2 + R_{21}^2}, R_{22})`,
    :math:`\psi = \mathrm{atan2}(R_{20}, R_{21})`,
    :math:`\phi = \mathrm{atan2}(R_{02}, -R_{12})` (active R).  So every
    angle comes back to round-off however close the middle one is to lock
    (theta = 1e-300 included), as long as that factor is a normal float64.

    At gimbal lock (the factor below the smallest normal number, 2.2e-308, or
    the middle angle within ``lock_tol`` of 0 or pi, or of +-pi/2 for
    Tait-Bryan sequences) only the sum or difference of the first and third
    angles is determined: the third is set to 0, the first is read from what
    is left of the matrix, and one :class:`GimbalLockWarning` is issued per
    call.  SciPy's ``as_euler`` reports lock (and loses the first and third
    angles) within 1e-7 rad; pass ``lock_tol=1e-7`` for the same band.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (passive, i.e. coordinate transformations, when
        ``passive`` is True).
    seq : str
        One of :data:`SEQUENCES`; default ``"ZXZ"``.
    passive : bool
        Whether ``R`` is the passive matrix (default) or the active one.
    degrees : bool
        Return degrees instead of radians (``lock_tol`` stays in radians).
    orth_tol : float
        ``R`` must satisfy ``max|R R^T - I| <= orth_tol`` (default 1e-6) and
        ``det R > 0``; otherwise :class:`mechpy.DomainError` (a ValueError).
    lock_tol : float
        Gimbal-lock band (rad), default 0: lock only where the angles are
        indeterminate in float64 (see above).

    Returns
    -------
    ndarray, shape (..., 3)
        ``(phi, theta, psi)`` in rad.

    Examples
    --------
    The angles come back from the matrix they make:

    >>> R = mp.rotation.euler_matrix(0.3, 1.1, -0.7)           # ZXZ, passive
    >>> np.round(mp.rotation.euler_angles(R), 12)
    array([ 0.3,  1.1, -0.7])
    >>> mp.rotation.euler_angles(mp.rotation.euler_matrix(30, 45, 60, "XYZ", degrees=True),
    ...                          "XYZ", degrees=True).round(9)
    array([30., 45., 60.])
    """
    R = _matrices(R)
    out = _angles_of(_core.rotation_euler_angles, R, 2, seq, passive,
                     _tol(orth_tol, "orth_tol"), _tol(lock_tol, "lock_tol"))
    return np.degrees(out) if _flag(degrees, "degrees") else out


def quat_from_matrix(R, *, orth_tol: float = ORTH_TOL) -> np.ndarray:
    r"""Unit quaternions (x, y, z, w) of rotation matrices.

    Markley's variant of Shepperd's method: the largest of
    :math:`(\mathrm{tr} R, R_{00}, R_{11}, R_{22})` selects the formula, e.g.
    :math:`q = (R_{21}-R_{12}, R_{02}-R_{20}, R_{10}-R_{01}, 1+\mathrm{tr} R)/|\cdot|`,
    so that no division by a small number occurs; the sign matches
    ``scipy.spatial.transform.Rotation.from_matrix(R).as_quat()``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices; ``max|R R^T - I| <= orth_tol`` and ``det R > 0``
        are required (:class:`mechpy.DomainError` otherwise).
    orth_tol : float
        Default 1e-6.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions, scalar last (dimensionless); ``matrix_from_quat``
        of them gives ``R`` back.

    Examples
    --------
    A quarter turn about z: q = (0, 0, sin(pi/4), cos(pi/4)).

    >>> R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    >>> q = mp.rotation.quat_from_matrix(R)
    >>> np.round(q, 12), round(float(np.sqrt(0.5)), 12)
    (array([0.        , 0.        , 0.70710678, 0.70710678]), 0.707106781187)
    """
    R = _matrices(R)
    shape = R.shape[:-2]
    q = _core.rotation_quat_from_matrix(R.reshape(-1, 9), _tol(orth_tol, "orth_tol"))
    return q.reshape(shape + (4,))


def matrix_from_quat(quat) -> np.ndarray:
    r"""Rotation matrices of quaternions (x, y, z, w), normalised first.

    .. math:: R = I + 2 w [v]_\times + 2 [v]_\times^2, \qquad v = (x, y, z),\ |q| = 1.

    Parameters
    ----------
    quat : array_like, shape (..., 4)
        Non-zero quaternions, scalar last.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The active rotation matrices (dimensionless), as
        ``Rotation.from_quat(quat).as_matrix()``.

    Examples
    --------
    The quaternion (0, 0, 1, 1) (normalised here) is a quarter turn about z:

    >>> np.round(mp.rotation.matrix_from_quat([0.0, 0.0, 1.0, 1.0]), 12)
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    q = _vectors(quat, "quat", 4)
    shape = q.shape[:-1]
    return _core.rotation_matrix_from_quat(q.reshape(-1, 4)).reshape(shape + (3, 3))


def quat_multiply(p, q) -> np.ndarray:
    r"""Hamilton product :math:`p q` (scalar last); broadcast over batch axes.

    .. math:: (p q)_w = p_w q_w - \vec p\cdot\vec q, \qquad
              \vec{(p q)} = p_w \vec q + q_w \vec p + \vec p \times \vec q.

    The product is the composition "q first, then p":
    ``matrix_from_quat(quat_multiply(p, q)) == matrix_from_quat(p) @ matrix_from_quat(q)``,
    as SciPy's ``Rotation.from_quat(p) * Rotation.from_quat(q)``.

    Parameters
    ----------
    p, q : array_like, shape (..., 4)
        Quaternions, scalar last (not normalised here).

    Returns
    -------
    ndarray, shape (..., 4)
        The products (dimensionless).

    Examples
    --------
    Two quarter turns about z make a half turn, (0, 0, 1, 0):

    >>> q = [0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)]
    >>> np.round(mp.rotation.quat_multiply(q, q), 12)
    array([0., 0., 1., 0.])
    """
    p = _vectors(p, "p", 4)
    q = _vectors(q, "q", 4)
    try:
        shape = np.broadcast_shapes(p.shape[:-1], q.shape[:-1])
    except ValueError:
        raise ValueError(f"p and q must broadcast together, got shapes {p.shape}, "
                         f"{q.shape}") from None
    pb = np.ascontiguousarray(np.broadcast_to(p, shape + (4,))).reshape(-1, 4)
    qb = np.ascontiguousarray(np.broadcast_to(q, shape + (4,))).reshape(-1, 4)
    return _core.rotation_quat_multiply(pb, qb).reshape(shape + (4,))


def quat_normalize(quat) -> np.ndarray:
    r"""Unit quaternions :math:`q / |q|` (overflow-safe); a zero quaternion is an error.

    Parameters
    ----------
    quat : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4)
        Quaternions of unit norm (dimensionless).

    Examples
    --------
    >>> mp.rotation.quat_normalize([0.0, 3.0, 0.0, 4.0])
    array([0. , 0.6, 0. , 0.8])
    """
    q = _vectors(quat, "quat", 4)
    shape = q.shape[:-1]
    return _core.rotation_quat_normalize(q.reshape(-1, 4)).reshape(shape + (4,))


def quat_from_euler(phi, theta=None, psi=None, seq: str = "ZXZ", passive: bool = True, *,
                    degrees: bool = False) -> np.ndarray:
    r"""Unit quaternions of the matrices :func:`euler_matrix` gives.

    Products of elementary quaternions
    :math:`q_A(\alpha) = (\sin\tfrac{\alpha}{2}\,\hat e_A, \cos\tfrac{\alpha}{2})`:
    :math:`q_A(\phi) q_B(\theta) q_C(\psi)` for intrinsic ``"ABC"``,
    :math:`q_c(\psi) q_b(\theta) q_a(\phi)` for extrinsic ``"abc"``; the passive
    quaternion is the conjugate.  With ``passive=False`` this is
    ``Rotation.from_euler(seq, angles).as_quat()`` (sign included).

    Parameters
    ----------
    phi, theta, psi : array_like
        Angles (rad), broadcast together; or one array (..., 3) as ``phi``.
    seq : str
        One of :data:`SEQUENCES`; default ``"ZXZ"``.
    passive : bool
        Default True (the textbook's coordinate transformation).
    degrees : bool
        Angles in degrees instead of radians.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions, scalar last (dimensionless).

    Examples
    --------
    The active rotation by phi about z (ZXZ with theta = psi = 0) is
    (0, 0, sin(phi/2), cos(phi/2)):

    >>> q = mp.rotation.quat_from_euler(1.0, 0.0, 0.0, passive=False)
    >>> np.round(q, 8), round(float(np.sin(0.5)), 8), round(float(np.cos(0.5)), 8)
    (array([0.        , 0.        , 0.47942554, 0.87758256]), 0.47942554, 0.87758256)
    """
    return _from_angles(_core.rotation_quat_from_euler, (4,), phi, theta, psi, seq, passive, degrees)


def euler_from_quat(quat, seq: str = "ZXZ", passive: bool = True, *, degrees: bool = False,
                    lock_tol: float = LOCK_TOL) -> np.ndarray:
    r"""Euler angles of quaternions (need not be unit): Bernardes and Viollet (2022).

    The middle angle is :math:`\theta = 2\,\mathrm{atan2}(|(c, d)|, |(a, b)|)` and
    the others :math:`\mathrm{atan2}(b, a) \pm \mathrm{atan2}(-d, c)`, exact to
    round-off as long as the smaller of :math:`|(a, b)|, |(c, d)|` is a normal
    number relative to the larger.  Ranges, gimbal-lock handling and the
    :class:`GimbalLockWarning` are those of :func:`euler_angles`.

    Parameters
    ----------
    quat : array_like, shape (..., 4)
        Non-zero quaternions, scalar last.
    seq : str
        One of :data:`SEQUENCES`; default ``"ZXZ"``.
    passive : bool
        Whether ``quat`` stands for the passive matrix (default) or the active one.
    degrees : bool
        Return degrees instead of radians.
    lock_tol : float
        Gimbal-lock band (rad), default 0 (see :func:`euler_angles`).

    Returns
    -------
    ndarray, shape (..., 3)
        ``(phi, theta, psi)`` in rad.

    Examples
    --------
    >>> q = mp.rotation.quat_from_euler(0.3, 1.1, -0.7)
    >>> np.round(mp.rotation.euler_from_quat(q), 12)
    array([ 0.3,  1.1, -0.7])
    >>> np.round(mp.rotation.euler_from_quat(2.5 * q), 12)     # need not be unit
    array([ 0.3,  1.1, -0.7])
    """
    q = _vectors(quat, "quat", 4)
    out = _angles_of(_core.rotation_euler_from_quat, q, 1, seq, passive,
                     _tol(lock_tol, "lock_tol"))
    return np.degrees(out) if _flag(degrees, "degrees") else out


def _pair(angles, other, name: str):
    a = as_vector3(angles, "angles", allow_empty=True)
    v = as_vector3(other, name, allow_empty=True)
    try:
        shape = np.broadcast_shapes(a.shape[:-1], v.shape[:-1])
    except ValueError:
        raise ValueError(f"angles and {name} must broadcast together, got shapes {a.shape}, "
                         f"{v.shape}") from None
    a = np.ascontiguousarray(np.broadcast_to(a, shape + (3,))).reshape(-1, 3)
    v = np.ascontiguousarray(np.broadcast_to(v, shape + (3,))).reshape(-1, 3)
    return a, v, shape


def angular_velocity(angles, rates, seq: str = "ZXZ", frame: str = "body") -> np.ndarray:
    r"""Angular velocity from Euler angles and their time derivatives.

    With :math:`R` the active matrix of the angles (body to space),
    :math:`[\omega_{space}]_\times = \dot R R^T` and
    :math:`[\omega_{body}]_\times = R^T \dot R = -\dot\lambda \lambda^T`.
    For intrinsic ``"ABC"``:
    :math:`\omega_{space} = \dot\phi\,\hat e_A + \dot\theta\,R_A \hat e_B + \dot\psi\,R_A R_B \hat e_C`.
    For the default ``"ZXZ"`` the body components are the textbook's

    .. math::
        \omega_1 = \dot\phi \sin\theta \sin\psi + \dot\theta \cos\psi, \quad
        \omega_2 = \dot\phi \sin\theta \cos\psi - \dot\theta \sin\psi, \quad
        \omega_3 = \dot\phi \cos\theta + \dot\psi.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        ``(phi, theta, psi)`` in rad.
    rates : array_like, shape (..., 3)
        Their time derivatives (rad/s); broadcast with ``angles``.
    seq : str
        One of :data:`SEQUENCES`; default ``"ZXZ"``.
    frame : {"body", "space"}
        Components along the body axes (default) or the fixed axes.

    Returns
    -------
    ndarray, shape (..., 3)
        Angular velocity (rad/s).

    Examples
    --------
    Spinning about the body's own axis only (theta fixed, psi_dot = 2): omega is
    (0, 0, 2) in the body; a pure precession phi_dot = 1 at theta = pi/2 has the
    body components (sin psi, cos psi, 0).

    >>> mp.rotation.angular_velocity([0.4, 0.9, 0.0], [0.0, 0.0, 2.0])
    array([0., 0., 2.])
    >>> psi = 0.5
    >>> np.round(mp.rotation.angular_velocity([0.0, np.pi / 2, psi], [1.0, 0.0, 0.0]), 12)
    array([0.47942554, 0.87758256, 0.        ])
    >>> round(float(np.sin(psi)), 8), round(float(np.cos(psi)), 8)
    (0.47942554, 0.87758256)
    """
    seq = _seq(seq)
    space = _frame(frame)
    a, r, shape = _pair(angles, rates, "rates")
    return _core.rotation_angular_velocity(a, r, seq, space).reshape(shape + (3,))


def euler_rates(angles, omega, seq: str = "ZXZ", frame: str = "body", *,
                lock_tol: float = RATES_LOCK_TOL) -> np.ndarray:
    r"""Euler-angle rates from the angular velocity (inverse of :func:`angular_velocity`).

    Solves :math:`J(\phi, \theta, \psi)\,(\dot\phi, \dot\theta, \dot\psi)^T = \omega`;
    :math:`\det J = \pm\sin\theta` for proper Euler sequences and
    :math:`\pm\cos\theta` for Tait-Bryan ones.  For ``"ZXZ"``, body frame:

    .. math::
        \dot\phi = \frac{\omega_1 \sin\psi + \omega_2 \cos\psi}{\sin\theta}, \quad
        \dot\theta = \omega_1 \cos\psi - \omega_2 \sin\psi, \quad
        \dot\psi = \omega_3 - \dot\phi \cos\theta.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        ``(phi, theta, psi)`` in rad.
    omega : array_like, shape (..., 3)
        Angular velocity (rad/s) in ``frame`` components; broadcast with ``angles``.
    seq : str
        One of :data:`SEQUENCES`; default ``"ZXZ"``.
    frame : {"body", "space"}
        The components ``omega`` is given in.
    lock_tol : float
        :class:`mechpy.SingularityError` is raised where ``|det J| <= lock_tol``
        (default 1e-12).

    Returns
    -------
    ndarray, shape (..., 3)
        ``(phi_dot, theta_dot, psi_dot)`` in rad/s.

    Raises
    ------
    mechpy.SingularityError
        At gimbal lock, where the rates are not determined by omega.

    Examples
    --------
    The inverse of :func:`angular_velocity`:

    >>> angles, rates = [0.4, 0.9, -1.2], [0.5, -0.25, 2.0]
    >>> omega = mp.rotation.angular_velocity(angles, rates)
    >>> np.round(mp.rotation.euler_rates(angles, omega), 12)
    array([ 0.5 , -0.25,  2.  ])
    """
    seq = _seq(seq)
    space = _frame(frame)
    a, w, shape = _pair(angles, omega, "omega")
    out = _core.rotation_euler_rates(a, w, seq, space, _tol(lock_tol, "lock_tol"))
    return out.reshape(shape + (3,))


def _scipy_rotation():
    """SciPy's ``Rotation`` class, or an ImportError that says what to install."""
    try:
        from scipy.spatial.transform import Rotation
    except ImportError as exc:  # pragma: no cover - SciPy is a test dependency
        raise ImportError("to_scipy and from_scipy need SciPy (pip install scipy)") from exc
    return Rotation


def to_scipy(R, *, passive: bool = True, orth_tol: float = ORTH_TOL):
    r"""A :class:`scipy.spatial.transform.Rotation` of rotation matrices.

    The default follows the module's: ``R`` is read as the passive matrix
    :math:`\lambda` that :func:`euler_matrix` gives by default, so
    ``to_scipy(euler_matrix(phi, theta, psi)).as_euler("ZXZ")`` returns
    ``(phi, theta, psi)``, and ``to_scipy`` and :func:`from_scipy` invert each
    other with their defaults.  SciPy's own matrices (``Rotation.as_matrix()``,
    active) need ``passive=False``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (more than one batch axis needs SciPy >= 1.17):
        coordinate transformations :math:`\lambda = R_{active}^T` (``passive=True``,
        the default, as the default :func:`euler_matrix` and :func:`matrix_from_quat`
        of a default :func:`quat_from_euler` give them), or active ones
        (``passive=False``, as ``euler_matrix(..., passive=False)`` gives them and as
        SciPy's ``as_matrix`` reads them).  ``max|R R^T - I| <= orth_tol`` and
        ``det R > 0`` are required (:class:`mechpy.DomainError` otherwise):
        the matrix is checked, never silently orthogonalised.
    passive : bool
        Whether ``R`` is the passive matrix (default True, as in :func:`euler_matrix`).
    orth_tol : float
        Default :data:`ORTH_TOL`.

    Returns
    -------
    scipy.spatial.transform.Rotation
        Single for ``R`` of shape (3, 3), of shape ``R.shape[:-2]`` otherwise; built from
        :func:`quat_from_matrix`, so ``to_scipy(R).as_matrix()`` is ``R.T`` (``R`` with
        ``passive=False``) to round-off.

    See Also
    --------
    from_scipy : the way back.

    Examples
    --------
    >>> import numpy as np
    >>> import mechpy as mp
    >>> lam = mp.rotation.euler_matrix(0.3, 0.2, 0.1)          # textbook ZXZ, passive
    >>> np.allclose(mp.rotation.to_scipy(lam).as_euler("ZXZ"), [0.3, 0.2, 0.1])
    True
    >>> R = mp.rotation.euler_matrix(0.3, 0.2, 0.1, passive=False)   # SciPy's matrix
    >>> np.allclose(mp.rotation.to_scipy(R, passive=False).as_euler("ZXZ"), [0.3, 0.2, 0.1])
    True
    """
    Rotation = _scipy_rotation()
    passive = _flag(passive, "passive")
    R = _matrices(R)
    q = quat_from_matrix(R, orth_tol=orth_tol)
    if passive:
        q = q * np.array([-1.0, -1.0, -1.0, 1.0])   # the inverse rotation: lambda^T
    try:
        return Rotation.from_quat(q)
    except ValueError as exc:
        if q.ndim > 2:   # SciPy before 1.17: one batch axis at most
            raise ValueError(f"R of shape {R.shape}: this SciPy's Rotation takes (3, 3) or "
                             f"(k, 3, 3) only") from exc
        raise


def from_scipy(rot, *, passive: bool = True) -> np.ndarray:
    r"""Rotation matrices of a :class:`scipy.spatial.transform.Rotation`.

    The default follows the module's (passive, as :func:`euler_matrix`), so
    ``from_scipy(Rotation.from_euler("ZXZ", a))`` equals ``euler_matrix(a)`` and
    ``from_scipy(to_scipy(R))`` is ``R``.

    Parameters
    ----------
    rot : scipy.spatial.transform.Rotation
        A single rotation or a stack of them.
    passive : bool
        True (default): the coordinate transformations :math:`\lambda`, the transposes
        of ``rot.as_matrix()``, as the default :func:`euler_matrix` gives them;
        False: SciPy's active matrices ``rot.as_matrix()``.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rotation matrices (dimensionless), float64, C-contiguous; the batch
        axes are ``rot``'s shape.

    See Also
    --------
    to_scipy : the way there.

    Examples
    --------
    >>> import numpy as np
    >>> import mechpy as mp
    >>> from scipy.spatial.transform import Rotation
    >>> rot = Rotation.from_euler("ZXZ", [0.3, 0.2, 0.1])
    >>> np.allclose(mp.rotation.from_scipy(rot), mp.rotation.euler_matrix(0.3, 0.2, 0.1))
    True
    >>> np.allclose(mp.rotation.from_scipy(rot, passive=False), rot.as_matrix())
    True
    """
    Rotation = _scipy_rotation()
    if not isinstance(rot, Rotation):
        raise TypeError(f"rot must be a scipy.spatial.transform.Rotation, got "
                        f"{type(rot).__name__}")
    passive = _flag(passive, "passive")
    m = np.asarray(rot.as_matrix(), dtype=np.float64)
    if passive:
        m = np.swapaxes(m, -1, -2)
    return np.ascontiguousarray(m)
