"""The tangent flow (mechpy.tangent, mechpy.phase.lyapunov_spectrum / floquet):
sensitivities against finite differences and the matrix exponential, Lyapunov spectra
against published values and the trace of the Jacobian, Floquet multipliers against
Liouville's formula, fits against the truth and a Monte Carlo spread."""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.linalg import expm

import mechpy as mp
from ref_ode import central_sensitivities


@pytest.fixture(scope="module")
def lorenz():
    x, y, z = sp.symbols("x y z")
    s, r, b = sp.symbols("sigma rho beta")
    return mp.equations([s * (y - x), x * (r - z) - y, x * y - b * z], [x, y, z],
                        params={"sigma": 10.0, "rho": 28.0, "beta": 8 / 3})


# ---- sensitivities ------------------------------------------------------------------
def test_pendulum_sensitivities_match_central_differences():
    sc = mp.scenes.Pendulum(damping=0.3, length=1.2, drive_amplitude=0.5, drive_frequency=1.1)
    y0 = np.array([1.0, 0.2])
    te = np.linspace(0, 10, 11)
    names = ("g", "length", "damping", "drive_amplitude", "drive_frequency")
    s = mp.sensitivity(sc, (0, 10), y0, params=names, t_eval=te, rtol=1e-12, atol=1e-14)
    assert s.S.shape == (2, 7, 11) and s.y.shape == (2, 11) and s.params == list(names)

    def run(scene, yy):
        return mp.solve(scene, (0, 10), yy, t_eval=te, rtol=1e-13, atol=1e-15).y

    np.testing.assert_allclose(s.y, run(sc, y0), atol=1e-10)
    fd = central_sensitivities(run, sc, y0, names)
    # measured 2.5e-9 of max |S| (the differences' own error: 1e-13 tolerance / 1e-5 step)
    assert np.abs(s.S - fd).max() <= 2.5e-8 * np.abs(fd).max()
    assert np.all(s.S[:, :, 0] == np.hstack([np.zeros((2, 5)), np.eye(2)]))


def test_linear_system_sensitivities_are_matrix_exponentials():
    """y' = A(k) y: dy/dy0 = expm(A t) and dy/dk = the top-right block of
    expm([[A, dA/dk], [0, A]] t) applied to y0 (Van Loan)."""
    k = sp.Symbol("k")
    u = sp.symbols("u0:3")
    A = sp.Matrix([[0, 1, 0], [-2, -k, 0.5], [0.1, 0, -1]])
    lin = mp.equations(list(A * sp.Matrix(u)), list(u), params={"k": 0.3})
    An = np.array(A.subs(k, 0.3), dtype=float)
    dA = np.zeros((3, 3))
    dA[1, 1] = -1.0
    y0 = np.array([1.0, -0.5, 0.25])
    te = np.array([0.5, 1.0, 3.0])
    s = mp.sensitivity(lin, (0, 3), y0, params=("k",), t_eval=te, rtol=1e-12, atol=1e-14)
    for i, tt in enumerate(te):
        # measured 3e-13 and 1e-12
        np.testing.assert_allclose(s.S[:, 1:, i], expm(An * tt), rtol=0, atol=3e-12)
        B = expm(np.block([[An, dA], [np.zeros((3, 3)), An]]) * tt)
        np.testing.assert_allclose(s.S[:, 0, i], B[:3, 3:] @ y0, rtol=0, atol=1e-11)


def test_lagrangian_route_equals_the_scene():
    """A pendulum from its Lagrangian (SymPy derivation) and the Pendulum scene (its C
    row's field): the same sensitivities; the mass cancels from the motion."""
    th, = mp.coordinates("theta")
    m, g, ln = sp.symbols("m g l", positive=True)
    L = m * ln ** 2 * th.diff() ** 2 / 2 + m * g * ln * sp.cos(th)
    lag = mp.lagrangian(L, [th], params={"m": 1.0, "g": 9.81, "l": 1.2})
    te = np.linspace(0, 5, 6)
    kw = dict(t_eval=te, rtol=1e-11, atol=1e-13)
    s1 = mp.sensitivity(lag, (0, 5), [1.0, 0.2], params=("l", "m"), **kw)
    s2 = mp.sensitivity(mp.scenes.Pendulum(length=1.2), (0, 5), [1.0, 0.2],
                        params=("length",), **kw)
    # measured 2e-11 and 8e-12
    np.testing.assert_allclose(s1.S[:, 0], s2.S[:, 0], rtol=0, atol=2e-10)
    np.testing.assert_allclose(s1.S[:, 2:], s2.S[:, 1:], rtol=0, atol=1e-10)
    assert np.all(s1.S[:, 1] == 0.0)


def test_a_warm_start_needs_no_sympy():
    """The augmented system is stored with the compiled cache: a second process loads it
    without deriving (no SymPy), and gets the same numbers."""
    import subprocess
    import sys
    code = ("import sys, mechpy as mp; s = mp.sensitivity(mp.scenes.Duffing(-1.0, 1.0, 0.2),"
            " (0, 1), [1.0, 0.0], params=('delta',), t_eval=[1.0]);"
            " print('sympy' in sys.modules, repr(float(s.S[0, 0, -1])))")
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
            for _ in range(2)]
    for r in runs:
        assert r.returncode == 0, r.stderr
    assert runs[1].stdout.split()[0] == "False"
    assert runs[0].stdout.split()[1] == runs[1].stdout.split()[1]


def test_ensemble_sensitivities_equal_single_runs():
    sc = mp.scenes.Pendulum(damping=0.3, length=1.2)
    y0s = np.array([[0.1, 0.0], [1.0, 0.5], [2.5, -0.2], [-1.0, 0.3], [0.4, 0.4]])
    te = np.linspace(0, 5, 6)
    e = mp.sensitivity(sc, (0, 5), y0s, params=("damping", "length"), t_eval=te,
                       rtol=1e-10, atol=1e-12)
    assert e.y.shape == (5, 2, 6) and e.S.shape == (5, 2, 4, 6)
    for i, y0 in enumerate(y0s):
        s = mp.sensitivity(sc, (0, 5), y0, params=("damping", "length"), t_eval=te,
                           rtol=1e-10, atol=1e-12)
        # the single runs are checked against differences above; lanes and the scalar
        # driver differ by round-off (measured 1.1e-14 of max |S|, 1.4e-14 in y)
        np.testing.assert_allclose(e.S[i], s.S, rtol=0, atol=1e-13 * np.abs(s.S).max())
        np.testing.assert_allclose(e.y[i], s.y, rtol=0, atol=1e-13)


# ---- Lyapunov spectra ---------------------------------------------------------------
def test_lorenz_spectrum(lorenz):
    lam, times, running = mp.phase.lyapunov_spectrum(lorenz, [0.906, 0.0, -14.57], 2000.0,
                                                     return_history=True)
    assert lam.shape == (3,) and np.all(np.diff(lam) < 0)
    assert running.shape == (times.size, 3) and times[-1] == pytest.approx(2000.0)
    # the sum is the trace -(sigma + 1 + beta), exactly up to the integration: 3.7e-9
    assert abs(lam.sum() + (10 + 1 + 8 / 3)) < 5e-8
    # published (Sprott 2003): 0.9056, 0, -14.5723; measured at t = 2000:
    # 0.9080, -0.0027, -14.5719
    assert abs(lam[0] - 0.9056) < 0.025
    assert abs(lam[1]) < 0.03
    assert abs(lam[2] + 14.5723) < 0.025


def test_henon_heiles_spectrum_pairs():
    x, y, px, py = sp.symbols("x y p_x p_y")
    H = (px ** 2 + py ** 2) / 2 + (x ** 2 + y ** 2) / 2 + x ** 2 * y - y ** 3 / 3
    hh = mp.equations([px, py, -sp.diff(H, x), -sp.diff(H, y)], [x, y, px, py], energy=H)
    E, y0 = 1 / 6, -0.1
    Y0 = [0.0, y0, np.sqrt(2 * E - y0 ** 2 + 2 * y0 ** 3 / 3), 0.0]
    lam = mp.phase.lyapunov_spectrum(hh, Y0, 2000.0)
    # measured: 0.1403, 0.0035, -0.0030, -0.1408; sum 3e-12 (the trace is 0)
    assert abs(lam.sum()) < 1e-10
    assert lam[0] > 0.05                       # a chaotic orbit
    assert abs(lam[0] + lam[3]) < 5e-3         # +- pairs
    assert abs(lam[1]) < 0.03 and abs(lam[2]) < 0.03


def test_driven_pendulum_spectrum():
    """Chaos in the driven damped pendulum (A = 1.5): the sum of the two exponents is the
    divergence -b; the largest agrees with mp.phase.lyapunov's (a single tangent vector
    integrated in Python)."""
    sc = mp.scenes.Pendulum(g=1, length=1, damping=0.5, drive_amplitude=1.5,
                            drive_frequency=2 / 3)
    lam = mp.phase.lyapunov_spectrum(sc, [0.2, 0.0], 500.0, transient=50.0)
    assert abs(lam.sum() + 0.5) < 1e-11                     # measured 1.3e-12
    lam1 = mp.phase.lyapunov(sc, [0.2, 0.0], 500.0, transient=50.0)
    assert lam[0] > 0.05 and abs(lam[0] - lam1) < 0.03      # measured 0.1024 vs 0.0996


# ---- Floquet multipliers ------------------------------------------------------------
def test_van_der_pol_floquet_multipliers_obey_liouville():
    mu = 1.0
    T, m = mp.phase.floquet(mp.scenes.VanDerPol(mu), [2.0, 0.0])
    assert m.shape == (2,) and m.dtype == complex

    def f(t, y):
        return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]]

    kw = dict(method="DOP853", rtol=1e-13, atol=1e-13)
    ya = solve_ivp(f, (0, 100), [2.0, 0.0], **kw).y[:, -1]          # onto the cycle

    def top(t, y):
        return y[1]
    top.direction = -1
    s = solve_ivp(f, (0, 30), ya, events=top, **kw)
    Tref = s.t_events[0][2] - s.t_events[0][1]
    div = solve_ivp(lambda t, y: [*f(t, y), mu * (1 - y[0] ** 2)], (0, Tref),
                    [*s.y_events[0][1], 0.0], **kw).y[2, -1]
    # measured: period 3e-13, multiplier exp(div) = 8.597e-4 to 5e-12 relative, trivial 2e-12
    assert abs(T - Tref) < 3e-11
    assert abs(m[1] - np.exp(div)) < 5e-11 * np.exp(div)
    assert abs(m[0] - 1.0) < 2e-11
    # from a start off the cycle, the same orbit (measured 1.2e-12)
    T2, m2 = mp.phase.floquet(mp.scenes.VanDerPol(mu), [1.0, 1.0])
    assert abs(T2 - Tref) < 1e-10 and abs(m2[1] - np.exp(div)) < 5e-11 * np.exp(div)


def test_pendulum_orbit_family_period_is_the_elliptic_integral():
    from scipy.special import ellipk
    T, m = mp.phase.floquet(mp.scenes.Pendulum(length=1.3), [1.0, 0.0])
    # T = 4 sqrt(L/g) K(sin^2(theta0/2)); measured 4e-13
    assert abs(T - 4 * np.sqrt(1.3 / 9.81) * ellipk(np.sin(0.5) ** 2)) < 4e-12
    # a Jordan block at 1, split by the integration error (measured 1.8e-6)
    assert np.all(np.abs(m - 1) < 2e-5)
    with pytest.raises(mp.ConvergenceError, match="fixed point"):
        mp.phase.floquet(mp.scenes.Pendulum(damping=0.3), [1.0, 0.0])


def test_forced_linear_oscillator_monodromy_is_the_exponential():
    x, v = sp.symbols("x v")
    c, w, a, om = sp.symbols("c w a Omega")
    osc = mp.equations([v, -w ** 2 * x - c * v + a * sp.cos(om * sp.Symbol("t"))], [x, v],
                       params={"c": 0.2, "w": 1.3, "a": 0.7, "Omega": 2.0})
    with pytest.raises(ValueError, match="forced.*period"):
        mp.phase.floquet(osc, [0.0, 0.0])
    P = 2 * np.pi / 2.0
    T, m = mp.phase.floquet(osc, [0.0, 0.0], period=P)
    ref = np.linalg.eigvals(expm(np.array([[0, 1], [-1.69, -0.2]]) * P))
    assert T == P
    # measured 2.7e-13
    np.testing.assert_allclose(np.sort_complex(m), np.sort_complex(ref), rtol=0, atol=3e-12)


# ---- fitting --------------------------------------------------------------------------
def _pendulum_data():
    sc = mp.scenes.Pendulum(damping=0.3, length=1.2)
    t = np.linspace(0, 10, 101)
    clean = mp.solve(sc, (0, 10), [1.0, 0.0], t_eval=t, rtol=1e-12, atol=1e-14).y[:1]
    return t, clean


def test_fit_recovers_damping_and_length_within_their_errors():
    t, clean = _pendulum_data()
    rng = np.random.default_rng(2024)
    noise = 0.01
    est, err = [], []
    for i in range(40):
        data = clean + noise * rng.normal(size=clean.shape)
        # a poor start: a third of the damping, 1.7x the length
        r = mp.fit(mp.scenes.Pendulum(), t, data, {"damping": 0.1, "length": 2.0},
                   y0=[1.0, 0.0], observe=0)
        assert r.success and r.residuals.shape == (1, 101) and r.cov.shape == (2, 2)
        est.append([r.params["damping"], r.params["length"]])
        err.append([r.stderr["damping"], r.stderr["length"]])
        if i == 0:
            assert abs(r.params["damping"] - 0.3) < 3 * r.stderr["damping"]
            assert abs(r.params["length"] - 1.2) < 3 * r.stderr["length"]
            np.testing.assert_allclose(r.chi2, np.sum(r.residuals ** 2))
    est, err = np.array(est), np.array(err)
    # the spread over noise draws is what the standard errors say (measured ratios 1.08
    # and 1.09 over 150 draws; 40 draws resolve them to about 11%)
    ratio = est.std(axis=0, ddof=1) / err.mean(axis=0)
    assert np.all(np.abs(ratio - 1) < 0.3), ratio
    assert np.all(np.abs(est.mean(axis=0) - [0.3, 1.2]) < 3 * err.mean(axis=0) / np.sqrt(40))


def test_fit_with_sigma_and_initial_state():
    t, clean = _pendulum_data()
    rng = np.random.default_rng(7)
    noise = 0.01
    data = clean + noise * rng.normal(size=clean.shape)
    r = mp.fit(mp.scenes.Pendulum(), t, data, {"damping": 0.1, "length": 2.0}, y0=[0.9, 0.1],
               observe=[0], sigma=noise, fit_y0=True)
    assert r.success and list(r.params) == ["damping", "length", "y0[0]", "y0[1]"]
    truth = [0.3, 1.2, 1.0, 0.0]
    for nm, v in zip(r.params, truth):
        assert abs(r.params[nm] - v) < 3 * r.stderr[nm], nm
    assert 0.7 < r.chi2 / r.dof < 1.3          # absolute sigma: chi2 / dof near 1
    # observing through a callable of the state: the same fit
    r2 = mp.fit(mp.scenes.Pendulum(), t, data, {"damping": 0.1, "length": 2.0},
                y0=[0.9, 0.1], observe=lambda y: y[:1], sigma=noise, fit_y0=True)
    for nm in r.params:
        assert abs(r2.params[nm] - r.params[nm]) < 1e-3 * r.stderr[nm]


# ---- bad input ----------------------------------------------------------------------
def test_bad_input():
    sc = mp.scenes.Pendulum(damping=0.3)
    t = np.linspace(0, 2, 5)
    data = np.zeros((1, 5))
    with pytest.raises(ValueError, match="'nope'"):
        mp.sensitivity(sc, (0, 1), [0.1, 0.0], params=("nope",))
    with pytest.raises(ValueError, match="'nope'"):
        mp.fit(sc, t, data, {"nope": 1.0}, y0=[0.1, 0.0], observe=0)
    with pytest.raises(TypeError, match="symbolic"):
        mp.sensitivity(lambda t, y: -y, (0, 1), [1.0], params=())
    with pytest.raises(TypeError, match="symbolic"):
        mp.phase.lyapunov_spectrum(lambda t, y: -y, [1.0], 10.0)
    with pytest.raises(TypeError, match="symbolic"):
        mp.fit(lambda t, y: -y, t, data, {"a": 1.0}, y0=[1.0])
    with pytest.raises(ValueError, match="no symbolic form"):
        mp.sensitivity(mp.scenes.SpringChain.uniform(3), (0, 1), np.zeros(6))
    with pytest.raises(ValueError, match=r"data must have shape \(k, m\) = \(1, 5\)"):
        mp.fit(sc, t, np.zeros((2, 5)), {"damping": 0.1}, y0=[0.1, 0.0], observe=0)
    with pytest.raises(ValueError, match=r"data\[0, 3\]"):
        mp.fit(sc, t, [[0, 0, 0, np.nan, 0]], {"damping": 0.1}, y0=[0.1, 0.0], observe=0)
    with pytest.raises(TypeError, match="params must be a non-empty dict"):
        mp.fit(sc, t, data, ("damping",), y0=[0.1, 0.0], observe=0)
    with pytest.raises(ValueError, match="length = -1.0 lies outside"):
        mp.fit(sc, t, data, {"length": -1.0}, y0=[0.1, 0.0], observe=0)
    with pytest.raises(ValueError, match=r"y0 must have shape \(2,\) or \(k, 2\)"):
        mp.sensitivity(sc, (0, 1), [0.1, 0.0, 1.0], params=("damping",))
    with pytest.raises(ValueError, match="fixed point"):
        mp.phase.floquet(mp.scenes.VanDerPol(), [0.0, 0.0])
    with pytest.raises(ValueError, match="sigma must be positive"):
        mp.fit(sc, t, data, {"damping": 0.1}, y0=[0.1, 0.0], observe=0, sigma=-1.0)


# ---- issue 51: non-smooth fields, and failures in the user's terms ---------------------

def test_rocket_sensitivities_across_burnout_against_central_differences():
    # drag k v|v| (Abs' = sign) and the burn-out switch m > m_dry (the sensitivities
    # jump there by the saltation matrix: the burn-out time depends on b, m_dry and m0)
    base = dict(exhaust_speed=2500.0, burn_rate=10.0, m0=1000.0, m_dry=200.0, g=9.81,
                drag=2e-3)
    rk = mp.scenes.Rocket(**base)
    y0 = rk.initial_state()
    te = [60.0, 120.0]                       # burn-out at 80 s
    names = ("exhaust_speed", "burn_rate", "m_dry", "g", "drag")
    s = mp.sensitivity(rk, (0, 120), y0, params=names, t_eval=te, rtol=1e-12, atol=1e-12)

    def run(kw, yy):
        sc = mp.scenes.Rocket(**{**base, **kw})
        return mp.solve(sc, (0, 120), yy, t_eval=te, rtol=1e-13, atol=1e-12).y

    cols = []
    for nm in names:
        h = 1e-5 * base[nm]
        cols.append((run({nm: base[nm] + h}, y0) - run({nm: base[nm] - h}, y0)) / (2 * h))
    for k, h in enumerate((1.0, 1e-2, 1e-2)):     # height enters linearly
        e = np.zeros(3)
        e[k] = h
        cols.append((run({}, y0 + e) - run({}, y0 - e)) / (2 * h))
    cd = np.stack(cols, axis=1)                  # (3, 8, 2)
    # measured: at most 4.5e-10 of each column's largest entry (burn_rate's)
    for j in range(8):
        scale = np.abs(cd[:, j]).max()
        assert np.abs(s.S[:, j] - cd[:, j]).max() <= 5e-9 * scale, (j, s.S[:, j], cd[:, j])
    # after burn-out the mass is m_dry whatever b or m0: its row vanishes but for m_dry
    assert np.abs(s.S[2, :, -1] - [0, 0, 1, 0, 0, 0, 0, 0]).max() < 1e-12


def test_rocket_fit_and_lyapunov_spectrum():
    # fit recovers drag and burn rate (the latter needs the jump at burn-out); the
    # Lyapunov spectrum has -inf for the mass, pinned at m_dry after burn-out
    base = dict(exhaust_speed=2500.0, burn_rate=10.0, m0=1000.0, m_dry=200.0, g=9.81,
                drag=2e-3)
    rk = mp.scenes.Rocket(**base)
    y0 = rk.initial_state()
    t = np.linspace(0, 120, 25)
    data = mp.solve(rk, (0, 120), y0, t_eval=t, rtol=1e-12, atol=1e-12).y[:2]
    r = mp.fit(rk, t, data, {"drag": 1e-3, "burn_rate": 9.0}, y0=y0, observe=[0, 1])
    assert r.success
    assert abs(r.params["drag"] / 2e-3 - 1) < 1e-8 and abs(r.params["burn_rate"] / 10 - 1) < 1e-8
    lam = mp.phase.lyapunov_spectrum(rk, y0, 100.0, dt=10.0)
    assert lam[0] == 0.0 and -0.1 < lam[1] < 0 and lam[2] == -np.inf


def test_underivable_field_names_the_users_row():
    # a function SymPy cannot differentiate: the message names f[1] and the component,
    # not a row of the generated augmented system
    x, v = sp.symbols("x v")
    F = sp.Function("F")
    with pytest.raises(ValueError, match=r"d f\[1\] / d y\[0\]"):
        mp.tangent._derivatives([v, -F(x)], [x, v], sp.Symbol("t"), [], ["x", "v"])


def test_lyapunov_overflow_within_dt_says_shorten_dt():
    # x'' = 900 x: the tangent vectors grow by exp(30 dt); over dt = 40 that is past
    # float64 (the state, started at 1e-300, is not): the error names dt, not the solver
    x, v = sp.symbols("x v")
    sad = mp.equations([v, 900 * x], [x, v])
    with pytest.raises(mp.MechpyError, match="shorter dt") as exc:
        mp.phase.lyapunov_spectrum(sad, [1e-300, 0.0], 40.0, dt=40.0)
    assert "dydt" not in str(exc.value) and "radau" not in str(exc.value)
    # with dt = 0.1: |Phi(t) e1| = |(cosh 30t, 30 sinh 30t)| -> e^(30 t) sqrt(901) / 2, so
    # lambda_1 over 40 s is 30 + ln(sqrt(901) / 2) / 40; the sum is the divergence, 0
    lam = mp.phase.lyapunov_spectrum(sad, [1e-300, 0.0], 40.0, dt=0.1)
    assert abs(lam[0] - (30 + np.log(np.sqrt(901) / 2) / 40)) < 3e-9   # measured 2.9e-10
    assert abs(lam.sum()) < 1e-9                 # measured 8.2e-11


def test_fit_with_a_callable_observe_has_the_jacobian_and_errors_of_its_residual():
    """A callable ``observe`` (here sin(theta) of a damped pendulum): the covariance
    fit returns is (J^T J)^-1 for J the central differences of the whole weighted
    residual (plain solves, the observation applied to them), and the standard errors
    are the spread of the estimates over noise draws.  Pins the derivative of the
    callable observation (tangent._observer's dh), which carries the Jacobian and the
    errors and which no other test reaches: dh off by a factor of 2 fails here.
    Measured: cov against the differences 4.8e-9 relative; spread / stderr 1.11 and 1.01
    over 40 draws (resolved to about 11%); ~0.4 s."""
    sc = mp.scenes.Pendulum(damping=0.3, length=1.2)
    t = np.linspace(0, 6, 61)
    noise = 0.01

    def obs(y):
        return np.sin(y[:1])

    clean = obs(mp.solve(sc, (0, 6), [1.0, 0.0], t_eval=t, rtol=1e-12, atol=1e-14).y)
    rng = np.random.default_rng(11)

    def fit(data):
        return mp.fit(mp.scenes.Pendulum(), t, data, {"damping": 0.2, "length": 1.0},
                      y0=[1.0, 0.0], observe=obs, sigma=noise)

    data = clean + noise * rng.normal(size=clean.shape)

    def residual(p):
        s = mp.solve(mp.scenes.Pendulum(damping=p[0], length=p[1]), (0, 6), [1.0, 0.0],
                     t_eval=t, rtol=1e-12, atol=1e-14)
        return ((obs(s.y) - data) / noise).ravel()

    r = fit(data)
    assert r.success and r.names == ["damping", "length"]
    p = np.array([r.params["damping"], r.params["length"]])
    h = 1e-5
    J = np.column_stack([(residual(p + h * e) - residual(p - h * e)) / (2 * h)
                         for e in np.eye(2)])
    np.testing.assert_allclose(r.cov, np.linalg.inv(J.T @ J), rtol=5e-8)   # measured 4.8e-9
    est = np.array([list(fit(clean + noise * rng.normal(size=clean.shape)).params.values())
                    for _ in range(40)])
    ratio = est.std(axis=0, ddof=1) / np.array([r.stderr["damping"], r.stderr["length"]])
    assert np.all(np.abs(ratio - 1) < 0.3), ratio


def test_sign_of_zero_is_zero_in_the_sensitivities():
    """sign as SymPy's (and numpy's): sign(0) = 0.  x' = p sign(x) from x0 = 0 stays
    at 0 with dx/dp = 0 (a sign(0) taken as 1 would drive it to x = p t); from
    x0 = +-0.5 it is x0 + sign(x0) p t with dx/dp = sign(x0) t and dx/dx0 = 1."""
    x, p = sp.symbols("x p")
    sys_ = mp.equations([p * sp.sign(x)], [x], params={"p": 2.0})
    te = np.array([0.1, 0.5, 1.0])
    s = mp.sensitivity(sys_, (0, 1), [0.0], params=("p",), t_eval=te, rtol=1e-12, atol=1e-14)
    assert np.all(s.y == 0.0) and np.all(s.S[0, 0] == 0.0)
    for x0 in (0.5, -0.5):
        s = mp.sensitivity(sys_, (0, 1), [x0], params=("p",), t_eval=te, rtol=1e-12,
                           atol=1e-14)
        np.testing.assert_allclose(s.y[0], x0 + np.sign(x0) * 2.0 * te, rtol=0, atol=1e-13)
        np.testing.assert_allclose(s.S[0, 0], np.sign(x0) * te, rtol=0, atol=1e-13)
        np.testing.assert_allclose(s.S[0, 1], 1.0, rtol=0, atol=1e-13)


def test_fit_from_the_edge_of_an_open_domain():
    """A scene's open domain end is nudged inwards by 1e-12 of the scale, as
    tangent._scene_bounds documents: RestrictedThreeBody's mu in (0, 1) is fitted
    within [1e-12, 1 - 1e-12].  A guess on either nudged end is accepted (the fit runs
    and stays in the domain); a guess nearer the open end than that is refused,
    naming the domain."""
    y0 = [0.5, 0.2, 0.0, 0.3]
    t = np.linspace(0.1, 1.0, 10)
    r3 = mp.scenes.RestrictedThreeBody(mu=0.9)
    data = mp.solve(r3, (0, 1), y0, t_eval=t, rtol=1e-12, atol=1e-12).y[:2]
    for guess in (1.0 - 1e-12, 1e-12):
        fit = mp.fit(r3, t, data, {"mu": guess}, y0=y0, observe=[0, 1])
        assert fit.success and 1e-12 <= fit.params["mu"] <= 1.0 - 1e-12
    for guess in (1.0 - 0.5e-12, 0.5e-12):
        with pytest.raises(ValueError, match="outside its domain") as err:
            mp.fit(r3, t, data, {"mu": guess}, y0=y0, observe=[0, 1])
        assert f"[{1e-12}, {1.0 - 1e-12}]" in str(err.value)
