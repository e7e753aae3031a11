"""Normal modes of coupled oscillators (Marion & Thornton, chapter 12).

Small oscillations about an equilibrium obey ``M q'' + K q = 0`` with ``K``
(stiffness, the Hessian of the potential energy, called A in the course
notes) symmetric and ``M`` (mass matrix) symmetric positive definite.  The
trial solution ``q = a exp(i omega t)`` gives the generalized eigenproblem

.. math:: K a = \\omega^2 M a,

whose eigenvectors, normalised so that ``a_j^T M a_k = delta_jk``, turn the
coupled equations into independent oscillators for the normal coordinates
``eta = V^T M q``: ``eta_k'' + omega_k^2 eta_k = 0``.

* :func:`normal_modes` solves it (LAPACK ``dsygvd`` for dense problems, an
  O(n^2) tridiagonal path, LAPACK ``dstemr``, for chains);
* :class:`Modes` evolves initial conditions exactly, gives normal coordinates
  and the energy in each mode;
* :func:`chain`, :func:`dispersion`, :func:`dispersion_diatomic` describe
  one-dimensional crystals; :func:`linear_triatomic` a CO2-like molecule.

Units: any consistent set.  With masses in kg and spring constants in N/m,
``omega`` is in rad/s and ``frequencies`` in Hz.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
coordinates last (NumPy stacks): ``Modes.evolve`` (len(t), n), ``coordinates`` (..., n).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import _core
from ._validate import as_array, as_finite_result, as_int, as_scalar, as_symmetric

__all__ = ["Modes", "normal_modes", "chain", "dispersion", "dispersion_diatomic",
           "linear_triatomic", "TriatomicModes"]

#: Relative size of the first vector component that decides a mode's sign.
SIGN_RTOL = 1e-8


@dataclass(frozen=True, eq=False)
class Modes:
    """The normal modes of ``M q'' + K q = 0``, from :func:`normal_modes`.

    Attributes
    ----------
    omega : ndarray (n,)
        Angular frequencies ``omega_k = sqrt(lambda_k)``, ascending (rad/s).
        Zero modes (free translation or rotation) have ``omega_k == 0``.
    vectors : ndarray (n, n)
        Mode shapes as columns ``V[:, k]``, M-orthonormal:
        ``V^T M V = I`` and ``V^T K V = diag(omega^2)``.  Sign rule: the
        first component of each column with ``|v_i| > 1e-8 max_j |v_j|`` is
        positive.  Within a degenerate cluster (equal omega) any orthonormal
        basis of the cluster's space is as valid; only the space is unique.
    mass : ndarray
        The mass matrix (n, n), or its diagonal (n,) when it is diagonal.

    Notes
    -----
    The general motion is the superposition

    .. math:: q(t) = \\sum_k V_{:,k} \\left(\\eta_k(0) \\cos\\omega_k t
              + \\dot\\eta_k(0) \\frac{\\sin\\omega_k t}{\\omega_k}\\right),
              \\qquad \\eta = V^T M q,

    with ``sin(omega t)/omega -> t`` for a zero mode (free motion
    ``eta = eta0 + eta0' t``).

    Examples
    --------
    Two unit masses between walls, three unit springs: the in-phase mode at
    omega = 1, the out-of-phase one at sqrt(3).

    >>> m = mp.modes.normal_modes([[2.0, -1.0], [-1.0, 2.0]])
    >>> np.round(m.omega, 12), round(3 ** 0.5, 12)
    (array([1.        , 1.73205081]), 1.732050807569)
    >>> np.round(m.vectors * 2 ** 0.5, 12)                       # (1, 1) and (1, -1), M-normalised
    array([[ 1.,  1.],
           [ 1., -1.]])
    >>> q = m.evolve([1.0, 1.0], [0.0, 0.0], [0.0, np.pi])       # the in-phase mode alone: cos t
    >>> np.round(q, 12) + 0.0
    array([[ 1.,  1.],
           [-1., -1.]])
    >>> np.round(m.energy([1.0, 1.0], [0.0, 0.0]), 12)          # all in mode 0: omega^2 |q|^2 / 2
    array([1., 0.])
    """

    omega: np.ndarray
    vectors: np.ndarray
    mass: np.ndarray = field(repr=False)

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return self.omega.shape[0]

    def __len__(self) -> int:
        return self.n

    @property
    def eigenvalues(self) -> np.ndarray:
        """``omega**2`` (rad^2/s^2): the eigenvalues of ``K a = lambda M a``."""
        return self.omega ** 2

    @property
    def frequencies(self) -> np.ndarray:
        """Ordinary frequencies ``omega / (2 pi)`` (Hz)."""
        return self.omega / (2.0 * np.pi)

    @property
    def zero_modes(self) -> np.ndarray:
        """Boolean mask of the zero modes, ``omega == 0``: free translations
        and rotations, eigenvalues within ``zero_tol`` (default
        ``16 n eps max|omega^2|``) of zero; see :func:`normal_modes`."""
        return self.omega == 0.0

    def __repr__(self) -> str:
        nz = int(np.count_nonzero(self.zero_modes))
        return f"Modes(n={self.n}, omega=[{self.omega[0]:.6g} .. {self.omega[-1]:.6g}] rad/s, " \
               f"zero modes={nz})"

    def _mdot(self, q: np.ndarray) -> np.ndarray:
        if self.mass.ndim == 1:
            return q * self.mass
        return q @ self.mass

    def _vector(self, x, name: str) -> np.ndarray:
        a = as_array(x, name, min_ndim=1)
        if a.shape[-1] != self.n:
            raise ValueError(f"{name} must have a last axis of length {self.n}, got shape {a.shape}")
        return a

    def coordinates(self, q) -> np.ndarray:
        """Normal coordinates ``eta = V^T M q``.

        Parameters
        ----------
        q : array_like (..., n)
            Displacements (or velocities, giving ``eta'``), in the units of q.

        Returns
        -------
        eta : ndarray (..., n)
            One coordinate per mode, in the order of ``omega``
            (units of q times sqrt(mass)); ``q = V eta``.
        """
        q = self._vector(q, "q")
        return self._mdot(q) @ self.vectors

    def energy(self, q, v) -> np.ndarray:
        """Energy in each mode, ``E_k = (eta_k'^2 + omega_k^2 eta_k^2) / 2``.

        Each is constant in time; their sum is the total energy
        ``v^T M v / 2 + q^T K q / 2`` (joules for SI inputs).

        Parameters
        ----------
        q, v : array_like (..., n)
            Displacements and velocities (broadcast together).

        Returns
        -------
        ndarray (..., n)
        """
        eta = self.coordinates(q)
        deta = self.coordinates(v)
        return 0.5 * (deta ** 2 + (self.omega * eta) ** 2)

    def evolve(self, q0, v0, t, *, velocities: bool = False):
        """Exact motion from ``q(0) = q0``, ``q'(0) = v0`` (no integration).

        .. math:: \\eta_k(t) = \\eta_k(0)\\cos\\omega_k t
                  + \\dot\\eta_k(0)\\,\\sin(\\omega_k t)/\\omega_k,\\quad q = V\\eta

        Zero modes move freely, ``eta_k(t) = eta_k(0) + eta_k'(0) t``.

        Parameters
        ----------
        q0, v0 : array_like (n,)
            Initial displacements and velocities.
        t : float or array_like (m,)
            Times (s).
        velocities : bool
            Also return ``q'(t)``.

        Returns
        -------
        q : ndarray (m, n), or (n,) for a scalar ``t``
        v : ndarray, same shape (only when ``velocities``)
        """
        q0 = self._vector(q0, "q0")
        v0 = self._vector(v0, "v0")
        if q0.ndim != 1 or v0.ndim != 1:
            raise ValueError("q0 and v0 must be vectors of length n")
        scalar_t = np.ndim(t) == 0
        t_arr = as_array(t, "t", allow_empty=True)
        if t_arr.ndim > 1:
            raise ValueError(f"t must be a scalar or a 1-D array, got shape {t_arr.shape}")
        tt = np.atleast_1d(t_arr)[:, None]
        eta0 = self.coordinates(q0)
        deta0 = self.coordinates(v0)
        w = self.omega
        zero = w == 0.0
        wsafe = np.where(zero, 1.0, w)
        cause = ("omega * t or a zero mode's drift eta'(0) t is beyond float64 (t up to "
                 f"{float(np.max(np.abs(tt))) if tt.size else 0.0:.3g}); use smaller times or "
                 "shift the time origin")
        with np.errstate(over="ignore", invalid="ignore"):
            phase = as_finite_result(w * tt, "Modes.evolve: the phase omega t", cause)
            c = np.cos(phase)
            s = np.sin(phase)
            sw = np.where(zero, tt, s / wsafe)          # sin(w t)/w, -> t at w = 0
            q = (eta0 * c + deta0 * sw) @ self.vectors.T
            q = as_finite_result(q, "Modes.evolve: q(t)", cause)
            if scalar_t:
                q = q[0]
            if not velocities:
                return q
            v = (deta0 * c - eta0 * w * s) @ self.vectors.T
            v = as_finite_result(v, "Modes.evolve: q'(t)", "omega eta(0) is beyond float64")
        if scalar_t:
            v = v[0]
        return q, v


def _sparse_bands(K, M):
    """Bands (kd, ke, md) of scipy.sparse K (tridiagonal) and M (diagonal),
    or None."""
    import scipy.sparse as sp

    n = K.shape[0]
    Kc, Mc = sp.coo_array(K), sp.coo_array(M)
    kmask = Kc.data != 0
    mmask = Mc.data != 0
    if np.any(np.abs(Kc.row[kmask].astype(np.int64) - Kc.col[kmask]) > 1):
        return None
    if np.any(Mc.row[mmask] != Mc.col[mmask]):
        return None
    Kd = sp.csr_array(K)
    return (np.asarray(Kd.diagonal(0)), np.asarray(Kd.diagonal(1)), np.asarray(Kd.diagonal(-1)),
            np.asarray(sp.csr_array(M).diagonal(0)), n)


def _check_band_symmetry(ke, kl, kd):
    scale = max(np.max(np.abs(kd)) if kd.size else 0.0, np.max(np.abs(ke)) if ke.size else 0.0)
    if ke.size and np.any(np.abs(ke - kl) > 1e-10 * scale):
        raise ValueError(f"K must be symmetric (max |K - K^T| = {np.max(np.abs(ke - kl)):.3g})")


def normal_modes(K, M=None, *, method: str = "auto", zero_tol: float | None = None) -> Modes:
    """Normal modes of ``M q'' + K q = 0``: solve ``K a = omega^2 M a``.

    Parameters
    ----------
    K : array_like (n, n) or scipy.sparse
        Stiffness matrix (the Hessian of the potential energy), symmetric,
        positive semi-definite for a stable equilibrium (N/m for SI).
    M : array_like (n, n) or scipy.sparse, optional
        Mass matrix, symmetric positive definite (kg).  Default: identity.
    method : {"auto", "dense", "chain"}
        ``"dense"``: LAPACK ``dsygvd`` (divide and conquer), O(n^3).
        ``"chain"``: for diagonal M and tridiagonal K, LAPACK ``dstemr`` on
        ``M^{-1/2} K M^{-1/2}``, O(n^2) for all modes.  ``"auto"`` uses the
        chain path whenever the structure allows it (sparse input that is
        not a chain is converted to dense).
    zero_tol : float, optional
        Eigenvalues with ``|omega^2| <= zero_tol * max|omega^2|`` are zero
        modes and set to exactly 0.  Default: the round-off bound
        ``16 n eps``, below which a dense solver cannot tell an eigenvalue
        from zero.  Pass 0 to keep tiny positive eigenvalues (the chain path
        computes them to high relative accuracy, e.g. with mass ratios 1e12).

    Returns
    -------
    Modes
        ``omega`` ascending (rad/s), M-orthonormal ``vectors`` as columns
        with the sign rule of :class:`Modes`, ``frequencies`` (Hz).

    Raises
    ------
    ValueError
        K or M not square, of different shapes, non-finite, or not symmetric
        (relative asymmetry above 1e-10).
    TypeError
        Non-numeric input.
    mechpy.NotPositiveDefiniteError
        M is not positive definite (a ``numpy.linalg.LinAlgError``).
    mechpy.UnstableSystemError
        An eigenvalue ``omega^2 < -max(16 n eps, zero_tol) max|omega^2|``:
        the equilibrium is unstable (a ``ValueError``; the message gives the
        eigenvalue).  Negative eigenvalues within that bound are round-off
        and set to 0, never a NaN.

    Notes
    -----
    The eigenvectors satisfy ``V^T M V = I`` and ``K V = M V diag(omega^2)``.
    The computation runs in C with the GIL released, in the calling thread.
    LAPACK cannot be stopped part-way.  Above 1024 masses the chain solver
    calls ``dstemr`` on chunks of max(128, n/48) eigenvalue indices and checks
    for Ctrl-C between chunks, so ``KeyboardInterrupt`` arrives within one
    chunk (well under 1 s for 6000 masses); the chunked solve takes about twice
    as long as one ``dstemr`` call for the whole spectrum (bisection instead of
    dqds for the eigenvalues).  The dense solver (``dsygvd``) is one call:
    Ctrl-C arrives when it returns (about 1 s for n = 1500).

    Examples
    --------
    >>> import mechpy as mp
    >>> K, M = mp.modes.chain(3, mass=2.0, spring=8.0)
    >>> mp.modes.normal_modes(K, M).omega     # 2 sqrt(k/m) sin(j pi / 8)
    array([1.53073373, 2.82842712, 3.69551813])
    """
    if method not in ("auto", "dense", "chain"):
        raise ValueError(f"method must be 'auto', 'dense' or 'chain', got {method!r}")
    zr = -1.0 if zero_tol is None else as_scalar(zero_tol, "zero_tol", nonnegative=True)
    try:
        import scipy.sparse as sp
        sparse_in = sp.issparse(K) or (M is not None and sp.issparse(M))
    except ImportError:  # pragma: no cover - scipy is a dependency of the tests only
        sparse_in = False
    if M is None:
        n0 = np.shape(K)[0] if np.ndim(K) == 2 else None
        if n0 is None:
            K = as_array(K, "K", ndim=2)
            n0 = K.shape[0]
        M = sp.identity(n0, format="csr") if sparse_in else np.eye(n0)
    if sparse_in:
        if not sp.issparse(K):
            K = sp.csr_array(as_array(K, "K", ndim=2))
        if not sp.issparse(M):
            M = sp.csr_array(as_array(M, "M", ndim=2))
        if K.shape[0] != K.shape[1] or M.shape != K.shape or K.shape[0] < 1:
            raise ValueError(f"K and M must be square of the same shape, got {K.shape} and {M.shape}")
        bands = _sparse_bands(K, M) if method != "dense" else None
        if bands is not None:
            kd, ke, kl, md, _ = bands
            kd, md = as_array(kd, "K"), as_array(md, "M")
            ke, kl = as_array(ke, "K", allow_empty=True), as_array(kl, "K", allow_empty=True)
            _check_band_symmetry(ke, kl, kd)
            return _chain_solve(kd, ke, md, zr)
        if method == "chain":
            raise ValueError("method='chain' needs a diagonal M and a tridiagonal K")
        K, M = K.toarray(), M.toarray()
    K = as_array(K, "K", ndim=2)
    M = as_array(M, "M", ndim=2)
    if K.shape[0] != K.shape[1]:
        raise ValueError(f"K must be a square matrix, got shape {K.shape}")
    if M.shape != K.shape:
        raise ValueError(f"M must have the shape of K {K.shape}, got {M.shape}")
    if method != "dense":
        bands = _core.modes_is_chain(K, M)
        if bands is not None:
            kd, ke, md = bands
            _check_band_symmetry(ke, np.diagonal(K, -1), kd)
            return _chain_solve(kd, ke, md, zr)
        if method == "chain":
            raise ValueError("method='chain' needs a diagonal M and a tridiagonal K")
    K = as_symmetric(K, "K")
    M = as_symmetric(M, "M")
    w, Z = _core.modes_dense(K, M, zr)
    return Modes(np.sqrt(w), Z.T, M)


def _chain_solve(kd, ke, md, zero_rtol) -> Modes:
    w, Z = _core.modes_tridiag(kd, ke, md, zero_rtol)
    return Modes(np.sqrt(w), Z.T, np.array(md))


_ENDS = ("fixed", "free", "periodic")


def chain(N: int, mass: float = 1.0, spring: float = 1.0, ends: str = "fixed",
          masses=None, springs=None, *, sparse: bool = False):
    """Stiffness and mass matrices of a one-dimensional chain of masses.

    Mass ``j`` (0-based) is joined to mass ``j + 1`` by spring ``j``; the
    ends are

    * ``"fixed"``: walls at both ends, N + 1 springs (spring 0 joins the left
      wall to mass 0, spring N joins mass N-1 to the right wall);
    * ``"free"``: no walls, N - 1 springs;
    * ``"periodic"``: a ring, N springs (spring N-1 joins mass N-1 to mass 0).

    The equations of motion are ``M x'' = -K x`` with

    .. math:: K_{jj} = k_{left} + k_{right},\\quad K_{j,j\\pm1} = -k,\\quad
              M = \\mathrm{diag}(m_j).

    Parameters
    ----------
    N : int
        Number of masses (>= 1).
    mass, spring : float
        Uniform mass (kg) and spring constant (N/m), used when ``masses`` /
        ``springs`` are not given.
    ends : {"fixed", "free", "periodic"}
    masses : array_like (N,), optional
        Individual masses (> 0): a mass defect, a diatomic chain.
    springs : array_like, optional
        Individual spring constants (>= 0), N + 1, N - 1 or N of them
        (fixed, free, periodic).
    sparse : bool
        Return ``scipy.sparse.csr_array`` matrices (for long chains).

    Returns
    -------
    K : ndarray (N, N)
        Stiffness matrix (N/m).
    M : ndarray (N, N)
        Diagonal mass matrix (kg).

    Examples
    --------
    >>> import mechpy as mp
    >>> K, M = mp.modes.chain(2, ends="fixed")
    >>> K
    array([[ 2., -1.],
           [-1.,  2.]])
    """
    N = as_int(N, "N", minimum=1)
    if ends not in _ENDS:
        raise ValueError(f"ends must be one of {_ENDS}, got {ends!r}")
    if masses is None:
        m = np.full(N, as_scalar(mass, "mass", positive=True))
    else:
        m = as_array(masses, "masses", shape=(N,), positive=True)
    ns = {"fixed": N + 1, "free": N - 1, "periodic": N}[ends]
    if springs is None:
        k = np.full(ns, as_scalar(spring, "spring", nonnegative=True))
    else:
        k = as_array(springs, "springs", shape=(ns,), nonnegative=True, allow_empty=(ns == 0))
    diag = np.zeros(N)
    off = np.zeros(max(N - 1, 0))
    corner = 0.0
    _err = np.seterr(over="ignore", invalid="ignore")
    if ends == "fixed":
        diag += k[:-1] + k[1:]
        off -= k[1:-1]
    elif ends == "free":
        diag[:-1] += k
        diag[1:] += k
        off -= k
    else:
        # spring j joins j and (j + 1) mod N; for N = 1 it joins a mass to itself (no force)
        if N > 1:
            diag += k + np.roll(k, 1)
            off -= k[:-1]
            corner = -k[-1]
            if N == 2:  # both springs join mass 0 and mass 1
                off -= k[-1]
                corner = 0.0
    np.seterr(**_err)
    with np.errstate(over="ignore", invalid="ignore"):
        as_finite_result(diag, "chain: the diagonal of K (sum of the two springs at a mass)",
                         "spring constants near the float64 limit 1.8e308; "
                         f"{'springs' if springs is not None else 'spring'} must be smaller "
                         "(or use other units)")
    if sparse:
        import scipy.sparse as sp
        Kd = sp.diags([off, diag, off], [-1, 0, 1], shape=(N, N), format="lil")
        if corner != 0.0:
            Kd[0, N - 1] = corner
            Kd[N - 1, 0] = corner
        return sp.csr_array(Kd), sp.csr_array(sp.diags(m, 0, shape=(N, N)))
    K = _dense_bands(diag, off)
    if corner != 0.0:
        K[0, N - 1] = corner
        K[N - 1, 0] = corner
    return K, _dense_bands(m, np.zeros(max(N - 1, 0)))


# rows of a dense band matrix written per block: 2^22 entries (32 MB), about 0.03 s of
# first-touch page zeroing, between two chances for Ctrl-C
_BLOCK_ENTRIES = 1 << 22


def _dense_bands(diag, off) -> np.ndarray:
    """The dense symmetric tridiagonal matrix with diagonal ``diag`` (N) and
    off-diagonal ``off`` (N - 1), written by blocks of rows.

    ``np.diag`` writes it in one call that the kernel's zeroing of every
    touched page makes long (3.3 s for N = 20000, 3.2 GB) and that Ctrl-C
    cannot stop; by blocks, KeyboardInterrupt arrives between two of them."""
    N = diag.size
    A = np.zeros((N, N))          # calloc: pages are zeroed when first written
    step = max(1, _BLOCK_ENTRIES // max(N, 1))
    for r0 in range(0, N, step):
        r = np.arange(r0, min(N, r0 + step))
        A[r, r] = diag[r]
        up = r[r < N - 1]
        A[up, up + 1] = off[up]
        dn = r[r > 0]
        A[dn, dn - 1] = off[dn - 1]
    return A


def dispersion(mass, spring, spacing, q) -> np.ndarray:
    """Dispersion relation of a uniform monatomic chain.

    .. math:: \\omega(q) = 2\\sqrt{\\kappa/m}\\,\\left|\\sin(q a / 2)\\right|

    Parameters
    ----------
    mass : float or array_like
        Mass of each particle (kg), > 0.
    spring : float or array_like
        Spring constant (N/m), >= 0.
    spacing : float or array_like
        Lattice spacing a (m), > 0.
    q : array_like
        Wave number (rad/m); all arguments broadcast.

    Returns
    -------
    omega : ndarray
        Angular frequency (rad/s).  A periodic chain of N masses has exactly
        the modes ``q = 2 pi j / (N a)``, j = 0 .. N-1.

    Examples
    --------
    At the zone boundary q = pi / a the frequency is the largest, 2 sqrt(kappa/m):

    >>> print(mp.modes.dispersion(1.0, 4.0, 0.5, np.pi / 0.5))
    4.0
    >>> np.round(mp.modes.dispersion(1.0, 1.0, 1.0, [0.0, 1e-3]), 9)   # sound: a sqrt(k/m) q
    array([0.   , 0.001])
    """
    m = as_array(mass, "mass", positive=True)
    k = as_array(spring, "spring", nonnegative=True)
    a = as_array(spacing, "spacing", positive=True)
    q = as_array(q, "q", allow_empty=True)
    # sqrt(k) |sin| / sqrt(m): 0 at q = 0 even when k/m overflows (no inf * 0 = NaN)
    return 2.0 * (np.sqrt(k) * np.abs(np.sin(0.5 * q * a))) / np.sqrt(m)


def dispersion_diatomic(mass1, mass2, spring, spacing, q):
    """Acoustic and optical branches of a diatomic chain (alternating masses).

    With a unit cell of length ``a`` holding one mass of each kind, all
    springs ``kappa``,

    .. math:: \\omega^2_\\mp = \\kappa\\mu^{-1} \\mp \\kappa\\sqrt{\\mu^{-2}
              - 4\\sin^2(qa/2)/(m_1 m_2)},\\qquad \\mu^{-1} = 1/m_1 + 1/m_2.

    Parameters
    ----------
    mass1, mass2 : float
        The two masses (kg), > 0.
    spring : float
        Spring constant (N/m), >= 0.
    spacing : float
        Length of the unit cell a (m), > 0 (neighbours are a/2 apart).
    q : array_like
        Wave number (rad/m).

    Returns
    -------
    acoustic, optical : ndarray
        Angular frequencies (rad/s) of the two branches, shape of ``q``.

    Examples
    --------
    At q = 0 the optical branch is at sqrt(2 kappa (1/m1 + 1/m2)); at the zone
    boundary q = pi/a the branches are sqrt(2 kappa / m2) and sqrt(2 kappa / m1)
    (m1 < m2):

    >>> ac, op = mp.modes.dispersion_diatomic(1.0, 4.0, 2.0, 1.0, [0.0, np.pi])
    >>> np.round(ac, 12), np.round(op, 12)
    (array([0., 1.]), array([2.23606798, 2.        ]))
    >>> round((2 * 2.0 * (1 + 1 / 4)) ** 0.5, 8)
    2.23606798
    """
    m1 = as_scalar(mass1, "mass1", positive=True)
    m2 = as_scalar(mass2, "mass2", positive=True)
    k = as_scalar(spring, "spring", nonnegative=True)
    a = as_scalar(spacing, "spacing", positive=True)
    q = as_array(q, "q", allow_empty=True)
    # scaled by the smaller mass, so that 1/m and 1/(m1 m2) do not overflow first:
    # with r = m_small / m_large <= 1, omega^2 = (k / m_small) (1 + r -+ sqrt((1 + r)^2 - 4 r s^2))
    ms, r = min(m1, m2), min(m1, m2) / max(m1, m2)
    s2 = np.sin(0.5 * q * a) ** 2
    root = np.sqrt(np.maximum((1.0 + r) ** 2 - 4.0 * r * s2, 0.0))
    # the acoustic branch without cancellation: (1 + r) - root = 4 r s^2 / ((1 + r) + root)
    lo = 4.0 * r * s2 / ((1.0 + r) + root)
    hi = (1.0 + r) + root
    cause = (f"spring / mass = {k:.3g} / {ms:.3g} gives frequencies beyond float64; "
             "use other units")
    with np.errstate(over="ignore", invalid="ignore"):
        scale = as_finite_result(np.sqrt(np.float64(k)) / np.sqrt(np.float64(ms)),
                                 "dispersion_diatomic: sqrt(spring / mass)", cause)
        acoustic = as_finite_result(scale * np.sqrt(lo), "dispersion_diatomic: acoustic branch",
                                    cause)
        optical = as_finite_result(scale * np.sqrt(hi), "dispersion_diatomic: optical branch",
                                   cause)
    return acoustic, optical


AMU = 1.66053906660e-27  # kg
_C_CM = 2.99792458e10    # speed of light (cm/s)


@dataclass(frozen=True, eq=False)
class TriatomicModes:
    """Modes of a linear triatomic molecule A-B-A, from :func:`linear_triatomic`.

    Attributes
    ----------
    modes : Modes
        All 9 modes; coordinates ordered (x, y, z) per atom, atom 0, 1 (the
        centre), 2, with x along the molecular axis.
    zero : ndarray of int
        Indices of the 5 zero modes (3 translations, 2 rotations).
    vibrational : ndarray of int
        Indices of the 4 = 3N - 5 vibrational modes, ascending omega.
    labels : tuple of str
        Name of each vibrational mode: ``"bend"`` (twice, degenerate),
        ``"symmetric stretch"``, ``"antisymmetric stretch"``.

    Examples
    --------
    >>> co2 = mp.modes.linear_triatomic()
    >>> co2.modes.n, len(co2.zero), len(co2.vibrational)          # 3N, 3 + 2 zero modes, 3N - 5
    (9, 5, 4)
    >>> bool(np.all(co2.modes.omega[co2.zero] == 0))
    True
    """

    modes: Modes
    zero: np.ndarray
    vibrational: np.ndarray
    labels: tuple

    @property
    def omega(self) -> np.ndarray:
        """Vibrational angular frequencies (rad/s)."""
        return self.modes.omega[self.vibrational]

    @property
    def wavenumbers(self) -> np.ndarray:
        """Vibrational wavenumbers ``omega / (2 pi c)`` (cm^-1)."""
        return self.omega / (2.0 * np.pi * _C_CM)


def linear_triatomic(mass_end: float = 15.999 * AMU, mass_center: float = 12.011 * AMU,
                     spring: float = 1680.0, bend: float = 7.7e-19,
                     length: float = 1.16e-10) -> TriatomicModes:
    """Vibrations of a linear symmetric triatomic molecule A-B-A (CO2-like).

    Two bonds of stiffness ``k`` (stretch) and a bending energy
    ``U_bend = bend * delta^2 / 2`` for the small angle
    ``delta = |(r_0 - r_1) + (r_2 - r_1)|_perp / length`` give, besides 5 zero
    modes (3 translations, 2 rotations),

    .. math:: \\omega_s = \\sqrt{k/m_A},\\quad
              \\omega_a = \\sqrt{k(1/m_A + 2/m_B)},\\quad
              \\omega_b = \\sqrt{\\frac{k_\\theta}{\\ell^2}(2/m_A + 4/m_B)}
              \\ (\\text{twice}).

    Parameters
    ----------
    mass_end, mass_center : float
        Masses of the end atoms A and the centre atom B (kg); default oxygen
        and carbon.
    spring : float
        Bond stretch constant k (N/m); default 1680 N/m (CO2).
    bend : float
        Bending constant k_theta (J/rad^2), >= 0; default 7.7e-19 (CO2's bend
        near 667 cm^-1).
    length : float
        Bond length (m); default 1.16e-10.

    Returns
    -------
    TriatomicModes
        The modes, the zero modes identified, the vibrational ones labelled;
        ``.wavenumbers`` in cm^-1 (defaults: about 667 (twice), 1335, 2556).

    Examples
    --------
    CO2 (the defaults): the bend twice near 667 cm^-1, the symmetric stretch at
    sqrt(k/m_O) and the antisymmetric one at sqrt(k (1/m_O + 2/m_C)):

    >>> co2 = mp.modes.linear_triatomic()
    >>> co2.labels
    ('bend', 'bend', 'symmetric stretch', 'antisymmetric stretch')
    >>> np.round(co2.wavenumbers)
    array([ 667.,  667., 1335., 2555.])
    >>> k, mO, mC = 1680.0, 2.65669645265334e-26, 1.99447347289326e-26
    >>> round(float(co2.omega[2] / (k / mO) ** 0.5), 12)
    1.0
    """
    mA = as_scalar(mass_end, "mass_end", positive=True)
    mB = as_scalar(mass_center, "mass_center", positive=True)
    k = as_scalar(spring, "spring", positive=True)
    kb = as_scalar(bend, "bend", nonnegative=True)
    L = as_scalar(length, "length", positive=True)
    K = np.zeros((9, 9))
    # stretch: bonds 0-1 and 1-2 along x
    for a, b in ((0, 1), (1, 2)):
        i, j = 3 * a, 3 * b
        K[i, i] += k
        K[j, j] += k
        K[i, j] -= k
        K[j, i] -= k
    # bend: delta_y = (y0 - 2 y1 + y2) / L, same for z
    bvec = np.array([1.0, -2.0, 1.0])
    for c in (1, 2):
        idx = np.array([c, 3 + c, 6 + c])
        K[np.ix_(idx, idx)] += kb / L ** 2 * np.outer(bvec, bvec)
    M = np.diag(np.repeat([mA, mB, mA], 3))
    modes = normal_modes(K, M)
    zero = np.flatnonzero(modes.zero_modes)
    vib = np.flatnonzero(~modes.zero_modes)
    labels = []
    for j in vib:
        v = modes.vectors[:, j]
        x = v[0::3]
        if np.sum(mA * x[[0, 2]] ** 2 + mB * x[1] ** 2) < 0.5:
            labels.append("bend")
        elif abs(x[0] + x[2]) < 1e-6 * np.max(np.abs(x)):
            labels.append("symmetric stretch")
        else:
            labels.append("antisymmetric stretch")
    return TriatomicModes(modes, zero, vib, tuple(labels))
