"""mp.scenes.SpringChain against the exact modal motion (mp.modes), SciPy's
solve_ivp on a NumPy right-hand side, conservation laws and the FPUT recurrence."""
import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechpy as mp
from mechpy.scenes import SpringChain

ENDS = ("fixed", "free", "periodic")
NSPRINGS = {"fixed": lambda n: n + 1, "free": lambda n: n - 1, "periodic": lambda n: n}


# ---------------------------------------------------------------- reference
def spring_list(n, ends):
    """(left, right) mass indices of each spring, -1 for a wall, written out
    from the definition (independent of the C loops)."""
    if ends == "fixed":
        return [(-1, 0)] + [(j, j + 1) for j in range(n - 1)] + [(n - 1, -1)]
    if ends == "free":
        return [(j, j + 1) for j in range(n - 1)]
    return [(j, (j + 1) % n) for j in range(n)]


class RefChain:
    """The FPUT chain in NumPy: V_j(r) = k_j (r^2/2 + a r^3/3 + b r^4/4)."""

    def __init__(self, masses, springs, ends, alpha=0.0, beta=0.0):
        self.m = np.asarray(masses, float)
        self.k = np.asarray(springs, float)
        self.n = self.m.size
        self.a, self.b = alpha, beta
        pairs = spring_list(self.n, ends)
        # extension r = D x: row j has +1 at the right mass, -1 at the left one
        D = np.zeros((len(pairs), self.n))
        for j, (lo, hi) in enumerate(pairs):
            if hi >= 0:
                D[j, hi] += 1.0
            if lo >= 0:
                D[j, lo] -= 1.0
        self.D = D

    def rhs(self, t, y):
        x, v = y[:self.n], y[self.n:]
        r = self.D @ x
        tension = self.k * (r + self.a * r ** 2 + self.b * r ** 3)
        return np.concatenate([v, -(self.D.T @ tension) / self.m])

    def jac(self, t, y):
        r = self.D @ y[:self.n]
        s = self.k * (1 + 2 * self.a * r + 3 * self.b * r ** 2)
        J = np.zeros((2 * self.n, 2 * self.n))
        J[:self.n, self.n:] = np.eye(self.n)
        J[self.n:, :self.n] = -(self.D.T * s) @ self.D / self.m[:, None]
        return J

    def energy(self, y):
        x, v = y[:self.n], y[self.n:]
        r = self.D @ x
        return 0.5 * self.m @ v ** 2 + np.sum(self.k * (r ** 2 / 2 + self.a * r ** 3 / 3
                                                         + self.b * r ** 4 / 4))


def random_chain(rng, n, ends, alpha=0.0, beta=0.0):
    m = rng.uniform(0.5, 2.0, n)
    k = rng.uniform(0.5, 2.0, NSPRINGS[ends](n))
    return SpringChain(m, k, ends, alpha=alpha, beta=beta), RefChain(m, k, ends, alpha, beta)


# ---------------------------------------------------------------- the model
@pytest.mark.parametrize("ends", ENDS)
@pytest.mark.parametrize("ab", [(0.0, 0.0), (0.3, 0.0), (0.0, 0.7), (0.25, -0.4)])
def test_rhs_jacobian_energy_match_reference(rng, ends, ab):
    for n in (1, 2, 3, 9):
        if ends == "free" and n == 1:
            ch = SpringChain([2.0], [], "free", alpha=ab[0], beta=ab[1])
            ref = RefChain([2.0], [], "free", *ab)
        else:
            ch, ref = random_chain(rng, n, ends, *ab)
        Y = rng.standard_normal((2 * n, 5))
        for i in range(5):
            y = Y[:, i]
            np.testing.assert_allclose(ch.rhs(0.0, y), ref.rhs(0.0, y), rtol=1e-13, atol=1e-13)
            np.testing.assert_allclose(ch.jacobian(0.0, y), ref.jac(0.0, y), rtol=1e-13,
                                       atol=1e-13)
            assert ch.energy(y) == pytest.approx(ref.energy(y), rel=1e-13, abs=1e-13)
        # vectorised over trailing axes
        E = ch.energy(Y.reshape(2 * n, 5, 1))
        assert E.shape == (5, 1)
        np.testing.assert_allclose(E[:, 0], [ref.energy(Y[:, i]) for i in range(5)], rtol=1e-13)


def test_jacobian_is_the_derivative_of_rhs(rng):
    ch, _ = random_chain(rng, 6, "fixed", alpha=0.4, beta=0.9)
    y = rng.standard_normal(12)
    J = ch.jacobian(0.0, y)
    eps = 1e-6
    Jfd = np.column_stack([(ch.rhs(0, y + eps * e) - ch.rhs(0, y - eps * e)) / (2 * eps)
                           for e in np.eye(12)])
    np.testing.assert_allclose(J, Jfd, atol=1e-8)


@pytest.mark.parametrize("ends", ENDS)
def test_linearisation_is_modes_chain(rng, ends):
    ch, _ = random_chain(rng, 7, ends)
    K, M = mp.modes.chain(7, ends=ends, masses=ch.params["masses"], springs=ch.params["springs"])
    x = rng.standard_normal(7)
    y = np.concatenate([x, np.zeros(7)])
    np.testing.assert_allclose(ch.rhs(0, y)[7:], -np.linalg.solve(M, K @ x), atol=1e-14)
    Kc, Mc = ch.matrices()
    np.testing.assert_array_equal(Kc, K)
    np.testing.assert_array_equal(Mc, M)
    # the FPUT chain linearised at rest has the same K
    fput = ch.replace(alpha=0.5, beta=2.0)
    np.testing.assert_allclose(fput.jacobian(0, np.zeros(14))[7:, :7], -np.linalg.solve(M, K),
                               atol=1e-14)
    w = ch.modes().omega
    ref = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
    np.testing.assert_allclose(w ** 2, ref, atol=1e-12)


# ---------------------------------------------------------------- linear motion
@pytest.mark.parametrize("ends", ENDS)
def test_dop853_matches_exact_modal_motion(rng, ends):
    n = 12
    ch, _ = random_chain(rng, n, ends)
    md = ch.modes()
    x0, v0 = rng.standard_normal(n), rng.standard_normal(n)
    t = np.linspace(0, 60, 61)
    sol = mp.solve(ch, (0, 60), ch.initial_state(x0, v0), method="dop853", rtol=1e-13,
                   atol=1e-13, t_eval=t)
    assert sol.success
    q, v = md.evolve(x0, v0, t, velocities=True)
    scale = np.max(np.abs(q))
    err = np.max(np.abs(sol.y[:n].T - q)) / scale
    assert err < 1e-11, err   # measured ~5e-13
    assert np.max(np.abs(sol.y[n:].T - v)) / np.max(np.abs(v)) < 1e-10
    # each mode keeps its energy along the integrated motion
    E = ch.mode_energies(sol.y)
    assert E.shape == (n, t.size)
    np.testing.assert_allclose(E, np.broadcast_to(E[:, :1], E.shape), atol=1e-10 * E.sum(axis=0)[0])


def test_single_mode_stays_in_its_mode():
    ch = SpringChain.uniform(10, mass=2.0, spring=8.0)
    md = ch.modes()
    # fixed chain: omega_k = 2 sqrt(k/m) sin(k pi / (2 (N + 1)))
    k = np.arange(1, 11)
    np.testing.assert_allclose(md.omega, 4.0 * np.sin(k * np.pi / 22), rtol=1e-13)
    y0 = ch.initial_state(md.vectors[:, 2])
    T = 2 * np.pi / md.omega[2]
    sol = mp.solve(ch, (0, 5 * T), y0, method="dop853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sol.y[:10, -1], md.vectors[:, 2], atol=1e-9)


def test_mass_defect_chain_vs_exact():
    # a light impurity in a fixed chain: a localized mode above the band edge 2 sqrt(k/m)
    m = np.ones(21)
    m[10] = 0.3
    ch = SpringChain(m, 1.0)
    md = ch.modes()
    assert md.omega[-1] > 2.0
    top = md.vectors[:, -1]
    assert abs(top[10]) == pytest.approx(np.max(np.abs(top)))
    x0 = np.zeros(21)
    x0[10] = 0.1
    t = np.linspace(0, 40, 81)
    sol = mp.solve(ch, (0, 40), ch.initial_state(x0), method="dop853", rtol=1e-12, atol=1e-14,
                   t_eval=t)
    np.testing.assert_allclose(sol.y[:21].T, md.evolve(x0, np.zeros(21), t), atol=1e-11)


@pytest.mark.parametrize("method", ["radau", "gauss4"])
def test_implicit_methods_with_the_analytic_jacobian(rng, method):
    ch, _ = random_chain(rng, 8, "fixed")
    x0 = rng.standard_normal(8)
    kw = dict(h=0.01) if method == "gauss4" else dict(rtol=1e-10, atol=1e-12)
    sol = mp.solve(ch, (0, 10), ch.initial_state(x0), method=method, **kw)
    assert sol.success
    exact = ch.modes().evolve(x0, np.zeros(8), 10.0)
    assert np.max(np.abs(sol.y[:8, -1] - exact)) < 1e-7


# ---------------------------------------------------------------- against SciPy
@pytest.mark.parametrize("ends", ENDS)
def test_fput_matches_solve_ivp(rng, ends):
    n = 10
    ch, ref = random_chain(rng, n, ends, alpha=0.3, beta=0.5)
    y0 = np.concatenate([0.5 * rng.standard_normal(n), 0.5 * rng.standard_normal(n)])
    t = np.linspace(0, 30, 31)
    ours = mp.solve(ch, (0, 30), y0, method="dop853", rtol=1e-12, atol=1e-12, t_eval=t)
    theirs = solve_ivp(ref.rhs, (0, 30), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t)
    assert ours.success and theirs.success
    # both 1e-12 solutions of the same problem (measured agreement ~2e-13)
    assert np.max(np.abs(ours.y - theirs.y)) < 1e-10
    # Radau with the scene's analytic Jacobian against SciPy's Radau with the reference one
    r = mp.solve(ch, (0, 30), y0, method="radau", rtol=1e-9, atol=1e-11)
    assert np.max(np.abs(r.y[:, -1] - theirs.y[:, -1])) < 1e-5


# ---------------------------------------------------------------- conservation
# measured max |dE/E0|: verlet 1.4e-4, yoshida4 1.1e-6, gauss4 6.3e-8
@pytest.mark.parametrize("method, h, bound", [("verlet", 0.05, 5e-4), ("yoshida4", 0.1, 5e-6),
                                              ("gauss4", 0.1, 5e-7)])
def test_symplectic_energy_has_no_drift(method, h, bound):
    ch = SpringChain.uniform(16, alpha=0.2, beta=0.3)
    i = np.arange(1, 17)
    y0 = ch.initial_state(0.5 * np.sin(np.pi * i / 17) + 0.2 * np.sin(3 * np.pi * i / 17))
    E0 = ch.energy(y0)
    T1 = 2 * np.pi / ch.modes().omega[0]
    tf = 200 * T1                      # ~ 200 periods of the slowest mode
    t = np.linspace(0, tf, 2001)
    sol = mp.solve(ch, (0, tf), y0, method=method, h=h, t_eval=t)
    assert sol.success
    dE = ch.energy(sol.y) / E0 - 1
    assert np.max(np.abs(dE)) < bound
    # no drift: the error in the last tenth is no larger than in the first tenth
    first, last = np.max(np.abs(dE[:200])), np.max(np.abs(dE[-200:]))
    assert last < 2 * first + 1e-13


def test_fput_energy_conserved_by_dop853():
    ch = SpringChain.uniform(24, alpha=0.25, beta=0.5, ends="periodic")
    rng = np.random.default_rng(3)
    y0 = ch.initial_state(0.3 * rng.standard_normal(24), 0.3 * rng.standard_normal(24))
    sol = mp.solve(ch, (0, 200), y0, method="dop853", rtol=1e-11, atol=1e-12,
                   t_eval=np.linspace(0, 200, 101))
    E = ch.energy(sol.y)
    assert np.max(np.abs(E / E[0] - 1)) < 1e-9  # measured 1.3e-10


@pytest.mark.parametrize("ends", ["free", "periodic"])
def test_momentum_conserved_and_centre_of_mass_moves_uniformly(rng, ends):
    n = 9
    ch, _ = random_chain(rng, n, ends, alpha=0.3, beta=0.2)
    y0 = ch.initial_state(0.3 * rng.standard_normal(n), 0.3 * rng.standard_normal(n) + 0.1)
    t = np.linspace(0, 50, 51)
    sol = mp.solve(ch, (0, 50), y0, method="dop853", rtol=1e-12, atol=1e-12, t_eval=t)
    P = ch.momentum(sol.y)
    np.testing.assert_allclose(P, P[0], atol=1e-11)
    m = ch.params["masses"]
    xc = m @ sol.y[:n] / m.sum()
    np.testing.assert_allclose(xc, xc[0] + P[0] / m.sum() * t, atol=1e-10)
    # the linear chain has one zero mode carrying the drift
    assert np.count_nonzero(ch.modes().omega == 0.0) == 1


def test_fput_recurrence():
    """Fermi, Pasta, Ulam and Tsingou (1955): alpha = 1/4, 32 masses, fixed
    ends, all the energy in mode 1.  It spreads to the other modes (mode 1
    falls below 15 % of it) and comes back to mode 1, above 95 %, after about
    160 periods of mode 1 (the recurrence; mode energies of the linear chain)."""
    N = 32
    ch = SpringChain.uniform(N, alpha=0.25)
    md = ch.modes()
    i = np.arange(1, N + 1)
    y0 = ch.initial_state(np.sin(np.pi * i / (N + 1)))
    T1 = 2 * np.pi / md.omega[0]
    t = np.linspace(0, 180 * T1, 3601)
    sol = mp.solve(ch, (0, t[-1]), y0, method="yoshida4", h=0.1, t_eval=t)
    E = ch.mode_energies(sol.y)
    frac = E[0] / E.sum(axis=0)
    assert frac[0] == pytest.approx(1.0, abs=1e-12)
    periods = t / T1
    mid = (periods > 40) & (periods < 100)
    assert frac[mid].max() < 0.5 and frac[mid].min() < 0.15          # shared
    late = (periods > 130) & (periods < 180)
    k = np.argmax(frac[late])
    assert frac[late][k] > 0.95                                      # recurred
    assert 140 < periods[late][k] < 170
    assert np.ptp(ch.energy(sol.y)) / ch.energy(y0) < 2e-6  # measured 2.1e-7


# ---------------------------------------------------------------- ensembles
def test_solve_many_per_row_params(rng):
    ch = SpringChain.uniform(8, ends="fixed")
    alphas = np.array([0.0, 0.2, 0.4])
    masses = np.ones((3, 8))
    masses[2, 4] = 3.0                                  # a heavy defect on the last row
    P = ch.ensemble_params(alpha=alphas, masses=masses)
    assert P.shape == (3, 4 + 8 + 9)
    y0 = ch.initial_state(0.4 * rng.standard_normal(8))
    t = np.linspace(0, 20, 21)
    ens = mp.solve_many(ch, (0, 20), np.tile(y0, (3, 1)), params=P, t_eval=t, rtol=1e-12,
                        atol=1e-12)
    for r in range(3):
        one = ch.replace(alpha=alphas[r], masses=masses[r])
        sol = mp.solve(one, (0, 20), y0, rtol=1e-12, atol=1e-12, t_eval=t)
        np.testing.assert_allclose(ens["y"][r], sol.y, atol=1e-13)
    # the linear row follows the exact modes
    exact = ch.modes().evolve(y0[:8], y0[8:], t)
    assert np.max(np.abs(ens["y"][0][:8].T - exact)) < 1e-10
    # a row for a different N or a negative mass is refused
    bad = P.copy()
    bad[1, 5] = -1.0
    with pytest.raises(mp.DomainError):
        mp.solve_many(ch, (0, 1), np.tile(y0, (3, 1)), params=bad)
    with pytest.raises(ValueError):
        mp.solve_many(ch, (0, 1), np.tile(y0, (3, 1)), params=P[:, :-1])


def test_ensemble_params_shapes():
    ch = SpringChain([1.0, 2.0, 3.0], [1.0, 1.0, 1.0, 1.0])
    P = ch.ensemble_params(4)
    assert P.shape == (4, 11)
    np.testing.assert_array_equal(P[0], ch._vector())
    P = ch.ensemble_params(beta=[0.1, 0.2], springs=2.0)
    np.testing.assert_array_equal(P[:, 3], [0.1, 0.2])
    np.testing.assert_array_equal(P[:, 7:], 2.0)
    with pytest.raises(ValueError, match="rows"):
        ch.ensemble_params(alpha=[0.1, 0.2], beta=[1, 2, 3])
    with pytest.raises(ValueError, match="masses"):
        ch.ensemble_params(masses=np.ones((2, 4)))
    with pytest.raises(ValueError, match="positive"):
        ch.ensemble_params(masses=[1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="ends"):
        ch.ensemble_params(ends="free")


# ---------------------------------------------------------------- interface
def test_params_replace_pickle_eq():
    ch = SpringChain([1.0, 2.0], 3.0, "free", alpha=0.1)
    assert ch.dim == 4 and ch.N == 2
    p = ch.params
    assert set(p) == {"masses", "springs", "ends", "alpha", "beta"}
    np.testing.assert_array_equal(p["springs"], [3.0])
    p["masses"][0] = 99.0                                # a copy
    assert ch.params["masses"][0] == 1.0
    r = ch.replace(beta=0.5)
    assert r.params["beta"] == 0.5 and r.params["alpha"] == 0.1 and r != ch
    assert pickle.loads(pickle.dumps(r)) == r
    assert hash(pickle.loads(pickle.dumps(r))) == hash(r)
    assert ch.nonlinear and not ch.replace(alpha=0.0).nonlinear
    assert "SpringChain(N=2" in repr(ch)
    assert SpringChain.uniform(3, ends="periodic") == SpringChain(np.ones(3), np.ones(3),
                                                                  "periodic")


def test_symplectic_and_plain_separable():
    # the linear and the FPUT chain are separable (the symplectic methods accept them)
    for a in (0.0, 0.3):
        ch = SpringChain.uniform(4, alpha=a)
        sol = mp.solve(ch, (0, 1), ch.initial_state([0.1, 0, 0, 0]), method="verlet", h=0.01)
        assert sol.success


def test_bad_input():
    with pytest.raises(ValueError, match="positive"):
        SpringChain([1.0, -1.0], 1.0)
    with pytest.raises(ValueError, match="positive"):
        SpringChain([1.0, 0.0], 1.0)
    with pytest.raises(ValueError, match="finite"):
        SpringChain([1.0, np.nan], 1.0)
    with pytest.raises(ValueError, match="finite"):
        SpringChain([1.0, 1.0], [1.0, np.inf, 1.0])
    with pytest.raises(ValueError, match="non-negative"):
        SpringChain([1.0, 1.0], [1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="non-negative"):
        SpringChain([1.0, 1.0], -2.0)
    with pytest.raises(ValueError, match="3 values"):
        SpringChain([1.0, 1.0], [1.0, 1.0])                 # fixed needs N + 1
    with pytest.raises(ValueError, match="1 values"):
        SpringChain([1.0, 1.0], [1.0, 1.0], "free")
    with pytest.raises(ValueError, match="at least one mass"):
        SpringChain([], 1.0)
    with pytest.raises(ValueError, match="1-D"):
        SpringChain([[1.0, 1.0]], 1.0)
    with pytest.raises(ValueError, match="ends"):
        SpringChain([1.0], 1.0, "clamped")
    with pytest.raises(ValueError, match="finite"):
        SpringChain([1.0], 1.0, alpha=np.nan)
    with pytest.raises(TypeError):
        SpringChain("heavy", 1.0)
    with pytest.raises(TypeError):
        SpringChain([1.0], 1.0, beta="big")
    with pytest.raises(ValueError):
        SpringChain.uniform(0)
    with pytest.raises(TypeError, match="unknown"):
        SpringChain.uniform(3).replace(damping=1.0)
    ch = SpringChain.uniform(3)
    with pytest.raises(ValueError, match="6 components"):
        ch.energy(np.zeros(5))
    with pytest.raises(ValueError):
        mp.solve(ch, (0, 1), np.zeros(4))
    with pytest.raises(ValueError, match="shape"):
        ch.initial_state([0.0, 1.0])
    # the C check refuses a malformed parameter vector, never crashes
    for vec in ([3, 0, 0, 0, 1, 1, 1, 1, 1, 1], [2.5, 0, 0, 0, 1, 1, 1, 1, 1],
                [3, 7, 0, 0, 1, 1, 1, 1, 1, 1, 1], [1e300, 0, 0, 0, 1, 1],
                [3, 0, 0, 0, 1, 1, -1, 1, 1, 1, 1], [np.nan, 0, 0, 0, 1, 1], []):
        with pytest.raises(mp.DomainError):
            mp._core.scene_eval("SpringChain", np.array(vec, float), "rhs", 0.0,
                                np.zeros((1, 6)))


def test_solve_many_params_dict_matches_single_solves():
    chain = mp.scenes.SpringChain.uniform(6, 1.0, 1.0, "fixed")
    alphas = np.array([0.0, 0.5, 1.0])
    y0 = chain.initial_state(np.sin(np.pi * np.arange(1, 7) / 7))
    te = np.linspace(0, 5, 6)
    ens = mp.solve_many(chain, (0, 5), np.tile(y0, (3, 1)), params={"alpha": alphas},
                        t_eval=te, rtol=1e-11, atol=1e-13)
    for i, a in enumerate(alphas):
        one = mp.solve(chain.replace(alpha=a), (0, 5), y0, t_eval=te, rtol=1e-11, atol=1e-13)
        np.testing.assert_allclose(ens.y[i], one.y, rtol=0, atol=1e-12)
