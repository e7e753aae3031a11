"""mechpy.modes against scipy.linalg.eigh, scipy.integrate.odeint and closed forms."""
import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp
from scipy.integrate import odeint

import mechpy as mp
from mechpy.modes import chain, dispersion, dispersion_diatomic, linear_triatomic, normal_modes

EPS = np.finfo(float).eps


# ---------------------------------------------------------------- references
def random_spd(rng, n, shift=1.0):
    A = rng.standard_normal((n, n))
    return A @ A.T / n + shift * np.eye(n)


def residual(K, M, modes):
    """max_k ||K v_k - w_k M v_k|| / ((||K|| + w_k ||M||) ||v_k||)."""
    V, w = modes.vectors, modes.omega ** 2
    R = K @ V - (M @ V) * w
    scale = (np.linalg.norm(K, 2) + w * np.linalg.norm(M, 2)) * np.linalg.norm(V, axis=0)
    return float(np.max(np.linalg.norm(R, axis=0) / scale))


def m_orthonormality(M, V):
    return float(np.max(np.abs(V.T @ M @ V - np.eye(V.shape[1]))))


def clusters(w, rtol=1e-8):
    """Index groups of (numerically) equal eigenvalues."""
    groups, start = [], 0
    scale = np.max(np.abs(w))
    for i in range(1, len(w) + 1):
        if i == len(w) or w[i] - w[i - 1] > rtol * scale:
            groups.append(np.arange(start, i))
            start = i
    return groups


def projector(V, M, idx):
    """M-orthogonal projector onto the span of the columns idx: V V^T M."""
    Vc = V[:, idx]
    return Vc @ Vc.T @ M


def check_sign_rule(V):
    for k in range(V.shape[1]):
        v = V[:, k]
        first = np.flatnonzero(np.abs(v) > 1e-8 * np.max(np.abs(v)))[0]
        assert v[first] > 0


def pencil_eigenvalue(kd, ke, md, k, rtol=1e-13):
    """k-th eigenvalue (0-based) of K - w M, K tridiagonal (kd, ke), M = diag(md), by
    bisection on Sylvester's inertia of the LDL^T factorisation, in 50-digit decimals
    from the exact double inputs (an independent high-precision reference)."""
    from decimal import Decimal, localcontext

    with localcontext() as ctx:
        ctx.prec = 50
        kd = [Decimal(float(x)) for x in kd]
        ke2 = [Decimal(float(x)) ** 2 for x in ke]
        md = [Decimal(float(x)) for x in md]

        def below(w):
            count, d = 0, None
            for i in range(len(kd)):
                d = kd[i] - w * md[i] - (ke2[i - 1] / d if i else 0)
                if d == 0:
                    d = Decimal("1e-60")
                count += d < 0
            return count

        lo, hi = Decimal("1e-30"), max(2 * (a / m) for a, m in zip(kd, md)) + 1
        while hi - lo > Decimal(rtol) * lo:
            mid = (lo * hi).sqrt()                  # geometric bisection
            if below(mid) > k:
                hi = mid
            else:
                lo = mid
        return float((lo + hi) / 2)


def chain_rhs(y, t, K, M):
    n = K.shape[0]
    return np.concatenate([y[n:], -np.linalg.solve(M, K @ y[:n])])


# ------------------------------------------------------- against scipy.eigh
@pytest.mark.parametrize("n", [1, 2, 7, 60, 200, 500])
def test_random_spd_pairs_vs_scipy(rng, n):
    K = random_spd(rng, n, shift=0.1)
    M = random_spd(rng, n)
    modes = normal_modes(K, M)
    ws, Vs = sl.eigh(K, M)
    w = modes.omega ** 2
    assert np.all(np.diff(modes.omega) >= 0)
    assert np.max(np.abs(w - ws) / np.abs(ws)) < 1e-12
    assert residual(K, M, modes) < 1e-14 * max(1, n) ** 0.5
    assert m_orthonormality(M, modes.vectors) < 1e-13 * max(1, n) ** 0.5
    np.testing.assert_allclose(modes.frequencies, np.sqrt(ws) / (2 * np.pi), rtol=1e-12)
    check_sign_rule(modes.vectors)
    # non-degenerate: each vector equals scipy's up to sign (M-norm 1 in both)
    s = np.sign(np.sum(modes.vectors * Vs, axis=0))
    err = np.max(np.abs(modes.vectors - Vs * s))
    gap = np.min(np.diff(ws)) if n > 1 else 1.0
    assert err < 1e-12 * n / gap


def test_degenerate_clusters_by_projectors(rng):
    n = 40
    M = random_spd(rng, n)
    L = np.linalg.cholesky(M)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    X = np.linalg.solve(L.T, Q)                      # X^T M X = I
    lam = np.repeat([0.5, 1.0, 2.0, 3.0, 7.0], [3, 10, 1, 6, 20]).astype(float)
    K = M @ X @ np.diag(lam) @ X.T @ M
    K = 0.5 * (K + K.T)
    modes = normal_modes(K, M)
    ws, Vs = sl.eigh(K, M)
    np.testing.assert_allclose(modes.omega ** 2, lam, rtol=1e-12)
    groups = clusters(ws)
    assert [len(g) for g in groups] == [3, 10, 1, 6, 20]
    for g in groups:
        P = projector(modes.vectors, M, g)
        Ps = projector(Vs, M, g)
        Pexact = projector(X, M, g)
        assert np.max(np.abs(P - Ps)) < 1e-11
        assert np.max(np.abs(P - Pexact)) < 1e-11
    assert residual(K, M, modes) < 1e-14
    assert m_orthonormality(M, modes.vectors) < 1e-13


def test_standard_problem_when_M_omitted(rng):
    K = random_spd(rng, 30)
    modes = normal_modes(K)
    np.testing.assert_allclose(modes.omega ** 2, sl.eigh(K, eigvals_only=True), rtol=1e-12)
    assert m_orthonormality(np.eye(30), modes.vectors) < 1e-13


# ------------------------------------------------- the two-mass system (§6)
def test_two_mass_system_section6():
    kappa, kappa12, m = 3.0, 0.7, 2.5
    K = np.array([[kappa + kappa12, -kappa12], [-kappa12, kappa + kappa12]])
    M = m * np.eye(2)
    for method in ("auto", "dense", "chain"):
        modes = normal_modes(K, M, method=method)
        np.testing.assert_allclose(modes.omega,
                                   [np.sqrt(kappa / m), np.sqrt((kappa + 2 * kappa12) / m)],
                                   rtol=1e-14)
        c = 1 / np.sqrt(2 * m)
        # eta_2 = x1 + x2 (slow, in phase), eta_1 = x1 - x2 (fast, opposed); first component > 0
        np.testing.assert_allclose(modes.vectors, [[c, c], [c, -c]], atol=1e-15)


# ------------------------------------------------------------------ chains
@pytest.mark.parametrize("N, method", [(1, "chain"), (5, "chain"), (64, "chain"), (1500, "chain"),
                                       (1, "dense"), (5, "dense"), (64, "dense")])
def test_fixed_chain_closed_form(N, method):
    kappa, m = 4.0, 0.25
    K, M = chain(N, mass=m, spring=kappa)
    modes = normal_modes(K, M, method=method)
    k = np.arange(1, N + 1)
    omega = 2 * np.sqrt(kappa / m) * np.sin(k * np.pi / (2 * (N + 1)))
    np.testing.assert_allclose(modes.omega, omega, rtol=1e-12, atol=1e-13 * omega[-1])
    j = np.arange(1, N + 1)[:, None]
    V = np.sqrt(2 / ((N + 1) * m)) * np.sin(j * k * np.pi / (N + 1))   # first row > 0
    assert np.max(np.abs(modes.vectors - V)) < 1e-13 * N * np.max(np.abs(V)) / (
        np.min(np.diff(omega ** 2)) / omega[-1] ** 2 if N > 1 else 1)
    assert m_orthonormality(M, modes.vectors) < 1e-12


@pytest.mark.parametrize("sparse", [False, True])
def test_free_chain_zero_mode(sparse):
    N, kappa, m = 30, 2.0, 3.0
    K, M = chain(N, mass=m, spring=kappa, ends="free", sparse=sparse)
    modes = normal_modes(K, M)
    k = np.arange(N)
    np.testing.assert_allclose(modes.omega, 2 * np.sqrt(kappa / m) * np.sin(k * np.pi / (2 * N)),
                               rtol=1e-12, atol=1e-14)
    assert modes.omega[0] == 0.0 and modes.zero_modes.sum() == 1
    assert not np.any(np.isnan(modes.omega))
    # the zero mode is the uniform translation, M-normalised
    np.testing.assert_allclose(modes.vectors[:, 0], np.full(N, 1 / np.sqrt(N * m)), rtol=1e-12)


def test_periodic_chain_dispersion_and_degenerate_pairs():
    N, kappa, m, a = 24, 5.0, 0.5, 0.3
    K, M = chain(N, mass=m, spring=kappa, ends="periodic")
    modes = normal_modes(K, M)
    q = 2 * np.pi * np.arange(N) / (N * a)
    np.testing.assert_allclose(modes.omega, np.sort(dispersion(m, kappa, a, q)),
                               rtol=1e-12, atol=1e-13)
    assert modes.zero_modes.sum() == 1
    # each pair (+q, -q) spans {cos(q x), sin(q x)}: compare projectors, not vectors
    ws = modes.omega ** 2
    x = np.arange(N)
    for g in clusters(ws):
        if len(g) != 2:
            continue
        j = round(np.arcsin(modes.omega[g[0]] / (2 * np.sqrt(kappa / m))) * N / np.pi)
        B = np.stack([np.cos(2 * np.pi * j * x / N), np.sin(2 * np.pi * j * x / N)], axis=1)
        B = B / np.sqrt(N * m / 2)                 # M-orthonormal basis
        assert np.max(np.abs(projector(modes.vectors, M, g) - projector(B, M, [0, 1]))) < 1e-12


def test_diatomic_periodic_chain_two_branches():
    cells, m1, m2, kappa, a = 16, 1.0, 3.0, 2.0, 1.0
    K, M = chain(2 * cells, masses=np.tile([m1, m2], cells), spring=kappa, ends="periodic")
    modes = normal_modes(K, M)
    q = 2 * np.pi * np.arange(cells) / (cells * a)
    ac, op = dispersion_diatomic(m1, m2, kappa, a, q)
    ref = np.sort(np.concatenate([ac, op]))
    np.testing.assert_allclose(modes.omega, ref, rtol=1e-11, atol=1e-12)
    # the gap between the branches: sqrt(2k/m2) .. sqrt(2k/m1)
    assert np.any(np.isclose(modes.omega, np.sqrt(2 * kappa / m2)))


def test_chain_matrices_by_hand():
    K, M = chain(3, masses=[1, 2, 3], springs=[1, 2, 3, 4])
    np.testing.assert_array_equal(K, [[3, -2, 0], [-2, 5, -3], [0, -3, 7]])
    np.testing.assert_array_equal(M, np.diag([1.0, 2.0, 3.0]))
    K, _ = chain(3, springs=[1, 2], ends="free")
    np.testing.assert_array_equal(K, [[1, -1, 0], [-1, 3, -2], [0, -2, 2]])
    K, _ = chain(3, springs=[1, 2, 3], ends="periodic")
    np.testing.assert_array_equal(K, [[4, -1, -3], [-1, 3, -2], [-3, -2, 5]])
    K, _ = chain(2, springs=[1, 2], ends="periodic")
    np.testing.assert_array_equal(K, [[3, -3], [-3, 3]])
    Ks, Ms = chain(5, springs=np.arange(1.0, 6.0), ends="periodic", sparse=True)
    Kd, Md = chain(5, springs=np.arange(1.0, 6.0), ends="periodic")
    np.testing.assert_array_equal(Ks.toarray(), Kd)
    np.testing.assert_array_equal(Ms.toarray(), Md)
    # sparse but not a chain (the ring's corners): the dense path, same modes
    np.testing.assert_allclose(normal_modes(Ks, Ms).omega ** 2, sl.eigh(Kd, Md, eigvals_only=True),
                               rtol=1e-12, atol=1e-14)


def test_mass_defect_chain_paths_agree_with_scipy(rng):
    N = 200
    masses = np.ones(N)
    masses[N // 2] = 0.2                       # a light impurity: a localised mode
    springs = rng.uniform(0.5, 2.0, N + 1)
    K, M = chain(N, masses=masses, springs=springs)
    ws = sl.eigh(K, M, eigvals_only=True)
    for method in ("chain", "dense"):
        modes = normal_modes(K, M, method=method)
        np.testing.assert_allclose(modes.omega ** 2, ws, rtol=1e-11, atol=1e-13 * ws[-1])
        assert residual(K, M, modes) < 1e-14
    top = normal_modes(K, M).vectors[:, -1]
    assert np.argmax(np.abs(top)) == N // 2     # the mode above the band sits on the defect
    # sparse input takes the chain path and gives the same modes
    Ks, Ms = chain(N, masses=masses, springs=springs, sparse=True)
    assert np.max(np.abs(normal_modes(Ks, Ms).vectors - normal_modes(K, M).vectors)) < 1e-12


@pytest.mark.parametrize("method", ["chain", "dense"])
def test_ill_conditioned_masses_by_residuals(rng, method):
    N = 120
    masses = 10.0 ** rng.uniform(0, 12, N)      # ratio up to 1e12
    masses[0], masses[1] = 1.0, 1e12
    K, M = chain(N, masses=masses, springs=rng.uniform(0.5, 2.0, N + 1))
    s = 1 / np.sqrt(masses)

    def scaled_residuals(modes):
        # backward error of T u = w u, T = M^-1/2 K M^-1/2, u = M^1/2 v (|u| = 1)
        V, w = modes.vectors, modes.omega ** 2
        return np.linalg.norm(s[:, None] * (K @ V - (M @ V) * w), axis=0)

    ws = sl.eigh(K, M, eigvals_only=True)
    # default: eigenvalues below the round-off bound 16 n eps max(w) are zero modes
    modes = normal_modes(K, M, method=method)
    w = modes.omega ** 2
    bound = 16 * N * EPS * ws[-1]
    assert np.all(ws[modes.zero_modes] < 1.01 * bound)
    assert np.max(scaled_residuals(modes)) < bound
    assert m_orthonormality(M, modes.vectors) < 1e-12
    assert np.all(np.diff(modes.omega) >= 0) and np.all(np.isfinite(modes.vectors))
    assert np.max(np.abs(w - ws)) < bound
    # zero_tol=0 keeps the tiny eigenvalues (k / 1e12): residuals at round-off of |T|
    modes = normal_modes(K, M, method=method, zero_tol=0.0)
    assert modes.zero_modes.sum() == 0
    assert np.max(scaled_residuals(modes)) < 1e-14 * ws[-1]
    assert m_orthonormality(M, modes.vectors) < 1e-12
    # the 6 smallest, relative to each, against a 50-digit bisection
    ref = [pencil_eigenvalue(np.diag(K), np.diag(K, 1), masses, k) for k in range(6)]
    rel = np.abs(modes.omega[:6] ** 2 - ref) / ref
    # chain (MRRR on the scaled matrix): ~2e-14; dense: absolute eps |T| only, as scipy (2e-3)
    assert np.max(rel) < (1e-12 if method == "chain" else 1e-2), rel


@pytest.mark.parametrize("method", ["chain", "dense"])
@pytest.mark.parametrize("n", [2, 7])
def test_default_zero_tol_is_the_documented_round_off_bound(method, n):
    """The docstring's bound 16 n eps max|omega^2|: a diagonal K (eigenvalues exact on
    both paths) with one eigenvalue 0.3% above it keeps it, 0.3% below it is a zero mode;
    a negative one 0.3% beyond it is UnstableSystemError, 0.3% within it is set to 0."""
    bound = 16 * n * EPS
    for f, zero in ((1.003, False), (0.997, True)):
        K = np.diag([1.0] + [f * bound] * (n - 1))
        modes = normal_modes(K, np.eye(n), method=method)
        assert modes.zero_modes.sum() == (n - 1 if zero else 0)
        if not zero:    # measured: exact
            assert np.abs(modes.omega[:-1] ** 2 / (f * bound) - 1).max() < 1e-15
    K = np.diag([1.0] + [-0.997 * bound] * (n - 1))
    assert normal_modes(K, np.eye(n), method=method).zero_modes.sum() == n - 1
    with pytest.raises(mp.UnstableSystemError):
        normal_modes(np.diag([1.0] + [-1.003 * bound] * (n - 1)), np.eye(n), method=method)


# ------------------------------------------------------------- the motion
@pytest.mark.parametrize("ends", ["fixed", "free"])
def test_evolve_matches_odeint(rng, ends):
    N = 6
    K, M = chain(N, masses=rng.uniform(0.5, 2.0, N), springs=rng.uniform(0.5, 2.0,
                 {"fixed": N + 1, "free": N - 1}[ends]), ends=ends)
    modes = normal_modes(K, M)
    q0, v0 = rng.standard_normal(N), rng.standard_normal(N)
    t = np.linspace(0.0, 20.0, 201)
    ref = odeint(chain_rhs, np.concatenate([q0, v0]), t, args=(K, M), rtol=1e-12, atol=1e-12)
    q, v = modes.evolve(q0, v0, t, velocities=True)
    assert q.shape == (len(t), N)
    assert np.max(np.abs(q - ref[:, :N])) < 1e-8
    assert np.max(np.abs(v - ref[:, N:])) < 1e-8
    np.testing.assert_allclose(q[0], q0, atol=1e-14)
    np.testing.assert_allclose(modes.evolve(q0, v0, 3.0), q[30], atol=1e-13)
    if ends == "free":   # the centre of mass moves uniformly
        m = np.diag(M)
        com = q @ m / m.sum()
        np.testing.assert_allclose(com, (m @ q0 + t * (m @ v0)) / m.sum(), atol=1e-12)


def test_energy_per_mode_constant_and_sums_to_total(rng):
    N = 10
    K, M = chain(N, masses=rng.uniform(0.5, 2.0, N), ends="fixed", spring=1.5)
    modes = normal_modes(K, M)
    q0, v0 = rng.standard_normal(N), rng.standard_normal(N)
    t = np.linspace(0, 50, 301)
    q, v = modes.evolve(q0, v0, t, velocities=True)
    E = modes.energy(q, v)
    assert E.shape == (len(t), N)
    assert np.max(np.abs(E - E[0])) < 1e-12 * E[0].sum()
    total = 0.5 * np.einsum("ti,ij,tj->t", v, M, v) + 0.5 * np.einsum("ti,ij,tj->t", q, K, q)
    np.testing.assert_allclose(E.sum(axis=1), total, rtol=1e-12)
    # a single-mode start stays in that mode
    E1 = modes.energy(*modes.evolve(modes.vectors[:, 3], np.zeros(N), t, velocities=True))
    assert np.max(np.delete(E1, 3, axis=1)) < 1e-25
    np.testing.assert_allclose(E1[:, 3], 0.5 * modes.omega[3] ** 2, rtol=1e-12)


def test_coordinates_round_trip(rng):
    K, M = random_spd(rng, 8), random_spd(rng, 8)
    modes = normal_modes(K, M)
    q = rng.standard_normal((5, 8))
    eta = modes.coordinates(q)
    np.testing.assert_allclose(eta @ modes.vectors.T, q, atol=1e-13)
    np.testing.assert_allclose(modes.coordinates(modes.vectors[:, 2]), np.eye(8)[2], atol=1e-13)


# ------------------------------------------------------------- molecule
def test_linear_triatomic_co2():
    mA, mB, k, kb, L = 16.0, 12.0, 1.7, 0.3, 1.1
    mol = linear_triatomic(mass_end=mA, mass_center=mB, spring=k, bend=kb, length=L)
    assert len(mol.zero) == 5 and len(mol.vibrational) == 4
    wb = np.sqrt(kb / L ** 2 * (2 / mA + 4 / mB))
    ws, wa = np.sqrt(k / mA), np.sqrt(k * (1 / mA + 2 / mB))
    np.testing.assert_allclose(mol.omega, np.sort([wb, wb, ws, wa]), rtol=1e-12)
    named = dict(zip(mol.labels, mol.omega))
    assert sorted(mol.labels) == ["antisymmetric stretch", "bend", "bend", "symmetric stretch"]
    np.testing.assert_allclose([named["bend"], named["symmetric stretch"],
                                named["antisymmetric stretch"]], [wb, ws, wa], rtol=1e-12)
    # the zero-mode space holds the 3 translations and the 2 rotations about y and z
    M = np.diag(np.repeat([mA, mB, mA], 3))
    P = projector(mol.modes.vectors, M, mol.zero)
    x = np.array([-L, 0.0, L])
    rigid = [np.tile(np.eye(3)[c], 3) for c in range(3)]
    rigid += [np.ravel(np.stack([np.zeros(3), x, np.zeros(3)], 1)),
              np.ravel(np.stack([np.zeros(3), np.zeros(3), x], 1))]
    for r in rigid:
        np.testing.assert_allclose(P @ r, r, atol=1e-12 * np.max(np.abs(r)))
    # default CO2 parameters: the stretches against scipy.linalg.eigh on the collinear
    # chain O-C-O written here, the bend against its closed form
    co2 = linear_triatomic()
    mO, mC, k, kb, L = 2.65669645265334e-26, 1.99447347289326e-26, 1680.0, 7.7e-19, 1.16e-10
    K1 = k * np.array([[1.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    w2 = sl.eigh(K1, np.diag([mO, mC, mO]), eigvals_only=True)[1:]
    to_cm = 1 / (2 * np.pi * 2.99792458e10)            # rad/s -> cm^-1
    wb = np.sqrt(kb / L ** 2 * (2 / mO + 4 / mC)) * to_cm
    np.testing.assert_allclose(co2.wavenumbers, [wb, wb, *np.sqrt(w2) * to_cm], rtol=1e-12)
    # measured CO2 fundamentals (Herzberg, Infrared and Raman Spectra, 1945; NIST
    # Chemistry WebBook): nu2 667.4, nu3 2349.1 cm^-1; nu1 is the Fermi dyad 1388.2 /
    # 1285.4 whose unperturbed centre is ~1337 cm^-1.  The two-constant valence model
    # has no stretch-stretch interaction: nu3 comes out ~9% high (model 2555), nu1
    # within 0.2%, nu2 fitted (0.07%); nu3 / nu1 is sqrt(1 + 2 mO / mC) = 1.91 against
    # the measured 1.76
    nu2, nu1, nu3 = co2.wavenumbers[1:]
    assert abs(nu1 / 1337.0 - 1) < 0.01 and 1285.4 < nu1 < 1388.2
    assert abs(nu2 / 667.4 - 1) < 0.005
    assert 0.05 < nu3 / 2349.1 - 1 < 0.12
    assert nu3 / nu1 == pytest.approx(np.sqrt(1 + 2 * mO / mC), rel=1e-12)


# ------------------------------------------------------------- bad input
def test_bad_input():
    K, M = chain(4)
    with pytest.raises(ValueError, match="symmetric"):
        normal_modes(K + np.triu(np.ones((4, 4)), 1) * 0.1, M)
    with pytest.raises(ValueError, match="symmetric"):
        normal_modes(K, M + np.triu(np.ones((4, 4)), 1) * 0.1)
    with pytest.raises(ValueError, match="symmetric"):   # tridiagonal but not symmetric
        Kb = K.copy()
        Kb[1, 0] = -3.0
        normal_modes(Kb, M)
    bad_M = np.array([[1.0, 2.0], [2.0, 1.0]])               # symmetric, indefinite
    with pytest.raises(mp.NotPositiveDefiniteError):
        normal_modes(np.eye(2), bad_M)
    with pytest.raises(np.linalg.LinAlgError):
        normal_modes(K, -M)                                  # chain path
    with pytest.raises(mp.NotPositiveDefiniteError):
        normal_modes(K, -M, method="dense")
    with pytest.raises(mp.NotPositiveDefiniteError):
        normal_modes(K, np.diag([1.0, 0.0, 1.0, 1.0]))
    with pytest.raises(mp.UnstableSystemError, match="omega"):
        normal_modes(np.array([[1.0, 0.0], [0.0, -1e-3]]), np.eye(2))
    with pytest.raises(mp.UnstableSystemError):
        normal_modes(np.array([[1.0, 2.0], [2.0, 1.0]]), np.eye(2), method="dense")
    with pytest.raises(ValueError, match="finite"):
        normal_modes(np.full((2, 2), np.nan), np.eye(2))
    with pytest.raises(ValueError, match="finite"):
        normal_modes(np.eye(2), np.diag([1.0, np.inf]))
    with pytest.raises(ValueError):
        normal_modes(np.eye(3), np.eye(2))
    with pytest.raises(ValueError):
        normal_modes(np.ones((2, 3)), np.eye(2))
    with pytest.raises(TypeError):
        normal_modes("K", np.eye(2))
    with pytest.raises(ValueError, match="zero_tol"):
        normal_modes(K, M, zero_tol=-1.0)
    with pytest.raises(ValueError, match="method"):
        normal_modes(K, M, method="qr")
    with pytest.raises(ValueError, match="chain"):
        normal_modes(random_spd(np.random.default_rng(0), 4), M, method="chain")
    with pytest.raises(ValueError, match="mass"):
        chain(3, mass=-1.0)
    with pytest.raises(ValueError, match="masses"):
        chain(3, masses=[1.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="springs"):
        chain(3, springs=[1.0, 1.0])
    with pytest.raises(ValueError, match="ends"):
        chain(3, ends="clamped")
    with pytest.raises(TypeError):
        chain(2.5)
    modes = normal_modes(K, M)
    with pytest.raises(ValueError, match="q0"):
        modes.evolve(np.zeros(3), np.zeros(4), [0.0])
    with pytest.raises(ValueError, match="t"):
        modes.evolve(np.zeros(4), np.zeros(4), [np.nan])
    with pytest.raises(ValueError, match="q"):
        modes.coordinates(np.zeros(5))


def test_round_off_negative_eigenvalue_is_a_zero_mode_not_nan():
    # a free pair whose K has a round-off negative eigenvalue
    k = 0.1 + 0.2
    K = np.array([[k, -0.3], [-0.3, 0.3]])
    modes = normal_modes(K, np.eye(2))
    assert modes.omega[0] == 0.0 and np.all(np.isfinite(modes.omega))


# ------------------------------------------------------------- properties
def test_random_chains_paths_and_scipy_agree():
    # hypothesis is imported here: without it only this test skips, not the module
    hypothesis = pytest.importorskip("hypothesis")
    st = hypothesis.strategies

    @hypothesis.settings(max_examples=40, deadline=None)
    @hypothesis.given(N=st.integers(1, 12), ends=st.sampled_from(["fixed", "free", "periodic"]),
                      seed=st.integers(0, 2 ** 32 - 1))
    def check(N, ends, seed):
        _random_chain_case(N, ends, seed)

    check()


def _random_chain_case(N, ends, seed):
    rng = np.random.default_rng(seed)
    ns = {"fixed": N + 1, "free": N - 1, "periodic": N}[ends]
    K, M = chain(N, masses=10 ** rng.uniform(-2, 2, N), springs=10 ** rng.uniform(-2, 2, ns),
                 ends=ends)
    ws = sl.eigh(K, M, eigvals_only=True)
    for method in (("auto", "dense") if ends == "periodic" and N > 2 else ("chain", "dense")):
        modes = normal_modes(K, M, method=method)
        assert np.all(np.isfinite(modes.omega)) and np.all(np.diff(modes.omega) >= 0)
        np.testing.assert_allclose(modes.omega ** 2, np.maximum(ws, 0), atol=1e-12 * ws[-1] + 1e-300)
        assert m_orthonormality(M, modes.vectors) < 1e-11
        check_sign_rule(modes.vectors)


@pytest.mark.parametrize("setup, call", [
    # a 6000-mass chain: dstemr runs for 10-30 s and cannot be stopped part-way
    ("import mechpy._core as c\nn = 6000\nkd = np.full(n, 2.0)\nke = np.full(n - 1, -1.0)\n"
     "md = np.linspace(1.0, 2.0, n)", "[c.modes_tridiag(kd, ke, md) for _ in range(5)]"),
    ("K, M = mp.modes.chain(6000, sparse=True)",
     "[mp.modes.normal_modes(K, M) for _ in range(5)]"),
    # the dense solve (dsygvd) runs in the calling thread: see test_dense_interrupt_exits
])
def test_ctrl_c_in_the_eigensolvers_is_prompt(setup, call):
    # was 35 s late for a long chain: dstemr now runs in chunks of indices in the
    # calling thread and Ctrl-C is asked for between chunks
    from sigint import interrupt_delay
    dt = interrupt_delay(setup, call, delay=0.5)
    assert dt < 1.0, f"KeyboardInterrupt {dt} CPU s after SIGINT"     # measured < 0.06 s


def test_dense_interrupt_exits():
    """Regression: the dense solve ran in an abandoned worker thread after Ctrl-C and
    OpenBLAS's exit-time shutdown then waited forever for its pool (4 hangs in 6 runs).
    It now runs in the calling thread: Ctrl-C arrives when the current solve ends
    (one n = 1500 solve: about 1 s here) and the interpreter exits."""
    from sigint import interrupt_delay
    setup = ("rng = np.random.default_rng(0)\nA = rng.normal(size=(1500, 1500))\n"
             "K = A @ A.T\nM = np.eye(1500) + 0.1 * np.diag(rng.uniform(size=1500))")
    dt = interrupt_delay(setup, "[mp.modes.normal_modes(K, M, method='dense') for _ in "
                         "range(50)]", delay=0.3)
    assert dt < 20.0, f"KeyboardInterrupt {dt} CPU s after SIGINT"   # one solve: ~1-3 s


def test_chain_interrupt_exits():
    """Regression: the chain solve ran in a worker thread abandoned on Ctrl-C, and the
    process crashed (exit -11) when it exited with the worker still in dstemr.  The
    chunks now run in the calling thread: the child prints and exits with status 0."""
    from sigint import interrupt_delay
    setup = "K, M = mp.modes.chain(6000, masses=np.linspace(1.0, 2.0, 6000), sparse=True)"
    dt = interrupt_delay(setup, "[mp.modes.normal_modes(K, M) for _ in range(5)]",
                         delay=0.5)
    assert dt < 1.0, f"KeyboardInterrupt {dt} CPU s after SIGINT"    # measured 0.096 CPU s


def test_chunked_chain_solve_equals_one_call():
    # n = 1500 runs dstemr in 6 chunks of 256 indices (RANGE = 'I'); SciPy's
    # eigh_tridiagonal calls dstemr once for the whole spectrum
    rng = np.random.default_rng(7)
    n = 1500
    md = rng.uniform(0.5, 2.0, n)
    kk = rng.uniform(0.5, 2.0, n + 1)
    kd, ke = kk[:-1] + kk[1:], -kk[1:-1]
    w, Z = mp._core.modes_tridiag(kd, ke, md)
    s = 1.0 / np.sqrt(md)
    w1, U = sl.eigh_tridiagonal(kd * s * s, ke * s[:-1] * s[1:], lapack_driver="stemr")
    V = (U * s[:, None]).T
    assert np.max(np.abs(w - w1)) <= 1e-12 * np.max(w1)          # measured 3e-14 (n = 6000)
    sg = np.sign(np.sum(V * Z, axis=1))
    assert np.max(np.abs(Z - sg[:, None] * V)) < 1e-9             # measured 4e-11 (n = 6000)
    G = (Z * md) @ Z.T
    assert np.max(np.abs(G - np.eye(n))) < 1e-10                   # measured 2e-12 (n = 6000)
    check_sign_rule(Z.T)


@pytest.mark.parametrize("sparse", [False, True])
def test_one_degree_of_freedom(sparse):
    """A single mass on a spring, dense or scipy.sparse: omega = sqrt(k/m),
    the mode normalised to v^T M v = 1, and the exact motion at a scalar t
    q = q0 cos wt + v0 sin(wt)/w, q' = v0 cos wt - q0 w sin wt."""
    k, m = 3.0, 0.75
    K, M = np.array([[k]]), np.array([[m]])
    md = normal_modes(sp.csr_array(K), sp.csr_array(M)) if sparse else normal_modes(K, M)
    w = np.sqrt(k / m)
    assert md.omega == pytest.approx([w], rel=1e-15)                 # measured: exact
    assert abs(md.vectors[0, 0]) == pytest.approx(m ** -0.5, rel=1e-15)
    q0, v0, t = 0.3, -0.5, 1.7
    q, v = md.evolve([q0], [v0], t, velocities=True)
    assert q.shape == v.shape == (1,)
    # measured: 1 ulp
    assert q[0] == pytest.approx(q0 * np.cos(w * t) + v0 * np.sin(w * t) / w, rel=1e-14)
    assert v[0] == pytest.approx(v0 * np.cos(w * t) - q0 * w * np.sin(w * t), rel=1e-14)


def test_results_after_an_interrupted_solve_are_unchanged():
    # the same call in one process after an interrupted solve gives the fresh result
    import subprocess
    import sys
    code = """
import os, signal, threading, numpy as np, mechpy as mp
signal.signal(signal.SIGINT, signal.default_int_handler)
K, M = mp.modes.chain(3000, masses=np.linspace(1, 2, 3000), sparse=True)
threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
try:
    mp.modes.normal_modes(K, M)
    print("FINISHED")
except KeyboardInterrupt:
    print("INTERRUPTED")
small = mp.modes.normal_modes(*mp.modes.chain(5, masses=[1, 2, 3, 4, 5]))
print(repr(small.omega.tolist()))
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=300)
    out = r.stdout.splitlines()
    assert r.returncode == 0, r.stderr[-2000:]
    assert out[0] == "INTERRUPTED"
    ref = mp.modes.normal_modes(*mp.modes.chain(5, masses=[1, 2, 3, 4, 5])).omega
    assert eval(out[-1]) == ref.tolist()


@pytest.mark.parametrize("K, M", [
    (np.array([[1.0, 0.0], [0.0, -1e-3]]), np.eye(2)),            # tridiagonal: the chain path
    (np.array([[1.0, 2.0], [2.0, 1.0]]), np.eye(2)),               # its eigenvalues: 3, -1
])
def test_errors_name_what_the_user_called(K, M):
    """The message names normal_modes(K, M), the call the user made; a tridiagonal
    K took the internal chain path and its message said "normal_modes(K, M) (chain)"
    to a user who never built a chain (issue #28)."""
    with pytest.raises(mp.UnstableSystemError) as e:
        normal_modes(K, M)
    assert str(e.value).startswith("normal_modes(K, M): ") and "chain" not in str(e.value)
    w = float(str(e.value).rsplit("=", 1)[1].split("<")[0])
    assert w == pytest.approx(np.linalg.eigvalsh(K)[0], rel=1e-12)   # the negative eigenvalue


@pytest.mark.parametrize("ends", ["fixed", "free", "periodic"])
def test_dense_chain_written_by_blocks_equals_the_sparse_one(ends):
    """chain() writes a long chain's dense K and M by blocks of rows (np.diag wrote
    20000 masses, 3.2 GB, in one call that Ctrl-C could not stop); 3000 masses take
    three blocks, and the matrices are the sparse ones', entry for entry."""
    N = 3000
    rng = np.random.default_rng(5)
    m = rng.uniform(1.0, 2.0, N)
    k = rng.uniform(1.0, 2.0, {"fixed": N + 1, "free": N - 1, "periodic": N}[ends])
    K, M = mp.modes.chain(N, ends=ends, masses=m, springs=k)
    Ks, Ms = mp.modes.chain(N, ends=ends, masses=m, springs=k, sparse=True)
    assert np.array_equal(K, Ks.toarray()) and np.array_equal(M, Ms.toarray())
    assert np.array_equal(K, K.T) and np.count_nonzero(K) == Ks.nnz


@pytest.mark.parametrize("method", ["auto", "dense"])
def test_sparse_shapes_are_checked_with_both_named(method):
    """Sparse K and M of different shapes: a ValueError naming both shapes, from the
    check of the sparse path (not an internal error of the chain's band solver)."""
    for K, M in ((sp.eye(3, format="csr"), sp.eye(2, format="csr")),
                 (sp.eye(2, format="csr"), np.eye(3)),
                 (sp.eye(2, format="csr"), sp.csr_array(np.ones((2, 3))))):
        with pytest.raises(ValueError, match=r"K and M must be square of the same shape, "
                                             rf"got \({K.shape[0]}, {K.shape[1]}\)"):
            normal_modes(K, M, method=method)
