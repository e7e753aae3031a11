"""The course's additions: the rocket (Tsiolkovsky, constant g, drag against
SciPy), the logistic map (Feigenbaum's delta, r = 4 closed form), the heavy
top's steady precession and sleeping top, free precession, and the faults
fixed in the variational solvers and the rotating hoop."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import newton

import mechpy as mp

U, B, M0, MD = 2500.0, 10.0, 1000.0, 200.0          # exhaust m/s, kg/s, kg, kg


# ---------------------------------------------------------------- rocket
def test_rocket_tsiolkovsky():
    r = mp.scenes.Rocket(U, B, M0, MD)
    assert r.burnout_time == 80.0
    t = np.linspace(0, 120, 25)
    sol = r.fly((0.0, 120.0), t_eval=t, rtol=1e-13, atol=1e-12)
    m = np.maximum(M0 - B * t, MD)
    # v = u ln(m0/m); measured 9e-14 relative
    np.testing.assert_allclose(sol.y[1], U * np.log(M0 / m), rtol=1e-12, atol=0)
    np.testing.assert_allclose(sol.y[2], m, rtol=1e-14)    # measured 2.7e-15


def test_rocket_constant_gravity_closed_form():
    g = 9.81
    r = mp.scenes.Rocket(U, B, M0, MD, g=g)
    tb = r.burnout_time
    sol = r.fly((0.0, 150.0), dense_output=True, rtol=1e-13, atol=1e-12)
    t = np.linspace(0.0, tb, 9)
    m = M0 - B * t
    v = U * np.log(M0 / m) - g * t
    # h = int v dt = u [t + (m/b) ln(m/m0)] - g t^2/2
    h = U * (t + (m / B) * np.log(m / M0)) - 0.5 * g * t * t
    np.testing.assert_allclose(sol.sol(t)[1], v, rtol=0, atol=1e-9)        # measured 1.2e-10 m/s
    np.testing.assert_allclose(sol.sol(t)[0], h, rtol=0, atol=5e-8)        # measured 5.7e-9 m
    # coasting after burn-out: ballistic from the burn-out state
    vb, hb = v[-1], h[-1]
    tc = np.linspace(tb, 150.0, 7)
    np.testing.assert_allclose(sol.sol(tc)[1], vb - g * (tc - tb), rtol=0, atol=1e-9)   # 1e-10
    np.testing.assert_allclose(sol.sol(tc)[0], hb + vb * (tc - tb) - 0.5 * g * (tc - tb) ** 2,
                               rtol=2e-13)                               # 2.5e-14
    assert np.all(sol.y[2][sol.t >= tb] == MD)


def _rocket_ref(t, y, u, b, md, g, k):
    burn = y[2] > md
    return [y[1], ((u * b if burn else 0.0) - k * y[1] * abs(y[1])) / y[2] - g,
            -b if burn else 0.0]


def test_rocket_drag_against_solve_ivp():
    g, k = 9.81, 0.02
    r = mp.scenes.Rocket(U, B, M0, MD, g=g, drag=k)
    tb = r.burnout_time
    t = np.linspace(0.0, 200.0, 21)
    sol = r.fly((0.0, 200.0), t_eval=t, rtol=1e-12, atol=1e-10)
    a = solve_ivp(_rocket_ref, (0, tb), [0, 0, M0], args=(U, B, MD, g, k), method="DOP853",
                  rtol=1e-12, atol=1e-10, dense_output=True)
    yb = a.y[:, -1].copy()
    yb[2] = MD
    b = solve_ivp(_rocket_ref, (tb, 200.0), yb, args=(U, B, MD, g, k), method="DOP853",
                  rtol=1e-12, atol=1e-10, dense_output=True)
    ref = np.where(t <= tb, a.sol(np.minimum(t, tb)), b.sol(np.maximum(t, tb)))
    np.testing.assert_allclose(sol.y, ref, rtol=1e-10, atol=1e-9)   # measured 1e-11 relative
    # the Jacobian against central differences, burning, and without thrust (no
    # propellant burnt: the coasting branch's formula, off the switch)
    for rk, y in ((r, [100.0, 300.0, 500.0]), (r.replace(burn_rate=0.0), [100.0, -50.0, 500.0])):
        J = rk.jacobian(0.0, np.array(y))
        for j in range(3):
            d = np.zeros(3)
            d[j] = 1e-4 * max(1.0, abs(y[j]))
            fd = (rk.rhs(0.0, np.add(y, d)) - rk.rhs(0.0, np.subtract(y, d))) / (2 * d[j])
            np.testing.assert_allclose(J[:, j], fd, rtol=1e-7, atol=1e-10)


def test_rocket_bad_parameters():
    with pytest.raises(ValueError, match="m_dry"):
        mp.scenes.Rocket(U, B, 100.0, 200.0)
    with pytest.raises(ValueError, match="burn_rate"):
        mp.scenes.Rocket(U, -1.0, M0, MD)
    with pytest.raises(ValueError, match="drag"):
        mp.scenes.Rocket(U, B, M0, MD, drag=-1.0)
    with pytest.raises(ValueError, match="t_span"):
        mp.scenes.Rocket(U, B, M0, MD).fly((10.0, 0.0))


# ---------------------------------------------------------------- logistic
def test_logistic_fixed_point_and_r4_closed_form():
    r = np.array([0.5, 1.5, 2.0, 2.8])
    x = mp.phase.logistic(r, 0.3, n=1, skip=2000)[:, 0]
    np.testing.assert_allclose(x, np.where(r > 1, 1 - 1 / r, 0.0), atol=1e-12)
    theta = np.array([0.3, 0.71, 1.2])
    x = mp.phase.logistic(4.0, np.sin(theta) ** 2, n=8)
    k = np.arange(8)
    # x_k = sin^2(2^k theta); errors double per step (Lyapunov ln 2): measured 8e-15
    np.testing.assert_allclose(x, np.sin(2.0 ** k * theta[:, None]) ** 2, atol=1e-13)
    one = mp.phase.logistic(3.7, 0.2, n=50, skip=10)
    np.testing.assert_array_equal(one, mp.phase.logistic([3.7, 3.7], 0.2, n=50, skip=10)[0])


def test_feigenbaum_delta_from_superstable_parameters():
    """R_n: x = 1/2 lies on the 2^n cycle, f^(2^n)(1/2) = 1/2.  Published
    delta = 4.669201609... (Feigenbaum 1978)."""
    def g(r, k):
        return mp.phase.logistic(r, 0.5, n=1, skip=2 ** k)[0] - 0.5
    R = [2.0, 1 + np.sqrt(5.0)]
    for k in range(2, 8):
        guess = R[-1] + (R[-1] - R[-2]) / 4.7
        R.append(newton(g, guess, args=(k,), tol=1e-14, maxiter=100))
    R = np.array(R)
    assert R[2] == pytest.approx(3.4985616993277, abs=1e-12)      # published R_2
    delta = (R[1:-1] - R[:-2]) / (R[2:] - R[1:-1])
    # delta from R_5..R_7 = 4.669157: 4.4e-5 from 4.669201609 (measured)
    assert abs(delta[-1] - 4.669201609) < 2e-4
    assert abs(delta[-1] - 4.669201609) < abs(delta[0] - 4.669201609) / 50


def test_logistic_bifurcation_periods_and_bad_input():
    x = mp.phase.logistic_bifurcation([2.9, 3.2, 3.5, 3.55], n=64)
    periods = [len(np.unique(np.round(row, 8))) for row in x]
    assert periods == [1, 2, 4, 8]
    with pytest.raises(ValueError, match="r must lie"):
        mp.phase.logistic(4.5)
    with pytest.raises(ValueError, match="x0"):
        mp.phase.logistic(3.0, 1.5)
    with pytest.raises(ValueError, match="n"):
        mp.phase.logistic(3.0, n=0)


# ---------------------------------------------------------------- heavy top
I1, I3, MASS, G, L = 0.02, 0.01, 0.5, 9.81, 0.1


def test_steady_precession_keeps_theta():
    th, w3 = 0.6, 120.0
    top = mp.scenes.HeavyTop(I1, I3, MASS, G, L)
    for rate in mp.rigid.steady_precession(I1, I3, MASS, G, L, th, w3):
        y0 = [0.0, th, 0.0, rate, 0.0, w3 - rate * np.cos(th)]
        sol = mp.solve(top, (0.0, 2.0), y0, rtol=1e-13, atol=1e-13,
                       t_eval=np.linspace(0, 2, 201))
        # theta constant to 1e-9 rad (measured drift 2e-14); phi_dot to 5e-12 (measured)
        assert np.max(np.abs(sol.y[1] - th)) < 1e-9
        np.testing.assert_allclose(sol.y[3], rate, rtol=5e-11)


def test_steady_precession_fast_top_limit_and_errors():
    th = 0.4
    for w3 in (1e2, 1e3, 1e4):
        slow, fast = mp.rigid.steady_precession(I1, I3, MASS, G, L, th, w3)
        approx = MASS * G * L / (I3 * w3)
        # slow = Mgl/(I3 w3) (1 + I1 Mgl cos(th)/(I3 w3)^2 + ...)
        corr = I1 * MASS * G * L * np.cos(th) / (I3 * w3) ** 2
        assert slow == pytest.approx(approx * (1 + corr), rel=3 * corr ** 2 + 1e-15)
        assert fast == pytest.approx(I3 * w3 / (I1 * np.cos(th)), rel=2 * corr)
    with pytest.raises(ValueError, match="no steady precession"):
        mp.rigid.steady_precession(I1, I3, MASS, G, L, 0.3, 1.0)
    with pytest.raises(ValueError, match="theta"):
        mp.rigid.steady_precession(I1, I3, MASS, G, L, 0.0, 100.0)


@pytest.mark.parametrize("factor, sleeps", [(1.3, True), (0.7, False)])
def test_sleeping_top_threshold(factor, sleeps):
    w_crit = np.sqrt(4 * I1 * MASS * G * L) / I3
    w3 = factor * w_crit
    assert mp.rigid.sleeping_top(I1, I3, MASS, G, L, w3) is sleeps
    top = mp.scenes.HeavyTop(I1, I3, MASS, G, L)
    th0 = 0.01
    sol = mp.solve(top, (0.0, 5.0), [0.0, th0, 0.0, 0.0, 0.0, w3], rtol=1e-11, atol=1e-12)
    tmax = np.max(sol.y[1])
    # above the threshold the tilt stays within a few th0; below it the top falls over
    assert bool(tmax < 5 * th0) is sleeps, tmax


def test_free_precession_against_free_rotation():
    m = np.array([2.0, 2.0, 3.0])
    w = np.array([0.3, 0.1, 4.0])
    body, space = mp.rigid.free_precession(m, w)
    assert body == pytest.approx(4.0 * (3.0 - 2.0) / 2.0, rel=1e-15)
    t = np.linspace(0.0, 3.0, 301)
    om = mp.rigid.free_rotation(m, w, t)
    ang = np.unwrap(np.arctan2(om[:, 1], om[:, 0]))
    rate = np.polyfit(t, ang, 1)[0]
    assert rate == pytest.approx(body, rel=1e-13)            # measured below 1e-15
    # space frame: the symmetry axis turns about L at L/I1
    rb = mp.scenes.RigidBody(m, orientation=True)
    sol = mp.solve(rb, (0.0, 3.0), rb.initial_state(w), rtol=1e-13, atol=1e-13, t_eval=t)
    from scipy.spatial.transform import Rotation
    R = Rotation.from_quat(sol.y[3:].T)
    axis = R.apply([0.0, 0.0, 1.0])
    Lsp = R[0].apply(m * w)
    Lh = Lsp / np.linalg.norm(Lsp)
    e1 = np.cross(Lh, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(Lh, e1)
    phi = np.unwrap(np.arctan2(axis @ e2, axis @ e1))
    assert np.polyfit(t, phi, 1)[0] == pytest.approx(space, rel=2e-13)   # measured 2e-14
    Lmag = np.linalg.norm(m * w)
    assert space == pytest.approx(m[2] * w[2] / (m[0] * (m[2] * w[2] / Lmag)), rel=1e-14)


def test_chandler_euler_period():
    """Euler's prediction of the Earth's free nutation: (C - A)/A = 1/305 gives a
    period of 305 sidereal days (Lambeck, The Earth's Variable Rotation, 1980,
    section 1; the observed Chandler period is about 433 days, lengthened by
    the Earth's elasticity)."""
    day = 86164.0905
    body, _ = mp.rigid.free_precession([1.0, 1.0, 1.0 + 1.0 / 305.0], [1e-9, 0.0, 2 * np.pi / day])
    assert 2 * np.pi / body / day == pytest.approx(305.0, rel=1e-12)
    with pytest.raises(ValueError, match="symmetric"):
        mp.rigid.free_precession([1.0, 1.5, 2.0], [0.1, 0.0, 1.0])


# ---------------------------------------------------------------- faults
def test_brachistochrone_integrand_refused():
    """Before: 8.5% below the cycloid's time with a residual of 5e-14 at n = 200,
    and a DomainError for n >= 400."""
    g = 9.81

    def F(x, y, p):
        return np.sqrt((1 + p * p) / (2 * g * y))
    for n in (200, 400):
        with pytest.raises(ValueError, match="singular at the end point x = 0.0"):
            mp.variational.minimize_functional(F, (0.0, 2.0), (0.0, 1.0), n=n)
    # the same problem in the form that is finite at the ends: the cycloid
    ref = mp.variational.brachistochrone(2.0, 1.0, n=400)
    assert abs(ref.time - ref.time_exact) < 1e-6
    # singular at the far end is found too; a smooth integrand is not refused
    with pytest.raises(ValueError, match="x = 1.0"):
        mp.variational.minimize_functional(lambda x, y, p: p * p / np.sqrt(1 - x),
                                           (0.0, 1.0), (0.0, 1.0))
    r = mp.variational.minimize_functional(lambda x, y, p: 0.5 * p * p + 0.5 * y * y,
                                           (0.0, 1.0), (0.0, 1.0))
    np.testing.assert_allclose(r.y, np.sinh(r.x) / np.sinh(1.0), atol=1e-4)


def test_stationary_paths_of_the_pendulum():
    """Linearised, theta'' = -theta with theta(0) = theta(T) = 0 has non-zero
    solutions at T = k pi: past k of them the pendulum has 2k + 1 paths."""
    P = mp.scenes.Pendulum(g=1.0)
    for T, count in ((2.0, 1), (4.5, 3), (8.0, 5)):
        paths = mp.variational.stationary_paths(P, 0.0, 0.0, T)
        assert len(paths) == count
        amps = sorted(float(np.max(np.abs(p.q))) for p in paths)
        assert amps[0] < 1e-12
        for p in paths:        # each a stationary path: the Euler-Lagrange residual
            assert p.q[0] == 0.0 and p.q[-1] == 0.0
        acts = [p.action for p in paths]
        assert acts == sorted(acts)
    three = mp.variational.stationary_paths(P, 0.0, 0.0, 4.5)
    # the two swings mirror each other
    np.testing.assert_allclose(three[0].q, -three[1].q, atol=1e-8)


def test_rotating_hoop_normal_force_scalar_t_batch():
    h = mp.variational.RotatingHoop(R=0.5, omega=3.0, g=9.81, m=2.0)
    y = np.random.default_rng(1).uniform(-1, 1, (2, 4, 5))
    N = h.normal_force(0.7, y)
    assert N.shape == (3, 4, 5)
    th, thd = y
    m, R, w, g = 2.0, 0.5, 3.0, 9.81
    np.testing.assert_allclose(N[0], -m * R * (thd**2 + w**2 * np.sin(th)**2) - m * g * np.cos(th),
                               atol=1e-12)
    np.testing.assert_allclose(N[1], 2 * m * R * w * thd * np.cos(th), atol=1e-12)
    np.testing.assert_allclose(N[2], 0.0, atol=1e-12)
